"""The edge curve of one window as the pipeline fits it: the interpolating NURBS of a smooth
loop, the smoothing fit of a faceted one, chosen by the loop's own geometry (issue 42 item 3:
the NURBS fit of a polygonal loop does not invent wiggles; chord error and curvature are
reported against the facet size).

**Which fit.** A loop from a low-poly mesh (the face-side line of a tessellated edge) is a
polygon: straight facets of length L joined at corners turning by theta, the chords of the
designed curve, whose curvature is about theta / L. The interpolating spline through its
points (spacing h) turns each corner's theta within about one spacing, at a curvature of
about theta / h; the CL planner places its points by that curvature and the orientation stage
turns the tool with the curve's frame, so both would follow every facet corner. The loop is
therefore fitted with :func:`~drakedeburr.path.edge_curve.fit_faceted_curve` (free by up to
each facet's sagitta in the middle of a facet, through the corners) when

* its points resolve facets of at least ``FACET_MIN_SPACINGS`` data spacings (L >= 3 h: the
  interpolant's corner curvature is then at least 3 x the facets') joined at a corner of a
  tessellation (at most ``FACET_MAX_TURN``, :func:`~drakedeburr.path.edge_curve.polygon_facets`),
* and some facet's sagitta exceeds the CL chord-height tolerance delta the path is planned
  with: that facet is then longer than the chords the CL planner lays on the designed curve
  (a chord of sagitta delta on curvature k is sqrt(8 delta / k) long, the facet sqrt(8 s / k)),
  so the CL points would resolve, and follow, its corners. Smaller facets lie within the path's
  own tolerance of the polygon and are spanned by its chords (the bundled hubs' ground truth
  is a polyline through the generator's mesh vertices: facets of 0.2-0.5 mm, sagitta <= 2.1
  um).

Any other loop (a densely sampled designed curve, an exact CAD edge) keeps the interpolating
fit, spline for spline: its plans do not change. The choice is made from the points, never
from the source's name.

**Polygons.** Either fit passes through a point that turns by more than ``FACET_MAX_TURN``
(no sample of a smooth curve: a corner the points do not resolve), and overshoots it. When the
fit so leaves the polyline, on the spans beside such a corner, by more than the bound it must
keep to it (the held bound below; without one the CL chord bound ``chord_tolerance``), the
loop is fitted as the polygon it is instead (:mod:`drakedeburr.path.polygon_fit`: straight on
its facets, turning inside each corner, within the bound of the polyline and of every point):
the low-poly rims of issue 42 (corners of 55-124 deg at 2 mm; the interpolating fit stood
0.17-0.30 mm off their polylines).

**Held to the loop's points.** The smoothing fit estimates the designed curve the facets were
cut from: free by up to a facet's sagitta in its middle (0.16-0.21 mm on the audibot rim's
8-9 mm facets). But the cut is judged against the loop's points themselves (verify's
``cl_chord_error``: the edge samples' distance from each CL chord <= delta_max), and a CL
chord is planned within ``chord_tolerance`` of the *fit*: an edge sample q lies from the chord
at most |q - C(u_q)| (its distance from the fit at its own parameter) + the chord's height on
the fit. The fit is therefore held within ``edge_tolerance - chord_tolerance`` of every point
(0.12 - 0.03 = 0.09 mm for the pipeline's CL targets) when it is not already: each point's
offset d to the smoothing fit is saturated to ``bound * tanh(|d| / bound)`` - the same where
it is small (beside the corners, where the designed curve meets the polygon: the curve keeps
its tangents there), below the bound in the middle of a long facet, one concave profile a
facet - and the interpolating spline is laid through the points so moved. It still follows no
facet corner: on rounded low-poly windows its curvature changes sign no more often than the
free fit's and 5-20 x less often than the interpolating fit's (tests/test_window_fit_bound.py);
its peak curvature rises (a corner of turn theta held within b bends at a radius of about
b / (1 - cos(theta / 2))), and beside a real (designed) corner it rings more than the free fit
(measured 48 vs 34 sign changes on a test window: the cubic through a 90 deg corner). A
planner that spends the whole ``edge_tolerance`` against the fit (``cl`` and ``orient``
compare the planners at delta_max on the curve itself) leaves nothing for the fit: it keeps
the designed-curve estimate, and its chord error against the points is reported.

**What is reported** (``EdgeCurve.fit``, copied into every ClPath's ``metrics["edge_fit"]``
and the ``cl`` table): the fit used ("faceted", "polygon" or "interpolating"), the facets
(count, median length, share of the loop, largest sagitta), the chord error of the fit
against the polygon (largest distance of the curve from the data polyline), the fit's
largest curvature against the largest curvature the facets imply (corner turn over the mean
of its two facets) and the inflections the fit adds; the bound the fit was held to, the
largest distance of a point from the fit at its parameter and whether the fit was held (one
pass: the offsets saturated once); the fit's peak curvature on each data span against the
curvature its corners need within the bound (``kappa_need``, ``kappa_need_ratio``:
:func:`~drakedeburr.path.polygon_fit.curvature_need`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.path.edge_curve import (
    FACET_POINT_SIGMA,
    EdgeCurve,
    facet_sagitta,
    fit_edge_curve,
    fit_faceted_curve,
    polyline_fit_report,
)
from drakedeburr.path.polygon_fit import (
    corner_deviation,
    curvature_against_need,
    fit_polygon_curve,
)

__all__ = ["fit_window_edge", "edge_fit_figures", "is_faceted", "point_errors",
           "bounded_faceted_fit"]


def is_faceted(facets: dict, chord_tolerance: float) -> bool:
    """True when :func:`facet_sagitta`'s figures show a tessellation corner between two
    straight facets that the points resolve with a sagitta above ``chord_tolerance`` [m], the
    CL chord-height tolerance (module doc)."""
    return facets["sagitta_max"] > max(chord_tolerance, FACET_POINT_SIGMA)


def point_errors(curve: EdgeCurve) -> np.ndarray:
    """(N,) distance of each fitted point from the fit at its own parameter, |p_i - C(u_i)|
    [m] (at least its distance from the curve)."""
    return np.linalg.norm(curve.position(curve.u_data) - curve.p_data, axis=1)


def edge_fit_figures(curve: EdgeCurve, facets: dict, fit: str, bound=None,
                     held: bool = False, *, need_bound: float | None = None) -> dict:
    """The report of one window's fit (module doc), SI: ``fit`` ("faceted", "polygon" or
    "interpolating"), ``facets``, ``facet_median_m``, ``facet_share``, ``sagitta_max_m``,
    ``chord_error_m`` (fit against the data polyline), ``point_error_m`` (the largest
    :func:`point_errors`), ``point_bound_m`` (the bound the fit was held to, None: none),
    ``held`` (the fit was moved to meet it), ``kappa_max`` and ``kappa_facets`` [1/m],
    ``kappa_ratio`` (kappa_max / kappa_facets, None without facet corners), ``inflections``;
    with ``need_bound`` [m] also ``kappa_need`` [1/m] and ``kappa_need_ratio``
    (:func:`~drakedeburr.path.polygon_fit.curvature_against_need`: the fit's peak curvature on
    each data span against what its corners need within ``need_bound``)."""
    rep = polyline_fit_report(curve)
    kf = facets["kappa_facets"]
    out = {"fit": fit, "facets": facets["facets"], "facet_median_m": facets["facet_median"],
           "facet_share": facets["facet_share"], "sagitta_max_m": facets["sagitta_max"],
           "chord_error_m": rep["deviation_max"],
           "point_error_m": float(point_errors(curve).max()), "point_bound_m": bound,
           "held": bool(held), "kappa_max": rep["kappa_max"],
           "kappa_facets": kf, "kappa_ratio": rep["kappa_max"] / kf if kf > 0 else None,
           "inflections": rep["inflections"]}
    if need_bound is not None:
        out.update(curvature_against_need(curve, need_bound))
    return out


def bounded_faceted_fit(p: np.ndarray, bound: float | None, *,
                        name: str = "edge") -> tuple[EdgeCurve, bool]:
    """(curve, held): :func:`fit_faceted_curve` of the loop ``p``, held within ``bound`` [m]
    of every point (module doc; None: not held). ``held`` is True when the fit was moved.

    Each point's offset d to the smoothing fit is saturated to ``bound * tanh(|d| / bound)``
    (the same offset where it is small, below the bound where it is not) and the interpolating
    fit is laid through the points so moved."""
    curve = fit_faceted_curve(p, name=name)
    d = curve.position(curve.u_data) - curve.p_data
    r = np.linalg.norm(d, axis=1)
    if bound is None or r.max() <= bound:
        return curve, False
    scale = bound * np.tanh(r / bound) / np.maximum(r, 1e-300)
    moved = fit_edge_curve(curve.p_data + d * scale[:, None], name=name)
    return replace(moved, p_data=curve.p_data), True


def fit_window_edge(p: np.ndarray, *, chord_tolerance: float,
                    edge_tolerance: float | None = ProcessParameters.delta_max,
                    name: str = "edge") -> EdgeCurve:
    """The window edge's NURBS fit (module doc): :func:`fit_faceted_curve` for a faceted
    loop (held within ``edge_tolerance - chord_tolerance`` of the points), :func:`fit_edge_curve`
    otherwise, with the figures in ``EdgeCurve.fit``.

    Args:
        p: (N, 3) loop points [m].
        chord_tolerance: the CL chord-height tolerance the path is planned with [m]
            (``PlannerParams.delta_max``): facets of a smaller sagitta are not smoothed.
        edge_tolerance: the CL chords' height bound against the points themselves [m]
            (verify's ``cl_chord_error``: ``ProcessParameters.delta_max``); None, or not above
            ``chord_tolerance``: the fit is not held to the points (module doc).
        name: for error messages.

    Raises:
        InputError: as :func:`fit_edge_curve`.
    """
    facets = facet_sagitta(np.asarray(p, float))
    bound, held = None, False
    if edge_tolerance is not None and edge_tolerance - chord_tolerance > FACET_POINT_SIGMA:
        bound = float(edge_tolerance - chord_tolerance)
    if is_faceted(facets, chord_tolerance):
        (curve, held), fit = bounded_faceted_fit(p, bound, name=name), "faceted"
    else:
        curve, fit = fit_edge_curve(p, name=name), "interpolating"
    # the bound the fit must keep to the polyline: the held bound, else the CL chord bound
    tube = bound if bound is not None else float(chord_tolerance)
    if corner_deviation(curve) > tube:
        curve, fit, held = fit_polygon_curve(curve.p_data, tube, name=name), "polygon", True
        bound = tube
    return replace(curve, fit=edge_fit_figures(curve, facets, fit, bound, held,
                                               need_bound=tube))
