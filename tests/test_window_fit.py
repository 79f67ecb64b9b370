"""drakedeburr.path.window_fit: the pipeline's fit of a window edge (issue 42 item 3). A
polygonal loop (a low-poly mesh's edge) gets the smoothing fit, a dense smooth loop keeps the
interpolating one point for point; the figures reported against the facets are re-measured
here on the curve itself (dense samples, independent of polyline_fit_report)."""

from __future__ import annotations

import numpy as np
import pytest

import drakedeburr.path.window_fit as mut
from drakedeburr.hub.extract import resample_loop
from drakedeburr.path.edge_curve import facet_sagitta, fit_edge_curve

U = np.linspace(0.0, 1.0, 40000, endpoint=False)


def _kappa_z(curve):
    """Signed curvature about +Z [1/m] from the spline's own derivatives."""
    d1, d2 = curve.spline(U, nu=1), curve.spline(U, nu=2)
    return np.cross(d1, d2)[:, 2] / np.linalg.norm(d1, axis=1) ** 3


def _sign_changes(k):
    s = np.sign(k[np.abs(k) > 1e-9 * np.abs(k).max()])
    return int(np.count_nonzero(s != np.roll(s, 1)))


def _distance_to_polyline(q, p):
    """Distance of each point of q (M, 3) from the closed polyline p (N, 3)."""
    A, B = p, np.roll(p, -1, axis=0)
    d = q[:, None, :] - A[None]
    t = np.clip(np.einsum("kij,ij->ki", d, B - A) / np.einsum("ij,ij->i", B - A, B - A), 0, 1)
    return np.linalg.norm(d - t[..., None] * (B - A)[None], axis=2).min(axis=1)


@pytest.mark.parametrize("n_facets", [24, 48])
def test_polygonal_circle_gets_the_faceted_fit(n_facets):
    """A circle of R = 50 mm cut into N facets, resampled every 0.5 mm as ``hub import`` stores
    a mesh's edge: the fit is within the facets' sagitta R (1 - cos(pi/N)) + 2 um of the true
    circle, its curvature within 7 % of 1/R everywhere (measured: 6.3 % with 24 facets, 4.1 %
    with 48: the smoothing spline ripples between the corners it passes through) and of one
    sign (no wiggles). The interpolating fit of the same points bends at every corner (> 4/R)
    and changes sign at the corners: what the faceted fit fixes. The reported figures match
    the facets and a dense evaluation of the curve. (Not held to the points, edge_tolerance
    None: the designed-curve estimate itself; held, tests/test_window_fit_bound.py.)"""
    R, z = 0.05, 0.01
    a = 2 * np.pi * np.arange(n_facets) / n_facets + 0.2
    p = resample_loop(np.c_[R * np.cos(a), R * np.sin(a), np.full(n_facets, z)], 0.5e-3)
    curve = mut.fit_window_edge(p, chord_tolerance=0.03e-3, edge_tolerance=None,
                                name="polygon")
    fig = curve.fit
    assert fig["fit"] == "faceted"
    q = curve.position(U)
    sagitta = R * (1 - np.cos(np.pi / n_facets))
    assert np.abs(np.linalg.norm(q[:, :2], axis=1) - R).max() <= sagitta + 2e-6
    np.testing.assert_allclose(q[:, 2], z, atol=1e-9)
    k = _kappa_z(curve)
    np.testing.assert_allclose(k, 1.0 / R, rtol=0.07)
    assert _sign_changes(k) == 0
    # the interpolating fit of the same points
    interp = fit_edge_curve(p)
    k_i = _kappa_z(interp)
    assert k_i.max() > 4.0 / R and _sign_changes(k_i) > 0
    # the report, re-measured
    facet = 2 * R * np.sin(np.pi / n_facets)
    assert fig["facets"] == n_facets
    assert fig["facet_median_m"] == pytest.approx(facet, abs=0.5e-3)
    assert fig["facet_share"] == pytest.approx(1.0, abs=0.01)
    assert fig["kappa_facets"] == pytest.approx((2 * np.pi / n_facets) / facet, rel=0.05)
    assert fig["sagitta_max_m"] == pytest.approx(sagitta, rel=0.1)
    assert fig["chord_error_m"] == pytest.approx(_distance_to_polyline(q, p).max(), abs=2e-6)
    assert fig["chord_error_m"] <= 1.2 * fig["sagitta_max_m"]
    assert fig["kappa_max"] == pytest.approx(np.abs(k).max(), rel=0.01)
    assert fig["kappa_ratio"] < 1.1 and fig["inflections"] == 0
    # the path stage carries the figures into its output
    from drakedeburr.path import plan_cl

    assert plan_cl(curve, "adaptive").metrics["edge_fit"] == fig


def test_dense_smooth_loop_keeps_the_interpolating_fit():
    """A densely sampled designed curve (a rounded-rectangle window: straight sides, 8 mm plan
    corners, 0.3 mm spacing; the bundled hubs' ground truth is such a loop) has no facet
    corner: the interpolating fit, spline for spline, so its plans do not change."""
    th = np.linspace(0, np.pi / 2, 60, endpoint=False)
    corner = np.c_[np.cos(th), np.sin(th)] * 0.008
    pts = []
    for k, (cx, cy) in enumerate(((0.03, 0.02), (-0.03, 0.02), (-0.03, -0.02), (0.03, -0.02))):
        rot = np.array([[np.cos(k * np.pi / 2), -np.sin(k * np.pi / 2)],
                        [np.sin(k * np.pi / 2), np.cos(k * np.pi / 2)]])
        pts.append(corner @ rot.T + [cx, cy])
    p2 = resample_loop(np.c_[np.vstack(pts), np.zeros(240)], 0.3e-3)
    curve = mut.fit_window_edge(p2, chord_tolerance=0.03e-3)
    assert curve.fit["fit"] == "interpolating" and curve.fit["facets"] == 0
    ref = fit_edge_curve(p2)
    np.testing.assert_array_equal(curve.spline.c, ref.spline.c)
    np.testing.assert_array_equal(curve.spline.t, ref.spline.t)


def test_real_mesh_loops_stay_within_their_facets(extdata):
    """The audibot rim (a public low-poly mesh, 10 windows), its loops as ``hub import`` stores
    them (0.5 mm), planned at a 0.03 mm CL chord height: a loop whose facets' sagitta exceeds
    it gets the faceted fit, the others the interpolating fit. Where the faceted fit is free
    (a facet), it leaves the polygon by about the facet's
    sagitta; elsewhere it follows the points as the interpolating fit does. Measured on the
    curve: its distance from the data polyline, beside a facet <= 1.6 x the largest facet
    sagitta + 2 um (the smoothing factor bounds the weighted residuals' sum, not each: window
    1 takes 1.40 x its 0.183 mm sagitta), elsewhere <= 1.1 x the interpolating fit's own
    + 2 um; its largest curvature no
    higher than the interpolating fit's (the faceted fit adds no bends; most of these loops'
    curvature is at real corners where they turn down a flank, which both fits keep), and the
    reported chord error is the measured one."""
    from scipy.spatial import cKDTree

    from drakedeburr.hub.extract import extract_window_edges
    from drakedeburr.hub.mesh_io import load_hub_mesh

    lm = load_hub_mesh(extdata / "wheel_models" / "audibot__wheel_rim_only_DERIVED_m.stl")
    res = extract_window_edges(lm.mesh, source="audibot", spacing=0.5e-3)
    assert len(res.windows) == 10
    faceted = 0
    for w in res.windows:
        curve = mut.fit_window_edge(w.p_HE, chord_tolerance=0.03e-3, name=f"window {w.index}")
        interp = fit_edge_curve(w.p_HE)
        fig = curve.fit
        assert (fig["fit"] == "faceted") == (fig["sagitta_max_m"] > 0.03e-3)
        if fig["fit"] != "faceted":  # facets within the CL chord height: the interpolating fit
            np.testing.assert_array_equal(curve.spline.c, interp.spline.c)
            continue
        faceted += 1
        q = curve.position(U[::4])
        d = _distance_to_polyline(q, w.p_HE)
        d_i = _distance_to_polyline(interp.position(U[::4]), w.p_HE)
        free = facet_sagitta(w.p_HE)["sigma"][cKDTree(w.p_HE).query(q)[1]] > 2e-6
        assert (d[free] <= 1.6 * fig["sagitta_max_m"] + 2e-6).all(), w.index
        assert (d[~free] <= 1.1 * d_i.max() + 2e-6).all(), w.index
        assert fig["chord_error_m"] == pytest.approx(d.max(), rel=0.05, abs=2e-6)
        assert fig["kappa_max"] <= 1.01 * interp.curvature(U).max()
    assert faceted >= 5  # measured: 7 of the 10 loops have a facet sagitta over 0.03 mm


def test_bundled_hubs_keep_the_interpolating_fit():
    """The bundled hubs' loops (the generator's ground truth: a polyline through its mesh
    vertices, 0.07-0.33 mm apart; the small windows of h5_split have facets of ~0.5 mm whose
    sagitta is <= 2.1 um) are fitted by the planner's chord height (plan.tool_paths.CL_DELTA)
    exactly as before: the interpolating fit, spline for spline, so their plans do not
    change."""
    from drakedeburr.hub.model import load_hub
    from drakedeburr.plan.tool_paths import CL_DELTA

    for name in ("h5_deepdish", "h5_split", "h5_straight", "h6_curved"):
        for w in load_hub(name).windows:
            curve = mut.fit_window_edge(w.p_HE, chord_tolerance=CL_DELTA)
            assert curve.fit["fit"] == "interpolating", (name, w.index)
            assert curve.fit["sagitta_max_m"] < 0.1 * CL_DELTA
            np.testing.assert_array_equal(curve.spline.c, fit_edge_curve(w.p_HE).spline.c)
