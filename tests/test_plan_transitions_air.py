"""plan.transitions.tcp_line / faster_move: a straight joint move swapped for the path whose
wrist runs the same joint line and whose tool point runs the straight line (issue 46: air moves
at the arm's limits under the programmed TCP speed). Read back by forward kinematics."""

import numpy as np
import pytest

import drakedeburr.plan.transitions as mut


@pytest.fixture(scope="module")
def kin():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    return cell_kinematics(load_cell("tool_in_hand", "h5_straight"))


def _ends(kin):
    """A move between windows with the wrist unwinding most of a half turn (J4 and J6 the
    other way: the default hub's transition 1 -> 2 does this), from the cell's home."""
    q0 = np.asarray(kin.q_home, float) + np.array([0.2, 0.15, -0.1, 1.3, -0.4, -1.4])
    q1 = np.asarray(kin.q_home, float) + np.array([-0.25, 0.05, 0.1, -1.3, 0.35, 1.5])
    return q0, q1


def _point_line_distance(p, a, b):
    d = (b - a) / np.linalg.norm(b - a)
    r = p - a
    return np.linalg.norm(r - (r @ d)[:, None] * d, axis=1), r @ d / np.linalg.norm(b - a)


def test_tcp_line_keeps_the_tool_point_on_the_straight_line_and_the_wrist_on_its_line(kin):
    q0, q1 = _ends(kin)
    step = 0.004
    q = mut.tcp_line(kin, q0, q1, step)
    assert q is not None
    np.testing.assert_array_equal(q[0], q0)
    np.testing.assert_array_equal(q[-1], q1)
    p = kin.p_HT(q)
    off, share = _point_line_distance(p, p[0], p[-1])
    assert off.max() < 1e-8
    u = np.linspace(0.0, 1.0, len(q))
    np.testing.assert_allclose(share, u, atol=1e-8)  # at the same share of the way
    np.testing.assert_allclose(q[:, 3:], q0[3:] + u[:, None] * (q1 - q0)[3:], atol=1e-12)
    assert np.max(np.abs(np.diff(q, axis=0))) <= step * (1 + 1e-9)
    assert np.all((q >= kin.q_lower) & (q <= kin.q_upper))
    # the straight joint line swings the tool point about the flange: a longer TCP travel
    line = q0 + u[:, None] * (q1 - q0)
    travel = np.linalg.norm(np.diff(kin.p_HT(line), axis=0), axis=1).sum()
    chord = np.linalg.norm(p[-1] - p[0])
    assert np.linalg.norm(np.diff(p, axis=0), axis=1).sum() == pytest.approx(chord, rel=1e-9)
    assert travel > 1.2 * chord


def test_tcp_line_refuses_what_leaves_the_joint_limits(kin):
    """The arm joints of the TCP line swing past both ends' values; with a joint limit moved
    between its ends' values and that excursion, the line is refused."""
    from dataclasses import replace

    q0, q1 = _ends(kin)
    q = mut.tcp_line(kin, q0, q1, 0.004)
    j = int(np.argmax(np.max(q[:, :3], axis=0) - np.maximum(q0, q1)[:3]))
    top = max(q0[j], q1[j])
    assert q[:, j].max() > top + 1e-3  # an excursion past both ends
    upper = np.array(kin.q_upper, float)
    upper[j] = 0.5 * (top + q[:, j].max())
    assert mut.tcp_line(replace(kin, q_upper=upper), q0, q1, 0.004) is None


class _Clear:
    """A stand-in checker: every sample ``d`` [m] from everything."""

    def __init__(self, d):
        self.d = d

    def min_distances_along(self, q, cap):
        return np.full(len(q), min(self.d, cap))


def _straight(kin, q0, q1, step=0.004):
    n = int(np.ceil(np.max(np.abs(q1 - q0)) / step))
    q = q0 + np.linspace(0.0, 1.0, n + 1)[:, None] * (q1 - q0)
    return mut.JointMove(q=q, s=mut._arc(q), clearance=0.01, method="straight", ok=True)


def _tcp_time(kin, v_cap=0.45):
    """The move's time at its TCP speed alone: tool travel over the cap (a stand-in timing)."""
    return lambda q, s: float(np.linalg.norm(np.diff(kin.p_HT(q), axis=0), axis=1).sum() / v_cap)


def test_faster_move_takes_the_tcp_line_where_clear_and_faster(kin):
    q0, q1 = _ends(kin)
    mv = _straight(kin, q0, q1)
    out = mut.faster_move(kin, _Clear(0.01), mv, _tcp_time(kin), 2e-3, 0.004)
    assert out.method == "tcp_line" and out.ok
    assert out.info["seconds"] < out.info["before_seconds"] - 1e-3
    np.testing.assert_array_equal(out.q[[0, -1]], mv.q[[0, -1]])
    np.testing.assert_allclose(out.s, mut._arc(out.q))
    # too close somewhere: the straight move stays
    assert mut.faster_move(kin, _Clear(1e-3), mv, _tcp_time(kin), 2e-3, 0.004) is mv
    # not faster under the caller's timing (joint travel: the TCP line's is longer): stays
    joint_time = lambda q, s: float(s[-1])  # noqa: E731
    assert mut.faster_move(kin, _Clear(0.01), mv, joint_time, 2e-3, 0.004) is mv
    # KTO moves (and via moves without their waypoints) are kept
    kto = mut.JointMove(q=mv.q, s=mv.s, clearance=0.01, method="kto", ok=True)
    assert mut.faster_move(kin, _Clear(0.01), kto, _tcp_time(kin), 2e-3, 0.004) is kto
    via = mut.JointMove(q=mv.q, s=mv.s, clearance=0.01, method="via", ok=True)
    assert mut.faster_move(kin, _Clear(0.01), via, _tcp_time(kin), 2e-3, 0.004) is via
    # no move at all (home to home when no window was planned): kept, never timed
    still = mut.JointMove(q=np.vstack([q0, q0]), s=np.zeros(2), clearance=0.01,
                          method="straight", ok=True)

    def no_timing(q, s):
        raise AssertionError("a move of no length was timed")

    assert mut.faster_move(kin, _Clear(0.01), still, no_timing, 2e-3, 0.004) is still


def _via_move(way, step=0.004):
    q = np.concatenate([a + np.linspace(0, 1, int(np.ceil(np.max(np.abs(b - a)) / step)),
                                        endpoint=False)[:, None] * (b - a)
                        for a, b in zip(way[:-1], way[1:], strict=True)] + [way[-1:]])
    return mut.JointMove(q=q, s=mut._arc(q), clearance=0.01, method="via", ok=True,
                         info=dict(via_points=len(way) - 2, waypoints=way))


WAY = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.3, 0.5, -0.2, 1.0, 0.4, -0.6],
                [0.35, 0.6, 0.3, 1.4, -0.2, 0.2], [0.9, 0.1, 0.2, 0.5, 0.0, 0.8]])


@pytest.mark.parametrize("share", [1.0, 0.6, 0.3])
def test_rounded_corners_stay_on_the_polyline_legs_and_turn_smoothly(share):
    step = 0.004
    q = mut.rounded_corners(WAY, share, step)
    np.testing.assert_array_equal(q[[0, -1]], WAY[[0, -1]])
    d = np.diff(q, axis=0)
    assert np.max(np.abs(d)) <= step * (1 + 1e-9)
    assert np.min(np.linalg.norm(d, axis=1)) > 1e-3 * step  # no repeated sample
    # no reversal and no kink: successive steps turn by little (the polyline turns by
    # 50-110 deg at its corners; a blend spreads that over its samples)
    u = d / np.linalg.norm(d, axis=1)[:, None]
    turn = np.degrees(np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=1), -1, 1)))
    corner = np.diff(WAY, axis=0)
    corner = corner / np.linalg.norm(corner, axis=1)[:, None]
    kinks = np.degrees(np.arccos(np.sum(corner[1:] * corner[:-1], axis=1)))
    assert kinks.min() > 30.0 and turn.max() < 0.25 * kinks.min()
    # inside the box of the polyline's points (each blend a convex combination of three)
    assert np.all(q >= WAY.min(axis=0) - 1e-12) and np.all(q <= WAY.max(axis=0) + 1e-12)
    # every sample is on a leg or within its blend's triangle: off the legs only near corners
    r_max = share * np.max(np.linalg.norm(np.diff(WAY, axis=0), axis=1))
    near = np.min(np.linalg.norm(q[:, None] - WAY[None, 1:-1], axis=2), axis=1)
    on_leg = np.zeros(len(q), bool)
    for a, b in zip(WAY[:-1], WAY[1:], strict=True):
        f = np.clip((q - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        on_leg |= np.linalg.norm(q - (a + f[:, None] * (b - a)), axis=1) < 1e-9
    assert np.all(on_leg | (near <= r_max + 1e-9))
    assert on_leg.sum() > 0.2 * len(q)


def test_faster_move_rounds_a_via_move_where_clear(kin):
    mv = _via_move(WAY)
    # the joint-travel timing of a rounded path is shorter (a blend cuts the corner)
    out = mut.faster_move(kin, _Clear(0.01), mv, lambda q, s: float(s[-1]), 2e-3, 0.004)
    assert out.method == "via_rounded"
    np.testing.assert_allclose(out.q, mut.rounded_corners(WAY, 0.9, 0.004))
    assert out.s[-1] < mv.s[-1]
    assert mut.faster_move(kin, _Clear(1e-3), mv, lambda q, s: float(s[-1]), 2e-3,
                           0.004) is mv
