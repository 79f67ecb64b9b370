"""drakedeburr.path.polygon_fit (issue 42 item 3): a low-poly window loop like those of the
dbw mkz13 and mondeo rims - straight facets joined at corners of 45-90 deg, resampled every
2 mm as ``cl`` does - is fitted as the polygon it is, within the CL chord bound of the
polyline and of every point, straight on its facets, turning at each corner with no more
curvature than the corner needs (x 2.5) and changing direction no more often than the
polyline. Everything re-measured here with own code: point-to-segment distances over all
segments, curvature from the spline's derivatives, the circle a corner needs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import drakedeburr.path.polygon_fit as mut
from drakedeburr.hub.extract import resample_loop
from drakedeburr.path.edge_curve import fit_edge_curve
from drakedeburr.path.window_fit import fit_window_edge

U = np.linspace(0.0, 1.0, 60000, endpoint=False)
CL_DELTA = 0.03e-3  # the pipeline's CL chord height against the fit (plan.tool_paths)
DELTA = 0.12e-3  # ProcessParameters.delta_max, the `cl` command's chord tolerance
#: (chord tolerance, edge tolerance, the bound the fit is held to): the pipeline, `cl`
MODES = [(CL_DELTA, DELTA, DELTA - CL_DELTA), (DELTA, DELTA, DELTA)]


def _tilted(xy: np.ndarray) -> np.ndarray:
    """Plan points on a plane tilted 20 deg about X, 10 mm up (a window is not in z = 0)."""
    a = np.radians(20.0)
    return np.c_[xy[:, 0], xy[:, 1] * np.cos(a), 0.01 + xy[:, 1] * np.sin(a)]


def _low_poly_window() -> np.ndarray:
    """The mesh vertices of a 70 x 40 mm window, the long sides cut into collinear facets of
    unequal length (7-16 mm), the corners low-poly: one 90 deg facet corner, one radius-6 mm
    corner in 2 facets (45 deg each), one radius-5 mm corner in 3 (30 deg), one radius-4 mm
    corner in 1 chamfer facet (2 x 45 deg): 27 facets."""
    W, H = 0.035, 0.02
    pts = [[-W, -H], [-W + 0.016, -H], [-W + 0.025, -H], [-W + 0.041, -H], [-W + 0.048, -H],
           [W - 0.006, -H]]

    def arc(cx, cy, r, a0, k):
        return [[cx + r * np.cos(a0 + j * np.pi / 2 / k), cy + r * np.sin(a0 + j * np.pi / 2 / k)]
                for j in range(k + 1)]

    pts += arc(W - 0.006, -H + 0.006, 0.006, -np.pi / 2, 2)
    pts += [[W, -H + 0.017], [W, H - 0.005]]
    pts += arc(W - 0.005, H - 0.005, 0.005, 0.0, 3)
    pts += [[W - 0.019, H], [W - 0.030, H], [W - 0.043, H], [-W + 0.011, H], [-W + 0.004, H]]
    pts += [[-W, H - 0.004], [-W, 0.004], [-W, -0.007]]
    return _tilted(np.asarray(pts))


def _regular_polygon(n: int, r: float) -> np.ndarray:
    a = 2 * np.pi * np.arange(n) / n + 0.1
    return _tilted(np.c_[r * np.cos(a), r * np.sin(a)])


def _distance_to_polyline(q: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(M,) distance of each q from the closed polyline p: own point-to-segment, all segments."""
    A, B = p, np.roll(p, -1, axis=0)
    out = np.full(len(q), np.inf)
    for a, b in zip(A, B, strict=True):
        t = np.clip((q - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        out = np.minimum(out, np.linalg.norm(q - (a + t[:, None] * (b - a)), axis=1))
    return out


def _normal(p: np.ndarray) -> np.ndarray:
    return np.linalg.svd(p - p.mean(axis=0), full_matrices=False)[2][2]


def _signed_kappa(curve, u, n) -> np.ndarray:
    d1, d2 = curve.spline(u, nu=1), curve.spline(u, nu=2)
    return np.cross(d1, d2) @ n / np.linalg.norm(d1, axis=1) ** 3


def _flips(k: np.ndarray) -> int:
    s = np.sign(k[np.abs(k) > 1.0])  # |kappa| > 1/m: a straight facet's round-off aside
    return int(np.count_nonzero(s != np.roll(s, 1)))


def _corner_need(p: np.ndarray, b: float) -> np.ndarray:
    """(N,) own: the curvature of the circle through corner i that passes the point within b,
    R (1 / cos(theta / 2) - 1) = b, and whose tangent points fit on the shorter facet."""
    c = np.roll(p, -1, axis=0) - p
    L = np.linalg.norm(c, axis=1)
    u = c / L[:, None]
    th = np.arccos(np.clip(np.sum(np.roll(u, 1, axis=0) * u, axis=1), -1.0, 1.0))
    l_min = np.minimum(L, np.roll(L, 1))
    return np.maximum((1 / np.cos(th / 2) - 1) / b, 2 * np.tan(th / 2) / l_min)


@pytest.mark.parametrize(("chord_tol", "edge_tol", "bound"), MODES)
def test_low_poly_window_is_fitted_as_its_polygon(chord_tol, edge_tol, bound):
    """The 27-facet window resampled every 2 mm: its corners turn 45-90 deg at single points,
    the interpolating fit of the same points leaves the polyline by more than the bound
    (the wiggles); the fit is classed polygon and (own measures) stays within the bound of the
    polyline and of every point, lies on the straight facets between corners (mid-span points
    on the polyline within 1 um), has at each data span a peak curvature <= 2.5 x what its
    corners need within the bound, and changes sign no more often than the polyline turns
    (here: a convex window, never)."""
    edge = resample_loop(_low_poly_window(), 2.0e-3)
    interp = fit_edge_curve(edge)
    assert _distance_to_polyline(interp.position(U[::4]), edge).max() > bound  # the case
    curve = fit_window_edge(edge, chord_tolerance=chord_tol, edge_tolerance=edge_tol)
    fig = curve.fit
    assert fig["fit"] == "polygon" and fig["held"]
    assert fig["point_bound_m"] == pytest.approx(bound)
    q = curve.position(U)
    assert _distance_to_polyline(q, edge).max() <= bound
    assert cKDTree(q).query(edge)[0].max() <= bound
    assert np.linalg.norm(curve.position(curve.u_data) - edge, axis=1).max() <= bound
    assert fig["chord_error_m"] <= bound and fig["point_error_m"] <= bound
    u0, u1 = curve.u_data, np.r_[curve.u_data[1:], 1.0]
    mid = curve.position(0.5 * (u0 + u1))
    need = _corner_need(edge, bound)
    turn_free = need < 1.0  # collinear with its neighbours (a need below 1/m)
    both = turn_free & np.roll(turn_free, -1)
    assert both.sum() >= 10
    assert _distance_to_polyline(mid[both], edge).max() <= 1e-6
    k = curve.curvature(u0[:, None] + np.linspace(0, 1, 33) * (u1 - u0)[:, None])
    end_need = np.maximum(np.maximum(need, np.roll(need, -1)), 1.0)
    assert (k.max(axis=1) <= 2.5 * end_need).all()
    assert fig["kappa_need_ratio"] == pytest.approx((k.max(axis=1) / end_need).max(), rel=0.05)
    n = _normal(edge)
    assert _flips(_signed_kappa(curve, U, n)) == 0
    assert _flips(_signed_kappa(interp, U, n)) > 0  # the interpolant's wiggles


@pytest.mark.parametrize(("n", "fit"), [(20, "faceted"), (30, "interpolating"),
                                        (40, "interpolating"), (60, "interpolating")])
def test_regular_low_poly_polygon(n, fit):
    """A regular n-gon (noise-free vertices, R = 25 mm: facets of 2.6-7.9 mm turning 6-18 deg)
    resampled every 2 mm: no corner the points leave unresolved (<= 32 deg), so the fit is
    what the facets make it - the held smoothing fit of a faceted loop with 20 facets (7.8 mm,
    >= 3 spacings, sagitta 0.31 mm), the interpolating one with 30-60 (facets of 2.6-5.2 mm:
    fewer than 3 spacings, not resolved as facets). That fit (own measures) stays within the
    bound of every point and within delta_max of the polyline between them and curves no more
    than 2.5 x what the corners need; it still rings a little about the facets (curvature
    reversals of up to 190 /m over a fraction of a spacing, 0.02-0.1 mm off the polyline:
    within the bound, kept so that the plans of loops without unresolved corners, the bundled
    hubs' among them, do not change). The polygon fit of the same points (fit_polygon_curve)
    meets the same bounds and never changes sign."""
    bound = DELTA - CL_DELTA
    edge = resample_loop(_regular_polygon(n, 0.025), 2.0e-3)
    assert not mut.is_polygon(edge)
    need = _corner_need(edge, bound).max()
    n_vec = _normal(edge)
    curve = fit_window_edge(edge, chord_tolerance=CL_DELTA, edge_tolerance=DELTA)
    assert curve.fit["fit"] == fit
    poly = mut.fit_polygon_curve(edge, bound)
    for c, tube in ((curve, DELTA), (poly, bound)):
        q = c.position(U)
        assert cKDTree(q).query(edge)[0].max() <= bound
        assert _distance_to_polyline(q, edge).max() <= tube
        assert c.curvature(U).max() <= 2.5 * need
    assert _flips(_signed_kappa(poly, U, n_vec)) == 0


def test_facet_corner_of_uneven_facets():
    """mut.fit_polygon_curve alone on a polygon of unequal facets (2-30 mm) with corners of
    18-101 deg, not resampled: every point within the bound, and a corner's curvature within
    3 x the need (the cubic corner takes about 2 (1 + c) / (3 c^2) x the circle's, c =
    cos(theta / 2): 2.3 at 90 deg) even where the facets beside it are short (the tangent
    limit 2 tan(theta / 2) / L)."""
    b = 0.05e-3
    xy = np.array([[0, 0], [0.030, 0], [0.032, 0.0015], [0.040, 0.020], [0.020, 0.028],
                   [0.006, 0.015], [0.002, 0.010]])
    p = _tilted(xy)
    curve = mut.fit_polygon_curve(p, b)
    q = curve.position(U)
    assert _distance_to_polyline(q, p).max() <= b
    assert cKDTree(q).query(p)[0].max() <= b
    need = _corner_need(p, b)
    u0, u1 = curve.u_data, np.r_[curve.u_data[1:], 1.0]
    k = curve.curvature(u0[:, None] + np.linspace(0, 1, 201) * (u1 - u0)[:, None])
    assert (k.max(axis=1) <= 3.0 * np.maximum(need, np.roll(need, -1))).all()
    assert _flips(_signed_kappa(curve, U, _normal(p))) == 0


def test_smooth_dense_loops_keep_the_interpolating_fit():
    """An analytic ellipse sampled every 2 mm and every 0.3 mm (turns <= 6 deg): interpolating,
    coefficient for coefficient fit_edge_curve's, in both modes."""
    for h in (2.0e-3, 0.3e-3):
        t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
        edge = resample_loop(_tilted(np.c_[0.04 * np.cos(t), 0.025 * np.sin(t)]), h)
        for chord_tol, edge_tol, _ in MODES:
            curve = fit_window_edge(edge, chord_tolerance=chord_tol, edge_tolerance=edge_tol)
            assert curve.fit["fit"] == "interpolating"
            np.testing.assert_array_equal(curve.spline.c, fit_edge_curve(edge).spline.c)


def test_corner_deviation_and_need_figures():
    """corner_deviation is 0 without an unresolved corner and the interpolant's ringing beside
    one (own distance); curvature_need is the circle's (1 / cos(theta / 2) - 1) / b at a
    90 deg corner of long facets."""
    square = resample_loop(_tilted(np.array([[0, 0], [0.02, 0], [0.02, 0.02], [0, 0.02]])),
                           2.0e-3)
    interp = fit_edge_curve(square)
    dev = mut.corner_deviation(interp)
    assert dev == pytest.approx(_distance_to_polyline(interp.position(U[::3]), square).max(),
                                rel=0.05)
    assert dev > 0.1e-3
    circle = fit_edge_curve(resample_loop(_regular_polygon(400, 0.03), 0.5e-3))
    assert mut.corner_deviation(circle) == 0.0
    need = mut.curvature_need(square, 0.1e-3)
    assert need.max() == pytest.approx((1 / np.cos(np.pi / 4) - 1) / 0.1e-3)
