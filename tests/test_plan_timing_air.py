"""Moves off the cut timed at the arm's limits (plan.timing.air_limits, issue 46): the joint
limits and the move's programmed TCP speed, no TCP path acceleration cap. Each timing is read
against a closed-form time-optimal profile and re-checked on the stored trajectory."""

import numpy as np
import pytest

import drakedeburr.plan.timing as mut
from drakedeburr.plan.types import JointTrajectory
from drakedeburr.verify.checks_process import min_time_1d

V_MAX = (3.0, 3.0, 3.0, 6.0, 6.0, 7.0)
A_MAX = (10.0, 10.0, 10.0, 20.0, 20.0, 25.0)


def _joint_line(q0, q1, step=0.004):
    """The planner's joint move samples: the straight joint line every ``step`` rad of the
    largest joint, parameterised by joint-space arc length."""
    n = int(np.ceil(np.max(np.abs(q1 - q0)) / step))
    q = q0 + np.linspace(0.0, 1.0, n + 1)[:, None] * (q1 - q0)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    return s, q


def _dense(tp, n=20000):
    traj = JointTrajectory(t=tp.t, c=tp.c)
    t = np.linspace(0.0, traj.duration, n)
    return traj, t


def _tip(q, arm=0.5):
    """A tool tip on a 0.5 m arm turned by J1 (the other joints carry no offset)."""
    return arm * np.stack([np.cos(q[..., 0]), np.sin(q[..., 0]), np.zeros(q.shape[:-1])], -1)


def test_air_limits_drop_the_tcp_acceleration_cap_and_nothing_else():
    lim = mut.TimingLimits(v_cap=0.45, a_cap=3.0, v_max=V_MAX, a_max=A_MAX)
    air = mut.air_limits(lim)
    assert air.a_cap == np.inf
    assert (air.v_cap, air.v_max, air.a_max) == (lim.v_cap, lim.v_max, lim.a_max)
    assert (air.velocity_fraction, air.acceleration_fraction) == (0.95, 0.9)


def test_straight_joint_move_takes_the_closed_form_least_time_of_the_line():
    """No TCP cap binding: the timed straight joint line takes the time-optimal trapezoid of
    its path parameter (u in [0, 1]: speed min_j f_v v_j / |dq_j|, acceleration min_j f_a a_j /
    |dq_j|), which is the slowest joint's own bang-bang/trapezoid least time
    (verify.checks_process.min_time_1d) when one joint binds both; the stored trajectory keeps
    every joint within its margins, sampled densely."""
    rng = np.random.default_rng(11)
    vf, af = 0.95, 0.9
    for case in range(8):
        dq = rng.uniform(-1.0, 1.0, 6) * np.array([1.5, 1.0, 1.0, 3.0, 2.0, 3.0])
        if case < 2:  # short moves: acceleration-bound triangles
            dq *= 0.05
        q0 = rng.uniform(-1.0, 1.0, 6)
        s, q = _joint_line(q0, q0 + dq)
        lim = mut.air_limits(mut.TimingLimits(v_cap=1e6, a_cap=3.0, v_max=V_MAX, a_max=A_MAX))
        tp = mut.time_path(s, q, _tip(q), lim, fk=_tip)
        V = np.min(vf * np.asarray(V_MAX) / np.abs(dq))
        A = np.min(af * np.asarray(A_MAX) / np.abs(dq))
        T = 1.0 / V + V / A if V * V / A <= 1.0 else 2.0 / np.sqrt(A)
        assert tp.t[-1] == pytest.approx(T, rel=2e-3), case
        jv = int(np.argmin(vf * np.asarray(V_MAX) / np.abs(dq)))
        ja = int(np.argmin(af * np.asarray(A_MAX) / np.abs(dq)))
        if jv == ja or V * V / A > 1.0:  # one joint binds: its own 1-D least time
            T1 = min_time_1d(float(dq[ja]), 0.0, 0.0, vf * V_MAX[ja], af * A_MAX[ja])[0]
            assert tp.t[-1] == pytest.approx(T1, rel=2e-3), case
        traj, t = _dense(tp)
        assert np.all(np.abs(traj.derivative(t, 1)) <= vf * np.asarray(V_MAX) * (1 + 1e-9))
        assert np.all(np.abs(traj.derivative(t, 2)) <= af * np.asarray(A_MAX) * (1 + 1e-6))
        np.testing.assert_allclose(traj.value(t[[0, -1]]), q[[0, -1]], atol=1e-12)
        assert np.allclose(traj.derivative(t[[0, -1]], 1), 0.0, atol=1e-12)


def test_programmed_tcp_speed_still_binds_with_joint_acceleration_ramps():
    """J1 turning a 0.5 m arm by 1.2 rad under a 450 mm/s cap (0.9 rad/s of J1, below its
    2.85 rad/s): the move cruises at the cap and ramps at J1's acceleration limit, not the
    recipe's 3 m/s^2 TCP acceleration: T = d / w + w / (f_a a_1) exactly, faster than with the
    TCP cap; the TCP speed on the stored trajectory never exceeds the cap."""
    q0 = np.zeros(6)
    q1 = np.array([1.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    s, q = _joint_line(q0, q1)
    base = mut.TimingLimits(v_cap=0.45, a_cap=3.0, v_max=V_MAX, a_max=A_MAX)
    tp = mut.time_path(s, q, _tip(q), mut.air_limits(base), fk=_tip)
    w = 0.45 / 0.5
    T = 1.2 / w + w / (0.9 * A_MAX[0])
    assert tp.t[-1] == pytest.approx(T, rel=1e-3)
    capped = mut.time_path(s, q, _tip(q), base, fk=_tip)
    # the TCP cap ramps at 3 m/s^2: 0.45 / 3 s a ramp instead of 0.1 s at J1's limit
    assert capped.t[-1] == pytest.approx(1.2 / w + 0.45 / 3.0, rel=1e-3)
    assert tp.t[-1] < capped.t[-1] - 0.04
    traj, t = _dense(tp)
    h = 1e-6
    tt = t[1:-1]
    v_tcp = np.linalg.norm(_tip(traj.value(tt + h)) - _tip(traj.value(tt - h)), axis=1) / (2 * h)
    assert v_tcp.max() <= 0.45 * (1 + 1e-6)
    assert v_tcp.max() >= 0.45 * (1 - 1e-6)
    # its TCP path acceleration is J1's: 0.5 m x 9 rad/s^2 = 4.5 m/s^2, over the 3 m/s^2 cap
    acc = np.diff(v_tcp) / np.diff(tt)
    assert np.max(np.abs(acc)) == pytest.approx(0.5 * 0.9 * A_MAX[0], rel=1e-2)


def test_curved_joint_move_keeps_the_joint_limits_without_the_tcp_row():
    """A via-like path with kinks rounded by the spline: without the TCP acceleration row the
    passes still keep every joint's acceleration (certified between samples) and speed."""
    from drakedeburr.verify.geometry import spline_extremes

    way = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.4, -0.3, 0.2, 1.5, 0.6, -1.0],
                    [0.9, 0.1, -0.2, 0.5, 1.2, 0.8]])
    q = np.concatenate([a + np.linspace(0, 1, 200, endpoint=False)[:, None] * (b - a)
                        for a, b in zip(way[:-1], way[1:], strict=True)] + [way[-1:]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    lim = mut.air_limits(mut.TimingLimits(v_cap=1e6, a_cap=3.0, v_max=V_MAX, a_max=A_MAX))
    tp = mut.time_path(s, q, _tip(q), lim, fk=_tip)
    traj = JointTrajectory(t=tp.t, c=tp.c)
    vals, _, rem = spline_extremes(traj)["qdd"]
    assert np.max((np.abs(vals) + rem[:, None]) / np.asarray(A_MAX)) <= 1.0
    _, t = _dense(tp, 40000)
    assert np.all(np.abs(traj.derivative(t, 1)) <= 0.95 * np.asarray(V_MAX) * (1 + 1e-6))
    # and no slower than the same path with the TCP acceleration cap
    capped = mut.time_path(s, q, _tip(q), mut.TimingLimits(
        v_cap=1e6, a_cap=3.0, v_max=V_MAX, a_max=A_MAX), fk=_tip)
    assert tp.t[-1] <= capped.t[-1] + 1e-9
