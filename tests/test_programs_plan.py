"""Plan -> RobotProgram (the one conversion): each target a move with its own speed and zone,
joint moves at the trajectory's speed, the arm and its mount from the plan, both cells."""

from dataclasses import replace

import numpy as np
import pytest

import drakedeburr.programs.plan_program as mut
from drakedeburr.errors import InputError
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment
from drakedeburr.programs import compare_programs, read_program, write_program
from drakedeburr.robots import abb_confdata, fk_opw, get_robot, joints_from_configuration

SEGS = ["home", "approach", "cut", "cut", "cut", "retract", "home"]
SPEEDS = [0.6, 0.45, 0.15, 0.0213, 0.1487, 0.45, 0.6]
ZONES = [0.0, 0.0, 0.0005, 0.0005, 0.0, 0.0, 0.0]


def _plan(robot="irb1600", mode="tool", failures=(), X_WB=None):
    spec = get_robot(robot)
    q0 = np.array([0.0, 0.1, -0.2, 0.3, 1.2, 0.1]) if robot == "irb1600" else \
        np.array([0.0, -1.2, 1.4, 0.3, 0.9, 0.1])
    qs = [q0 + np.array([0.02 * k, 0.01 * k, 0.0, 0.01 * k, 0.0, -0.02 * k]) for k in range(7)]
    X_WB = np.eye(4) if X_WB is None else X_WB
    X_WH = np.eye(4)
    X_WH[:3, 3] = [0.7, 0.0, 0.2]
    X_FT = np.eye(4)
    X_FT[:3, 3] = [0.1, 0.0, 0.25]
    targets = tuple(
        CartesianTarget(window_index=-1 if s == "home" else 0, segment=s, cl_index=k,
                        X_HT=np.eye(4), X_WF=X_WB @ fk_opw(spec.opw, q), q=q, speed=v, zone=z,
                        motion="joint" if s == "home" else "linear")
        for k, (s, q, v, z) in enumerate(zip(SEGS, qs, SPEEDS, ZONES, strict=True)))
    t = np.array([0.0, 1.0, 5.0, 6.0])
    qd = np.zeros((4, 6))
    qd[1, 0] = 0.5 * spec.v_max[0]  # 50 % of axis 1 on the way to the first target
    qd[3, 4] = 0.2 * spec.v_max[4]  # 20 % of axis 5 on the way home
    traj = JointTrajectory.from_hermite(t=t, q=np.array([qs[0], qs[0], qs[-1], qs[-1]]), qd=qd)
    segments = (PlanSegment(-1, "home", (0, 1), (0.0, 1.0)), PlanSegment(0, "cut", (1, 6),
                                                                         (1.0, 5.0)),
                PlanSegment(-1, "home", (6, 7), (5.0, 6.0)))
    meta = dict(X_FT=X_FT.tolist(), X_FH=X_FT.tolist(), X_WT=X_WH.tolist(), robot=robot,
                X_WB=X_WB.tolist())
    return Plan(scenario="tool_in_hand", hub="hub", mode=mode, X_WH=X_WH, targets=targets,
                segments=segments, trajectory=traj, failures=failures, meta=meta)


def test_targets_become_moves_with_their_own_speed_and_zone():
    plan = _plan()
    loads = mut.FlangeLoads(3.05, (-0.018, 0.0, 0.127), source="cell models (spindle)")
    full = mut.program_from_plan(plan, "hub1", loads=loads)
    # the targets' moves (the bent joint path home also gets via points: next test)
    moves = [m for m in full.moves if any(np.array_equal(m.q, t.q) for t in plan.targets)]
    prog = replace(full, moves=tuple(moves))
    assert [m.move_type for m in prog.moves] == ["joint"] + ["linear"] * 5 + ["joint"]
    assert [m.speed for m in prog.moves] == SPEEDS and [m.zone for m in prog.moves] == ZONES
    assert [m.comment for m in prog.moves] == ["home", "approach window 0", "cut window 0", "",
                                               "", "retract window 0", "home"]
    assert prog.moves[0].joint_fraction == pytest.approx(0.5)
    assert prog.moves[-1].joint_fraction == pytest.approx(0.2)
    assert prog.tool_mass == 3.05 and prog.load_source == "cell models (spindle)"
    assert prog.flag == "UNVERIFIED" and np.allclose(prog.X_WO, plan.X_WH)
    X_FT = np.asarray(plan.meta["X_FT"])
    for m, t in zip(prog.moves, plan.targets, strict=True):
        X_WF = m.X_WT @ np.linalg.inv(X_FT)
        assert np.allclose(X_WF, t.X_WF, atol=1e-12)
        q = joints_from_configuration(prog.kinematics, X_WF, "abb", abb_confdata(prog.kinematics,
                                                                               t.q))
        assert np.abs(q - t.q).max() < 1e-9
    assert mut.program_from_plan(plan, "hub1", verified=True).flag == ""
    assert mut.program_from_plan(_plan(failures=({"point": 3},)), "h").flag == "FORCED"


def test_a_bent_joint_path_is_written_as_via_points_the_controller_interpolates():
    """PTP/MoveJ/J interpolate the joints linearly: the plan's home move bends (its knots
    have speed), so the program carries via points; the joint-space polyline they make stays
    within VIA_TOLERANCE of the plan's path (checked densely here), the targets in order."""
    plan = _plan()
    prog = mut.program_from_plan(plan, "hub1")
    Q = np.array([m.q for m in prog.moves])
    last = len(prog.moves) - 1
    assert np.array_equal(Q[last], plan.targets[-1].q)
    k0 = next(i for i in range(last) if np.array_equal(Q[i], plan.targets[-2].q))
    vias = Q[k0 + 1:last]
    assert len(vias) >= 1 and all(m.move_type == "joint" for m in prog.moves[k0 + 1:])
    t = np.linspace(5.0, 6.0, 2001)
    path = plan.trajectory.value(t)
    poly = np.vstack([Q[k0], vias, Q[last]])
    # distance of each dense plan sample to the polyline, joint by joint (max norm)
    best = np.full(len(path), np.inf)
    for a, b in zip(poly[:-1], poly[1:], strict=True):
        f = np.linspace(0, 1, 2001)[:, None]
        seg = a + f * (b - a)
        d = np.abs(path[:, None, :] - seg[None, ::20, :]).max(axis=2).min(axis=1)
        best = np.minimum(best, d)
    assert best.max() <= mut.VIA_TOLERANCE + 2e-4  # + the 1/100 sampling of the chords
    assert prog.consistency_error().max() < 1e-9


def test_the_arm_and_its_mount_come_from_the_plan(tmp_path):
    X_WB = np.eye(4)
    X_WB[:3, 3] = [0.35, 0.0, -0.2]
    plan = _plan("kr6_r700", X_WB=X_WB)
    prog = mut.program_from_plan(plan)
    assert prog.spec is get_robot("kr6_r700") and prog.controller == "kuka"
    # poses are in the arm's base frame: the mount is taken out
    assert np.allclose(prog.X_WO, np.linalg.inv(X_WB) @ plan.X_WH)
    assert prog.consistency_error().max() < 1e-9
    with pytest.raises(InputError, match="made for kr6_r700, not irb1600"):
        mut.program_from_plan(plan, robot="irb1600")
    paths = write_program(prog, tmp_path / "deburr_kr6.src")
    assert compare_programs(prog, read_program(paths[0])) == []
    # an older plan without meta["robot"] is the default arm's
    old = replace(_plan(), meta={k: v for k, v in _plan().meta.items() if k != "robot"})
    assert mut.plan_robot(old).name == "irb1600"


@pytest.mark.parametrize("robot, suffix", [("irb1600", ".mod"), ("kr6_r700", ".src"),
                                           ("m10ia", ".ls")])
def test_workpiece_in_hand_plan_gives_a_stationary_tool_program(tmp_path, robot, suffix):
    """The flange carries the hub (X_FH), the fixed frame is the spindle's TCP (X_WT)."""
    plan = _plan(robot, mode="workpiece")
    loads = mut.FlangeLoads(4.0, (0.0, 0.0, 0.12), 11.1, (0.0, 0.0, 0.266), "test")
    prog = mut.program_from_plan(plan, "wp", loads=loads)
    assert prog.stationary_tool and prog.tool_name == "tSpindle"
    np.testing.assert_allclose(prog.X_FT, plan.meta["X_FH"])
    np.testing.assert_allclose(prog.X_WO, plan.meta["X_WT"])
    assert prog.consistency_error().max() < 1e-9
    path = write_program(prog, tmp_path / f"wp{suffix}")[0]
    back = read_program(path)
    assert back.stationary_tool and compare_programs(prog, back) == []
    text = path.read_text()
    marker = {".mod": "PERS tooldata tSpindle := [FALSE,", ".src": "$IPO_MODE = #TCP",
              ".ls": "mm/sec FINE RTCP ;"}[suffix]
    assert marker in text


def test_empty_or_odd_plans_are_refused():
    with pytest.raises(InputError, match="no targets"):
        mut.program_from_plan(replace(_plan(), targets=()))
    with pytest.raises(InputError, match="neither 'tool' nor 'workpiece'"):
        mut.program_from_plan(replace(_plan(), mode="both"))
    for mode, lost in (("tool", "X_FT"), ("workpiece", "X_FH"), ("workpiece", "X_WT")):
        plan = _plan(mode=mode)
        meta = {k: v for k, v in plan.meta.items() if k != lost}
        with pytest.raises(InputError, match=f"no {lost} "):
            mut.program_from_plan(replace(plan, meta=meta))


def test_the_plans_cell_frames_are_typed_from_its_record():
    plan = _plan(X_WB=np.diag([1.0, -1.0, -1.0, 1.0]))
    f = plan.frames
    np.testing.assert_array_equal(f.X_WB, plan.meta["X_WB"])
    np.testing.assert_array_equal(f.X_FT, plan.meta["X_FT"])
    assert f.carried("tool")[1] is None
    X_FH, X_WT = f.carried("workpiece")
    np.testing.assert_array_equal(X_FH, plan.meta["X_FH"])
    np.testing.assert_array_equal(X_WT, plan.meta["X_WT"])
    old = replace(plan, meta={"X_FT": plan.meta["X_FT"]}).frames  # before mounts: base = world
    np.testing.assert_array_equal(old.X_WB, np.eye(4))
    assert old.X_FH is None and old.X_WT is None


def test_a_plan_made_with_another_burr_says_so_in_the_program(tmp_path):
    """The long-reach burr's plan: the header asks for that burr; the TCP is the plan's."""
    plan = _plan()
    plain = mut.program_from_plan(plan, "hub1")
    assert not any("burr" in n for n in plain.notes)
    lr = replace(plan, meta={**plan.meta, "tool": "long_reach",
                             "tool_title": "long-reach burr (75 mm stick-out)"})
    prog = mut.program_from_plan(lr, "hub1")
    assert [n for n in prog.notes if n.startswith("burr")] == [
        "burr: long-reach burr (75 mm stick-out): mount it before running"]
    out = write_program(prog, tmp_path / "hub1.mod", "rapid")
    assert "long-reach burr" in out[0].read_text()
    assert np.allclose(prog.X_FT, plan.meta["X_FT"])
