"""time_budget: where the cycle's time goes, each figure re-computed independently of the
verifier (the joint-space bound by a discretised linear programme and by hand, the edge length
from the CL points, the binding limit from the spline's own derivatives)."""

from __future__ import annotations

import numpy as np
import pytest
import verify_support as vs
from scipy.optimize import linprog

from drakedeburr.verify.checks_process import joint_move_bound, min_time_1d


def _reachable(T: float, d: float, v0: float, v1: float, v_max: float, a_max: float,
               n: int = 300) -> bool:
    """Can a double integrator move by ``d`` from ``v0`` to ``v1`` in time T under the bounds?
    A linear feasibility programme over ``n`` steps of constant acceleration (velocity is then
    piecewise linear: the bound at the nodes holds everywhere). Any feasible discrete profile
    is a feasible continuous one, so infeasible below the true minimum time, and feasible just
    above it once the grid is fine enough."""
    h = T / n
    # variables: accelerations a_0..a_{n-1}; v_k = v0 + h sum_{i<k} a_i
    Lv = np.tril(np.ones((n, n)), -1)[1:] * h  # v_1..v_{n-1} (interior nodes) minus v0
    # x_n = v0 T + sum_i a_i h^2 (n - i - 1/2)
    cx = h * h * (n - np.arange(n) - 0.5)
    A_eq = np.vstack([cx, np.full(n, h)])
    b_eq = [d - v0 * T, v1 - v0]
    A_ub = np.vstack([Lv, -Lv])
    b_ub = np.concatenate([np.full(n - 1, v_max - v0), np.full(n - 1, v_max + v0)])
    res = linprog(np.zeros(n), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq,
                  bounds=[(-a_max, a_max)] * n, method="highs")
    return res.status == 0


@pytest.mark.parametrize("d, v0, v1", [
    (0.5, 0.0, 0.0),      # rest to rest, cruises
    (0.05, 0.0, 0.0),     # rest to rest, never reaches v_max
    (-0.8, 0.0, 0.0),     # negative direction
    (0.3, 0.6, 0.0),      # arrives at rest moving the right way
    (0.3, -0.6, 0.4),     # starts the wrong way
    (-0.02, 0.8, 0.8),    # must reverse to end with the same speed further back
    (0.0, 0.5, -0.5),     # no displacement, velocity reversed
])
def test_min_time_is_the_least_time_of_the_double_integrator(d, v0, v1):
    v_max, a_max = 1.0, 4.0
    T, _ = min_time_1d(d, v0, v1, v_max, a_max)
    assert T > 0
    assert not _reachable(0.99 * T, d, v0, v1, v_max, a_max)
    assert _reachable(1.01 * T, d, v0, v1, v_max, a_max)


def test_min_time_rest_to_rest_is_the_trapezoid_by_hand():
    v, a = 2.0, 5.0  # v^2 / a = 0.8 rad: below it a triangle, above it a trapezoid
    T, cruise = min_time_1d(1.2, 0.0, 0.0, v, a)
    assert cruise and T == pytest.approx(1.2 / 2.0 + 2.0 / 5.0, rel=1e-12)
    T, cruise = min_time_1d(-0.45, 0.0, 0.0, v, a)
    assert not cruise and T == pytest.approx(2 * np.sqrt(0.45 / 5.0), rel=1e-12)
    # the move is as slow as its slowest joint, and says which
    T, j, cruise = joint_move_bound(np.zeros(3), np.array([0.1, -1.2, 0.45]), np.zeros(3),
                                    np.zeros(3), np.array([3.0, 2.0, 2.0]),
                                    np.array([5.0, 5.0, 5.0]))
    assert j == 1 and cruise and T == pytest.approx(1.0, rel=1e-12)


@pytest.fixture(scope="module")
def budget():
    plan = vs.good_plan()
    report = vs.verify(plan)
    return plan, report, report.item("time_budget")


def _cell_limits():
    cell, _ = vs.cell_and_hub()
    return (np.maximum(np.abs(cell.v_lower), np.abs(cell.v_upper)),
            np.maximum(np.abs(cell.a_lower), np.abs(cell.a_upper)))


def test_cut_time_against_the_edge_length_of_the_cl_points(budget):
    plan, report, item = budget
    _, hub = vs.cell_and_hub()
    assert not item.required and item.passed and item.comparison == "info"
    v_g = vs.PARAMS.grinding_speed
    cut_total = 0.0
    for w in vs.WINDOWS:
        rec = item.per_window[w]
        seg = next(g for g in plan.segments if g.kind == "cut" and g.window_index == w)
        # the CL points: the plan's ToolPath of the window, a closed loop
        cl = list(np.asarray(plan.tool_path[w].p_HC, float))
        assert len(cl) > 10
        length = sum(float(np.linalg.norm(cl[(i + 1) % len(cl)] - cl[i]))
                     for i in range(len(cl)))
        assert rec["edge_length_m"] == pytest.approx(length, rel=1e-12)
        # geometric truth: chords inscribed in the true edge are no longer than it, and
        # (chord height <= 0.12 mm) shorter by little
        e = np.asarray(hub.windows[w].p_HE)
        true_length = float(np.linalg.norm(np.diff(np.vstack([e, e[:1]]), axis=0),
                                           axis=1).sum())
        assert true_length * (1 - 1e-3) <= rec["edge_length_m"] <= true_length * (1 + 1e-9)
        cut_s = seg.t_range[1] - seg.t_range[0]
        assert rec["cut_s"] == pytest.approx(cut_s, rel=1e-12)
        assert rec["edge_seconds"] == pytest.approx(length / v_g, rel=1e-12)
        assert rec["cut_ratio"] == pytest.approx(cut_s * v_g / length, rel=1e-12)
        # the cut runs at or below the feed (+ band): it cannot beat the edge time by more
        assert rec["cut_ratio"] >= (1 - 0.05) / (1 + 0.05)
        # the wrist ranges over the cut's samples, re-read from the series
        s = report.series
        m = (s["kind"] == 3) & (s["window"] == w)
        np.testing.assert_allclose(
            [rec["j4_range_rad"], rec["j5_range_rad"], rec["j6_range_rad"]],
            np.ptp(s["q"][m][:, 3:6], axis=0), rtol=1e-12)
        cut_total += cut_s
    assert cut_total < plan.trajectory.duration


def test_moves_off_the_cut_against_their_joint_bound_by_hand(budget):
    """Every move off the cut is counted once, in order; each is a joint displacement between
    rests here (the reference plan's moves start and stop at rest), whose least time is the
    slowest joint's trapezoid (by hand); the plan's move respects the limits, so it is never
    faster than that bound."""
    plan, _, item = budget
    v_max, a_max = _cell_limits()
    moves = [m for w in vs.WINDOWS for m in item.per_window[w]["air_before"]]
    moves += item.per_window[-1]["air_after"]
    off_cut = [g for g in plan.segments if g.kind != "cut"]
    assert [m["kind"] for m in moves] == [g.kind for g in off_cut]
    for m, g in zip(moves, off_cut, strict=True):
        t0, t1 = g.t_range
        q0, q1 = plan.trajectory.value(np.array([t0, t1]))
        np.testing.assert_allclose(plan.trajectory.derivative(np.array([t0, t1]), 1), 0,
                                   atol=1e-9)
        d = np.abs(q1 - q0)
        by_hand = np.where(d >= v_max ** 2 / a_max, d / v_max + v_max / a_max,
                           2 * np.sqrt(d / a_max))
        j = int(np.argmax(by_hand))
        assert m["bound_s"] == pytest.approx(by_hand[j], rel=1e-9)
        assert m["bound_joint"] == f"J{j + 1}"
        assert m["bound_limit"] == ("speed" if d[j] >= v_max[j] ** 2 / a_max[j]
                                    else "acceleration")
        assert m["duration_s"] == pytest.approx(t1 - t0, rel=1e-12)
        assert m["duration_s"] >= m["bound_s"] * (1 - 1e-9)
    total = sum(item.per_window[w]["cut_s"] for w in vs.WINDOWS) + sum(
        m["duration_s"] for m in moves)
    assert total == pytest.approx(plan.trajectory.duration, rel=1e-9)
    bound = sum(item.per_window[w]["edge_seconds"] for w in vs.WINDOWS) + sum(
        m["bound_s"] for m in moves)
    assert item.value == pytest.approx(plan.trajectory.duration / bound, rel=1e-9)


def test_slow_stretch_binding_limit_from_the_spline_derivatives(budget):
    """Each slow stretch's binding limit, re-read at its least point: the largest share of a
    joint's speed or acceleration limit (the spline's own first and second derivatives) or of
    the TCP acceleration (finite differences of FK) within 1 mm of tool travel."""
    from drakedeburr.plan.kinematics import cell_kinematics

    plan, _, item = budget
    cell, _ = vs.cell_and_hub()
    kin = cell_kinematics(cell)
    v_max, a_max = _cell_limits()
    a_tcp = vs.PARAMS.tcp_acceleration
    traj = plan.trajectory
    checked = 0
    for w in vs.WINDOWS:
        seg = next(g for g in plan.segments if g.kind == "cut" and g.window_index == w)
        t0, t1 = seg.t_range
        knots = traj.t[(traj.t > t0) & (traj.t < t1)]
        t = np.unique(np.concatenate([np.linspace(t0, t1, int((t1 - t0) / 0.25e-3) + 1),
                                      knots]))
        p = kin.X_HT_from_q(traj.value(t))[:, :3, 3]
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        h = 1e-5
        # central differences (the trajectory runs on past the cut's ends)
        tm, tp = np.maximum(t - h, 0.0), np.minimum(t + h, traj.t[-1])
        pm = kin.X_HT_from_q(traj.value(tm))[:, :3, 3]
        pp = kin.X_HT_from_q(traj.value(tp))[:, :3, 3]
        vel = (pp - pm) / (tp - tm)[:, None]
        pc = kin.X_HT_from_q(traj.value(0.5 * (tm + tp)))[:, :3, 3]
        acc = 4 * (pp - 2 * pc + pm) / (tp - tm)[:, None] ** 2
        speed = np.linalg.norm(vel, axis=1)
        along = np.einsum("ij,ij->i", vel, acc) / np.maximum(speed, 1e-12)
        along = np.where(speed > 1e-6, along, np.linalg.norm(acc, axis=1))
        shares = {**{(f"J{j + 1}", "speed"): np.abs(traj.derivative(t, 1)[:, j]) / v_max[j]
                     for j in range(6)},
                  **{(f"J{j + 1}", "acceleration"):
                     np.abs(traj.derivative(t, 2)[:, j]) / a_max[j] for j in range(6)},
                  ("TCP", "acceleration"): np.abs(along) / a_tcp}
        for st in item.per_window[w]["slow_stretches"]:
            near = np.abs(s - st["least_at_m"]) <= 1e-3
            peak = {k: float(v[near].max()) for k, v in shares.items()}
            top = max(peak, key=peak.get)
            assert (st["joint"], st["limit"]) == top, (w, st, peak)
            assert st["ratio"] == pytest.approx(peak[top], rel=2e-2)
            checked += 1
    assert checked >= 2 * len(vs.WINDOWS)  # each cut starts and stops at rest


def test_time_budget_is_in_the_json_and_the_html(budget):
    import json

    from drakedeburr.verify.html import report_html
    from drakedeburr.verify.report import report_json

    _, report, item = budget
    doc = json.loads(report_json(report, include_run=False))
    got = next(i for i in doc["items"] if i["name"] == "time_budget")
    assert set(got["per_window"]) == {str(w) for w in vs.WINDOWS} | {"-1"}
    assert got["per_window"]["0"]["cut_ratio"] == pytest.approx(item.per_window[0]["cut_ratio"])
    page = report_html(report, figures={})
    assert 'id="time-budget"' in page and 'id="air-moves"' in page
    table = page[page.index('id="air-moves"'):]
    n_moves = sum(len(item.per_window[w]["air_before"]) for w in vs.WINDOWS) + len(
        item.per_window[-1]["air_after"])
    assert table[:table.index("</table>")].count("<tr>") == n_moves + 1  # + header
