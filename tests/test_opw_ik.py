"""Analytic OPW IK: reference cases (rs-opw-kinematics), Drake FK, selection, path continuity."""

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

import drakedeburr.robots.opw_ik as mut
from drakedeburr.robots import IRB1600_10_120, IRB1600_10_120_ROBOT, OpwParameters, fk_opw

REPO = Path(__file__).resolve().parent.parent
ROBOT = IRB1600_10_120_ROBOT


def _angle_diff(a, b):
    return np.abs((a - b + np.pi) % (2 * np.pi) - np.pi)


@pytest.fixture(scope="module")
def opw_cases(extdata):
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    with open(extdata / "kinematics" / "opw_cases_rs-opw-kinematics.yaml") as f:
        cases = yaml.load(f, Loader=loader)["cases"]
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    params = {
        "Irb2400_10": OpwParameters.from_mapping(ref["opw_parameters"]["ABB_IRB2400_10"]),
        "KukaKR6_R700_sixx": OpwParameters.from_mapping(
            ref["opw_parameters"]["KUKA_KR6_R700_sixx"]),
    }
    return cases, params


def _is_singular(joints_deg):
    # J5 at 0 or +-180 deg: wrist singular (the file's +-180 cases are print-rounded)
    j5 = abs(joints_deg[4])
    return j5 < 1.0 or abs(j5 - 180.0) < 1.0


def test_all_reference_solutions_found_and_fk_back(opw_cases):
    cases, params = opw_cases
    n_checked = {"Irb2400_10": 0, "KukaKR6_R700_sixx": 0}
    for case in cases:
        if _is_singular(case["joints"]):
            continue
        p = params[case["parameters"]]
        X = np.eye(4)
        X[:3, :3] = Rotation.from_quat(case["pose"]["quaternion"]).as_matrix()
        X[:3, 3] = case["pose"]["translation"]
        # the listed pose is the FK of the listed joints (checks our FK on the same data)
        assert np.abs(fk_opw(p, np.deg2rad(case["joints"])) - X).max() < 1e-9, case["id"]
        sols = mut.ik_opw(p, X)
        mine = sols.q[0][sols.valid[0]]
        listed = np.deg2rad(np.array(case["solutions"]))
        assert len(mine) == len(listed), case["id"]  # 8, or 4 when the back is out of reach
        for sol in listed:  # every listed solution is one of ours
            assert _angle_diff(mine, sol).max(axis=1).min() < 1e-6, (case["id"], sol)
        # every one of ours maps back to the pose
        assert np.abs(fk_opw(p, mine) - X[None]).max() < 1e-9, case["id"]
        n_checked[case["parameters"]] += 1
    assert min(n_checked.values()) > 950, n_checked


def test_branch_bookkeeping_matches_geometry():
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    q = rng.uniform(lo, hi, size=(200, 6))
    sols = mut.ik_opw(ROBOT.opw, fk_opw(ROBOT.opw, q))
    for i in range(len(q)):
        v = sols.valid[i]
        br = mut.arm_branches(ROBOT.opw, sols.q[i][v])
        assert np.array_equal(br, sols.branch[v])
        # the 8 solutions are 8 distinct branches
        assert len({tuple(b) for b in br}) == int(v.sum())


def test_unreachable_pose_has_no_solution():
    X = np.eye(4)
    X[:3, 3] = [3.0, 0.0, 0.5]  # 3 m away: beyond the 1.2 m reach
    sols = mut.ik_opw(IRB1600_10_120, X)
    assert not sols.valid.any()
    res = mut.solve_path(ROBOT, X[None])
    assert res.failed == (0,) and not res.ok and np.isnan(res.q[0]).all()


def _check_drake_model(model: Path, base_name: str, flange_name: str):
    """Drake FK of ``model`` (base -> flange) equals the OPW model; the analytic IK of Drake's
    poses returns the joints Drake was given. Returns the plant for further checks."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(model))
    base = plant.GetFrameByName(base_name)
    plant.WeldFrames(plant.world_frame(), base)
    plant.Finalize()
    assert plant.num_positions() == 6
    ctx = plant.CreateDefaultContext()
    flange = plant.GetFrameByName(flange_name)
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    for _ in range(50):
        q = rng.uniform(lo, hi)
        plant.SetPositions(ctx, q)
        X = plant.CalcRelativeTransform(ctx, base, flange).GetAsMatrix4()
        assert np.abs(X - fk_opw(IRB1600_10_120, q)).max() < 1e-9
        if abs(np.sin(q[4])) < 1e-3:
            continue
        cand = mut.joint_candidates(mut.ik_opw(IRB1600_10_120, X).q[0], ROBOT.limits)
        assert np.abs(cand - q[None]).max(axis=1).min() < 1e-9
    return plant


def test_against_drake_fk_of_reference_urdf():
    """The ros-industrial IRB1600 joint chain (tests/data) in Drake."""
    _check_drake_model(REPO / "tests" / "data" / "irb1600_6_12_reference.urdf", "base_link",
                       "tool0")


def test_drake_model_of_the_project():
    """The project's own Drake model (models/robots/irb1600_10_120.sdf, cell stage)."""
    from drakedeburr.resources import models_dir

    plant = _check_drake_model(models_dir() / "robots" / "irb1600_10_120.sdf", "base", "flange")
    # the model's joint limits are the ones the IK uses
    assert np.allclose(plant.GetPositionLowerLimits(), ROBOT.limits.lower, atol=1e-3)
    assert np.allclose(plant.GetPositionUpperLimits(), ROBOT.limits.upper, atol=1e-3)


def test_joint_candidates_unwraps_turns_within_limits():
    q = np.array([[0.1, 0.2, -0.3, 3.0, 0.5, 1.0]])
    cand = mut.joint_candidates(q, ROBOT.limits)
    # J4 limit +-3.49 rad: 3.0 and 3.0 - 2 pi (= -3.28) fit; J6 limit +-6.98: 1, 1 - 2 pi
    # (1 + 2 pi = 7.28 is outside)
    assert cand.shape == (2 * 2, 6)
    assert ROBOT.limits.contains(cand).all()
    assert np.allclose(np.sort(np.unique(cand[:, 3])), [3.0 - 2 * np.pi, 3.0])
    assert np.allclose(np.sort(np.unique(cand[:, 5])), [1 - 2 * np.pi, 1.0])


def test_select_solution_paper_rule():
    w = mut.travel_weights(IRB1600_10_120)
    assert w[0] > w[1] > w[2]  # J1 swings the longest lever
    q_prev = np.zeros(6)
    cand = np.array([
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],   # arm travel 0.2 * w1
        [0.0, 0.21, 0.0, 0.0, 0.0, 0.0],  # arm travel 0.21 * w2 (< 0.2 * w1)
        [0.0, 0.21, 0.0, 1.0, 0.0, 0.0],  # same arm, larger wrist change
    ])
    assert mut.select_solution(cand, q_prev, w) == 1
    assert mut.select_solution(cand[[2, 1]], q_prev, w) == 1  # tie on arm -> smaller wrist


def test_solve_path_keeps_configuration_and_unwraps_j6():
    # a circle traced with J6 winding past +pi: the path must stay continuous
    t = np.linspace(0, 1, 60)
    q = np.stack([0.3 * np.sin(2 * np.pi * t), 0.2 + 0 * t, -0.2 + 0 * t, 0.1 + 0 * t,
                  0.9 + 0 * t, 2.5 + 2.5 * t], -1)
    X = fk_opw(IRB1600_10_120, q)
    res = mut.solve_path(ROBOT, X, q_start=q[0])
    assert res.ok and res.configuration_changes == ()
    assert np.abs(res.q - q).max() < 1e-9  # J6 followed beyond pi, not wrapped back
    assert np.abs(np.diff(res.q, axis=0)).max() < 0.3
    assert np.abs(fk_opw(IRB1600_10_120, res.q) - X).max() < 1e-9


def test_solve_path_reports_a_forced_configuration_change():
    # J4 limited to +-0.5 rad: through J5 = 0 the wrist cannot flip back with J4 +- pi,
    # so the branch must change and is reported
    tight = mut.RobotKinematics(
        opw=IRB1600_10_120,
        limits=mut.JointLimits(lower=(-np.pi, -1.0, -3.0, -0.5, -2.0, -np.pi),
                               upper=(np.pi, 1.5, 0.9, 0.5, 2.0, np.pi)))
    t = np.linspace(0, 1, 21)
    q = np.stack([0.2 + 0 * t, 0.3 + 0 * t, -0.3 + 0 * t, 0.2 + 0 * t, 0.5 - t, 0.1 + 0 * t], -1)
    q = q[np.abs(q[:, 4]) > 1e-6]  # skip the exactly singular pose
    res = mut.solve_path(tight, fk_opw(IRB1600_10_120, q), q_start=q[0])
    assert res.ok and len(res.configuration_changes) == 1
    i = res.configuration_changes[0]
    assert res.branch[i - 1, 2] == 1 and res.branch[i, 2] == -1 and q[i, 4] < 0 < q[i - 1, 4]
    assert np.abs(res.q - q).max() < 1e-9  # the planned joints are recovered
