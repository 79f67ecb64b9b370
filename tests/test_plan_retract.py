"""plan.transitions.clear_retract / retract_pose (used by plan.finish for each stretch's
approach and retract): the move off the cut along the tool axis where it keeps the clearance,
else tilted toward the hub's face normal +Z_H by the least of RETRACT_TILTS that does.

Seen on the audibot rim (window 8, its first run ending at CL 27): the retract along the axis
ended 1.95 mm from the rim (2.0 mm needed), and the joint move to the window's next run, which
starts there, could not be clear at its own first sample. Here on an analytic wall with a
stand-in arm (the tool point is the joint vector), every figure read back from the path."""

from __future__ import annotations

import numpy as np
import pytest

import drakedeburr.plan.transitions as mut


class _PointArm:
    """A stand-in kinematics: the joints are the tool point (x, y, z, 0, 0, 0); every pose
    is reachable."""

    def X_WF_from_X_HT(self, X):
        return X

    def track(self, X, q0):
        q = np.zeros((len(X), 6))
        q[:, :3] = X[:, :3, 3]
        return q, np.ones(len(X), bool)


class _Wall:
    """The clearance to the plane x = ``x_wall`` [m] (the cell on the side x < x_wall)."""

    def __init__(self, x_wall: float):
        self.x_wall = x_wall

    def min_distances_along(self, q, cap):
        return np.minimum(np.asarray(q)[:, 0] - self.x_wall, cap)


def _pose(lean_deg: float) -> np.ndarray:
    """A cut's end at the origin, its tool axis +Z_T leaning ``lean_deg`` from -Z_H toward
    +X_H (backing off along the axis moves the tool point toward -X_H and up)."""
    a = np.radians(lean_deg)
    z_T = np.array([np.sin(a), 0.0, -np.cos(a)])
    x_T = np.array([np.cos(a), 0.0, np.sin(a)])
    X = np.eye(4)
    X[:3, :3] = np.column_stack([x_T, np.cross(z_T, x_T), z_T])
    return X


def test_retract_pose_turns_the_axis_back_off_toward_the_face_normal():
    X = _pose(50.0)
    np.testing.assert_array_equal(mut.retract_pose(X, 0.015), mut.approach_pose(X, 0.015))
    back = -X[:3, 2]
    for tilt_deg in (30.0, 45.0):
        Y = mut.retract_pose(X, 0.015, np.radians(tilt_deg))
        v = Y[:3, 3] - X[:3, 3]
        np.testing.assert_allclose(Y[:3, :3], X[:3, :3])  # the orientation kept
        assert np.linalg.norm(v) == pytest.approx(0.015)
        assert np.degrees(np.arccos(v @ back / 0.015)) == pytest.approx(tilt_deg)
        assert abs(v[1]) < 1e-15  # in the plane of the axis and +Z_H
        assert v[2] / 0.015 > back[2]  # turned toward +Z_H
    Y = mut.retract_pose(X, 0.015, np.radians(90.0))  # past +Z_H: onto it, not beyond
    np.testing.assert_allclose(Y[:3, 3] - X[:3, 3], [0.0, 0.0, 0.015], atol=1e-15)


def test_the_axis_retract_is_kept_where_it_clears():
    mv = mut.clear_retract(_PointArm(), _Wall(-0.02), _pose(40.0), np.zeros(6), 0.015,
                           2e-3, 2.5e-4)
    assert mv.tilt == 0.0 and mv.tried == ("0 deg",)
    np.testing.assert_allclose(mv.path.X_HT[-1], mut.approach_pose(_pose(40.0), 0.015))
    # read back: the tool point's least distance to the wall, 20 - 15 sin 40 = 10.4 mm
    assert np.min(mv.path.q[1:, 0] + 0.02) == pytest.approx(0.02 - 0.015 * np.sin(np.radians(40)))
    assert mv.clearance >= 2e-3  # the reading capped 1 mm above the bound


def test_a_retract_along_the_axis_into_the_wall_is_lifted_out_of_the_face():
    """The wall 3 mm off: along the axis (40 deg lean) the tool point comes within
    3 - 15 sin 40 < 0 mm; 30 deg toward +Z_H still 3 - 15 sin 10 = 0.40 mm; 60 deg turns it
    onto +Z_H (the axis is 40 deg from it): 3 mm all the way."""
    X = _pose(40.0)
    mv = mut.clear_retract(_PointArm(), _Wall(-0.003), X, np.zeros(6), 0.015, 2e-3, 2.5e-4)
    assert mv.tilt == pytest.approx(np.radians(60.0))
    assert mv.tried == ("0 deg", "30 deg", "60 deg")
    np.testing.assert_allclose(mv.path.X_HT[-1][:3, 3], [0.0, 0.0, 0.015], atol=1e-12)
    q = mv.path.q
    assert np.min(q[1:, 0] + 0.003) >= 2e-3 and mv.clearance == pytest.approx(0.003)


def test_where_no_tilt_clears_the_least_shortfall_is_returned_and_named():
    X = _pose(40.0)
    mv = mut.clear_retract(_PointArm(), _Wall(-0.001), X, np.zeros(6), 0.015, 2e-3, 2.5e-4)
    assert mv.clearance == pytest.approx(0.001) and mv.clearance < 2e-3
    assert mv.tried == ("0 deg", "30 deg", "60 deg", "90 deg")
    assert mv.tilt == pytest.approx(np.radians(60.0))  # the first with the best reading
