"""Plan -> :class:`RobotProgram`: the one conversion export, demo and the verifier use.

Every :class:`~drakedeburr.plan.types.CartesianTarget` becomes one move carrying the verified
motion: its flange pose and joints, its own TCP speed and its zone (never rounded to a standard
speed here; the formats' resolutions are in :mod:`drakedeburr.programs.common`). Linear
targets become MoveL/LIN/L, joint targets MoveJ/PTP/J at the fraction of the axes' top speed
the planned trajectory reaches on the way there.

* tool in hand: the flange carries the tool T (``X_FT``), the work object is the hub frame H
  (``X_WO = X_BH``): hub coordinates, so re-targeting a registered hub means changing the
  work object only;
* workpiece in hand: a stationary-tool program; the flange carries the hub (``X_FT := X_FH``),
  the fixed frame is the spindle's TCP (``X_WO := X_BT``).

Poses are expressed in the arm's base frame B: ``X_BF = X_WB^-1 X_WF`` with the mount ``X_WB``
recorded in the plan (``plan.frames.X_WB``; identity for plans made before mounts existed).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.programs.program import (
    JOINT,
    LINEAR,
    ProgramMove,
    RobotProgram,
    zones_within_half_moves,
)
from drakedeburr.robots import DEFAULT_ROBOT, RobotSpec, fk_opw, get_robot

__all__ = ["FlangeLoads", "program_from_plan", "plan_robot", "joint_fractions", "joint_vias",
           "VIA_TOLERANCE"]

log = logging.getLogger(__name__)

_JOINT_SEGMENTS = ("home", "transition")


@dataclass(frozen=True)
class FlangeLoads:
    """What the arm carries, from the cell's models (``Cell.flange_loads()``).

    Attributes:
        tool_mass: [kg] of the equipment bolted to the flange (spindle, or gripper).
        tool_cog: (3,) its centre of gravity in the flange frame F [m].
        workpiece_mass, workpiece_cog: the workpiece held (workpiece in hand), else 0.
        source: where the numbers come from (written in the program header).
    """

    tool_mass: float
    tool_cog: tuple[float, float, float]
    workpiece_mass: float = 0.0
    workpiece_cog: tuple[float, float, float] = (0.0, 0.0, 0.0)
    source: str = ""


def plan_robot(plan) -> RobotSpec:
    """The arm a plan was made for (``plan.meta["robot"]``; the default arm for older plans)."""
    name = plan.meta.get("robot") if isinstance(plan.meta, dict) else None
    if name is None:
        log.info("plan without meta['robot'] (made before the arm registry): %s", DEFAULT_ROBOT)
    return get_robot(name)


def joint_fractions(plan, spec: RobotSpec) -> dict[int, float]:
    """target index -> fraction of the axes' top speed the trajectory reaches on the joint
    segment that ends there (max over the segment's knots of |qd_i| / v_max_i)."""
    out = {}
    t, qd = np.asarray(plan.trajectory.t), np.asarray(plan.trajectory.qd)
    for seg in plan.segments:
        if seg.kind not in _JOINT_SEGMENTS:
            continue
        t0, t1 = seg.t_range
        sel = (t >= t0 - 1e-9) & (t <= t1 + 1e-9)
        frac = float((np.abs(qd[sel]) / spec.v_max).max()) if np.any(sel) else 0.0
        for k in range(*seg.target_range):
            out[k] = float(np.clip(frac, 0.01, 1.0))
    return out


#: [rad] how far the controller's joint-space straight line between two written joint moves may
#: leave the plan's joint path on a home/transition segment (a PTP/MoveJ/J move interpolates
#: the joints linearly): the plan's transitions bend around the hub, so their shape is
#: written as via points (Douglas-Peucker in joint space, largest joint deviation)
VIA_TOLERANCE = 1e-3


def _simplify(Q: np.ndarray, tol: float) -> list[int]:
    """Indices of the samples ``Q`` (M, 6) to keep so that the polyline through them is within
    ``tol`` (largest joint difference) of every sample; first and last always kept."""
    keep, stack = {0, len(Q) - 1}, [(0, len(Q) - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        f = (np.arange(a + 1, b) - a) / (b - a)
        chord = Q[a] + f[:, None] * (Q[b] - Q[a])
        err = np.abs(Q[a + 1:b] - chord).max(axis=1)
        j = int(np.argmax(err))
        if err[j] > tol:
            m = a + 1 + j
            keep.add(m)
            stack += [(a, m), (m, b)]
    return sorted(keep)


def joint_vias(plan, k: int, tol: float = VIA_TOLERANCE) -> np.ndarray:
    """(V, 6) joints on the plan's path into joint target ``k`` (its home/transition segment)
    where a straight joint-space move from the previous written point would leave the path by
    more than ``tol``; empty when the segment is a straight line in joint space."""
    seg = next((s for s in plan.segments if s.kind in _JOINT_SEGMENTS
                and s.target_range == (k, k + 1)), None)
    if seg is None or k == 0:
        return np.zeros((0, 6))
    t = np.linspace(seg.t_range[0], seg.t_range[1], 400)
    Q = np.asarray(plan.trajectory.value(t))
    idx = _simplify(Q, tol)
    return Q[idx[1:-1]]


def _comments(targets) -> list[str]:
    out, prev = [], None
    for t in targets:
        label = (t.segment, t.window_index)
        out.append("" if label == prev else
                   t.segment + (f" window {t.window_index}" if t.window_index >= 0 else ""))
        prev = label
    return out


def program_from_plan(
    plan,
    name: str = "Deburr",
    *,
    robot: RobotSpec | str | None = None,
    loads: FlangeLoads | None = None,
    verified: bool = False,
    flag: str = "",
    flag_reason: str = "",
    include_transitions: bool = True,
) -> RobotProgram:
    """The program of a plan (module docstring).

    Args:
        plan: :class:`~drakedeburr.plan.types.Plan`.
        name: program/module name (KRL and LS take the file name when written).
        robot: the arm; default: the plan's (``meta["robot"]``).
        loads: the cell's loads (``Cell.flange_loads()``); None: the program's defaults, and
            the header says they are not from a tool model.
        verified: the plan passed verification (otherwise the header says UNVERIFIED).
        flag, flag_reason: header warning; empty: FORCED when the plan has failures, else
            UNVERIFIED unless ``verified``.
        include_transitions: keep home/transition joint moves.

    Raises:
        InputError: an empty plan, or ``robot`` is not the arm the plan was made for.
    """
    spec = plan_robot(plan)
    if robot is not None and get_robot(robot) is not spec:
        raise InputError(f"the plan was made for {spec.name}, not {get_robot(robot).name}: "
                         "re-plan with --robot")
    if not plan.targets:
        raise InputError("program_from_plan: the plan has no targets")
    keep = [k for k, t in enumerate(plan.targets)
            if include_transitions or t.segment not in _JOINT_SEGMENTS]
    targets = [plan.targets[k] for k in keep]
    frames = plan.frames
    X_BW = np.linalg.inv(frames.X_WB)
    if plan.mode not in ("tool", "workpiece"):
        raise InputError(f"plan mode {plan.mode!r} is neither 'tool' nor 'workpiece'")
    try:
        X_Fc, X_WT = frames.carried(plan.mode)
    except KeyError as exc:
        raise InputError(f"the plan's record has no {exc.args[0]} (the {plan.mode}-in-hand "
                         "cell's frame): re-plan") from exc
    if plan.mode == "tool":
        X_BO, tool_name = X_BW @ plan.X_WH, "tBurr"
    else:
        X_BO, tool_name = X_BW @ X_WT, "tSpindle"
    fractions = joint_fractions(plan, spec)
    comments = _comments(targets)
    moves = []
    for k, t, c in zip(keep, targets, comments, strict=True):
        joint = getattr(t, "motion", None) == "joint" or (
            getattr(t, "motion", None) is None and t.segment in _JOINT_SEGMENTS)
        if joint and moves:  # the plan's bent joint path, as via points
            for q in joint_vias(plan, k):
                moves.append(ProgramMove(X_WT=fk_opw(spec.opw, q) @ X_Fc, q=q, move_type=JOINT,
                                         speed=float(t.speed), zone=0.0,
                                         joint_fraction=fractions.get(k)))
        moves.append(ProgramMove(
            X_WT=X_BW @ np.asarray(t.X_WF, float) @ X_Fc, q=np.asarray(t.q, float),
            move_type=JOINT if joint else LINEAR, speed=float(t.speed), zone=float(t.zone),
            comment=c, joint_fraction=fractions.get(k)))
    if not flag:
        if plan.failures:
            flag, flag_reason = "FORCED", f"{len(plan.failures)} planning failure(s) in the plan"
        elif not verified:
            flag, flag_reason = "UNVERIFIED", "plan not verified"
    extra = {}
    if loads is not None:
        extra = dict(tool_mass=loads.tool_mass, tool_cog=tuple(loads.tool_cog),
                     workpiece_mass=loads.workpiece_mass,
                     workpiece_cog=tuple(loads.workpiece_cog), load_source=loads.source)
    notes = (f"plan: scenario {plan.scenario}, hub {plan.hub}, mode {plan.mode}",
             f"cycle {plan.trajectory.duration:.2f} s, {len(plan.failures)} failure records")
    tool = plan.meta.get("tool") if isinstance(plan.meta, dict) else None
    if tool:  # not the standard burr: the operator mounts this one (the TCP is its)
        notes += (f"burr: {plan.meta.get('tool_title') or tool}: mount it before running",)
    return zones_within_half_moves(RobotProgram(
        name=name, moves=moves, X_FT=X_Fc, X_WO=X_BO, robot=spec,
        stationary_tool=plan.mode == "workpiece", tool_name=tool_name, wobj_name="wobjHub",
        source=f"drakedeburr plan {plan.hub}", flag=flag, flag_reason=flag_reason,
        notes=notes, **extra))
