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
    # the paper's fix: scale the part model, then a rigid fit explains the touches
    refit = mut.fit_touch_points(mut.scale_about(p_T, fit.scale), p_W)
    assert refit.rms_rigid < 0.05e-3


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
