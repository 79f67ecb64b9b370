"""The verifier's checks, in report order: what each protects and whether it gates.

Each check is one function ``(SampledPlan, Config) -> CheckItem`` in one of the ``checks_*``
modules, listed here once with its purpose:

* ``"required"`` - guards the robot, the part or the accuracy; a failure means no program;
* ``"process"`` - a process figure, reported with its bound; it fails only where the part's
  recipe sets a threshold (:class:`drakedeburr.config.Acceptance`);
* ``"info"`` - statistics, never failing.

To add a check: write the function next to its kind, add one line to :data:`CHECKS`
(docs/verify.md shows an example).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Literal

from drakedeburr.verify import checks_distance as dist
from drakedeburr.verify import checks_motion as motion
from drakedeburr.verify import checks_path as path
from drakedeburr.verify import checks_payload as load
from drakedeburr.verify import checks_plan as plan
from drakedeburr.verify import checks_process as process
from drakedeburr.verify.report import CheckItem

__all__ = ["Check", "CHECKS", "run_checks"]

Purpose = Literal["required", "process", "info"]


@dataclass(frozen=True)
class Check:
    """One check: its report name, its function, its purpose and a line for the docs."""

    name: str
    run: Callable[..., CheckItem]
    purpose: Purpose
    doc: str


CHECKS: tuple[Check, ...] = (
    Check("structure", plan.structure, "required",
          "segments tile the trajectory and the target list"),
    Check("planner_failures", plan.planner_failures, "required",
          "the plan records no failed point or move"),
    Check("recipe_deviations", plan.recipe_deviations, "info",
          "where the plan departs from the part's recipe, and where the hub was placed"),
    Check("fk_agreement", plan.fk_agreement, "required",
          "Drake plant and analytic OPW forward kinematics agree"),
    Check("target_consistency", plan.target_consistency, "required",
          "each target's joints reach its pose; the trajectory reaches each segment's end"),
    Check("path_deviation", path.path_deviation, "required",
          "tool point vs the linear program, both ways"),
    Check("orientation_agreement", path.orientation_agreement, "required",
          "tool orientation vs the program's slerp"),
    Check("program_zones", path.program_zones, "required",
          "the trajectory passes each target within its zone"),
    Check("windows", plan.windows, "required", "every window cut, every CL point targeted"),
    Check("uncut_edge", plan.uncut_edge, "required",
          "no edge left uncut in a partial window (cut N of M mm, the stretches left, why)"),
    Check("edge_deviation", path.edge_deviation, "required",
          "executed contact point vs the hub's true edge"),
    Check("edge_coverage", path.edge_coverage, "required",
          "every true edge point near the executed contact path"),
    Check("burr_engagement", path.burr_engagement, "required",
          "the true edge's depth in the burr cone within the depth of cut"),
    Check("cone", path.cone, "required", "executed tool axis inside its admissible cone"),
    Check("theta_box", path.theta_box, "process",
          "share of the cut with the axis inside the source's theta box"),
    Check("theta_statistics", path.theta_statistics, "info",
          "theta_A/theta_B at the CL targets (source Tab. 3-6)"),
    Check("clearance", dist.clearance, "required",
          "robot and tool vs hub and cell, burr head-hub excepted"),
    Check("clearance_certificate", dist.clearance_certificate, "required",
          "clearance and self distance bounded between the samples, over the whole trajectory"),
    Check("self_collision", dist.self_collision, "required", "robot and tool vs themselves"),
    Check("burr_contact", dist.burr_contact, "required",
          "burr head into the hub at most the depth of cut (cutting moves), clear elsewhere"),
    Check("joint_position", motion.joint_position, "required",
          "joint positions inside the limits (exact on the spline)"),
    Check("joint_velocity", motion.joint_velocity, "required",
          "joint velocities inside the limits (exact on the spline)"),
    Check("joint_acceleration", motion.joint_acceleration, "required",
          "joint accelerations inside the limits (exact on the spline)"),
    Check("payload", load.payload, "required",
          "tool + gripper + part within the arm's rated payload (mass; wrist moments and "
          "inertias where the vendor publishes them)"),
    Check("rest_at_ends", motion.rest_at_ends, "required", "at rest at start and end"),
    Check("start_end_home", motion.start_end_home, "info", "starts and ends at home"),
    Check("configuration", motion.configuration, "required",
          "one shoulder/elbow/wrist configuration per window"),
    Check("tcp_speed_band", process.tcp_speed_band, "process",
          "share of the cut within the feed band"),
    Check("slowdowns_justified", process.slowdowns_justified, "required",
          "where a cut runs below the feed, a joint or TCP limit binds (no needless slack)"),
    Check("tcp_speed_max", process.tcp_speed_max, "required",
          "TCP speed never above the programmed speed + band"),
    Check("program_speeds", process.program_speeds, "required",
          "each cutting move's programmed speed is the speed the motion runs there"),
    Check("wrist_singularity", motion.wrist_singularity, "required",
          "|J5| keeps its margin from the wrist singularity"),
    Check("manipulability", motion.manipulability, "info", "|det J| of the flange Jacobian"),
    Check("j4_j6_range", process.j4_j6_range, "process", "J4-J6 ranges per window"),
    Check("cycle_time", process.cycle_time, "process", "cycle time vs its physical bound"),
    Check("time_budget", process.time_budget, "info",
          "where the cycle goes: per window the cut vs edge length / feed, the moves off the "
          "cut vs their joint-limit bound, J4-J6 ranges, the limit binding each slow stretch"),
    Check("cl_chord_error", path.cl_chord_error, "required",
          "chord-height error of the CL points vs the true edge"),
    Check("cl_chord_length", path.cl_chord_length, "required", "longest chord between CL points"),
)


def run_checks(sp, config, checks: tuple[Check, ...] = CHECKS) -> tuple[CheckItem, ...]:
    """Every check's item, its ``required`` flag set by its purpose."""
    return tuple(replace(c.run(sp, config), name=c.name, required=c.purpose == "required")
                 for c in checks)
