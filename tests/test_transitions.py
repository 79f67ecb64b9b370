"""plan.transitions: approach poses and a collision-checked joint move between two poses."""

import numpy as np

import drakedeburr.plan.transitions as mut


def test_approach_pose_backs_off_along_the_tool_axis():
    rng = np.random.default_rng(0)
    from scipy.spatial.transform import Rotation

    X = np.eye(4)
    X[:3, :3] = Rotation.random(random_state=1).as_matrix()
    X[:3, 3] = rng.normal(size=3)
    Y = mut.approach_pose(X, 0.015)
    np.testing.assert_allclose(Y[:3, :3], X[:3, :3])
    # the tip moves 15 mm toward the spindle: -Z_T
    np.testing.assert_allclose(Y[:3, 3] - X[:3, 3], -0.015 * X[:3, 2], atol=1e-15)
