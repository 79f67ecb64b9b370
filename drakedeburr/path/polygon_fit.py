"""The NURBS fit of a loop that is a polygon (issue 42 item 3: the fit of a polygonal loop does
not invent wiggles; chord error and curvature are reported against the facet size).

**When a loop is a polygon.** A designed curve sampled at spacing h turns by about h / R at
each point; a mesher cuts a smooth curve into at least 12 chords a full turn, so a point of a
tessellated or sampled smooth curve turns by at most ``FACET_MAX_TURN`` (32 deg). A point
turning more is a corner of the polyline the points do not resolve as a curve: the loop's
points are the mesh vertices and straight facets between them (the low-poly rims of issue 42,
resampled at 2 mm, turn 55-124 deg at single points between collinear runs), or a designed
corner. Nothing between the points is known there better than the polyline itself. The
interpolating spline through such a corner overshoots on both sides and rings along the
straight facets beside it (measured 0.17-0.30 mm off the polyline on the dbw mkz13 and mondeo
rims, at 60-700 x the curvature the corner needs): it invents wiggles. Such a loop is fitted
with :func:`fit_polygon_curve` instead (:func:`is_polygon`).

**The fit.** A periodic cubic B-spline whose control polygon is the data polyline itself: the
points, plus two control points on the facets beside each point at a distance a_i from it
(knots at the control points' arc positions). Four consecutive collinear control points make
a straight span, so the curve *is* each facet between B_i and A_(i+1) and turns only on
[A_i, B_i] around each point, inside the corner's own triangle; a B-spline changes direction
no more often than its control polygon (variation diminishing), so it adds no inflection and
no turn the polyline does not have. a_i starts at ``min(0.45 L, 3 b / sin(theta / 2))`` (a
uniform cubic cuts a corner of turn theta by a sin(theta / 2) / 3) and is halved where the
curve, checked on dense samples, leaves the two facets by more than the bound b or passes its
point farther than b: the fit holds every point within b and stays within b of the polyline.

**What a corner needs.** The least curvature with which a curve turns theta within b of two
straight facets is the circle's tangent to both, kappa = (1 - cos(theta / 2)) / b, and no less
than 2 tan(theta / 2) / L_min when the facets are too short for it (the circle's tangent
points must lie on the facets): :func:`curvature_need`. The B-spline corner takes about 1.3 x
that (4 sin^2(theta / 2) / (6 b cos(theta / 2)) at the uniform corner); the report gives the fit's
peak curvature on each data span against the larger need of its two ends
(:func:`curvature_against_need`), for every fit.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import BSpline

from drakedeburr.path.edge_curve import (
    FACET_MAX_TURN,
    EdgeCurve,
    checked_loop,
    edge_curve_of_spline,
)

__all__ = ["is_polygon", "fit_polygon_curve", "curvature_need", "curvature_against_need",
           "loop_turns", "corner_deviation"]

#: the share of a facet next to a point that its control point may take (the rest keeps the
#: facet straight between the corners: 0.1 L at least)
_SHARE = 0.45
#: samples per corner region for the bound check
_SAMPLES = 32
#: the bound the samples are held to, as a share of b (the curve between samples)
_MARGIN = 0.98
#: the factor a corner's control distance shrinks by where the bound is not met, and the
#: rounds before it is left as it is (0.9^130 ~ 1e-6: on the corner)
_SHRINK = 0.9
_ROUNDS = 130


def loop_turns(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(turn (N,) at each point between its chords [rad], chord lengths (N,) [m]: chord i runs
    from point i to i + 1) of a closed polyline."""
    chord = np.roll(p, -1, axis=0) - p
    length = np.linalg.norm(chord, axis=1)
    unit = chord / np.maximum(length, 1e-300)[:, None]
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", np.roll(unit, 1, axis=0), unit), -1, 1))
    return turn, length


def is_polygon(p: np.ndarray) -> bool:
    """True when some point of the closed loop ``p`` turns by more than ``FACET_MAX_TURN``:
    a corner its points do not resolve as a curve (module doc)."""
    return bool(loop_turns(np.asarray(p, float))[0].max() > FACET_MAX_TURN)


def corner_deviation(curve: EdgeCurve, samples: int = 16) -> float:
    """The largest distance [m] of the fit from the data polyline on the spans beside the
    corners its points do not resolve (points turning more than ``FACET_MAX_TURN``: the two
    spans before and after each), each sample against its own span's segment (an upper bound
    of its distance from the polyline); 0 without such corners."""
    p = curve.p_data
    turn = loop_turns(p)[0]
    near = np.zeros(len(p), bool)
    for k in (-2, -1, 0, 1):  # span j runs from point j to j + 1
        near |= np.roll(turn > FACET_MAX_TURN, k)
    j = np.flatnonzero(near)
    if not len(j):
        return 0.0
    u0 = curve.u_data
    u1 = np.r_[u0[1:], 1.0]
    t = (np.arange(samples) + 0.5) / samples
    q = curve.position(u0[j, None] + t[None, :] * (u1 - u0)[j, None])
    return float(_to_segment(q, p[j, None], np.roll(p, -1, axis=0)[j, None]).max())


def curvature_need(p: np.ndarray, bound: float) -> np.ndarray:
    """(N,) the least curvature [1/m] with which a curve turns each point's corner passing
    the point within ``bound`` [m]: max((1 / cos(theta / 2) - 1) / b, 2 tan(theta / 2) / L_min)
    (module doc; theta capped at 179 deg)."""
    turn, length = loop_turns(np.asarray(p, float))
    half = 0.5 * np.minimum(turn, np.radians(179.0))
    l_min = np.minimum(length, np.roll(length, 1))
    return np.maximum((1.0 / np.cos(half) - 1.0) / bound, 2.0 * np.tan(half) / l_min)


def curvature_against_need(curve: EdgeCurve, bound: float, samples: int = 16) -> dict:
    """The fit's curvature against what the corners need (:func:`curvature_need` with
    ``bound``): ``{"kappa_need": the largest need [1/m], "kappa_need_ratio": the largest ratio,
    over the data spans, of the fit's peak curvature on the span to the larger need of its two
    ends, at least 1/m (a radius of 1 m, straighter than any window: on a straight facet the
    ratio is the fit's own curvature in 1/m)}``."""
    need = np.maximum(curvature_need(curve.p_data, bound), 1.0)
    u0 = curve.u_data
    u1 = np.r_[u0[1:], 1.0]
    t = (np.arange(samples + 1)) / samples
    k = curve.curvature(u0[:, None] + t[None, :] * (u1 - u0)[:, None]).max(axis=1)
    return {"kappa_need": float(need.max()),
            "kappa_need_ratio": float((k / np.maximum(need, np.roll(need, -1))).max())}


def _controls(p: np.ndarray, a: np.ndarray, s: np.ndarray, length: np.ndarray):
    """(control points (M, 3), their arc positions (M,) [m] from point 0): each point P_i, and
    on each facet i (P_i -> P_i+1) the points at a_i, 2 a_i, 4 a_i, ... from P_i and at
    a_i+1, 2 a_i+1, ... from P_i+1, each side up to the facet's middle (collinear: the facet
    stays straight; the knot intervals beside a corner are all a_i, as at a uniform corner,
    and grow by 2 at most towards the middle)."""
    unit = (np.roll(p, -1, axis=0) - p) / length[:, None]
    a_next = np.roll(a, -1)
    q, tau = [], []
    for i in range(len(p)):
        half = 0.5 * length[i]
        near = a[i] * 2.0 ** np.arange(int(np.ceil(np.log2(half / a[i]))) + 1)
        far = a_next[i] * 2.0 ** np.arange(int(np.ceil(np.log2(half / a_next[i]))) + 1)
        x = np.r_[0.0, near[near < half], length[i] - far[far < half][::-1]]
        q.append(p[i] + x[:, None] * unit[i])
        tau.append(s[i] + x)
    return np.concatenate(q), np.concatenate(tau)


def _spline(q: np.ndarray, tau: np.ndarray) -> BSpline:
    """The periodic cubic B-spline on [0, 1) with control point j's basis centred at
    ``tau[j]`` (increasing from 0, in [0, 1))."""
    m = len(q)
    i = np.arange(-3, m + 4)
    t = tau[np.mod(i, m)] + np.floor_divide(i, m)
    c = q[np.mod(np.arange(m + 3) - 1, m)]
    return BSpline(t, c, 3, extrapolate="periodic")


def _violations(spline: BSpline, p: np.ndarray, u_a, u_p, u_b, bound: float) -> np.ndarray:
    """(N,) bool: the curve on [A_i, B_i] leaves the facets i - 1, i by more than the bound, or
    passes point i farther than it at its parameter."""
    t = np.linspace(0.0, 1.0, _SAMPLES + 1)
    span = np.mod(u_b - u_a, 1.0)
    q = spline(np.mod(u_a[:, None] + t[None, :] * span[:, None], 1.0))
    prev, nxt = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
    d = np.minimum(_to_segment(q, prev[:, None], p[:, None]),
                   _to_segment(q, p[:, None], nxt[:, None])).max(axis=1)
    e = np.linalg.norm(spline(u_p) - p, axis=1)
    return np.maximum(d, e) > _MARGIN * bound


def _to_segment(q, a, b):
    ab = b - a
    t = np.clip(((q - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(q - (a + t[..., None] * ab), axis=-1)


def fit_polygon_curve(p: np.ndarray, bound: float, *, name: str = "edge") -> EdgeCurve:
    """The B-spline of the polygonal loop ``p`` (module doc): straight on its facets, turning
    at each point inside the corner, within ``bound`` [m] of the polyline and of every point.

    Raises:
        InputError: as :func:`drakedeburr.path.edge_curve.fit_edge_curve`.
    """
    p = checked_loop(p, name)
    turn, length = loop_turns(p)
    s = np.concatenate([[0.0], np.cumsum(length)])
    total = s[-1]
    share = _SHARE * np.minimum(length, np.roll(length, 1))
    a = np.minimum(share, _MARGIN * 3.0 * bound / np.maximum(np.sin(0.5 * turn), 1e-12))
    for _ in range(_ROUNDS):
        q, tau = _controls(p, a, s[:-1], length)
        spline = _spline(q, tau / total)
        u_p = s[:-1] / total
        bad = _violations(spline, p, np.mod(s[:-1] - a, total) / total, u_p,
                          (s[:-1] + a) / total, bound)
        if not bad.any():
            break
        a = np.where(bad, _SHRINK * a, a)
    return edge_curve_of_spline(spline, np.r_[s[:-1] / total, 1.0], p)
