import numpy as np
import pytest

import drakedeburr.plan.targets as mut


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_upright_burr_cuts_a_45_degree_chamfer_of_leg_d():
    # edge along +Y at the origin; material at x < 0 and z < 0; N = +X into the opening
    burr_r, d = 3e-3, 1.5e-3
    C = np.zeros((1, 3))
    n = np.array([[1.0, 0.0, 0.0]])
    axis = np.array([[0.0, 0.0, 1.0]])  # upright: spindle above
    p_T = mut.tool_point_H(C, n, axis, d, burr_r)
    # the cone flank (45 deg) through the contact circle at T's height: radius r at height z
    # above T is r_c + z (it widens toward the spindle)
    def flank_x(z):  # x of the flank on the material side at height z over the face
        return p_T[0, 0] - (burr_r + (z - p_T[0, 2]))
    assert flank_x(0.0) == pytest.approx(-d, abs=1e-12)  # meets the face d into the material
    # and the side wall (x = 0) at depth d below the face
    z_wall = p_T[0, 2] + (p_T[0, 0] - burr_r)  # flank_x(z) = 0
    assert z_wall == pytest.approx(-d, abs=1e-12)


def test_edge_point_inverts_tool_point_for_tilted_axes():
    rng = np.random.default_rng(0)
    C = rng.normal(size=(50, 3)) * 0.1
    n = _unit(rng.normal(size=(50, 3)))
    axis = _unit(n * rng.uniform(0.1, 0.5, (50, 1)) + np.array([0, 0, 1.0]))
    p_T = mut.tool_point_H(C, n, axis, 1.2e-3, 3e-3)
    t = _unit(np.cross(n, [0, 0, 1.0]))
    X = mut.X_HT_from_axis(p_T, axis, t, rng.uniform(-np.pi, np.pi, 50))
    np.testing.assert_allclose(mut.edge_point_from_tool_pose(X, n, 1.2e-3, 3e-3), C, atol=1e-12)


def test_X_HT_from_axis_is_a_rotation_with_z_along_minus_axis_and_spin_recovered():
    rng = np.random.default_rng(0)
    axis = _unit(rng.normal(size=(20, 3)))
    t = _unit(rng.normal(size=(20, 3)))
    spin = rng.uniform(-3, 3, 20)
    X = mut.X_HT_from_axis(np.zeros((20, 3)), axis, t, spin)
    R = X[:, :3, :3]
    np.testing.assert_allclose(np.einsum("nji,njk->nik", R, R), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    np.testing.assert_allclose(R[:, :, 2], -axis, atol=1e-12)
    np.testing.assert_allclose(mut.spin_of(X, t), spin, atol=1e-12)


def test_cutting_lower_on_the_flank_lifts_the_tool_but_keeps_the_chamfer():
    from drakedeburr.cell.tools import BURR

    r, lift = mut.contact_geometry(2.25e-3)
    assert lift == pytest.approx((BURR.contact_radius - r) / np.tan(BURR.cone_half_angle))
    d = 1.5e-3
    n = np.array([[1.0, 0.0, 0.0]])
    axis = np.array([[0.0, 0.0, 1.0]])
    p_T = mut.tool_point_H(np.zeros((1, 3)), n, axis, d, r, lift)
    assert p_T[0, 2] == pytest.approx(lift)
    # flank radius at height z (measured from T along the axis toward the spindle): r_c + z
    z_face = -p_T[0, 2]
    assert p_T[0, 0] - (BURR.contact_radius + z_face) == pytest.approx(-d, abs=1e-12)
    X = mut.X_HT_from_axis(p_T, axis, np.array([[0.0, 1.0, 0.0]]))
    np.testing.assert_allclose(mut.edge_point_from_tool_pose(X, n, d, r, lift), 0.0, atol=1e-15)
    with pytest.raises(ValueError, match="flank"):
        mut.contact_geometry(1.0)


def test_an_axis_into_the_hub_on_a_climbing_edge_names_the_slope():
    """A 3-D window loop (issue 42) that runs along the hub axis, 10 mm down a flank: its
    local frame's upright axis is horizontal and the orientation stage's axis points into the
    hub; the refusal says where and that the edge there runs at ~90 deg to the face plane."""
    from types import SimpleNamespace

    import numpy as np

    from drakedeburr.errors import InputError
    from drakedeburr.frames.local_frames import R_HL_from_normals
    from drakedeburr.plan.window_targets import WindowTargets

    z = np.linspace(0.0, -0.01, 6)
    p = np.c_[np.full(6, 0.15), np.zeros(6), z]
    t = np.tile([0.0, 0.0, -1.0], (6, 1))  # down the flank
    n = np.tile([-1.0, 0.0, 0.0], (6, 1))  # into the opening (toward the axis)
    R = R_HL_from_normals(t, n)
    zT = R[:, :, 2]  # upright in L: +Z_T along Z_L, horizontal here
    tp = SimpleNamespace(window_index=3, kind="large", p_HC=p, R_HL=R, zT_H=zT,
                         cone_zT_H=zT, cone_half_angle=0.1, cone_outer_half_angle=0.12,
                         depth_of_cut=0.5e-3)
    # the axis from tip to spindle (-Z_L) is horizontal here: perpendicular to the face normal
    assert np.abs(zT[:, 2]).max() < 1e-12 and np.allclose(np.linalg.norm(zT, axis=1), 1.0)
    with pytest.raises(InputError, match=r"window 3: tool axis .* points into the hub at CL "
                                         r"point 0 at \[150\.0, 0\.0, 0\.0\] mm .* runs at 90 "
                                         r"deg to the face plane"):
        WindowTargets.from_tool_path(tp)


def _X_HT_np_cross(p_HT, retract_H, t_H, spin=0.0):
    """X_HT_from_axis as written before its cross products were spelled out (np.cross)."""
    p = np.atleast_2d(np.asarray(p_HT, float))
    z = -_unit(np.atleast_2d(np.asarray(retract_H, float)))
    t = np.atleast_2d(np.asarray(t_H, float))
    e1 = _unit(t - np.sum(t * z, axis=-1, keepdims=True) * z)
    e2 = np.cross(z, e1)
    s = np.broadcast_to(np.asarray(spin, float), (p.shape[0],))[:, None]
    x = np.cos(s) * e1 + np.sin(s) * e2
    y = np.cross(z, x)
    X = np.zeros((p.shape[0], 4, 4))
    X[:, :3, 0], X[:, :3, 1], X[:, :3, 2], X[:, :3, 3] = x, y, z, p
    X[:, 3, 3] = 1.0
    return X


@pytest.mark.parametrize("shape_a, shape_b", [((1000, 3), (1000, 3)), ((3,), (3,)),
                                              ((3,), (500, 3)), ((7, 9, 3), (9, 3))])
def test_cross_is_np_cross_bit_for_bit(shape_a, shape_b):
    rng = np.random.default_rng(42)
    for scale in (1e-9, 1.0, 1e6):
        a = rng.normal(size=shape_a) * scale
        b = rng.normal(size=shape_b) * rng.uniform(0.5, 2.0, shape_b)
        got, ref = mut.cross(a, b), np.cross(a, b)
        assert got.shape == ref.shape
        assert got.tobytes() == ref.tobytes()
        # and geometric truth: orthogonal to both factors, |a x b| = |a||b| sin(angle)
        if len(shape_a) == len(shape_b) == 2:
            assert np.allclose(np.sum(got * a, axis=-1), 0.0, atol=1e-9 * scale ** 2)
            na, nb = np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1)
            cos = np.sum(a * b, axis=-1) / (na * nb)
            np.testing.assert_allclose(np.linalg.norm(got, axis=-1),
                                       na * nb * np.sqrt(1 - cos ** 2), rtol=1e-6)


def test_X_HT_from_axis_and_spin_of_equal_the_np_cross_versions_bit_for_bit():
    rng = np.random.default_rng(7)
    m = 2000
    p = rng.normal(size=(m, 3)) * 0.3
    a = _unit(rng.normal(size=(m, 3)))
    t = rng.normal(size=(m, 3))
    for spin in (0.0, -1.1, np.float64(2.5), rng.uniform(-np.pi, np.pi, m)):
        X = mut.X_HT_from_axis(p, a, t, spin)
        assert X.tobytes() == _X_HT_np_cross(p, a, t, spin).tobytes()
        z = X[:, :3, 2]
        e1 = _unit(t - np.sum(t * z, axis=-1, keepdims=True) * z)
        e2 = np.cross(z, e1)
        ref = np.arctan2(np.sum(X[:, :3, 0] * e2, axis=-1), np.sum(X[:, :3, 0] * e1, axis=-1))
        assert mut.spin_of(X, t).tobytes() == ref.tobytes()
    one = mut.X_HT_from_axis(p[0], a[0], t[0], 0.3)
    assert one.tobytes() == _X_HT_np_cross(p[0], a[0], t[0], 0.3).tobytes()


def test_unit_rows_equal_np_linalg_norm_division_bit_for_bit():
    rng = np.random.default_rng(3)
    for shape in ((1000, 3), (3,), (5, 7, 3), (1, 3)):
        v = rng.normal(size=shape) * rng.choice([1e-8, 1.0, 1e5], size=shape[:-1] + (1,))
        ref = v / np.linalg.norm(v, axis=-1, keepdims=True)
        got = mut._unit(v)
        assert got.tobytes() == ref.tobytes()
        np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, rtol=1e-15, atol=0)
