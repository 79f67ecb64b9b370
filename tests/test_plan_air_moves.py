"""The planner's moves off the cut (home, transitions) on the default hub, re-checked on the
stored trajectory independently of the planner (slow: plans one window with Drake IK): clear
of the cell by the acceptance bound (burr head counted) at joint steps finer than the
planner's, joint speed and acceleration within the limits and the TCP speed within the move's
programmed speed sampled every millisecond, and never faster than the least time of the joint
displacement or the chord at the programmed speed allow; faster than the straight joint line
under the timing the planner used before issue 46 (TCP path acceleration cap included)."""

import numpy as np
import pytest

from drakedeburr.config import load_config


@pytest.fixture(scope="module")
def planned():
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.plan.kinematics import cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    cfg = load_config("tool_in_hand", "h5_straight")
    plan = plan_hub(cfg, options=PlanOptions(windows=(0,)))
    cell = load_plan_cell(plan)
    return plan, cell, cell_kinematics(cell), cfg


@pytest.mark.slow
def test_air_moves_are_clear_within_limits_and_at_least_their_bounds(planned):
    from drakedeburr.plan.kinematics import ClearanceChecker
    from drakedeburr.plan.timing import TimingLimits, time_path
    from drakedeburr.verify.checks_process import joint_move_bound

    plan, cell, kin, cfg = planned
    traj = plan.trajectory
    free = ClearanceChecker(cell, filter_burr_contact=False)
    moves = [g for g in plan.segments if g.kind in ("home", "transition")]
    assert len(moves) == 2
    total, total_before = 0.0, 0.0
    for g in moves:
        t0, t1 = g.t_range
        v_prog = float(plan.targets[g.target_range[1] - 1].speed)
        t = np.linspace(t0, t1, max(50, int(np.ceil((t1 - t0) / 1e-3)) + 1))
        q = traj.value(t)
        qd, qdd = traj.derivative(t, 1), traj.derivative(t, 2)
        assert np.all(np.abs(qd) <= 0.95 * kin.v_max * (1 + 1e-6))
        assert np.all(np.abs(qdd) <= kin.a_max * (1 + 1e-6))
        h = 1e-6
        tt = np.clip(t, t0 + h, t1 - h)
        v_tcp = np.linalg.norm(kin.p_HT(traj.value(tt + h)) - kin.p_HT(traj.value(tt - h)),
                               axis=1) / (2 * h)
        assert v_tcp.max() <= v_prog * (1 + 1e-4)
        # clearance on joint steps of at most 1 mrad (the planner checks every 4 mrad)
        n = int(np.ceil(1.5 * (t1 - t0) * np.abs(qd).max() / 1e-3)) + 1
        qq = traj.value(np.linspace(t0, t1, n))
        assert np.max(np.abs(np.diff(qq, axis=0))) <= 1e-3
        d = free.min_distances_along(qq, cfg.tolerances.min_clearance + 1e-3)
        assert d.min() >= cfg.tolerances.min_clearance
        # ends at rest, where the neighbouring stretches start and end
        assert np.allclose(qd[[0, -1]], 0.0, atol=1e-12)
        dur = t1 - t0
        bound = joint_move_bound(q[0], q[-1], np.zeros(6), np.zeros(6), kin.v_max, kin.a_max)[0]
        chord = np.linalg.norm(kin.p_HT(q[[-1]])[0] - kin.p_HT(q[[0]])[0])
        assert dur >= max(bound, chord / v_prog) - 1e-9
        # the straight joint line under the former timing (the TCP acceleration cap on)
        m = int(np.ceil(np.max(np.abs(q[-1] - q[0])) / 0.004))
        line = q[0] + np.linspace(0.0, 1.0, m + 1)[:, None] * (q[-1] - q[0])
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line, axis=0), axis=1))])
        before = TimingLimits(v_cap=v_prog, a_cap=cfg.process.tcp_acceleration,
                              v_max=tuple(kin.v_max), a_max=tuple(kin.a_max))
        t_before = time_path(s, line, kin.p_HT(line), before, fk=kin.p_HT).t[-1]
        assert dur <= t_before + 1e-6
        total += dur
        total_before += t_before
    assert total <= total_before - 0.05, (total, total_before)
