"""5-axis spin resolution: FK re-check, the rules compared, the flange-axis shortcut against
the general solver, segments, joint turns and limits."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drakedeburr.post.tool_axis as mut
from drakedeburr.errors import InputError
from drakedeburr.post.cl_reader import read_cl
from drakedeburr.robots import IRB1600_10_120_ROBOT as ROBOT
from drakedeburr.robots.opw import fk_opw
from drakedeburr.robots.opw_ik import ik_opw, travel_weights
from drakedeburr.units import INCH_M

MSYS_NX = np.array([3.0, 3.0, 0.0]) * INCH_M  # the NX file's MCS origin (applied by the reader)


@pytest.fixture(scope="module")
def nx_points(extdata):
    prog = read_cl(extdata / "cl_files" / "MECH491_NX_CLSF__APT_Variable_Axis.txt",
                   units="inch")
    sl = slice(20, 60)
    return prog.p_C[sl] - MSYS_NX + np.array([0.75, 0.0, 0.25]), prog.axis_C[sl]


def _tilted_tool():
    X_FT = np.eye(4)
    X_FT[:3, :3] = Rotation.from_euler("Y", 30, degrees=True).as_matrix()
    X_FT[:3, 3] = [0.05, 0.0, 0.15]
    return X_FT


def _straight_tool(offset: float = 0.0):
    X_FT = np.eye(4)
    X_FT[:3, :3] = Rotation.from_euler("Z", 20, degrees=True).as_matrix()
    X_FT[:3, 3] = [offset, 0.0, 0.2]
    return X_FT


def _check_fk(res, p_W, axis_W, X_FT):
    ok = res.reachable
    X = fk_opw(ROBOT.opw, res.q[ok]) @ X_FT
    assert np.abs(X[:, :3, 3] - p_W[ok]).max() < 1e-9
    assert np.abs(X[:, :3, 2] + axis_W[ok]).max() < 1e-9
    assert np.abs(X - res.X_WT[ok]).max() < 1e-9
    assert ROBOT.limits.contains(res.q[ok]).all()


def test_tool_frames_axis_and_spin():
    axis = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    X = mut.tool_frames(np.zeros((2, 3)), axis, [0.0, 0.3])
    assert np.allclose(X[:, :3, 2], -axis)
    for R in X[:, :3, :3]:
        assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
    X2 = mut.tool_frames(np.zeros((2, 3)), axis, [0.1, 0.3 + 0.2])
    ang = np.arctan2(np.einsum("ij,ij->i", np.cross(X[:, :3, 0], X2[:, :3, 0]), X[:, :3, 2]),
                     np.einsum("ij,ij->i", X[:, :3, 0], X2[:, :3, 0]))
    assert np.allclose(ang, [0.1, 0.2])  # spin rotates about Z_T


@pytest.mark.parametrize("mode", mut.SPIN_MODES)
@pytest.mark.parametrize("tool", ["tilted", "straight"])
def test_fk_reproduces_cl_points(nx_points, mode, tool):
    p_W, axis_W = nx_points
    X_FT = _tilted_tool() if tool == "tilted" else _straight_tool()
    res = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT, mode=mode)
    assert res.ok and res.configuration_changes == ()
    _check_fk(res, p_W, axis_W, X_FT)


def _travel_from_start(q: np.ndarray) -> float:
    """The min_travel objective: the move from READY_POSE to the first point plus the path."""
    w = travel_weights(ROBOT.opw)
    return float(np.abs(q[0] - mut.READY_POSE) @ w) + mut.path_travel(ROBOT, q)["weighted"]


def test_rules_compared_for_a_tilted_tool(nx_points):
    p_W, axis_W = nx_points
    X_FT = _tilted_tool()
    res = {m: mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT, m) for m in mut.SPIN_MODES}
    travel = {m: _travel_from_start(r.q) for m, r in res.items()}
    # the whole-path optimum (from the start pose) is no worse than the per-point rule or the
    # J6 = 0 constraint
    assert travel["min_travel"] <= min(travel["greedy"], travel["theta6_zero"]) + 1e-9
    # theta6 = 0 holds wherever the configuration allows it (Newton-polished)
    assert np.mean(np.abs(res["theta6_zero"].q[:, 5]) < 1e-6) > 0.85
    # greedy: at each point no spin on a fine grid (same branch) moves the joints less than
    # the chosen one, to the rule's resolution (33 samples, 4 passes of 1/16 from 5 deg)
    g = res["greedy"]
    w = travel_weights(ROBOT.opw)
    X_TF = np.linalg.inv(X_FT)
    for i in (5, 17, 33):
        spins = np.linspace(-np.pi, np.pi, 721)
        X = mut.tool_frames(np.repeat(p_W[i:i + 1], 721, 0), np.repeat(axis_W[i:i + 1], 721, 0),
                            spins) @ X_TF
        sols = ik_opw(ROBOT.opw, X)
        q_prev = g.q[i - 1]
        d = np.abs(sols.q - q_prev)
        d[..., 5] = np.minimum(d[..., 5], 2 * np.pi - d[..., 5])  # J6 turns are free
        d[..., 3] = np.minimum(d[..., 3], 2 * np.pi - d[..., 3])
        cost = np.where(sols.valid, d @ w, np.inf)
        chosen = np.abs(g.q[i] - q_prev) @ w
        resolution = (2 * np.pi / 72) / 16**3 * w.sum()
        assert chosen <= np.nanmin(cost) + resolution


def test_min_travel_is_a_local_optimum(nx_points):
    """No single spin, moved on a fine grid around its value with the neighbours fixed, lowers
    the path's travel by more than the solver's spin resolution allows."""
    p_W, axis_W = nx_points
    X_FT = _tilted_tool()
    res = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT, "min_travel")
    w = travel_weights(ROBOT.opw)
    X_TF = np.linalg.inv(X_FT)
    spacing = 2 * np.pi / 16 / 8**3  # the last pass's grid [rad]
    for i in (3, 11, 24, 38):
        spins = res.spin[i] + np.linspace(-0.05, 0.05, 201)
        X = mut.tool_frames(np.repeat(p_W[i:i + 1], 201, 0), np.repeat(axis_W[i:i + 1], 201, 0),
                            spins) @ X_TF
        sols = ik_opw(ROBOT.opw, X)
        def ang(d):
            return np.abs(np.angle(np.exp(1j * d)))  # joint differences modulo 2 pi

        k = int(np.nanargmin(ang(sols.q[100] - res.q[i]).max(axis=1)))  # the chosen branch
        q = sols.q[:, k]
        cost = ang(q - res.q[i - 1]) @ w + ang(res.q[i + 1] - q) @ w
        chosen = ang(res.q[i] - res.q[i - 1]) @ w + ang(res.q[i + 1] - res.q[i]) @ w
        assert chosen <= np.nanmin(cost) + 2 * spacing * w.sum()


@pytest.mark.parametrize("mode", mut.SPIN_MODES)
def test_flange_axis_tool_is_exact(nx_points, mode):
    """Tool on the flange axis: J6 is held (or zero), joints 1-5 are the spin-0 IK of a branch;
    the general solver on a tool 0.1 mm off the axis finds no shorter path."""
    p_W, axis_W = nx_points
    X_FT = _straight_tool()
    res = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT, mode)
    _check_fk(res, p_W, axis_W, X_FT)
    j6 = 0.0 if mode == "theta6_zero" else mut.READY_POSE[5]
    assert np.allclose(res.q[:, 5], j6, atol=1e-9)
    sols = ik_opw(ROBOT.opw, mut.tool_frames(p_W, axis_W, 0.0) @ np.linalg.inv(X_FT))
    for i in range(len(p_W)):
        assert np.abs(np.angle(np.exp(1j * (sols.q[i, :, :5] - res.q[i, :5])))).max(
            axis=1).min() < 1e-9
    if mode == "min_travel":
        off = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, _straight_tool(1e-4), mode)
        assert off.ok and (mut.path_travel(ROBOT, res.q)["weighted"]
                           <= mut.path_travel(ROBOT, off.q)["weighted"] + 1e-3)


def test_segments_join(nx_points, monkeypatch):
    p_W, axis_W = nx_points
    X_FT = _tilted_tool()
    whole = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT)
    monkeypatch.setattr(mut, "SEGMENT", 9)
    monkeypatch.setattr(mut, "OVERLAP", 30)  # each segment sees the rest of this short path
    calls = []
    parts = mut.solve_tool_axis_path(ROBOT, p_W, axis_W, X_FT,
                                     progress=lambda d, t, lab: calls.append((d, t)))
    _check_fk(parts, p_W, axis_W, X_FT)
    assert parts.configuration_changes == ()
    assert calls[-1] == (40, 40) and len(calls) == 5
    # committed segment by segment, the path costs (almost) what the whole-path DP finds
    assert _travel_from_start(parts.q) <= 1.01 * _travel_from_start(whole.q)


def test_joint_turns_stay_in_limits_and_jumps_are_reported():
    """Three turns around a cone: the wrist winds up; every joint stays inside its limits and
    every step of more than pi in a joint is listed as a configuration change."""
    t = np.linspace(0, 6 * np.pi, 300)
    p = np.stack([0.8 + 0.05 * np.cos(t), 0.05 * np.sin(t), 0.3 + 0 * t], 1)
    axis = np.stack([0.5 * np.cos(t), 0.5 * np.sin(t), np.ones_like(t)], 1)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    X_FT = _tilted_tool()
    res = mut.solve_tool_axis_path(ROBOT, p, axis, X_FT, "min_travel")
    _check_fk(res, p, axis, X_FT)
    big = np.flatnonzero(np.abs(np.diff(res.q, axis=0)).max(axis=1) > np.pi) + 1
    assert set(big) <= set(res.configuration_changes)


def test_unreachable_points_are_listed_not_raised():
    p = np.array([[0.8, 0.0, 0.3], [5.0, 0.0, 0.3], [0.8, 0.05, 0.3]])
    axis = np.tile([0.0, 0.0, 1.0], (3, 1))
    for X_FT in (_straight_tool(), _tilted_tool()):
        res = mut.solve_tool_axis_path(ROBOT, p, axis, X_FT)
        assert res.failed == (1,) and not res.ok
        assert np.isnan(res.q[1]).all() and res.reachable.tolist() == [True, False, True]
        _check_fk(res, p, axis, X_FT)
    with pytest.raises(InputError, match="spin mode"):
        mut.solve_tool_axis_path(ROBOT, p, axis, X_FT, mode="free")
