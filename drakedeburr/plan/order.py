"""The order the planned windows are cut in, chosen for the cycle.

Each window is planned on its own (:mod:`drakedeburr.plan.window`: the same plan in any order),
so what the order decides is only the moves off the cut: home -> first window's approach,
each retract -> the next approach, the last retract -> home. The order (and with it the start
window, where the loop from home is closed) is the one of least estimated air time:

* each move is estimated by :func:`move_seconds`: the larger of its joint displacement rest
  to rest at the joint velocity/acceleration limits (at the planner's margins) and the
  straight distance of its tool points at the move's programmed TCP speed (home legs at
  ``home_speed``, the moves between windows at ``window_switch_speed``): what the planner's
  straight move or TCP line needs at least, and microseconds to compute (timing each
  candidate move as planned took ~40 s for the 30 moves of a five-window hub). No clearance
  query here: the planner plans the chosen order's moves in full, every check unchanged, and
  keeps the given order when those are not faster;
* ties (to a millisecond) go to the least weighted wrist travel (J4-J6 joint displacement),
  then to the given order; another order replaces the given one only when its estimate is
  :data:`ESTIMATE_MARGIN` shorter (the estimate's own error);
* exact over every order (Held-Karp dynamic programming over subsets) up to
  :data:`EXACT_WINDOWS` windows; beyond, the nearest-neighbour order improved by moving single
  windows (or-opt) until no move helps. Deterministic.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["AirCosts", "EXACT_WINDOWS", "air_costs", "best_order", "order_seconds",
           "move_seconds"]

#: windows up to which every order is searched (Held-Karp: 2^n n^2 steps)
EXACT_WINDOWS = 10

#: [s] two estimates this close are a tie (then the wrist travel decides)
TIE_SECONDS = 1e-3

#: share of the given order's estimate another order must save to replace it: the estimate is
#: a lower bound, and on the default hub (tool in hand) it fell short of the planned moves by
#: 4-25 % per move (the joint line's detours, the TCP acceleration at its ends), so an order
#: it finds 1 % shorter planned 4.6 % longer (4.09 s against 3.91 s)
ESTIMATE_MARGIN = 0.10


def move_seconds(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray, distance: float,
                 v_cap: float) -> float:
    """Estimated time [s] of a move by ``dq`` (6,) [rad] from rest to rest: the slowest joint's
    trapezoid (triangle when it never reaches ``v_max``; Lynch & Park, Modern Robotics
    sec. 9.2.2: ``|d| / v + v / a`` when ``|d| >= v^2 / a``, else ``2 sqrt(|d| / a)``) under
    ``v_max``/``a_max`` (6,) [rad/s, rad/s^2], or ``distance`` [m] at ``v_cap`` [m/s] if
    longer."""
    d = np.abs(np.asarray(dq, float))
    v, a = np.asarray(v_max, float), np.asarray(a_max, float)
    t = np.where(d >= v * v / a, d / v + v / a, 2.0 * np.sqrt(d / a))
    return float(max(float(t.max(initial=0.0)), distance / v_cap))


@dataclass(frozen=True)
class AirCosts:
    """Estimated cost of each move off the cut between ``n`` planned windows.

    Attributes:
        from_home: (n,) home -> window i's first configuration [s].
        between: (n, n) window i's last configuration -> window j's first [s] (diagonal
            unused).
        to_home: (n,) window i's last configuration -> home [s].
        wrist: (n + 1, n + 1) wrist travel (|J4| + |J5| + |J6| displacement) [rad] of the
            same moves; row/column n is home (row: from home, column: to home).
    """

    from_home: np.ndarray
    between: np.ndarray
    to_home: np.ndarray
    wrist: np.ndarray

    @property
    def n(self) -> int:
        return len(self.from_home)


def air_costs(q_home: np.ndarray, q_first: Sequence[np.ndarray], q_last: Sequence[np.ndarray],
              seconds: Callable[[np.ndarray, np.ndarray, str], float]) -> AirCosts:
    """The moves' estimates (:class:`AirCosts`) for windows starting at ``q_first[i]`` and
    ending at ``q_last[i]`` (6,) [rad]; ``seconds(q0, q1, kind)`` times one move (kind "home"
    or "transition")."""
    n = len(q_first)
    q_home = np.asarray(q_home, float)
    first = [np.asarray(q, float) for q in q_first]
    last = [np.asarray(q, float) for q in q_last]
    from_home = np.array([seconds(q_home, first[i], "home") for i in range(n)])
    to_home = np.array([seconds(last[i], q_home, "home") for i in range(n)])
    between = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            if i != j:
                between[i, j] = seconds(last[i], first[j], "transition")
    ends = [*last, q_home]
    starts = [*first, q_home]
    wrist = np.array([[float(np.abs(b[3:6] - a[3:6]).sum()) for b in starts] for a in ends])
    return AirCosts(from_home=from_home, between=between, to_home=to_home, wrist=wrist)


def order_seconds(costs: AirCosts, order: Sequence[int]) -> tuple[float, float]:
    """(estimated air time [s], wrist travel [rad]) of cutting the windows in ``order``
    (positions into ``costs``), from home and back."""
    if not len(order):
        return 0.0, 0.0
    n = costs.n
    t = float(costs.from_home[order[0]] + costs.to_home[order[-1]])
    w = float(costs.wrist[n, order[0]] + costs.wrist[order[-1], n])
    for a, b in zip(order[:-1], order[1:], strict=True):
        t += float(costs.between[a, b])
        w += float(costs.wrist[a, b])
    return t, w


def _better(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether cost ``a`` beats ``b``: shorter by :data:`TIE_SECONDS`, or as short with less
    wrist travel (by 1 mrad)."""
    if a[0] < b[0] - TIE_SECONDS:
        return True
    return abs(a[0] - b[0]) <= TIE_SECONDS and a[1] < b[1] - 1e-3


def _held_karp(costs: AirCosts) -> list[int]:
    """The order of least estimated time over every order (ties: the lexicographically first
    order the recursion meets, i.e. deterministic)."""
    n = costs.n
    full = (1 << n) - 1
    # best[(mask, last)] = (time, wrist, previous)
    best: dict[tuple[int, int], tuple[float, float, int]] = {
        (1 << i, i): (float(costs.from_home[i]), float(costs.wrist[n, i]), -1)
        for i in range(n)}
    for size in range(2, n + 1):
        for mask in range(1, full + 1):
            if bin(mask).count("1") != size:
                continue
            for j in range(n):
                if not mask >> j & 1:
                    continue
                prev = mask ^ (1 << j)
                cand = None
                for i in range(n):
                    if not prev >> i & 1:
                        continue
                    t, w, _ = best[(prev, i)]
                    c = (t + float(costs.between[i, j]), w + float(costs.wrist[i, j]), i)
                    if cand is None or _better(c[:2], cand[:2]):
                        cand = c
                best[(mask, j)] = cand
    end = None
    for j in range(n):
        t, w, _ = best[(full, j)]
        c = (t + float(costs.to_home[j]), w + float(costs.wrist[j, n]), j)
        if end is None or _better(c[:2], end[:2]):
            end = c
    order, mask, j = [], full, end[2]
    while j >= 0:
        order.append(j)
        _, _, i = best[(mask, j)]
        mask ^= 1 << j
        j = i
    return order[::-1]


def _or_opt(costs: AirCosts, order: list[int]) -> list[int]:
    """``order`` improved by moving one window elsewhere while that shortens it."""
    cur = order_seconds(costs, order)
    improved = True
    while improved:
        improved = False
        for k in range(len(order)):
            for pos in range(len(order)):
                if pos == k:
                    continue
                trial = order[:k] + order[k + 1:]
                trial.insert(pos, order[k])
                c = order_seconds(costs, trial)
                if _better(c, cur):
                    order, cur, improved = trial, c, True
                    break
            if improved:
                break
    return order


def _nearest(costs: AirCosts) -> list[int]:
    n = costs.n
    left = list(range(n))
    cur = min(left, key=lambda i: (costs.from_home[i], i))
    order = [cur]
    left.remove(cur)
    while left:
        cur = min(left, key=lambda j, c=cur: (costs.between[c, j], j))
        order.append(cur)
        left.remove(cur)
    return order


def best_order(costs: AirCosts, margin: float = ESTIMATE_MARGIN) -> list[int]:
    """The order (positions 0..n-1) of least estimated air time (module docstring); the given
    order 0..n-1 unless that one's estimate is shorter by ``margin`` of the given order's
    (:data:`ESTIMATE_MARGIN`; with ``margin`` 0: by :data:`TIE_SECONDS`, or as short with
    less wrist travel)."""
    n = costs.n
    given = list(range(n))
    if n < 2:
        return given
    found = _held_karp(costs) if n <= EXACT_WINDOWS else _or_opt(costs, _nearest(costs))
    t_found, t_given = order_seconds(costs, found), order_seconds(costs, given)
    if margin > 0.0:
        return found if t_found[0] < (1.0 - margin) * t_given[0] else given
    return found if _better(t_found, t_given) else given
