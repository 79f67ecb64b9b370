"""Plan -> RobotProgram: targets become moves; the written program reaches the plan's joints."""

import numpy as np
import pytest

import drakedeburr.post.plan_program as mut
from drakedeburr.errors import InputError
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment
from drakedeburr.post.configuration import abb_confdata, joints_from_configuration
from drakedeburr.post.opw import fk_opw
from drakedeburr.post.opw_ik import IRB1600_10_120_ROBOT as ROBOT
from drakedeburr.post.writers import format_rapid


def _plan(mode="tool", failures=()):
    q0 = np.array([0.0, 0.1, -0.2, 0.0, 1.2, 0.0])
    qs = [q0 + np.array([0.02 * k, 0.01 * k, 0.0, 0.01 * k, 0.0, -0.02 * k]) for k in range(5)]
    segs = ["home", "approach", "cut", "cut", "retract"]
    X_WH = np.eye(4)
    X_WH[:3, 3] = [0.7, 0.0, 0.2]
    targets = tuple(
        CartesianTarget(window_index=-1 if s == "home" else 0, segment=s, cl_index=k,
                        X_HT=np.eye(4), X_WF=fk_opw(ROBOT.opw, q), q=q,
                        speed=0.15 if s == "cut" else 0.45, zone=0.0005 if s == "cut" else 0.0)
        for k, (s, q) in enumerate(zip(segs, qs, strict=True)))
    traj = JointTrajectory.from_hermite(t=np.array([0.0, 1.0]), q=np.array([qs[0], qs[-1]]),
                           qd=np.zeros((2, 6)))
    return Plan(scenario="cell", hub="hub", mode=mode, X_WH=X_WH, targets=targets,
                segments=(PlanSegment(0, "cut", (0, 5), (0.0, 1.0)),), trajectory=traj,
                failures=failures)


def test_program_from_plan_round_trip():
    X_FT = np.eye(4)
    X_FT[:3, 3] = [0.0, 0.0, 0.18]
    plan = _plan()
    prog = mut.program_from_plan(plan, "hub1", X_FT)
    assert [m.move_type for m in prog.moves] == ["joint"] + ["linear"] * 4
    assert [m.comment for m in prog.moves] == ["home", "approach window 1", "cut window 1", "",
                                               "retract window 1"]
    assert prog.flag == "UNVERIFIED" and np.allclose(prog.X_WO, plan.X_WH)
    for m, t in zip(prog.moves, plan.targets, strict=True):
        X_WF = m.X_WT @ np.linalg.inv(X_FT)
        assert np.allclose(X_WF, t.X_WF, atol=1e-12)
        q = joints_from_configuration(ROBOT, X_WF, "abb", abb_confdata(ROBOT, t.q))
        assert np.abs(q - t.q).max() < 1e-9
    text = format_rapid(prog)
    assert "MoveL p3, v150, zDD_0_50" in text and "MoveJ p1, vDD_450_0, fine" in text
    assert mut.program_from_plan(plan, "hub1", X_FT, verified=True).flag == ""
    assert mut.program_from_plan(_plan(failures=({"point": 3},)), "h", X_FT).flag == "FORCED"


def test_workpiece_plan_refused():
    with pytest.raises(InputError, match="workpiece-in-hand"):
        mut.program_from_plan(_plan(mode="workpiece"), "h", np.eye(4))
