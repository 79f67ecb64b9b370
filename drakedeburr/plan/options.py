"""Planner settings (:class:`PlanOptions`) and what a planning run works with
(:class:`PlanContext`: the cell, its kinematics, the clearance checkers and the configuration).

Process numbers (speeds, TCP acceleration, depth of cut, boxes) come from the run's recipe and
acceptance bounds (clearance, wrist margin, program orientation) from its tolerances
(:class:`drakedeburr.config.Config`); the options hold only how the planner searches.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.config import Config
from drakedeburr.plan.fillets import FilletOptions
from drakedeburr.plan.ik import IkOptions
from drakedeburr.plan.timing import TimingLimits

if TYPE_CHECKING:
    from drakedeburr.cell.station import Cell
    from drakedeburr.plan.kinematics import CellKinematics, ClearanceChecker

__all__ = ["PlanOptions", "PlanContext", "RunMode"]


class RunMode(enum.Enum):
    """How a window pass is run: an argument of :func:`drakedeburr.plan.window.plan_window`
    (the hub policy's passes choose it, :mod:`drakedeburr.plan.planner`), not a planner
    setting; never recorded in the plan.

    ``FULL``: every target, every start configuration, both spin rules. ``FAIL_FAST``: stop a
    window's IK pass at its first failed target, and a window whose executed cut stays under
    the clearance after its axis is pinned (the window fails under the recipe whatever the
    rest does: status ``ABANDONED``), instead of planning the rest of it; the other start
    seeds and spin rule are still tried, each stopping at its first failure (the first pass of
    a hub with relaxation on, and the relaxed variants). ``REPORT_ONLY``: plan a window once,
    for its report: the first start configuration and the IK's own spin rule, every target
    tried (a window the fail-fast pass abandoned and no relaxation cut: it fails whichever
    start fails least, so the search for that start is not made)."""

    FULL = "full"
    FAIL_FAST = "fail_fast"
    REPORT_ONLY = "report_only"


@dataclass(frozen=True)
class PlanOptions:
    """How the planner searches (process numbers and bounds come from the Config).

    Attributes:
        ik: per-target IK settings.
        dense_step: tool travel between dense samples of the executed motion [m].
        approach_distance: approach/retract length along the tool axis [m].
        joint_step: joint-space sample spacing of joint moves [rad].
        max_joint_jump: largest joint change allowed between dense samples [rad] (a flip or a
            2*pi turn shows as ~1-6 rad; fast wrist motion at corners reaches ~0.05).
        windows: indices of the windows to plan (None = all), in this order.
        fit_spacings: knot spacings [m] of the least-squares joint spline of approach and
            retract, widest first.
        fit_tolerance: largest tool deviation [m] the joint-spline fit may cause.
        contact_radius: radius of the flank circle that cuts [m] (None: the burr's nominal
            3 mm); smaller lifts the shank off the face (:func:`targets.contact_geometry`).
        window_attempts: distinct start configurations tried when a window's IK fails.
        blend_deviation: largest distance of a corner blend from its target [m]
            (:mod:`drakedeburr.plan.cut_path`: corners blended, the smoothest axis in the cones).
        spin_sigma: Gaussian width of the IK orientations' smoothing before the axis program [m].
        axis_margin: the smoothed axis keeps this far inside its cone [rad] (so the program's
            own slerp between targets stays inside too).
        spin_search: choose the spin about the tool axis by dynamic programming
            (:mod:`drakedeburr.plan.spin`); False: the IK's spin, smoothed.
        spin_band: the search stays within this of the IK's spin [rad].
        program_orientation_share: via targets (``cl_index`` -1) are added on the executed path
            where the program's orientation (slerp between consecutive targets, as a controller
            interpolates) strays from the executed one by more than this share of
            ``Tolerances.orientation_match``.
        program_position_share: and where the executed tool point strays from the program's
            linear moves (read as the verifier reads it) by more than this share of
            ``Tolerances.path_deviation`` (a via on the path splits the move's chord; the
            corner blends keep 0.6 of it, so only a path that winds between targets gets one).
        via_rounds: rounds of via insertion.
        conform_program: where the program still strays after the vias (moves too short for
            one), pull the executed orientation onto the program's there
            (:func:`drakedeburr.plan.program_fit.conform_to_program`).
        retry_in_band: a window planned without failure records but with less than this share
            of its cut within the speed band is planned again with the other warm-start spin
            rule, and the faster of the two kept.
        acceleration_scale: what-if factor on the robot model's joint acceleration limits and
            on the recipe's TCP acceleration (1: plan to the model). The model's accelerations
            are assumed values; this factor measures how the speed band and cycle time depend
            on them (``benchmarks/bench_plan.py --accel-sweep``). The verifier checks the
            model's own limits, so a plan made with a factor above 1 fails its acceleration
            check: to plan for a robot whose real accelerations are known, put them in the
            model instead.
        fillets: fillet repair (:mod:`drakedeburr.plan.fillets`, on by default): where the
            timed cut falls below the speed band, the feed program finds a tool orientation
            that holds the feed where one exists; None: off.
        placement: choose the hub's pose on its mount and each window's arm branch by a
            search before planning (:mod:`drakedeburr.plan.placement`); False: the hub where
            the cell's mount puts it, each window's starts ranked from home.
        relax: plan a window the recipe cannot cut again with a milder tilt box, the
            deviation recorded (:mod:`drakedeburr.plan.relax`).
        tool_precheck: before a window's IK, search the cone at each target for an axis on
            which the round tool parts clear the part (:func:`drakedeburr.plan.window.
            tool_refusal`); a window with a target where none can is refused with that
            reason and no IK is run. False: every window goes to the IK (a baseline).
        partial_windows: a window the pre-check refuses has its clear runs planned as open
            stretches, the rest recorded as uncut (:mod:`drakedeburr.plan.partial`); False:
            the whole window is refused.
        workers: processes planning windows at once (:mod:`drakedeburr.plan.parallel`; None:
            the cores this process may use, 1: one after the other here). The plan is the
            same whatever the number (it is not recorded in the plan).
    """

    ik: IkOptions = field(default_factory=IkOptions)
    dense_step: float = 0.25e-3
    approach_distance: float = 15e-3
    joint_step: float = 0.004
    max_joint_jump: float = 0.2
    windows: tuple[int, ...] | None = None
    fit_spacings: tuple[float, ...] = (6e-3, 4e-3, 2e-3, 1e-3)
    fit_tolerance: float = 0.03e-3
    contact_radius: float | None = 1.6e-3
    window_attempts: int = 4
    blend_deviation: float = 0.03e-3
    spin_sigma: float = 3e-3
    axis_margin: float = 10e-3
    spin_search: bool = True
    spin_band: float = 1.2
    program_orientation_share: float = 0.6
    program_position_share: float = 0.8
    via_rounds: int = 8
    conform_program: bool = True
    retry_in_band: float = 0.5
    tool_precheck: bool = True
    partial_windows: bool = True
    acceleration_scale: float = 1.0
    fillets: FilletOptions | None = field(default_factory=FilletOptions)
    placement: bool = True
    relax: bool = True
    workers: int | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.acceleration_scale) and self.acceleration_scale > 0):
            raise ValueError("PlanOptions.acceleration_scale must be a positive number, got "
                             f"{self.acceleration_scale!r}")


@dataclass(frozen=True, eq=False)
class PlanContext:
    """What a planning run works with: the loaded cell, its kinematics, clearance checkers
    (``checker``: the burr head/hub contact filtered, for cutting moves; ``free_checker``: not
    filtered, for moves that do not cut), the run's configuration, the options and the
    per-window branch references.

    The IK's clearance bounds follow the configuration: ``options.ik`` is held at
    ``config.tolerances.min_clearance`` (:meth:`drakedeburr.plan.ik.IkOptions.at_clearance`),
    so the plan records the bounds its IK used."""

    cell: Cell
    kin: CellKinematics
    checker: ClearanceChecker
    free_checker: ClearanceChecker | None
    config: Config
    options: PlanOptions
    #: window -> (6,) a configuration on the branch chosen to cut it (placement search)
    q_refs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        # a stand-in configuration without tolerances (a test's) keeps the options' own bounds
        tol = getattr(self.config, "tolerances", None)
        if tol is not None:
            ik = self.options.ik.at_clearance(tol.min_clearance)
            object.__setattr__(self, "options", replace(self.options, ik=ik))

    @property
    def process(self):
        return self.config.process

    @property
    def min_clearance(self) -> float:
        return self.config.tolerances.min_clearance

    @property
    def cut_clearance(self) -> float:
        """Least clearance [m] the planner keeps at a dense sample of a move that cuts or
        approaches: the verifier's limit plus what can hide between two samples. The tool
        travels ``dense_step`` between samples, and a point passing a hub edge or vertex at
        distance d dips up to step^2 / (8 d) below the chord of its two samples' readings (the
        distance along the pass is sqrt(d^2 + s^2)): 3.9 um at 0.25 mm and 2 mm; plus the
        readings' numerical slack. The verifier still proves the clearance over the whole
        trajectory (``clearance_certificate``).

        Design note: a bound at the limit itself let a plan of an unseen catalogue hub pass the
        planner's samples and fail the verifier's by 0.1 um."""
        from drakedeburr.plan.kinematics import DISTANCE_SLACK

        d = self.min_clearance
        return d + self.options.dense_step ** 2 / (8 * d) + DISTANCE_SLACK

    @property
    def program_orientation(self) -> float:
        """Largest program-vs-executed orientation the planner leaves [rad]."""
        return self.options.program_orientation_share * self.config.tolerances.orientation_match

    @property
    def program_position(self) -> float:
        """Largest executed-vs-program tool point distance the planner leaves [m]."""
        return self.options.program_position_share * self.config.tolerances.path_deviation

    def limits(self, v_cap: float) -> TimingLimits:
        """Timing limits of a stretch with TCP speed cap ``v_cap`` [m/s]."""
        f = self.options.acceleration_scale
        return TimingLimits(v_cap=v_cap, a_cap=self.process.tcp_acceleration * f,
                            v_max=tuple(self.kin.v_max),
                            a_max=tuple(np.asarray(self.kin.a_max) * f))
