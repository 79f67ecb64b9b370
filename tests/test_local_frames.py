import numpy as np
import pytest

import drakedeburr.frames.local_frames as mut
from drakedeburr.errors import InputError


def _random_tn(rng, m=200):
    t = rng.normal(size=(m, 3))
    n = rng.normal(size=(m, 3))
    return t, n


def test_frames_orthonormal_right_handed_and_follow_eqs_4_6():
    rng = np.random.default_rng(0)
    t, n = _random_tn(rng)
    R = mut.R_HL_from_normals(t, n)
    assert mut.check_rotations(R).max() < 1e-12
    t_hat = t / np.linalg.norm(t, axis=1)[:, None]
    np.testing.assert_allclose(R[:, :, 1], t_hat, atol=1e-12)  # Y = T
    b = np.cross(t, n)  # eq. 4; the right-handed frame's Z is -B
    np.testing.assert_allclose(R[:, :, 2], -b / np.linalg.norm(b, axis=1)[:, None], atol=1e-12)
    # N_new lies in the (T, N) plane on N's side
    assert np.all(np.einsum("ij,ij->i", R[:, :, 0], n) > 0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", R[:, :, 0], b), 0, atol=1e-12)
    np.testing.assert_allclose(np.cross(R[:, :, 0], R[:, :, 1]), R[:, :, 2], atol=1e-12)


def test_flat_ccw_window_gives_z_into_the_material():
    ang = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    t = np.c_[-np.sin(ang), np.cos(ang), np.zeros(40)]  # CCW about +Z
    n_wall = -np.c_[np.cos(ang), np.sin(ang), np.zeros(40)]  # into the opening (centre)
    R = mut.R_HL_from_normals(t, n_wall)
    np.testing.assert_allclose(R[:, :, 2], np.tile([0, 0, -1.0], (40, 1)), atol=1e-12)


def test_angle_axis_round_trip_both_ways():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1.5, 1.5, 500)
    b = rng.uniform(-1.5, 1.5, 500)
    v = mut.axis_from_angles(a, b)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-14)
    a2, b2 = mut.angles_from_axis(v)
    np.testing.assert_allclose(a2, a, atol=1e-12)
    np.testing.assert_allclose(b2, b, atol=1e-12)
    w = rng.normal(size=(500, 3))
    w[:, 2] = np.abs(w[:, 2]) + 0.1  # the map covers the hemisphere around B
    a3, b3 = mut.angles_from_axis(w)
    np.testing.assert_allclose(mut.axis_from_angles(a3, b3), w / np.linalg.norm(w, axis=1)[:, None],
                               atol=1e-12)


def test_angle_definition_matches_rotations_and_documented_signs():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(1)
    for a, b in rng.uniform(-1, 1, (20, 2)):
        # intrinsic: first about Y by -theta_A, then about the new X by theta_B
        R = Rotation.from_euler("YX", [-a, b]).as_matrix()
        np.testing.assert_allclose(mut.axis_from_angles(a, b), R[:, 2], atol=1e-12)
    v = mut.axis_from_angles(0.3, 0.0)
    assert v[0] < 0  # positive theta_A: tip toward the material (-N), spindle over the opening
    v = mut.axis_from_angles(0.0, 0.3)
    assert v[1] < 0  # positive theta_B tilts the tip back against the feed (T): top leads
    # the source's "angle between axis and normal" is pi/2 - theta_A for theta_B = 0
    np.testing.assert_allclose(np.arccos(-mut.axis_from_angles(0.3, 0.0)[0]), np.pi / 2 - 0.3)


def test_axis_jacobian_matches_finite_differences():
    rng = np.random.default_rng(2)
    a, b = rng.uniform(-1, 1, 30), rng.uniform(-1, 1, 30)
    J = mut.axis_jacobian(a, b)
    h = 1e-6
    fd_a = (mut.axis_from_angles(a + h, b) - mut.axis_from_angles(a - h, b)) / (2 * h)
    fd_b = (mut.axis_from_angles(a, b + h) - mut.axis_from_angles(a, b - h)) / (2 * h)
    np.testing.assert_allclose(J[..., 0], fd_a, atol=1e-8)
    np.testing.assert_allclose(J[..., 1], fd_b, atol=1e-8)


def test_world_axes_round_trip_through_frames():
    rng = np.random.default_rng(3)
    t, n = _random_tn(rng, 50)
    R = mut.R_HL_from_normals(t, n)
    a, b = rng.uniform(0.09, 0.44, 50), rng.uniform(0.09, 0.44, 50)
    axis_H = mut.zT_H_from_angles(R, a, b)
    a2, b2 = mut.angles_from_zT_H(R, axis_H)
    np.testing.assert_allclose(a2, a, atol=1e-12)
    np.testing.assert_allclose(b2, b, atol=1e-12)


def test_normal_parallel_to_tangent_is_an_input_error():
    t = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    n = np.array([[2.0, 0, 0], [1.0, 0, 0]])
    with pytest.raises(InputError, match=r"window 7: normal parallel to tangent at point\(s\) \[0"):
        mut.R_HL_from_normals(t, n, name="window 7")


def test_tool_rotation_is_proper_and_its_z_is_the_axis():
    rng = np.random.default_rng(4)
    a, b = rng.uniform(-1, 1, 40), rng.uniform(-1, 1, 40)
    R = mut.R_LT_from_angles(a, b)
    assert mut.check_rotations(R).max() < 1e-12
    np.testing.assert_allclose(R[:, :, 2], mut.axis_from_angles(a, b), atol=1e-14)
