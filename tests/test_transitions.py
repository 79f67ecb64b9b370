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


def test_a_lift_the_wrist_cannot_make_is_made_turned_about_the_tool_axis():
    """Workpiece cell, wrist near its J5 limit (seen between windows of a 21 in hub: every
    lift bent J5 past 115 deg and the move between windows failed): the lift is made with
    the tool turned about its own axis. Read back by FK: the tool point rises by one of the
    lift heights along Z_H, the tool axis is unchanged, the turn is at most 90 deg, the
    joints are in their limits; where the plain lift is possible it is taken unturned."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(load_cell("workpiece_in_hand", "h5_straight"))
    rng = np.random.default_rng(3)
    turned = plain = 0
    lift = 0.2
    heights = lift * np.array([1.0, 0.5, 0.25, 0.125])
    for _ in range(400):
        q = rng.uniform(kin.q_lower, kin.q_upper) * np.array([0.6, 0.5, 0.5, 0.8, 1.0, 0.5])
        q[4] = rng.choice([-1.0, 1.0]) * rng.uniform(1.85, 2.0)
        X = kin.X_HT_from_q(q)
        qq = mut._lifted(kin, q, lift)
        if qq is None:
            continue
        Y = kin.X_HT_from_q(qq)
        assert kin.within_limits(qq)
        np.testing.assert_allclose(Y[:3, 2], X[:3, 2], atol=1e-9)  # the axis kept
        rise = Y[:3, 3] - X[:3, 3]
        np.testing.assert_allclose(rise[:2], 0.0, atol=1e-9)
        assert np.min(np.abs(rise[2] - heights)) < 1e-9
        turn = np.arctan2(*(X[:3, :3].T @ Y[:3, 0])[1::-1])
        assert abs(turn) <= np.pi / 2 + 1e-9
        Xh = X.copy()
        Xh[2, 3] += lift
        q_plain, ok = kin.track(kin.X_WF_from_X_HT(Xh[None]), q)
        if ok[0]:
            np.testing.assert_array_equal(qq, q_plain[0])
            plain += 1
        elif abs(turn) > 1e-6:
            turned += 1
    assert turned >= 5 and plain >= 5, (turned, plain)
