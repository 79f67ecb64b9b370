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
        order = mut.best_order(costs)
        assert sorted(order) == list(range(n))
        t, _ = mut.order_seconds(costs, order)
        assert t <= _brute(costs) + mut.TIE_SECONDS + 1e-12


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
    a, b = mut.best_order(costs), mut.best_order(costs)
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
