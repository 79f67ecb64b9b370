import numpy as np
from scipy.spatial.transform import Rotation

import drakedeburr.plan.interpolate as mut
from drakedeburr.plan.smoothing import smooth_orientations


def _poses(n, rng):
    X = np.tile(np.eye(4), (n, 1, 1))
    X[:, :3, 3] = np.cumsum(rng.uniform(1e-3, 2e-3, (n, 3)), axis=0)
    X[:, :3, :3] = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.02, (n, 3)), axis=0)
                                        + [np.pi, 0, 0]).as_matrix()
    return X


def test_dense_poses_are_linear_and_slerped_between_targets():
    rng = np.random.default_rng(0)
    X = _poses(6, rng)
    D, s, idx = mut.dense_poses(X, step=0.5e-3)
    np.testing.assert_allclose(D[idx], X, atol=1e-12)
    assert np.all(np.diff(s) <= 0.5e-3 + 1e-12) and np.all(np.diff(s) > 0)
    for k in range(5):
        a, b = idx[k], idx[k + 1]
        p0, p1 = X[k, :3, 3], X[k + 1, :3, 3]
        f = (s[a:b + 1] - s[a]) / (s[b] - s[a])
        np.testing.assert_allclose(D[a:b + 1, :3, 3], p0 + f[:, None] * (p1 - p0), atol=1e-12)
        # constant angular rate along a slerp
        ang = (Rotation.from_matrix(D[a:b + 1, :3, :3][:-1]).inv()
               * Rotation.from_matrix(D[a:b + 1, :3, :3][1:])).magnitude()
        np.testing.assert_allclose(ang / np.diff(f), ang[0] / np.diff(f)[0], rtol=1e-6)


def test_smoothing_keeps_positions_and_the_cone():
    rng = np.random.default_rng(0)
    X = _poses(40, rng)
    cone = -X[:, :3, 2]
    noisy = X.copy()
    noisy[:, :3, :3] = Rotation.from_rotvec(rng.normal(0, 0.03, (40, 3))).as_matrix() @ X[:, :3, :3]
    out = smooth_orientations(noisy, cone, 0.05, sigma=2.0)
    np.testing.assert_allclose(out[:, :3, 3], noisy[:, :3, 3])
    ang = np.arccos(np.clip(np.sum(-out[:, :3, 2] * cone, axis=1), -1, 1))
    assert np.all(ang <= 0.05 + 1e-9)
    # smoother: the step-to-step rotation is smaller on average
    def steps(Y):
        R = Rotation.from_matrix(Y[:, :3, :3])
        return (R[:-1].inv() * R[1:]).magnitude()
    assert steps(out).mean() < 0.6 * steps(noisy).mean()
