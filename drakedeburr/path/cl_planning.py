"""Cutter-location (CL) point planners on a closed EdgeCurve (source §1.2 and §3.1).

Every planner has the same interface, ``plan_cl(curve, method=..., params=...) -> ClPath``:

``proposed``
    The source's method, step by step (§1.2, Fig. 3): curvature of the initial CL points;
    K-means on curvature with K chosen by the elbow of the SSE curve (eq. 3); clusters ranked
    by centroid: the top cluster is "near max curvature" (kept), the bottom one "low
    curvature" (chord-length / chord-height walk with L_max and delta_max, eq. 2), clusters in
    between "near median" (sorted by curvature descending, every other point kept); the kept
    points re-sorted by their original index. It selects a *subset of the initial points* and
    checks its thresholds only inside the low-curvature walk, as the source does; its other
    segments are not bounded (the metrics show by how much).
``isoparametric``
    Equal steps of arc length (the source uses the initial points' accumulated arc length as
    the parameter). The source does not say how it picks the step; we take the fewest equal
    steps for which every segment has true chord height <= delta_max and chord <= L_max.
``equal_chord_height``
    The classic baseline: march along the curve, each next point as far as the true chord
    height allows (delta_max); no length cap.
``adaptive`` (ours)
    Optimal segmentation of the closed curve on a fine arc-length grid (step L_max/64) by
    dynamic programming: every segment must keep chord <= L_max and chord height <= delta_max;
    for every point count from the fewest feasible up to ``count_budget`` (default: the
    proposed method's count) the DP finds the plan with the smallest sum of squared chords
    (the most even chords for that count); the plan with the smallest all-pairs c_v (then
    neighbour c_v) is returned. Each plan is re-checked against the TRUE chord height on the
    spline before it is accepted. When the budget is infeasible (the proposed method broke
    its own thresholds) the fewest feasible points are returned.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import pdist

from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.hub.types import WindowKind
from drakedeburr.path.cl_equal_chord import (
    SAMPLED_MARGIN,
    plan_equal_chord_height,
    samples_for,
)
from drakedeburr.path.edge_curve import EdgeCurve
from drakedeburr.path.metrics import cl_metrics
from drakedeburr.path.types import ClPath

__all__ = [
    "PlannerParams",
    "METHODS",
    "plan_cl",
    "plan_all",
    "kmeans_sse",
    "elbow_k",
    "cluster_roles",
    "every_other_by_curvature",
    "chord_walk",
    "proposed_indices",
]

log = logging.getLogger(__name__)

METHODS: tuple[str, ...] = ("proposed", "isoparametric", "equal_chord_height", "adaptive")

# start points tried by the adaptive DP (each is one DP pass)
N_STARTS = 5


@dataclass(frozen=True)
class PlannerParams:
    """Thresholds of the CL planners (defaults: source §3.1 via ProcessParameters).

    Attributes:
        l_max: max chord length between CL points [m] (10 mm).
        delta_max: max chord-height error [m] (0.12 mm).
        k_max: largest K tried by the elbow method.
        seed: random state of K-means.
        count_budget: ``adaptive`` only: max point count (None: the proposed method's count).
    """

    l_max: float = ProcessParameters.l_max
    delta_max: float = ProcessParameters.delta_max
    k_max: int = 8
    seed: int = 0
    count_budget: int | None = None

    def __post_init__(self) -> None:
        if not (self.l_max > 0 and self.delta_max > 0):
            raise InputError(f"planner thresholds must be > 0: l_max={self.l_max}, "
                             f"delta_max={self.delta_max}")
        if self.k_max < 1:
            raise InputError(f"k_max must be >= 1, got {self.k_max}")


# ---------------------------------------------------------------------------------------------
# proposed method, one function per step (each unit-tested)
# ---------------------------------------------------------------------------------------------
def kmeans_sse(kappa: np.ndarray, k_max: int, seed: int = 0) -> tuple[np.ndarray, list]:
    """K-means (scikit-learn) on the curvature values for K = 1..k_max (eq. 3).

    Args:
        kappa: (N,) curvature values [1/m].
        k_max: largest K (clipped to the number of distinct values).
        seed: random state.

    Returns:
        sse: (K,) within-cluster sum of squares for K = 1..K; labels: list of (N,) arrays.
    """
    from sklearn.cluster import KMeans
    from threadpoolctl import threadpool_limits

    x = np.asarray(kappa, float).reshape(-1, 1)
    k_max = max(1, min(k_max, len(np.unique(np.round(x[:, 0], 12)))))
    sse, labels = [], []
    # a few hundred 1-D values: OpenMP threads only add start-up cost (measured 8 s vs 0.3 s
    # for K = 1..8 on a loaded 2-core machine), so run single-threaded
    with threadpool_limits(1):
        for k in range(1, k_max + 1):
            km = KMeans(n_clusters=k, n_init=10, random_state=seed).fit(x)
            sse.append(float(km.inertia_))
            labels.append(km.labels_.copy())
    return np.array(sse), labels


def elbow_k(sse: np.ndarray) -> int:
    """The elbow of an SSE-versus-K curve (K = 1, 2, ...): the point farthest below the line
    from the first to the last point, both axes normalised to [0, 1] ("kneedle").

    Returns 1 when the SSE is already ~0 at K = 1 (all curvatures equal) or only K = 1 exists.
    """
    sse = np.asarray(sse, float)
    if len(sse) < 3 or sse[0] <= 1e-12 * max(1.0, abs(sse).max()):
        return 1 if len(sse) < 2 or sse[0] <= 1e-12 * max(1.0, abs(sse).max()) else 2
    x = np.linspace(0.0, 1.0, len(sse))
    y = (sse - sse[-1]) / max(sse[0] - sse[-1], 1e-300)
    return int(np.argmax((1.0 - x) - y)) + 1


def cluster_roles(kappa: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Role of every point from its cluster: 2 near max, 1 near median, 0 low curvature.

    Clusters are ranked by their mean curvature: the top one is "near max", the bottom one
    "low", all in between "near median". One cluster: everything is "low" (the walk alone).

    Returns:
        (N,) int roles.
    """
    kappa = np.asarray(kappa, float)
    ids = np.unique(labels)
    roles = np.zeros(len(kappa), int)
    if len(ids) == 1:
        return roles
    order = ids[np.argsort([kappa[labels == i].mean() for i in ids])]
    for rank, cid in enumerate(order):
        roles[labels == cid] = 2 if rank == len(order) - 1 else (0 if rank == 0 else 1)
    return roles


def every_other_by_curvature(idx: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """Near-median step: sort the points by curvature descending, keep every other one
    (the 1st, 3rd, ...). Ties keep the original order (stable sort).

    Args:
        idx: (n,) indices of the near-median points.
        kappa: (N,) curvature of all points.

    Returns:
        kept indices (in curvature-descending order).
    """
    idx = np.asarray(idx, int)
    order = idx[np.argsort(-kappa[idx], kind="stable")]
    return order[::2]


def chord_walk(curve: EdgeCurve, u: np.ndarray, l_max: float, delta_max: float) -> np.ndarray:
    """Low-curvature step: walk the points in order from the first one (the start); drop the
    next point while both the chord length and the chord-height error (eq. 2) from the start
    stay below their thresholds; otherwise keep it and make it the new start.

    Args:
        curve: the edge curve (chords and eq.-2 chord heights are measured on it).
        u: (n,) increasing parameters of the low-curvature points.

    Returns:
        (k,) positions into ``u`` of the kept points (the first point is always kept).
    """
    u = np.asarray(u, float)
    if len(u) == 0:
        return np.zeros(0, int)
    kept = [0]
    start, n = 0, len(u)
    j0, block = 1, 8
    # the next kept point is the first j after the start whose chord or eq.-2 height fails:
    # tested for a block of j at once (the same values as one call per j), doubling the block
    while j0 < n:
        j = np.arange(j0, min(j0 + block, n))
        l = curve.chord_length(np.full(len(j), u[start]), u[j])
        d = curve.chord_height_circle(np.full(len(j), u[start]), u[j])
        fail = np.flatnonzero(~((l < l_max) & (d < delta_max)))
        if len(fail) == 0:
            j0, block = j0 + len(j), 2 * block
            continue
        start = int(j[fail[0]])
        kept.append(start)
        j0, block = start + 1, 8
    return np.array(kept, int)


def proposed_indices(curve: EdgeCurve, params: PlannerParams) -> dict:
    """The source's planner on the initial points ``curve.u_data``; all intermediate results.

    Returns:
        dict with ``kappa`` (N,), ``sse`` (K,), ``k`` (elbow), ``labels`` (N,), ``roles`` (N,),
        ``kept`` (sorted indices into the initial points).
    """
    u = curve.u_data
    kappa = curve.curvature(u)
    sse, labels = kmeans_sse(kappa, params.k_max, params.seed)
    k = elbow_k(sse)
    lab = labels[k - 1]
    roles = cluster_roles(kappa, lab)
    keep_max = np.flatnonzero(roles == 2)
    keep_med = every_other_by_curvature(np.flatnonzero(roles == 1), kappa)
    low = np.flatnonzero(roles == 0)
    keep_low = low[chord_walk(curve, u[low], params.l_max, params.delta_max)]
    kept = np.sort(np.concatenate([keep_max, keep_med, keep_low]))
    return {"kappa": kappa, "sse": sse, "k": k, "labels": lab, "roles": roles, "kept": kept}


def _plan_proposed(curve: EdgeCurve, params: PlannerParams) -> np.ndarray:
    return curve.u_data[proposed_indices(curve, params)["kept"]]


# ---------------------------------------------------------------------------------------------
# baselines and ours
# ---------------------------------------------------------------------------------------------
def _segments_ok(curve: EdgeCurve, u: np.ndarray, params: PlannerParams,
                 length_cap: bool = True) -> bool:
    u_next = np.roll(u, -1)
    u_next[-1] += 1.0
    if length_cap and (curve.chord_length(u, u_next) > params.l_max).any():
        return False
    samples = samples_for(curve, u, u_next)
    target = params.delta_max * (1.0 - SAMPLED_MARGIN)
    # every 8th sample first: a plan failing there fails the full test (same values, fewer)
    if (curve.sampled_chord_height_lower_bound(u, u_next, samples) > target).any():
        return False
    d = curve.chord_height(u, u_next, samples=samples, refine=False)
    return bool((d <= target).all())


def _plan_isoparametric(curve: EdgeCurve, params: PlannerParams) -> np.ndarray:
    """The fewest points equally spaced in arc length (to within 2 %) that meet both
    thresholds. An arc of length L lies within L/2 of an end of its chord, so ``n_cap``
    points (arcs of at most twice the chord-height target) meet any target: the search ends
    there at the latest, also on a cusp; failing there, the curve's arc length is wrong."""
    target = params.delta_max * (1.0 - SAMPLED_MARGIN)
    n_cap = max(4, int(np.ceil(curve.length / (2.0 * target))) + 1)
    n = min(max(4, int(np.ceil(curve.length / params.l_max))), n_cap)
    while True:
        u = curve.u_from_arc(np.arange(n) * curve.length / n)
        if _segments_ok(curve, u, params):
            return u
        if n >= n_cap:
            raise InputError(f"edge curve of {curve.length * 1e3:.1f} mm: {n} points equally "
                             f"spaced in arc length still break the chord height of "
                             f"{params.delta_max * 1e3:.3f} mm (its arc-length table is "
                             "inconsistent)")
        n = min(n + max(1, n // 50), n_cap)


def _chords_and_heights(p: np.ndarray, reach: int, l_max: float, delta: float):
    """For a closed grid of curve points p (G, 3): chord (G, R) and sampled chord height
    (G, R) of the segment from grid point i to i + r (r = 1..R): the max distance of the grid
    points between them from the chord. Rows stop (inf) at the first r whose segment breaks
    chord <= l_max or height <= delta (longer segments from the same start break them too)."""
    G = len(p)
    chord = np.full((G, reach), np.inf)
    height = np.full((G, reach), np.inf)
    alive = np.arange(G)
    # D[i, k] = p[(i + 1 + k) % G] - p[i]: the inner points seen from each start, and their
    # squared lengths, computed once for all segment lengths (a zero-copy sliding view of
    # the wrapped grid; per segment only the rows still alive are gathered)
    p_ext = np.concatenate([p, p[: reach + 1]])
    window = np.lib.stride_tricks.as_strided(p_ext[1:], (G, reach, 3),
                                             (p_ext.strides[0], p_ext.strides[0], p_ext.strides[1]),
                                             writeable=False)
    D = window - p[:, None, :]
    DD = np.einsum("nkj,nkj->nk", D, D)
    for r in range(1, reach + 1):
        a = p[alive]
        b = p_ext[alive + r]
        c = np.linalg.norm(b - a, axis=1)
        h = np.zeros(len(alive))
        if r > 1:
            # squared distance of the inner points to the segment, without (n, r-1, 3)
            # temporaries beyond ap: |ap|^2 - 2 t ap.ab + t^2 |ab|^2, t clipped to [0, 1]
            ap = D[alive, : r - 1]  # (n, r-1, 3)
            ab = b - a
            L2 = np.maximum(c * c, 1e-300)[:, None]
            dot = np.einsum("nkj,nj->nk", ap, ab)
            t = np.clip(dot / L2, 0.0, 1.0)
            d2 = DD[alive, : r - 1] - 2 * t * dot + t * t * L2
            h = np.sqrt(np.maximum(d2.max(1), 0.0))
        chord[alive, r - 1] = c
        height[alive, r - 1] = h
        alive = alive[(c <= l_max) & (h <= delta)]
        if len(alive) == 0:
            break
    return chord, height


def _feasible(chord: np.ndarray, height: np.ndarray, l_max: float, delta: float):
    """(chord with inf where infeasible, ok): ok[i, r] = every segment from i up to i + r
    keeps chord <= l_max and height <= delta (prefix-closed, like the true constraint)."""
    ok = np.logical_and.accumulate((chord <= l_max) & (height <= delta), axis=1)
    return np.where(ok, chord, np.inf), ok


def _dp_layers(chord: np.ndarray, ok: np.ndarray, start: int, k_max: int, k_enough: int = 0):
    """Shortest-path layers over the closed grid from ``start`` back to it: best[k][j] = min
    sum of squared chords of k feasible segments from start to j (j in 0..G, G = back at
    start). Returns (best (K+1, G+1), arg (K+1, G+1)) with +inf where unreachable.

    Only what can be finite is computed: segment lengths up to the longest feasible one, and in
    layer k only the positions that k segments can reach (the others stay +inf, arg 1: what
    the full (G+1, R) minimum gives them)."""
    G = chord.shape[0]
    R = max(1, int(np.flatnonzero(ok.any(axis=0))[-1]) + 1 if ok.any() else 1)
    chord, ok = chord[:, :R], ok[:, :R]
    roll = (np.arange(G + 1) + start) % G  # position j on the unrolled loop -> grid index
    cost = np.where(ok, chord**2, np.inf)
    j = np.arange(G + 1)
    i = j[:, None] - np.arange(1, R + 1)[None, :]  # (G+1, R) segment start on the unrolled loop
    valid = i >= 0
    seg_cost = np.where(valid, cost[roll[np.where(valid, i, 0)], np.arange(R)[None, :]], np.inf)
    # best[k] is stored after R entries of +inf, so that best[k-1][j - r] (r = 1..R) for the
    # rows j of a layer is a zero-copy sliding view (+inf before the start, as the
    # unreachable start positions have)
    pad = np.full((k_max + 1, R + G + 1), np.inf)
    best = pad[:, R:]
    arg = np.ones((k_max + 1, G + 1), int)
    best[0, 0] = 0.0
    step = pad.strides[1]
    lo = hi = 0  # positions that can be finite in the previous layer
    for k in range(1, k_max + 1):
        lo, hi = min(lo + 1, G + 1), min(hi + R, G)
        if lo <= hi:
            prev = np.lib.stride_tricks.as_strided(  # prev[j - lo, r - 1] = best[k-1][j - r]
                pad[k - 1, R + lo - 1:], (hi + 1 - lo, R), (step, -step), writeable=False)
            cand = prev + seg_cost[lo: hi + 1]
            r_best = np.argmin(cand, axis=1)
            best[k, lo: hi + 1] = cand[np.arange(hi + 1 - lo), r_best]
            arg[k, lo: hi + 1] = r_best + 1
        if k >= k_enough and np.isfinite(best[k, G]):  # the budget and the fewest are covered
            return best[: k + 1], arg[: k + 1]
    return best, arg


def _backtrack(arg: np.ndarray, k: int, G: int) -> np.ndarray:
    pos, out = G, []
    for layer in range(k, 0, -1):
        pos -= arg[layer, pos]
        out.append(pos)
    return np.array(out[::-1])


def _plan_adaptive(curve: EdgeCurve, params: PlannerParams) -> np.ndarray:
    """Ours: optimal CL points on a fine arc-length grid by dynamic programming.

    Every segment must pass chord <= L_max and the grid-sampled chord height <= delta_max
    (grid step L_max/64; with a margin of 0.3 %, tightened until the plan passes the TRUE chord
    height on the spline). Among such plans: the fewest points
    N_min (lexicographically first), then for each count N from N_min up to the budget
    (default: the proposed method's count) the plan minimising the sum of squared chords,
    i.e. the most uniform chords for that count; the count with the smallest c_v is returned.
    A few start points on the grid are tried. Written by hand: no library solves this
    constrained 1-D segmentation.
    """
    step = min(params.l_max / 64.0, curve.length / 400.0)
    G = max(64, int(np.ceil(curve.length / step)))
    u_grid = curve.u_from_arc(np.arange(G) * curve.length / G)
    p = curve.position(u_grid)
    reach = min(G - 1, int(np.ceil(1.25 * params.l_max / (curve.length / G))))
    n_lo = max(3, int(np.ceil(curve.length / params.l_max)))
    budget = params.count_budget
    if budget is None:
        budget = len(_plan_proposed(curve, params))
    k_max = max(budget, 3 * n_lo) + 2
    chords, heights = _chords_and_heights(p, reach, params.l_max, params.delta_max)
    # the grid samples the chord height (slightly low): plans are re-checked on the spline,
    # best first; the margin is tightened only if none passes
    for margins in ((1.0, 0.997), (0.99, 0.97), (0.94, 0.9)):
        cands = []
        for margin in margins:
            chord, ok = _feasible(chords, heights, params.l_max, params.delta_max * margin)
            km = k_max
            found = _dp_candidates(curve, u_grid, chord, ok, budget, km)
            while not found and km < G:  # sharp corners need more points than guessed
                km = min(G, 3 * km)
                found = _dp_candidates(curve, u_grid, chord, ok, budget, km)
            cands += found
        ranked = [u for _, u in sorted(cands, key=lambda c: c[0])]
        for u in ranked:
            if _true_ok(curve, u, params):
                return u
    # a feature sharper than the grid resolves (a corner of a few tenths of a millimetre): the
    # best grid plans (of the loosest margins) with the segments that fail on the spline split
    # until they pass
    split = [v for u in ranked[:3] if (v := _split_failing(curve, u, params)) is not None]
    if split:
        u = min(split, key=len)
        log.warning("adaptive: no plan on the grid passes the spline check (a feature sharper "
                    "than the grid); its failing segments split: %d points", len(u))
        return u
    log.warning("adaptive: no plan on the grid passes the spline check; using isoparametric")
    return _plan_isoparametric(curve, params)


def _split_failing(curve: EdgeCurve, u: np.ndarray, params: PlannerParams,
                   rounds: int = 40) -> np.ndarray | None:
    """``u`` with every segment that fails the true chord-length or chord-height check split
    at its arc-length midpoint, round after round until all pass (None after ``rounds``)."""
    for _ in range(rounds):
        bad = _failing(curve, u, params)
        if not bad.any():
            return u
        s = curve.arc_length(u)
        s_next = np.roll(s, -1)
        s_next[-1] += curve.length
        mid = curve.u_from_arc(0.5 * (s[bad] + s_next[bad]))
        u = np.sort(np.concatenate([u, mid]))
    return None


def _dp_candidates(curve, u_grid, chord, ok, budget, k_max) -> list:
    """(key, u) for every start and every count from the fewest up to the budget; key sorts
    within-budget plans by all-pairs c_v (the source's Tab. 2 figure), then neighbour c_v;
    over-budget ones by count."""
    G = len(u_grid)
    out = []
    for start in np.linspace(0, G, N_STARTS, endpoint=False).astype(int) % G:
        best, arg = _dp_layers(chord, ok, int(start), k_max, k_enough=budget)
        finite = np.flatnonzero(np.isfinite(best[:, G]))
        if len(finite) == 0:
            continue
        for n in finite[finite <= max(budget, int(finite[0]))]:
            u = np.sort(u_grid[(_backtrack(arg, int(n), G) + start) % G])
            d = pdist(curve.position(u))
            key = (n > budget, n if n > budget else 0, float(d.std() / d.mean()),
                   _neighbour_cv(curve, u))
            out.append((key, u))
    return out


def _failing(curve: EdgeCurve, u: np.ndarray, params: PlannerParams) -> np.ndarray:
    """(N,) which segments of the closed plan ``u`` fail L_max or the true chord height."""
    u_next = np.roll(u, -1)
    u_next[-1] += 1.0
    return ((curve.chord_length(u, u_next) > params.l_max)
            | (curve.chord_height(u, u_next) > params.delta_max))


def _true_ok(curve: EdgeCurve, u: np.ndarray, params: PlannerParams) -> bool:
    return not _failing(curve, u, params).any()


def _neighbour_cv(curve: EdgeCurve, u: np.ndarray) -> float:
    u_next = np.roll(u, -1)
    u_next[-1] += 1.0
    d = curve.chord_length(u, u_next)
    return float(d.std() / d.mean())


_PLANNERS: dict[str, Callable[[EdgeCurve, PlannerParams], np.ndarray]] = {
    "proposed": _plan_proposed,
    "isoparametric": _plan_isoparametric,
    "equal_chord_height": plan_equal_chord_height,
    "adaptive": _plan_adaptive,
}


def plan_cl(
    curve: EdgeCurve,
    method: str = "proposed",
    params: PlannerParams | None = None,
    *,
    window_index: int = 0,
    kind: WindowKind = "large",
) -> ClPath:
    """Plan CL points on one closed edge curve.

    Args:
        curve: the fitted window edge (frame H, metres).
        method: one of ``METHODS``.
        params: thresholds (default: L_max = 10 mm, delta_max = 0.12 mm).
        window_index, kind: copied into the ClPath.

    Returns:
        ClPath with points in edge order and ``metrics`` from :func:`cl_metrics`.

    Raises:
        InputError: unknown method.
    """
    if method not in _PLANNERS:
        raise InputError(f"unknown CL planning method {method!r}; choose from {', '.join(METHODS)}")
    params = params or PlannerParams()
    u = np.sort(np.mod(np.asarray(_PLANNERS[method](curve, params), float), 1.0))
    metrics = cl_metrics(curve, u)
    metrics["method"] = method
    if curve.fit:  # how the edge was fitted, against its facets (path.window_fit)
        metrics["edge_fit"] = dict(curve.fit)
    return ClPath(
        window_index=window_index,
        kind=kind,
        method=method,
        u=u,
        p_HC=curve.position(u),
        t_H=curve.tangent(u),
        kappa=curve.curvature(u),
        arc_length=curve.arc_length(u),
        total_length=curve.length,
        metrics=metrics,
    )


def plan_all(curve: EdgeCurve, params: PlannerParams | None = None, *, window_index: int = 0,
             kind: WindowKind = "large", methods=METHODS) -> dict[str, ClPath]:
    """Run several planners on one curve; ``adaptive`` gets the proposed count as budget."""
    params = params or PlannerParams()
    out: dict[str, ClPath] = {}
    for m in methods:
        p = params
        if m == "adaptive" and params.count_budget is None and "proposed" in out:
            p = PlannerParams(params.l_max, params.delta_max, params.k_max, params.seed,
                              count_budget=len(out["proposed"]))
        out[m] = plan_cl(curve, m, p, window_index=window_index, kind=kind)
    return out
