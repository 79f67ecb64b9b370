"""Plan (planning stage contract) -> RobotProgram for the writers.

Tool-in-hand plans only: every :class:`~drakedeburr.plan.types.CartesianTarget` becomes one
move with its flange pose, joints, speed and zone; cut/approach/retract targets are linear
moves, home/transition targets joint moves. A plan with failures is flagged FORCED.
"""

from __future__ import annotations

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.plan.types import Plan
from drakedeburr.post.opw_ik import IRB1600_10_120_ROBOT, RobotKinematics
from drakedeburr.post.program import JOINT, LINEAR, ProgramMove, RobotProgram

__all__ = ["program_from_plan"]

_JOINT_SEGMENTS = ("home", "transition")


def program_from_plan(
    plan: Plan,
    name: str,
    X_FT: np.ndarray,
    X_WO: np.ndarray | None = None,
    robot: RobotKinematics = IRB1600_10_120_ROBOT,
    verified: bool = False,
    **kwargs,
) -> RobotProgram:
    """Build the program of a tool-in-hand plan.

    Args:
        plan: the plan.
        name: program name.
        X_FT: (4, 4) tool (burr cutting point) in the flange frame [m], the one the plan used.
        X_WO: (4, 4) work object for the program [m]; default: the plan's hub pose X_WH, so
            the robtargets are hub coordinates and re-targeting a registered hub means
            changing the work object only.
        robot: kinematics.
        verified: the plan passed verification (otherwise the header says UNVERIFIED).
        **kwargs: other :class:`RobotProgram` fields (tool_name, notes, ...).

    Raises:
        InputError: workpiece-in-hand plan, or an empty plan.
    """
    if plan.mode != "tool":
        raise InputError("program_from_plan: workpiece-in-hand plans need a stationary-tool "
                         "program (ABB robhold/ufprog); not supported yet")
    if not plan.targets:
        raise InputError("program_from_plan: the plan has no targets")
    X_FT = np.asarray(X_FT, float)
    moves = []
    prev = None
    for t in plan.targets:
        label = (t.segment, t.window_index)
        comment = ""
        if label != prev:
            comment = t.segment + (f" window {t.window_index + 1}" if t.window_index >= 0 else "")
        prev = label
        moves.append(ProgramMove(
            X_WT=np.asarray(t.X_WF, float) @ X_FT, q=np.asarray(t.q, float),
            move_type=JOINT if t.segment in _JOINT_SEGMENTS else LINEAR,
            speed=float(t.speed), zone=float(t.zone), comment=comment))
    if plan.failures:
        flag, reason = "FORCED", f"{len(plan.failures)} planning failure(s) in the plan"
    elif not verified:
        flag, reason = "UNVERIFIED", "plan not verified"
    else:
        flag, reason = "", ""
    kwargs.setdefault("source", f"plan {plan.scenario} / {plan.hub}")
    kwargs.setdefault("flag", flag)
    kwargs.setdefault("flag_reason", reason)
    return RobotProgram(name=name, moves=tuple(moves), X_FT=X_FT,
                        X_WO=np.asarray(plan.X_WH if X_WO is None else X_WO, float),
                        robot=robot, **kwargs)
