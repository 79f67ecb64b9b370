"""EdgeCurve: a closed NURBS (periodic B-spline) fit of one window edge (source §1.1, eqs. 1-2).

The source fits a NURBS curve (eq. 1) through the equidistant "initial CL points" of a window
edge with accumulated chord-length parameterisation. A NURBS curve whose weights are all 1 *is*
a B-spline, and a fit through points has no reason to use other weights, so we use SciPy's
interpolating B-spline (``scipy.interpolate.make_interp_spline``) with periodic boundary
conditions. The source writes a clamped knot vector; on a closed loop that leaves a C0 seam at
the start point, so we use the periodic form (C2 everywhere, the seam is invisible).

Shape features (all SI, derivatives analytic from the spline):
    position C(u), unit tangent T(u), curvature kappa(u) = |C' x C''| / |C'|^3,
    arc length s(u), chord length l(u0, u1) = |C(u1) - C(u0)|,
    circle-approximated chord-height error (eq. 2): delta = R - sqrt(R^2 - (l/2)^2),
    and the true chord-height error: max distance of the arc C([u0, u1]) from the chord.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

from drakedeburr.errors import InputError
from drakedeburr.path.brent import minimize_bounded_batch

__all__ = ["EdgeCurve", "fit_edge_curve", "fit_faceted_curve", "facet_sagitta",
           "polygon_facets", "chord_parameters", "polyline_fit_report", "checked_loop",
           "edge_curve_of_spline"]

# samples per data span for the arc-length table (Gauss-Legendre, exact to ~1e-12 for cubics)
_GAUSS_ORDER = 8
# samples per segment for the true chord height before the local refinement
_CHORD_SAMPLES = 48
# Gauss-Legendre nodes and weights, computed once (numpy's leggauss solves an eigenproblem on
# every call: it was half of the CL planners' time)
_GL8 = np.polynomial.legendre.leggauss(_GAUSS_ORDER)
_GL16 = np.polynomial.legendre.leggauss(16)


def _norm(v: np.ndarray) -> np.ndarray:
    """|v| over the last axis: numpy's own ``linalg.norm(v, axis=-1)`` formula for real v
    (the same values), without its Python-level dispatch (called ~10^5 times per hub)."""
    return np.sqrt(np.add.reduce(v * v, axis=-1))


def _clip01(v):
    return np.minimum(np.maximum(v, 0.0), 1.0)  # = np.clip(v, 0, 1), a third of the overhead


def chord_parameters(p: np.ndarray) -> np.ndarray:
    """Accumulated chord-length parameters of a closed polyline.

    Args:
        p: (N, 3) points, first point not repeated.

    Returns:
        (N + 1,) parameters in [0, 1]; the last one (= 1) belongs to the closing point p[0].
    """
    d = np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(d)])
    return s / s[-1]


@dataclass(frozen=True, eq=False)
class EdgeCurve:
    """A closed, periodic cubic B-spline C(u), u in [0, 1), through the initial CL points.

    Attributes:
        spline: the periodic scipy BSpline, maps u -> (3,) point in the data frame [m].
        u_data: (N,) parameters of the fitted (initial) points, increasing from 0.
        p_data: (N, 3) the fitted points [m] (frame of the input, H for window edges).
        s_table: (K,) arc length [m] at the parameters ``u_table`` (monotone, s(1) = length).
        u_table: (K,) parameters of the arc-length table.
        length: total length of the closed curve [m].
        fit: how the curve was fitted, against the loop's facets (:mod:`.window_fit`), or {}.
    """

    spline: BSpline
    u_data: np.ndarray
    p_data: np.ndarray
    u_table: np.ndarray
    s_table: np.ndarray
    length: float
    fit: dict = field(default_factory=dict)

    # ----- evaluation ---------------------------------------------------------------------
    def position(self, u) -> np.ndarray:
        """C(u): (..., 3) points [m] for parameters u (any shape; wrapped into [0, 1))."""
        return self.spline(np.mod(u, 1.0))

    def derivative(self, u, order: int = 1) -> np.ndarray:
        """d^k C / du^k at u: (..., 3)."""
        return self.spline(np.mod(u, 1.0), nu=order)

    def tangent(self, u) -> np.ndarray:
        """Unit tangent T(u): (..., 3), in the direction of increasing u."""
        d1 = self.derivative(u, 1)
        return d1 / np.linalg.norm(d1, axis=-1, keepdims=True)

    def curvature(self, u) -> np.ndarray:
        """kappa(u) = |C' x C''| / |C'|^3 [1/m]; same shape as u."""
        d1 = self.derivative(u, 1)
        d2 = self.derivative(u, 2)
        return np.linalg.norm(np.cross(d1, d2), axis=-1) / np.linalg.norm(d1, axis=-1) ** 3

    # ----- arc length ---------------------------------------------------------------------
    def arc_length(self, u0, u1=None, *, s0=None) -> np.ndarray:
        """Arc length [m] from u0 to u1 going forward (wrapping through u = 1 if u1 < u0).

        With one argument: arc length from u = 0 to u (u in [0, 1]). ``s0``: the arc length
        from u = 0 to u0 if already known (``arc_length(u0 % 1)``), for repeated calls.
        """
        if u1 is None:
            return self._s(np.asarray(u0, float))
        u0 = np.asarray(u0, float)
        u1 = np.asarray(u1, float)
        s0 = self._s(np.mod(u0, 1.0)) if s0 is None else s0
        s = self._s(np.mod(u1, 1.0)) - s0
        s = np.where(s < 0, s + self.length, s)
        # a full turn (u1 = u0 + 1) is the whole length, not zero
        return np.where((u1 - u0) >= 1.0 - 1e-15, self.length, s)

    def _s(self, u: np.ndarray) -> np.ndarray:
        return self._s_and_speed(u)[0]

    def _s_and_speed(self, u: np.ndarray, speed_at: np.ndarray | None = None):
        """(s(u), |C'(speed_at)| or None): arc length exact within a span (Gauss-Legendre on
        the table span holding u); the speed at ``speed_at`` comes from the same spline call
        (pointwise evaluation: the values are those of separate calls)."""
        u = _clip01(u)
        i = np.minimum(np.maximum(np.searchsorted(self.u_table, u, side="right") - 1, 0),
                       len(self.u_table) - 2)
        a = self.u_table[i]
        x, w = _GL8
        h = (u - a)[..., None]
        t = a[..., None] + (x + 1.0) * 0.5 * h
        if speed_at is not None:
            t = np.concatenate([t, np.asarray(speed_at, float)[..., None]], axis=-1)
        speed = _norm(self.spline(t, nu=1))
        s = self.s_table[i] + 0.5 * (speed[..., :8] * w).sum(-1) * h[..., 0]
        return s, (None if speed_at is None else speed[..., 8])

    def u_from_arc(self, s) -> np.ndarray:
        """Parameter u at arc length s [m] from u = 0 (s wrapped into [0, length))."""
        s = np.mod(np.asarray(s, float), self.length)
        u = np.interp(s, self.s_table, self.u_table)
        for _ in range(4):  # Newton on s(u) - s = 0; ds/du = |C'(u)|
            s_u, speed = self._s_and_speed(u, speed_at=u)
            u = u - (s_u - s) / speed
            u = _clip01(u)
        return u

    # ----- chords -------------------------------------------------------------------------
    def chord_length(self, u0, u1) -> np.ndarray:
        """|C(u1) - C(u0)| [m]."""
        return _norm(self.position(u1) - self.position(u0))

    def mean_curvature(self, u0, u1) -> np.ndarray:
        """Mean curvature over the arc [u0, u1] (forward): turning angle / arc length [1/m].

        This is the curvature of the circle that turns as much as the arc does; its inverse is
        the "mean curvature radius R" of eq. (2).
        """
        u0 = np.atleast_1d(np.asarray(u0, float))
        u1 = np.atleast_1d(np.asarray(u1, float))
        u1 = np.where(u1 <= u0, u1 + 1.0, u1)
        x, w = _GL16
        t = u0[:, None] + (x + 1.0) * 0.5 * (u1 - u0)[:, None]
        d1 = self.derivative(t, 1)
        d2 = self.derivative(t, 2)
        speed = _norm(d1)
        kappa = _norm(np.cross(d1, d2)) / speed**3
        turn = 0.5 * (kappa * speed * w).sum(-1) * (u1 - u0)
        length = 0.5 * (speed * w).sum(-1) * (u1 - u0)
        return turn / np.maximum(length, 1e-300)

    def chord_height_circle(self, u0, u1) -> np.ndarray:
        """Chord-height error of eq. (2): delta = R - sqrt(R^2 - (l/2)^2) [m].

        R = 1 / mean curvature of the arc [u0, u1]. Where the chord is longer than the
        circle's diameter (l/2 >= R) the formula has no value; we return R + (l/2 - R),
        i.e. at least l/2, which always fails any sensible threshold.
        """
        l_half = 0.5 * np.atleast_1d(self.chord_length(u0, u1))
        kbar = self.mean_curvature(u0, u1)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(kbar > 0, 1.0 / kbar, np.inf)
            inside = l_half < r
            # R - sqrt(R^2 - h^2) = h^2 / (R + sqrt(R^2 - h^2)): stable for large R
            delta = np.where(inside, l_half**2 / (r + np.sqrt(np.maximum(r**2 - l_half**2, 0))),
                             l_half)
        return delta

    def _sampled(self, u0, u1, samples: int, index=None):
        """Arcs forward from u0 to u1 sampled at t = linspace(0, 1, samples + 1) (or the
        entries ``index`` of it): (u0 (M,), u1 (M,) unwrapped, chord ends a, b (M, 3),
        sample parameters (M, S), their distances from the chord segment (M, S))."""
        u0 = np.atleast_1d(np.asarray(u0, float))
        u1 = np.atleast_1d(np.asarray(u1, float))
        u1 = np.where(u1 <= u0, u1 + 1.0, u1)
        a = self.position(u0)
        b = self.position(u1)
        t = np.linspace(0.0, 1.0, samples + 1)
        if index is not None:
            t = t[index]
        uu = u0[:, None] + t * (u1 - u0)[:, None]
        return u0, u1, a, b, uu, _dist_to_segment(self.position(uu), a[:, None, :],
                                                  b[:, None, :])

    def chord_height_at(self, u0, u1, t: np.ndarray) -> np.ndarray:
        """Sampled chord height, (M,): max distance from the chord of the arc points at
        u0 + t (u1 - u0) for the rows t (M, S) of fractions (one sample set per arc; with
        t = linspace(0, 1, samples + 1) in every row this is ``chord_height(u0, u1, samples,
        refine=False)``, value for value)."""
        u0 = np.atleast_1d(np.asarray(u0, float))
        u1 = np.atleast_1d(np.asarray(u1, float))
        u0 = np.broadcast_to(u0, u1.shape)
        u1 = np.where(u1 <= u0, u1 + 1.0, u1)
        a = self.position(u0)
        b = self.position(u1)
        uu = u0[:, None] + t * (u1 - u0)[:, None]
        return _dist_to_segment(self.position(uu), a[:, None, :], b[:, None, :]).max(axis=1)

    def sampled_chord_height_lower_bound(self, u0, u1, samples: int, every: int = 8):
        """A lower bound of ``chord_height(u0, u1, samples, refine=False)``, (M,): the same
        distances at every ``every``-th sample only (identical values: the same parameters
        and arithmetic), a cheap first test for arcs that fail a threshold."""
        return self._sampled(u0, u1, samples, slice(every // 2, samples, every))[5].max(axis=1)

    def chord_height(self, u0, u1, samples: int = _CHORD_SAMPLES, refine: bool = True):
        """True chord-height error: max distance of the arc C([u0, u1]) from the chord [m].

        Measured on the fitted curve: dense samples, then a bounded scalar search around the
        worst sample. Distance is to the chord *segment*.

        Args:
            u0, u1: scalars or (M,) arrays; the arc runs forward from u0 to u1 (wrapping).
            samples: samples per arc before the refinement.
            refine: run the local 1-D maximisation (accurate to ~1e-12 m).

        Returns:
            (M,) chord heights [m].
        """
        u0, u1, a, b, uu, d = self._sampled(u0, u1, samples)
        if not refine:
            return d.max(axis=1)
        k = np.argmax(d, axis=1)
        rows = np.arange(len(u0))
        d_best = d[rows, k]
        lo = uu[rows, np.maximum(k - 1, 0)]
        hi = uu[rows, np.minimum(k + 1, samples)]
        out = d_best.copy()
        go = np.flatnonzero(hi - lo > 0)
        if len(go):
            a_g, b_g = a[go], b[go]
            f_min = minimize_bounded_batch(
                lambda x: -_dist_to_segment(self.position(x), a_g, b_g), lo[go], hi[go],
                1e-13 * (1 + hi[go]))
            out[go] = np.maximum(d_best[go], -f_min)
        return out


def _dist_to_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    L2 = np.maximum((ab * ab).sum(-1, keepdims=True), 1e-300)
    t = _clip01(((p - a) * ab).sum(-1, keepdims=True) / L2)
    return _norm(p - (a + t * ab))


def checked_loop(p: np.ndarray, name: str = "edge") -> np.ndarray:
    """The (N, 3) points of a closed loop as every fit takes them (N >= 5, finite, no repeated
    consecutive points, a repeated closing point dropped). Raises InputError otherwise."""
    p = np.asarray(p, float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 5:
        raise InputError(f"{name}: need (N >= 5, 3) loop points, got shape {p.shape}")
    if not np.isfinite(p).all():
        bad = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
        raise InputError(f"{name}: point {bad} is not finite: {p[bad]}")
    if np.linalg.norm(p[0] - p[-1]) < 1e-12:
        p = p[:-1]  # tolerate a repeated closing point
    seg = np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1)
    if (seg < 1e-9 * seg.sum()).any():
        bad = int(np.flatnonzero(seg < 1e-9 * seg.sum())[0])
        raise InputError(f"{name}: points {bad} and {(bad + 1) % len(p)} coincide")
    return p


def edge_curve_of_spline(spline: BSpline, u: np.ndarray, p: np.ndarray) -> EdgeCurve:
    """The EdgeCurve of a periodic cubic spline on [0, 1) with the (N + 1,) data parameters
    ``u`` (the last one, 1, the closing point's) of the (N, 3) points ``p``: the arc-length
    table on the data parameters (Gauss-Legendre per span)."""
    x, w = _GL8
    t = u[:-1, None] + (x + 1.0) * 0.5 * np.diff(u)[:, None]
    speed = np.linalg.norm(spline(t, nu=1), axis=-1)
    ds = 0.5 * (speed * w).sum(-1) * np.diff(u)
    s_table = np.concatenate([[0.0], np.cumsum(ds)])
    return EdgeCurve(spline=spline, u_data=u[:-1], p_data=p, u_table=u, s_table=s_table,
                     length=float(s_table[-1]))


def fit_edge_curve(p: np.ndarray, *, name: str = "edge") -> EdgeCurve:
    """Fit a closed cubic B-spline (NURBS with unit weights) through a closed polyline.

    Accumulated chord-length parameterisation, periodic end conditions (the loop is closed).

    Args:
        p: (N, 3) points of the closed loop [m], in order, first point not repeated; N >= 5.
        name: for error messages (e.g. "window 2").

    Returns:
        The EdgeCurve, with ``u_data`` the parameters of the points.

    Raises:
        InputError: too few points, non-finite values, or repeated consecutive points.
    """
    p = checked_loop(p, name)
    u = chord_parameters(p)
    try:
        spline = make_interp_spline(u, np.vstack([p, p[:1]]), k=3, bc_type="periodic")
    except (np.linalg.LinAlgError, ValueError) as exc:  # degenerate loop: named, not a crash
        raise InputError(f"{name}: the periodic B-spline fit of its {len(p)} points failed "
                         f"({type(exc).__name__}: {str(exc)[:160]})") from exc
    return edge_curve_of_spline(spline, u, p)


#: the smallest expected deviation of a data point from the true curve [m] (a point on a
#: straight facet, or at a corner: the mesh's own vertex precision)
FACET_POINT_SIGMA = 1e-6
#: the largest turn [rad] at a corner of a tessellated smooth curve: a mesher cuts a curve into
#: at least 12 chords a full turn (30 deg a corner; STL exports' angular tolerances are 0.1-0.5
#: rad). A loop turning more at one point has a real corner there (a window's loop turning down
#: a spoke flank), which the smoothing fit must keep, not cut by a "sagitta" of its facets
FACET_MAX_TURN = np.radians(32.0)
#: a straight facet spans at least this many data spacings (shorter ones are not resolved: the
#: points near a corner are the corner; see :mod:`drakedeburr.path.window_fit`)
FACET_MIN_SPACINGS = 3.0


def _turns(p: np.ndarray):
    """(turn (N,) at each point between its chords [rad], arc positions s (N + 1,), median
    chord [m]) of a closed polyline."""
    chord = np.roll(p, -1, axis=0) - p
    length = _norm(chord)
    unit = chord / np.maximum(length, 1e-300)[:, None]
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", np.roll(unit, 1, axis=0), unit), -1, 1))
    return turn, np.concatenate([[0.0], np.cumsum(length)]), float(np.median(length))


def polygon_facets(p: np.ndarray, *, corner_angle: float = np.radians(1.0)) -> dict:
    """The straight facets of a closed polyline: stretches between two tessellation corners
    whose points turn, all together, by less than ``corner_angle`` (a chord of the mesh).

    A tessellation corner is a point turning by more than ``corner_angle`` (or two neighbours:
    equal-arc resampling cuts a vertex into two turns at neighbouring points), by at
    most ``FACET_MAX_TURN`` in all; a facet is at least ``FACET_MIN_SPACINGS`` spacings long.
    A longer run of turning points is a densely sampled curve (a fillet: its points lie on the
    curve), a sharper turn a real corner; the stretches beside them are not facets.

    Returns:
        ``{"corner_pos": (K,) arc positions [m], "corner_turn": (K,) [rad], "facet": (K,)
        lengths [m] (facet k from corner k to k + 1), "straight": (K,) bool, "s": (N + 1,)
        arc positions of the points [m], "length": loop length [m], "spacing": median data
        spacing [m]}``.
    """
    turn, s, spacing = _turns(np.asarray(p, float))
    pos, tot, i0, i1 = _corner_runs(turn, s, corner_angle, 1.5 * spacing)
    total = float(s[-1])
    if not len(pos):
        return {"corner_pos": pos, "corner_turn": tot, "facet": np.zeros(0), "s": s,
                "straight": np.zeros(0, bool), "length": total, "spacing": spacing}
    n = len(turn)
    span = np.mod(s[i1] - s[i0], total)
    # the points next to a run carry what is left of a vertex cut unevenly by the resampling
    tot = tot + turn[(i0 - 1) % n] + turn[(i1 + 1) % n]
    tess = (span <= 1.5 * spacing) & (tot <= FACET_MAX_TURN)
    facet = np.diff(np.r_[pos, pos[0] + total])
    # turn of the points inside facet k (after run k's last + 1, before run k + 1's first - 1)
    cs = np.concatenate([[0.0], np.cumsum(np.r_[turn, turn])])
    nxt0 = np.roll(i0, -1)
    nxt0 = np.where(nxt0 <= i1, nxt0 + n, nxt0)
    inner = np.maximum(cs[np.maximum(nxt0 - 1, i1 + 2)] - cs[i1 + 2], 0.0)
    straight = (tess & np.roll(tess, -1) & (inner <= corner_angle) & (len(pos) > 1)
                & (facet >= FACET_MIN_SPACINGS * spacing))
    return {"corner_pos": pos, "corner_turn": tot, "facet": facet, "straight": straight,
            "s": s, "length": total, "spacing": spacing}


def facet_sagitta(p: np.ndarray, *, corner_angle: float = np.radians(1.0)) -> dict:
    """How far the points of a polygonal loop (a low-poly mesh's edge, resampled along its
    facets) can lie from the smooth curve the facets were cut from.

    A mesher cuts a curve into chords within a chordal tolerance: a facet of length L on a
    curve of curvature k lies up to k L^2 / 8 (its sagitta) off the curve, at its middle, and
    on it at its corners. The curvature a corner between two straight facets implies is its
    turn over its shorter facet (:func:`polygon_facets` finds the straight facets), so a
    facet's sagitta is at most ``turn * L_short / 8`` of either of its corners (the smaller: a
    long straight facet beside a tight corner is straight, as a chord-tolerance mesher makes
    it; a facet beside a curve or a real corner is a designed straight: 0), and a point's
    expected deviation is that sagitta times ``4 x (1 - x)`` at the fraction x along its
    facet (at least ``FACET_POINT_SIGMA``). Points that are on no straight facet (a densely
    sampled curve, a real corner) are on the curve: ``FACET_POINT_SIGMA``.

    Returns:
        ``{"sigma": (N,) [m], "facets": straight facets, "facet_median": their median length
        [m] (0 without), "facet_share": their share of the loop length, "sagitta_max": [m],
        "kappa_facets": the largest curvature the facets imply, corner turn over the mean of
        its two facets [1/m] (0 without)}``.
    """
    p = np.asarray(p, float)
    f = polygon_facets(p, corner_angle=corner_angle)
    s = f["s"]
    straight = f["straight"]
    if not straight.any():
        return {"sigma": np.full(len(p), FACET_POINT_SIGMA), "facets": 0, "facet_median": 0.0,
                "facet_share": 0.0, "sagitta_max": 0.0, "kappa_facets": 0.0}
    pos, tot, facet, total = f["corner_pos"], f["corner_turn"], f["facet"], f["length"]
    # facet k runs corner k -> k + 1; only a corner between two straight facets implies a
    # curvature (a facet beside a curve or a real corner is a designed straight: sagitta 0)
    both = straight & np.roll(straight, 1)  # corner k joins facets k - 1 and k
    corner_sag = np.where(both, tot * np.minimum(facet, np.roll(facet, 1)) / 8.0, 0.0)
    sag = np.where(straight, np.minimum(corner_sag, np.roll(corner_sag, -1)), 0.0)
    k = (np.searchsorted(pos, s[:-1], side="right") - 1) % len(pos)
    x = np.mod(s[:-1] - pos[k], total) / facet[k]
    sigma = np.maximum(4.0 * x * (1.0 - x) * sag[k], FACET_POINT_SIGMA)
    # corners between two straight facets: their turn over the mean facet
    k_implied = tot / np.maximum(0.5 * (facet + np.roll(facet, 1)), 1e-300)
    return {"sigma": sigma, "facets": int(straight.sum()),
            "facet_median": float(np.median(facet[straight])),
            "facet_share": float(facet[straight].sum() / total),
            "sagitta_max": float(sag.max()),
            "kappa_facets": float(k_implied[both].max()) if both.any() else 0.0}


def fit_faceted_curve(p: np.ndarray, *, name: str = "edge",
                      corner_angle: float = np.radians(1.0)) -> EdgeCurve:
    """A closed cubic B-spline that smooths a polygonal loop within its facets' chord error
    (issue 42: the interpolating fit of a low-poly mesh's edge bends at every facet corner,
    6-26 x the curvature the facets imply, :func:`polyline_fit_report`).

    scipy's ``make_splprep`` (periodic, chord-length parameters) with weights 1 / sigma, sigma
    each point's expected deviation from the true curve (:func:`facet_sagitta`), and the
    smoothing factor s = N: the fit stays within about one sigma of the points on average,
    on the corners and on straight facets (sigma = 1 um) and free by up to the sagitta in the
    middle of a curved facet (a bound on the sum: one facet of a real mesh loop took 1.4 x its
    sagitta, tests/test_window_fit.py). A loop without facets (a dense smooth edge) is fitted
    within 1 um: practically the interpolating fit.

    Raises:
        InputError: as :func:`fit_edge_curve`.
    """
    from scipy.interpolate import make_splprep

    p = checked_loop(p, name)
    u = chord_parameters(p)
    sigma = facet_sagitta(p, corner_angle=corner_angle)["sigma"]
    w = 1.0 / np.r_[sigma, sigma[:1]]
    try:
        fit, _ = make_splprep(np.vstack([p, p[:1]]).T, u=u, w=w, s=float(len(w)),
                              bc_type="periodic")
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise InputError(f"{name}: the smoothing B-spline fit of its {len(p)} points failed "
                         f"({type(exc).__name__}: {str(exc)[:160]})") from exc
    spline = BSpline(fit.t, np.asarray(fit.c), fit.k, extrapolate="periodic")
    return edge_curve_of_spline(spline, u, p)


def _corner_runs(turn: np.ndarray, s: np.ndarray, angle: float, merge: float):
    """(arc positions (K,), turns (K,), first (K,) and last (K,) point index) of a closed
    polyline's corners: points turning more than ``angle``, runs of them within ``merge`` of
    each other joined (turn summed, position turn-weighted), in loop order."""
    idx = np.flatnonzero(turn > angle)
    if not len(idx):
        empty = np.zeros(0, int)
        return np.zeros(0), np.zeros(0), empty, empty
    L = s[-1]
    groups = [[idx[0]]]
    for i in idx[1:]:
        (groups[-1].append(i) if s[i] - s[groups[-1][-1]] <= merge else groups.append([i]))
    if len(groups) > 1 and s[groups[0][0]] + L - s[groups[-1][-1]] <= merge:
        groups[0] = groups.pop() + groups[0]
    pos, tot = [], []
    for g in groups:
        g = np.asarray(g)
        sg = s[g] - np.where(s[g] > s[g[-1]], L, 0.0)  # a group over the seam: unwrapped
        pos.append(float(np.average(sg, weights=turn[g])) % L)
        tot.append(float(turn[g].sum()))
    order = np.argsort(pos)
    first = np.array([g[0] for g in groups])[order]
    last = np.array([g[-1] for g in groups])[order]
    return np.asarray(pos)[order], np.asarray(tot)[order], first, last


def polyline_fit_report(curve: EdgeCurve, *, corner_angle: float = np.radians(1.0),
                        samples: int = 16) -> dict:
    """How the fit follows a polygonal loop (issue 42: a low-poly mesh's edge is a polygon of
    facets): what the spline does between and across its data points, against the facets.

    The data polyline is split into facets at its corners (a turn of more than
    ``corner_angle`` between consecutive chords; collinear points inside a facet are one
    facet; turns closer than 2.5 data spacings are one corner: equal-arc resampling cuts a
    corner into two). Figures, SI:

    * ``facet_median``, ``facet_min`` [m]: facet lengths; ``spacing`` [m]: median data spacing;
    * ``deviation_max`` [m]: largest distance of C(u) from the polyline (``samples`` per data
      span, and at each point's parameter) - the fit's own chord error against the facets;
      ``deviation_per_facet`` its ratio to ``facet_median``;
    * ``kappa_max`` [1/m]: the fit's largest curvature (at the samples);
      ``kappa_polyline`` [1/m]: the polyline's largest corner turn over the mean of its two
      facets (the curvature the facets themselves imply); ``kappa_ratio`` = kappa_max /
      kappa_polyline;
    * ``inflections``: sign changes of the curvature about the loop's mean plane normal where
      the polyline itself turns only one way (0 on a convex polygon if the fit invents no
      wiggles); ``facets``: facet count.
    """
    p = curve.p_data
    turn, s, spacing = _turns(p)
    unit = np.roll(p, -1, axis=0) - p
    corners, turns = _corner_runs(turn, s, corner_angle, 2.5 * spacing)[:2]
    if len(corners) < 3:
        corners, turns = s[:-1], turn
    facet = np.diff(np.r_[corners, corners[0] + s[-1]])
    # the polyline's own curvature: corner turn over the mean of its two facets
    k_poly = turns / np.maximum(0.5 * (facet + np.roll(facet, 1)), 1e-300)
    # the fit between its data points
    t = (np.arange(samples) + 0.5) / samples
    u0 = curve.u_data
    u1 = np.r_[u0[1:], 1.0]
    uu = (u0[:, None] + t[None, :] * (u1 - u0)[:, None]).ravel()
    q = curve.position(uu)
    a = np.repeat(p, samples, axis=0)
    b = np.repeat(np.roll(p, -1, axis=0), samples, axis=0)
    dev = _dist_to_segment(q, a, b)
    # and at the points' own parameters, against the two segments beside each point (where a
    # fit that cuts a corner, path.polygon_fit, stands farthest from the polyline)
    at = curve.position(u0)
    dev0 = np.minimum(_dist_to_segment(at, np.roll(p, 1, axis=0), p),
                      _dist_to_segment(at, p, np.roll(p, -1, axis=0)))
    d1, d2 = curve.derivative(uu, 1), curve.derivative(uu, 2)
    c = p.mean(axis=0)
    normal = np.linalg.svd(p - c, full_matrices=False)[2][2]
    k_signed = (np.cross(d1, d2) @ normal) / _norm(d1) ** 3
    k_abs = _norm(np.cross(d1, d2)) / _norm(d1) ** 3
    poly_sign = np.sign(np.cross(np.roll(unit, 1, axis=0), unit) @ normal)[turn > corner_angle]
    one_way = bool(np.all(poly_sign >= 0) or np.all(poly_sign <= 0))
    sgn = np.sign(k_signed[np.abs(k_signed) > 1e-9])
    flips = int(np.count_nonzero(sgn != np.roll(sgn, 1))) if one_way and len(sgn) else 0
    kp = float(k_poly.max())
    return {"facets": int(len(corners)), "facet_median": float(np.median(facet)),
            "facet_min": float(facet.min()), "spacing": spacing,
            "deviation_max": float(max(dev.max(), dev0.max())),
            "deviation_per_facet": float(max(dev.max(), dev0.max()) / np.median(facet)),
            "kappa_max": float(k_abs.max()), "kappa_polyline": kp,
            "kappa_ratio": float(k_abs.max() / kp) if kp > 0 else float("inf"),
            "inflections": flips}
