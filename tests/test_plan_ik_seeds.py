"""plan.ik_seeds.reach_shortfall: how far a target lies outside the arm's reach (OPW
wrist-centre annulus), checked on the home pose (reachable) and on the same target carried
away from the robot (the shortfall grows with the distance, at most 1:1)."""

from __future__ import annotations

import functools

import numpy as np

from drakedeburr.plan.ik_seeds import reach_shortfall


@functools.cache
def _kin():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    return cell_kinematics(load_cell("tool_in_hand", "h5_straight"))


def test_home_is_within_reach_and_a_far_target_is_out_by_its_distance():
    kin = _kin()
    X = kin.X_HT_from_q(kin.q_home)
    p, retract, t = X[:3, 3], -X[:3, 2], X[:3, 0]
    assert reach_shortfall(kin, p, retract, t) <= 0.0
    # away from the robot base along the line base -> target (in H)
    p_base_H = np.linalg.inv(kin.X_WH)[:3] @ np.append(kin.X_WB[:3, 3], 1.0)
    d = (p - p_base_H) / np.linalg.norm(p - p_base_H)
    far = [reach_shortfall(kin, p + k * d, retract, t) for k in (3.0, 4.0, 5.0)]
    assert far[0] > 1.0
    steps = np.diff(far)
    assert np.all(steps > 0.9) and np.all(steps <= 1.0 + 1e-9), steps
