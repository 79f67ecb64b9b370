import numpy as np
from scipy.spatial.transform import Rotation

import drakedeburr.plan.interpolate as mut


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
