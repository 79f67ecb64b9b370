"""Window order chosen for the cycle (drakedeburr.plan.order): the search is re-checked against
every order by brute force, on move times computed independently of the module."""

from itertools import permutations

import numpy as np
import pytest

import drakedeburr.plan.order as mut


def _costs(rng, n):
    """Windows at random joint configurations; a move's time: its largest joint displacement
    over 1 rad/s (a stand-in timing, computed here)."""
    q_home = np.zeros(6)
    first = rng.uniform(-2, 2, (n, 6))
    last = first + rng.uniform(-0.5, 0.5, (n, 6))

    def seconds(q0, q1, kind):
        return float(np.max(np.abs(q1 - q0))) / (1.0 if kind == "home" else 0.8)

    return mut.air_costs(q_home, list(first), list(last), seconds), q_home, first, last


def _brute(costs):
    return min(mut.order_seconds(costs, p)[0] for p in permutations(range(costs.n)))


@pytest.mark.parametrize("n", [2, 3, 5, 7])
def test_exact_order_is_least_over_every_order(n):
    rng = np.random.default_rng(n)
    for _ in range(5):
        costs, *_ = _costs(rng, n)
        order = mut.best_order(costs, margin=0.0)
        assert sorted(order) == list(range(n))
        t, _ = mut.order_seconds(costs, order)
        assert t <= _brute(costs) + mut.TIE_SECONDS + 1e-12
        # with the estimate's margin: that order, or the given one when it is within it
        kept = mut.best_order(costs)
        t_given = mut.order_seconds(costs, list(range(n)))[0]
        assert kept == order or (kept == list(range(n))
                                 and t >= (1 - mut.ESTIMATE_MARGIN) * t_given)


def test_order_seconds_sums_the_moves_independently():
    rng = np.random.default_rng(0)
    costs, q_home, first, last = _costs(rng, 4)
    order = [2, 0, 3, 1]
    t, w = mut.order_seconds(costs, order)
    ends = [q_home] + [q for k in order for q in (first[k], last[k])] + [q_home]
    moves = list(zip(ends[0::2], ends[1::2], strict=True))
    expect = sum(float(np.max(np.abs(b - a))) / (1.0 if k in (0, len(moves) - 1) else 0.8)
                 for k, (a, b) in enumerate(moves))
    wrist = sum(float(np.abs(b[3:] - a[3:]).sum()) for a, b in moves)
    assert t == pytest.approx(expect, rel=1e-12)
    assert w == pytest.approx(wrist, rel=1e-12)


def test_move_seconds_is_the_slowest_joints_trapezoid_or_the_tcp_distance():
    v, a = np.full(6, 2.0), np.full(6, 4.0)
    # 2 rad at 2 rad/s, 4 rad/s^2: cruise (2 >= 1): 2/2 + 2/4 = 1.5 s; 0.25 rad: 2 sqrt(1/16)
    assert mut.move_seconds(np.r_[2.0, 0.25, 0, 0, 0, 0], v, a, 0.1, 1.0) == pytest.approx(1.5)
    assert mut.move_seconds(np.r_[0.25, 0, 0, 0, 0, 0], v, a, 0.1, 1.0) == pytest.approx(0.5)
    assert mut.move_seconds(np.r_[0.25, 0, 0, 0, 0, 0], v, a, 0.9, 1.0) == pytest.approx(0.9)
    # the trapezoid is the least time: a denser bang-bang integration is not faster
    d, dt = 2.0, 1e-4
    x, vel, t = 0.0, 0.0, 0.0
    while x < d:
        brake = vel * vel / (2 * 4.0) >= d - x
        vel = max(min(vel + (-4.0 if brake else 4.0) * dt, 2.0), 1e-9)
        x += vel * dt
        t += dt
    assert t == pytest.approx(1.5, abs=1e-2)


def test_given_order_kept_on_a_tie():
    # every move takes the same time and the same wrist travel: no order beats the given one
    n = 4
    q = [np.zeros(6)] * n
    costs = mut.air_costs(np.zeros(6), q, q, lambda a, b, kind: 1.0)
    assert mut.best_order(costs) == list(range(n))


def test_order_deterministic_and_never_worse_beyond_the_exact_search():
    n = mut.EXACT_WINDOWS + 2
    rng = np.random.default_rng(3)
    costs, *_ = _costs(rng, n)
    a, b = mut.best_order(costs, margin=0.0), mut.best_order(costs, margin=0.0)
    assert a == b and sorted(a) == list(range(n))
    assert mut.order_seconds(costs, a)[0] <= mut.order_seconds(costs, list(range(n)))[0]


def test_windows_on_a_line_are_cut_along_it():
    # windows spread along J1 given out of order (3.6 s): the least air time is out to the
    # farthest and back (2.4 s), every window passed on the way
    j1 = np.array([0.9, 0.3, 1.2, 0.6])
    first = [np.r_[x, np.zeros(5)] for x in j1]
    costs = mut.air_costs(np.zeros(6), first, first,
                          lambda a, b, kind: float(np.max(np.abs(b - a))))
    order = mut.best_order(costs)
    assert order != list(range(4))
    assert mut.order_seconds(costs, order)[0] == pytest.approx(2 * j1.max())


def _stand_in_window(kin, w, q):
    """A planned window that cuts in place at ``q`` (a cut of no length: what the order
    changes are the moves between windows)."""
    from types import SimpleNamespace

    from drakedeburr.plan.results import Stretch, WindowPlan, WindowStatus
    from drakedeburr.plan.stretch import make_target
    from drakedeburr.plan.timing import rest_path

    figures = dict(window=w, tool_travel_m=0.0, cut_seconds=0.0)
    stats = SimpleNamespace(cut_seconds=0.0, speed_in_band_fraction=1.0, reached=3,
                            cl_points=3, via_targets=0, to_dict=lambda: dict(figures))
    cut = Stretch("cut", w, rest_path(q), [make_target(kin, q, w, "cut", 0, 0.15, "linear")])
    return WindowPlan(window=w, status=WindowStatus.OK, stretches=[cut], stats=stats,
                      q_start=np.asarray(q, float))


def test_planner_cuts_the_windows_in_the_chosen_order_and_its_moves_are_faster():
    """drakedeburr.plan.planner assembles stand-in windows (J1 turned from home) given in a
    poor order in the order of least air time: the trajectory visits each window's joints in
    that order, every move's clearance is checked as before (no failure records) and the
    moves' time, read off the assembled trajectory, is below the given order's."""
    from types import SimpleNamespace

    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import load_config
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.planner import assemble_windows

    config = load_config("tool_in_hand", "h5_straight")
    cell = load_cell(config.scenario, config.hub)
    kin = cell_kinematics(cell)
    tol = config.tolerances
    ctx = PlanContext(cell=cell, kin=kin, checker=ClearanceChecker(cell, tolerances=tol),
                      free_checker=ClearanceChecker(cell, filter_burr_contact=False,
                                                    tolerances=tol),
                      config=config, options=PlanOptions(placement=False))
    turns = [0.4, -0.4, 0.2]  # J1 from home: 0.4 + 0.8 + 0.6 + 0.2 rad in the given order
    qs = [kin.q_home + np.r_[d, 0, 0, 0, 0, 0] for d in turns]
    wts = [SimpleNamespace(window_index=w, source="stand-in", depth_of_cut=0.0, tool_path=None)
           for w in range(3)]
    results = [_stand_in_window(kin, w, q) for w, q in enumerate(qs)]
    plan = assemble_windows(ctx, wts, results, None, 0.0).plan()
    assert not plan.failures
    rec = plan.meta["window_order"]
    assert rec["given"] == [0, 1, 2] and rec["kept"] == "chosen"
    cuts = [s for s in plan.segments if s.kind == "cut"]
    assert [s.window_index for s in cuts] == rec["chosen"] != [0, 1, 2]
    # re-checked on the trajectory itself: each cut holds its window's joints
    for s in cuts:
        q = plan.trajectory.value(np.array([s.t_range[0]]))[0]
        assert np.allclose(q, qs[s.window_index], atol=1e-9)
    air = sum(s.t_range[1] - s.t_range[0] for s in plan.segments if s.kind != "cut")
    assert air == pytest.approx(rec["chosen_air_s"], abs=1e-9)
    assert air < rec["given_air_s"] - 1e-3
