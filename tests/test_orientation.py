"""Orientation models and solvers on synthetic windows with analytic frames."""

import numpy as np
import pytest
from orient_geometry import cl_from_loop, rounded_rect_loop
from pydrake.math import RigidTransform, RotationMatrix
from scipy.spatial.transform import Rotation

import drakedeburr.orientation.orient as mut
from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.frames.local_frames import (
    R_HL_from_normals,
    angles_from_zT_H,
    axis_from_angles,
)
from drakedeburr.orientation.exact import projected_gradient_norm, solve_exact
from drakedeburr.orientation.models import make_problem
from drakedeburr.orientation.pso import PsoOptions
from drakedeburr.orientation.smoothing import gaussian_smooth_mirror
from drakedeburr.orientation.stats import angle_statistics, axis_turning


def _window(kind="large", dish=3.0, n=90, size=(0.03, 0.02, 0.006), index=0):
    """A rounded-rectangle window on a dished face z = dish (x^2 + y^2) [m]."""
    p, t, n_wall, kappa, s = rounded_rect_loop(*size, n)
    p[:, 2] = dish * (p[:, 0] ** 2 + p[:, 1] ** 2)
    # tangent of the lifted curve; the wall normal stays horizontal
    t = np.roll(p, -1, 0) - np.roll(p, 1, 0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    return cl_from_loop(p, t, kappa, s, index, kind), n_wall


WINDOWS = [_window("large", 3.0, 90, (0.03, 0.02, 0.006), 0),
           _window("small", 5.0, 50, (0.015, 0.01, 0.004), 1),
           _window("large", 0.0, 70, (0.025, 0.012, 0.008), 2)]


def _problem(cl, n, model="axis", w2nd=0.0):
    b = ProcessParameters().bounds_large if cl.kind == "large" else ProcessParameters().bounds_small
    return make_problem(model, cl.p_HC, R_HL_from_normals(cl.t_H, n), b,
                        second_difference_weight=w2nd, name=f"window {cl.window_index}")


def test_paper_model_is_degenerate_any_constant_pair_is_optimal():
    cl, n = WINDOWS[0]
    prob = _problem(cl, n, "paper")
    rng = np.random.default_rng(0)
    for a, b in rng.uniform(0.26, 0.44, (5, 2)):
        assert prob.objective(np.tile([a, b], prob.m)) == 0.0
    rep = solve_exact(prob)
    assert rep.objective == 0.0 and rep.success
    # ... yet the real tool axis turns wherever the edge turns
    turn = axis_turning(cl.p_HC, prob.axes(rep.x))
    assert turn.max() > 50.0  # [rad/m] around the 6 mm corners


def test_paper_model_objective_matches_eq_11_by_hand():
    cl, n = WINDOWS[1]
    prob = _problem(cl, n, "paper")
    x = np.random.default_rng(1).uniform(0.09, 0.26, prob.n_vars)
    th = x.reshape(-1, 2)
    total = 0.0
    for i in range(1, len(th)):  # eq. 11: i = 2..n, open
        d = np.linalg.norm(cl.p_HC[i] - cl.p_HC[i - 1])
        total += np.sqrt(0.6 * ((th[i, 0] - th[i - 1, 0]) / d) ** 2
                         + 0.4 * ((th[i, 1] - th[i - 1, 1]) / d) ** 2)
    assert prob.objective(x) == pytest.approx(total, rel=1e-12)


@pytest.mark.parametrize("w2nd", [0.0, 1e-5])
def test_axis_model_gradient_matches_finite_differences(w2nd):
    cl, n = WINDOWS[1]
    prob = _problem(cl, n, "axis", w2nd)
    x = np.random.default_rng(2).uniform(0.09, 0.26, prob.n_vars)
    g = prob.gradient(x)
    h = 1e-6
    for k in np.random.default_rng(3).choice(prob.n_vars, 12, replace=False):
        e = np.zeros(prob.n_vars)
        e[k] = h
        fd = (prob.objective(x + e) - prob.objective(x - e)) / (2 * h)
        assert g[k] == pytest.approx(fd, rel=1e-5, abs=1e-6)
    # objective by hand: sum |a_j - a_i|^2 / d over the closed loop
    a = prob.axes(x)
    d = np.linalg.norm(np.roll(cl.p_HC, -1, 0) - cl.p_HC, axis=1)
    first = (np.linalg.norm(np.roll(a, -1, 0) - a, axis=1) ** 2 / d).sum()
    if w2nd == 0.0:
        assert prob.objective(x) == pytest.approx(first, rel=1e-12)
    else:
        assert prob.objective(x) > first


@pytest.mark.parametrize("index", range(len(WINDOWS)))
def test_exact_beats_pso_holds_bounds_and_is_locally_optimal(index):
    cl, n = WINDOWS[index]
    prob = _problem(cl, n, "axis")
    exact = mut.solve_problem(prob, "exact")
    pso = mut.solve_problem(prob, "pso", mut.OrientOptions(pso=PsoOptions(iterations=100)))
    assert exact.success, exact.message
    assert exact.objective <= pso.objective
    assert exact.objective <= pso.info["objective_raw"]
    th = exact.x.reshape(-1, 2)
    assert np.all(th >= prob.theta_min - 1e-9) and np.all(th <= prob.theta_max + 1e-9)
    assert projected_gradient_norm(prob, exact.x) < 1e-5 * np.abs(prob.gradient(prob.lower)).max()
    # feasible random perturbations never decrease the objective (re-check of optimality)
    rng = np.random.default_rng(index)
    f0 = exact.objective
    for scale in (1e-4, 1e-3, 1e-2):
        xs = np.clip(exact.x + rng.normal(0, scale, (200, prob.n_vars)), prob.lower, prob.upper)
        assert prob.objective(xs).min() >= f0 * (1 - 1e-9)
    # and better than the naive constant choices (box centre, corners)
    for c in (prob.theta_min, 0.5 * (prob.theta_min + prob.theta_max), prob.theta_max):
        assert f0 <= prob.objective(np.full(prob.n_vars, c))


@pytest.mark.parametrize("w2nd", [0.0, 1e-5])
@pytest.mark.parametrize("index", [0, 1])
def test_exact_solver_internal_model_matches_the_problem(w2nd, index):
    """The exact solver's fast banded model (its own trig tables, band numbering) must be the
    problem's model: objective, gradient, Gauss-Newton diagonal and the whole Hessian (band
    storage unpacked) against models.py at random angles (a stale copy of an older theta_A
    sign once made it optimise a different problem)."""
    from drakedeburr.orientation.banded import BandedAxisModel

    cl, n = WINDOWS[index]
    prob = _problem(cl, n, "axis", w2nd)
    fast = BandedAxisModel(prob)
    perm = fast.layout.perm
    rng = np.random.default_rng(4)
    for x in rng.uniform(-0.5, 0.6, (3, prob.n_vars)):
        xb = fast.to_band(x)
        np.testing.assert_array_equal(fast.from_band(xb), x)
        f, g, hv, curv = fast.derivatives(xb)
        assert f == pytest.approx(prob.objective(x), rel=1e-12)
        assert fast.objective(xb) == pytest.approx(prob.objective(x), rel=1e-12)
        np.testing.assert_allclose(g, prob.gradient(x)[perm], rtol=0,
                                   atol=1e-9 * np.abs(g).max())
        _, _, H_gn, _ = prob.derivatives(x)
        H = prob.hessian(x)[np.ix_(perm, perm)]  # band numbering
        np.testing.assert_allclose(fast.gauss_newton_diagonal(hv), np.diag(H_gn)[perm],
                                   rtol=1e-12)
        ab = fast.hessian_band(hv, curv)
        H_fast = np.zeros_like(H)
        for d in range(fast.bandwidth + 1):  # LAPACK lower band storage
            k = np.arange(prob.n_vars - d)
            H_fast[k + d, k] = ab[d, : prob.n_vars - d]
            H_fast[k, k + d] = ab[d, : prob.n_vars - d]
        np.testing.assert_allclose(H_fast, H, rtol=0, atol=1e-9 * np.abs(H).max())
        v = rng.normal(size=prob.n_vars)
        np.testing.assert_allclose(fast.hess_vec(ab, v), H @ v, rtol=0,
                                   atol=1e-9 * np.abs(H @ v).max())


@pytest.mark.parametrize("index", range(len(WINDOWS)))
def test_exact_from_the_bounds_reaches_the_same_kkt_point_quickly(index):
    cl, n = WINDOWS[index]
    prob = _problem(cl, n, "axis")
    ref = solve_exact(prob)
    scale = np.abs(prob.gradient(prob.lower)).max()
    for x0 in (prob.lower, prob.upper):
        rep = solve_exact(prob, x0=x0)
        assert rep.success, rep.message
        assert projected_gradient_norm(prob, rep.x) < 1e-5 * scale
        assert rep.objective == pytest.approx(ref.objective, rel=1e-9)
        # active-set refinement: not one bound variable released per Newton step
        assert rep.iterations <= 10


def test_exact_warm_start_converges_to_the_same_optimum():
    cl, n = WINDOWS[0]
    prob = _problem(cl, n, "axis")
    cold = solve_exact(prob)
    warm = solve_exact(prob, x0=cold.x)
    lower = solve_exact(prob, x0=prob.lower)
    assert warm.iterations <= 2
    assert warm.objective == pytest.approx(cold.objective, rel=1e-9)
    assert lower.objective == pytest.approx(cold.objective, rel=1e-6)


def test_smoothing_is_gaussian_with_mirror_padding():
    rng = np.random.default_rng(0)
    v = rng.uniform(0.26, 0.44, 40)
    sigma = 2.0
    out = gaussian_smooth_mirror(v, sigma)
    # second implementation: mirror-pad (d c b | a b c d | c b a) and convolve
    radius = int(4 * sigma + 0.5)
    k = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    k /= k.sum()
    padded = np.pad(v, radius, mode="reflect")  # numpy "reflect" excludes the edge sample
    np.testing.assert_allclose(out, np.convolve(padded, k, mode="valid"), atol=1e-12)
    assert out.min() >= v.min() and out.max() <= v.max()
    np.testing.assert_allclose(gaussian_smooth_mirror(np.full(9, 0.3), 2.0), 0.3)


def test_statistics_like_tables_3_6():
    th_a = np.array([0.3, 0.4, 0.35, 0.3])
    th_b = np.array([0.2, 0.2, 0.2, 0.2])
    p = np.array([[0, 0, 0], [1e-3, 0, 0], [1e-3, 1e-3, 0], [0, 1e-3, 0.0]])
    ax = np.tile([0, 0, 1.0], (4, 1))
    ax[1] = [np.sin(0.01), 0, np.cos(0.01)]
    s = angle_statistics(th_a, th_b, p, ax)
    assert s["theta_A"]["max"] == 0.4 and s["theta_A"]["min"] == 0.3
    assert s["theta_A"]["variance"] == pytest.approx(np.var(th_a))
    assert s["theta_A"]["cv"] == pytest.approx(np.std(th_a) / np.mean(th_a))
    assert s["theta_B"]["variance"] == 0.0
    assert s["axis_turn_rad_per_mm"]["max"] == pytest.approx(0.01)
    assert s["axis_turn_deg_per_mm"]["max"] == pytest.approx(np.degrees(0.01))
    assert s["axis_turn_total_deg"] == pytest.approx(np.degrees(0.02))


def test_tool_path_is_consistent_and_follows_the_hub_pose():
    cl, n = WINDOWS[0]
    X_WH = RigidTransform(RotationMatrix.MakeZRotation(0.7), [0.8, -0.1, 0.3])
    tp = mut.orient_window(cl, n, X_WH=X_WH)
    assert tp.success and len(tp) == len(cl)
    assert tp.depth_of_cut == ProcessParameters().depth_of_cut_large
    # independent re-check: angles -> axis through the frames, and back
    a, b = angles_from_zT_H(tp.R_HL, tp.zT_H)
    np.testing.assert_allclose(a, tp.theta_A, atol=1e-12)
    np.testing.assert_allclose(b, tp.theta_B, atol=1e-12)
    np.testing.assert_allclose(tp.R_HT[:, :, 2], tp.zT_H, atol=1e-12)
    np.testing.assert_allclose(tp.ijk_H, -tp.zT_H)
    assert tp.admissible(tp.axis_W).all()
    np.testing.assert_allclose(tp.p_WC, X_WH.multiply(cl.p_HC.T).T, atol=1e-15)
    # every axis inside the inner cone is admissible; the outer cone contains the box corners
    rng = np.random.default_rng(0)
    for _ in range(20):
        v = rng.normal(size=3)
        v -= (v @ np.array([0, 0, 1.0])) * np.array([0, 0, 1.0])
        v /= np.linalg.norm(v)
        ang = tp.cone_half_angle * rng.uniform(0, 1)
        local = np.cos(ang) * np.array([0, 0, 1.0]) + np.sin(ang) * v
        c = 0.5 * (tp.bounds.theta_min + tp.bounds.theta_max)
        # rotate the sample from +z onto the cone axis (same in every local frame)
        rot, _ = Rotation.align_vectors([axis_from_angles(c, c)], [[0, 0, 1.0]])
        axis_H = np.einsum("mij,j->mi", tp.R_HL, rot.apply(local))
        np.testing.assert_allclose(np.arccos(np.clip(np.einsum("ij,ij->i", axis_H, tp.cone_zT_H),
                                                     -1, 1)), ang, atol=1e-9)
        assert tp.admissible((X_WH.rotation().matrix() @ axis_H.T).T, tol=1e-12).all()
    corners = axis_from_angles(np.array([0.26, 0.26, 0.44, 0.44]),
                               np.array([0.26, 0.44, 0.26, 0.44]))
    ang = np.arccos(np.clip(corners @ axis_from_angles(0.35, 0.35), -1, 1))
    assert ang.max() <= tp.cone_outer_half_angle + 1e-12
    moved = tp.with_hub_pose(RigidTransform([0.01, 0, 0]))
    np.testing.assert_allclose(moved.p_WC, cl.p_HC + [0.01, 0, 0], atol=1e-15)
    assert moved.objective == tp.objective


def test_pso_solver_and_paper_model_pipeline_run_with_smoothing():
    cl, n = WINDOWS[1]
    tp = mut.orient_window(cl, n, model="paper", solver="pso",
                           options=mut.OrientOptions(pso=PsoOptions(iterations=50)))
    assert "Gaussian smoothing" in tp.message
    assert np.all((tp.theta_A >= 0.09) & (tp.theta_A <= 0.26))
    assert tp.objective >= 0.0
    assert tp.stats["theta_A"]["max"] <= 0.26


def test_bad_inputs_are_named():
    cl, n = WINDOWS[0]
    with pytest.raises(InputError, match="window 0: n_H has shape"):
        mut.orient_window(cl, n[:-1])
    with pytest.raises(InputError, match="unknown orientation model 'nope'"):
        mut.orient_window(cl, n, model="nope")
    with pytest.raises(InputError, match="unknown solver 'magic'"):
        mut.orient_window(cl, n, solver="magic")


def test_axis_model_hessian_matches_finite_differences_of_the_gradient():
    cl, n = WINDOWS[1]
    prob = _problem(cl, n, "axis", 1e-5)
    x = np.random.default_rng(5).uniform(0.09, 0.26, prob.n_vars)
    f, g, H_gn, _ = prob.derivatives(x)
    H = prob.hessian(x)
    assert f == pytest.approx(prob.objective(x), rel=1e-12)
    h = 1e-6
    for k in np.random.default_rng(6).choice(prob.n_vars, 8, replace=False):
        e = np.zeros(prob.n_vars)
        e[k] = h
        fd = (prob.gradient(x + e) - prob.gradient(x - e)) / (2 * h)
        np.testing.assert_allclose(H[:, k], fd, rtol=1e-5, atol=1e-5 * np.abs(H).max())
    J = prob.residual_jacobian(x)
    np.testing.assert_allclose(H_gn, 2 * J.T @ J, atol=1e-10 * np.abs(H_gn).max())


@pytest.mark.parametrize("m, w2nd, closed", [(40, 0.0, True), (40, 1e-5, True), (4, 1e-5, True),
                                             (3, 0.0, True), (12, 1e-5, False)])
def test_coefficients_gram_and_its_bands_match_the_residuals(m, w2nd, closed):
    """C (built from sparse rows), G = C^T C (accumulated without BLAS) and G's cyclic bands
    against the residuals by hand: r = C @ axes, first differences / sqrt(d) then the
    weighted second differences."""
    from drakedeburr.orientation.models import OrientationProblem

    rng = np.random.default_rng(m)
    phi = np.sort(rng.uniform(0, 2 * np.pi, m))
    p = np.c_[0.02 * np.cos(phi), 0.015 * np.sin(phi), 0.002 * np.sin(2 * phi)]
    R = Rotation.random(m, random_state=1).as_matrix()
    prob = OrientationProblem("axis", p, R, -0.3, 0.4, second_difference_weight=w2nd,
                              closed=closed)
    x = rng.uniform(-0.3, 0.4, prob.n_vars)
    a = prob.axes(x)
    seg = m if closed else m - 1
    i = np.arange(seg)
    j = (i + 1) % m
    d = np.linalg.norm(p[j] - p[i], axis=1)
    slope = (a[j] - a[i]) / d[:, None]
    rows = [(a[j] - a[i]) / np.sqrt(d)[:, None]]
    if w2nd > 0:
        after = np.arange(seg) if closed else np.arange(1, seg)
        before = (after - 1) % seg
        dbar = 0.5 * (d[before] + d[after])
        rows.append((slope[after] - slope[before]) * np.sqrt(w2nd / dbar)[:, None])
    r = np.concatenate(rows)
    C = prob.coefficients()
    np.testing.assert_allclose(C @ a, r, rtol=0, atol=1e-12 * np.abs(r).max())
    np.testing.assert_allclose(prob.residuals(x), r, rtol=0, atol=1e-12 * np.abs(r).max())
    G = prob._gram[0]
    np.testing.assert_allclose(G, C.T @ C, rtol=0, atol=1e-12 * np.abs(G).max())
    offsets, Gk = prob.gram_bands
    G_bands = np.zeros((m, m))
    for k, off in enumerate(offsets):
        G_bands[np.arange(m), (np.arange(m) + off) % m] += Gk[k]
    np.testing.assert_allclose(G_bands, G, rtol=0, atol=1e-12 * np.abs(G).max())
    assert len(set(offsets.tolist())) == len(offsets) and offsets.max() < m
    offsets_g, Gk_g = prob._gram_bands_general()  # the closed form is the general sums
    np.testing.assert_array_equal(offsets_g, offsets)
    np.testing.assert_array_equal(Gk_g, Gk)


def test_slope_limited_tangents_keep_the_burr_in_front_on_a_climbing_edge():
    """Issue 42: a loop that runs down a flank (tangent along -Z_H). The frame's tangent keeps
    its climb's sign, its slope is limited to 45 deg and its plan direction is across the
    inner-side normal (n x Z_H), so the upright axis of the frame (-Z_L, tip -> spindle) is
    45 deg off +Z_H instead of horizontal, and the true edge stays at >= 45 deg to every axis
    perpendicular to the frame tangent: a 90 deg cone still touches it with its flank. A flat
    tangent is left as it is."""
    import math

    from drakedeburr.frames.local_frames import R_HL_from_normals
    from drakedeburr.orientation.orient import slope_limited_tangents

    t = np.array([[0.0, 0.0, -1.0], [0.05, 0.02, -0.998], [1.0, 0.0, 0.0],
                  [0.6, 0.0, 0.8]])
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    out = slope_limited_tangents(t, n, math.radians(45.0))
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0)
    np.testing.assert_allclose(out[2], t[2])  # flat: unchanged
    s = math.sqrt(0.5)
    np.testing.assert_allclose(out[0], [s, 0.0, -s], atol=1e-12)  # n x z = +x, going down
    np.testing.assert_allclose(out[1], [s, 0.0, -s], atol=1e-12)
    np.testing.assert_allclose(out[3], [s, 0.0, s], atol=1e-12)  # climbing up
    R = R_HL_from_normals(out, n)
    up = -R[:, :, 2]  # -Z_L: the upright tool axis from tip to spindle
    assert (up[:, 2] >= s - 1e-12).all()
    lead = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", out, t), -1, 1)))
    assert lead.max() <= 45.0 + 1e-9


def test_slope_limit_leaves_a_flat_loop_bit_for_bit():
    """A loop within the slope limit (every bundled and random hub) gets the very tangents it
    came with, not a re-normalised copy, so its frames and tool axes are those of the planner
    before the limit existed, bit for bit (a last-bit change moves the IK's iterates)."""
    import math

    from drakedeburr.orientation.orient import slope_limited_tangents

    rng = np.random.default_rng(4)
    phi, slope = rng.uniform(0, 2 * np.pi, 50), np.radians(rng.uniform(-40, 40, 50))
    t = np.c_[np.cos(slope) * np.cos(phi), np.cos(slope) * np.sin(phi), np.sin(slope)]
    t *= 1.0 + 1e-15 * rng.normal(size=(50, 1))  # unit to the last bits, as a fit gives them
    n = np.cross(t, [0.0, 0.0, 1.0])
    out = slope_limited_tangents(t, n, math.radians(45.0))
    assert np.abs(np.degrees(np.arcsin(np.abs(t[:, 2])))).max() < 45.0
    np.testing.assert_array_equal(out, t)
