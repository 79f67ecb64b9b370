"""Touch-point calibration: synthetic noisy touches, scale compensation, degenerate input."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drakedeburr.post.calibration as mut
from drakedeburr.errors import InputError


def _truth():
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("xyz", [0.02, -0.03, 1.1]).as_matrix()
    X[:3, 3] = [0.85, -0.12, 0.31]
    return X


def _table_points(rng, n=8):
    # touch points spread over a 400 x 300 mm worktable, some raised on a block
    return np.column_stack([rng.uniform(-0.2, 0.2, n), rng.uniform(-0.15, 0.15, n),
                            rng.choice([0.0, 0.05], n)])


def _angle(R1, R2):
    return np.arccos(np.clip((np.trace(R1.T @ R2) - 1) / 2, -1, 1))


def test_recovers_transform_within_noise():
    rng = np.random.default_rng(0)
    X = _truth()
    sigma = 0.05e-3  # 0.05 mm touch noise
    p_T = _table_points(rng, 12)
    p_W = p_T @ X[:3, :3].T + X[:3, 3] + rng.normal(0, sigma, p_T.shape)
    fit = mut.fit_touch_points(p_T, p_W)
    # position error of a least-squares fit ~ sigma / sqrt(N); rotation ~ sigma / spread
    assert np.linalg.norm(fit.X_WT[:3, 3] - X[:3, 3]) < 5 * sigma
    assert _angle(fit.X_WT[:3, :3], X[:3, :3]) < 5 * sigma / 0.1
    assert fit.rms_rigid < 2 * sigma and fit.residuals_rigid.shape == (12,)
    # independent check: residuals recomputed from the returned transform
    r = np.linalg.norm(p_W - (p_T @ fit.X_WT[:3, :3].T + fit.X_WT[:3, 3]), axis=1)
    assert np.allclose(r, fit.residuals_rigid)
    assert fit.scale == 1.0


def test_scale_compensation_removes_systematic_error():
    rng = np.random.default_rng(1)
    X = _truth()
    s_true = 1.004  # ~0.8 mm at 200 mm: systematic error growing with distance
    p_T = _table_points(rng, 10)
    p_W = s_true * p_T @ X[:3, :3].T + X[:3, 3] + rng.normal(0, 0.02e-3, p_T.shape)
    fit = mut.fit_touch_points(p_T, p_W, estimate_scale=True)
    assert fit.scale == pytest.approx(s_true, abs=2e-4)
    assert fit.rms_rigid > 0.3e-3 and fit.rms_scaled < 0.05e-3  # before / after
    # the paper's fix: the paths (model) in T compensated, then a rigid fit explains the
    # touches: the robot's coordinates of a table point are s times T's
    comp = fit.scale_compensation()
    assert comp.scale == pytest.approx(1 / fit.scale)  # the cell makes 1/s of the command
    refit = mut.fit_touch_points(comp.compensate_path(p_T), p_W)
    assert refit.rms_rigid < 0.05e-3
    assert np.allclose(comp.compensate_path(p_T), fit.scale * p_T)


def test_calibrated_pose_applies_transform():
    rng = np.random.default_rng(2)
    X = _truth()
    p_T = _table_points(rng, 6)
    fit = mut.fit_touch_points(p_T, p_T @ X[:3, :3].T + X[:3, 3])
    X_TH = np.eye(4)
    X_TH[:3, 3] = [0.05, 0.0, 0.12]
    X_WH = mut.calibrated_pose(fit, X_TH)
    assert np.allclose(X_WH, X @ X_TH, atol=1e-12)


@pytest.mark.parametrize("p_T, match", [
    (np.array([[0, 0, 0], [0.1, 0, 0]]), "at least 3"),
    (np.array([[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0.3, 0, 0]]), "collinear"),
    (np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0, 0.0002], [0, 0.1, 0]]), "points 2 and 3"),
    (np.array([[0, 0, 0], [0.1, 0, 0], [np.nan, 0, 0], [0, 0.1, 0]]), "point 3 is not finite"),
])
def test_degenerate_input_refused(p_T, match):
    with pytest.raises(InputError, match=match):
        mut.fit_touch_points(p_T, p_T + 0.5)


# ------------------------------------------------------------ scale compensation (machined)
def _rounded_rect(a=0.12, b=0.08, r=0.02, n=24):
    """A 240 x 160 mm part contour with 20 mm corner radii, counter-clockwise [m]."""
    pts = []
    for cx, cy, t0 in ((a - r, b - r, 0), (-a + r, b - r, np.pi / 2), (-a + r, -b + r, np.pi),
                       (a - r, -b + r, 1.5 * np.pi)):
        t = np.linspace(t0, t0 + np.pi / 2, n)
        pts += list(zip(cx + r * np.cos(t), cy + r * np.sin(t), 0 * t, strict=True))
    return np.array(pts)


def _point_on_polygon(x, poly):
    """Closest points of 2-D x (M, 2) on the closed polygon (N, 2), numpy only."""
    a, b = poly, np.roll(poly, -1, 0)
    t = np.clip(np.einsum("mnk,nk->mn", x[:, None] - a[None], b - a)
                / np.sum((b - a) ** 2, 1), 0, 1)
    foot = a[None] + t[..., None] * (b - a)[None]
    j = np.argmin(np.linalg.norm(x[:, None] - foot, axis=-1), 1)
    return foot[np.arange(len(x)), j]


@pytest.mark.parametrize("model", ["scale", "similarity", "affine"])
def test_machined_contour_fit_recovers_an_exact_map_and_compensates_the_right_way(model):
    """A cell that makes m = c + s R (n - c) (+ a per-direction stretch for "affine"): the
    fit, from scan points anywhere on the machined edge, finds the map; the compensated path
    machined by the same cell gives the nominal contour; the model scaled by s instead
    doubles the error (the tutorial's old way)."""
    n = _rounded_rect()
    c, s = np.array([0.03, -0.02, 0.0]), 1.008
    th = 0.004 if model != "scale" else 0.0
    L = s * np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    if model == "affine":
        L = L @ np.diag([1.0, 0.996, 1.0])
    L[2, 2] = 1.0

    def make(path):  # the cell
        return (path - c) @ L.T + c

    edge = make(n)
    rng = np.random.default_rng(3)
    k = rng.integers(0, len(n), 150)  # scan points between the vertices
    u = rng.uniform(0, 1, 150)[:, None]
    scan = edge[k] + u * (np.roll(edge, -1, 0)[k] - edge[k])
    fit = mut.fit_machined_contour(n, scan, model=model)
    assert fit.predicted_residual < 1e-9
    assert fit.scale == pytest.approx(abs(np.linalg.det(L[:2, :2])) ** 0.5, abs=1e-9)
    assert np.allclose(fit.center, c, atol=1e-7)
    assert fit.error_before > 0.5e-3
    made = make(fit.compensate_path(n))
    assert np.abs(made - n).max() < 1e-9  # the compensated path makes the nominal part
    wrong = make((n - c) @ L.T + c)  # the model scaled the wrong way round
    d_wrong = np.linalg.norm(wrong[:, :2] - _point_on_polygon(wrong[:, :2], n[:, :2]), axis=1)
    assert d_wrong.max() > 1.8 * fit.error_before


def test_machined_contour_refuses_bad_input():
    n = _rounded_rect()
    with pytest.raises(InputError, match="compensation model"):
        mut.fit_machined_contour(n, n, model="cubic")
    with pytest.raises(InputError, match="at least"):
        mut.fit_machined_contour(n, n[:3])
    bad = n.copy()
    bad[5, 0] = np.nan
    with pytest.raises(InputError, match="measured point 6 is not finite"):
        mut.fit_machined_contour(n, bad)
    with pytest.raises(InputError, match="compensate_path"):
        mut.fit_machined_contour(n, n * 1.01).compensate_path(n[:, :2])
