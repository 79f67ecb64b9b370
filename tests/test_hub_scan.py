import math

import numpy as np
import pytest

import drakedeburr.hub.scan as mut
from drakedeburr.errors import InputError
from drakedeburr.hub.model import load_hub


@pytest.fixture(scope="module")
def hub():
    return load_hub("h5_split")


@pytest.fixture(scope="module")
def scene(hub):
    import open3d as o3d

    s = o3d.t.geometry.RaycastingScene()
    s.add_triangles(o3d.core.Tensor(hub.vertices_H.astype(np.float32)),
                    o3d.core.Tensor(hub.faces.astype(np.uint32)))
    return s


def _dist(scene, p):
    import open3d as o3d

    return scene.compute_signed_distance(o3d.core.Tensor(p.astype(np.float32))).numpy()


def test_noise_sigma_is_measured_back(hub, scene):
    cloud = mut.simulate_scan(hub, mut.ScannerModel(sigma=5e-5), spacing=3e-3, seed=1)
    assert 10_000 < len(cloud.p_S) < 100_000
    d = _dist(scene, cloud.p_S)
    # points near edges can be nearer another face; the bulk follows the sigma
    core = d[np.abs(d) < 5 * 5e-5]
    assert core.std() == pytest.approx(5e-5, rel=0.05)
    assert abs(np.mean(core)) < 5e-6
    assert cloud.n_S is None and cloud.meta["count"] == len(cloud.p_S)


def test_noise_free_scan_lies_on_the_visible_surface(hub, scene):
    cloud = mut.simulate_scan(hub, mut.ScannerModel(sigma=0.0), spacing=4e-3, seed=0,
                              with_normals=True)
    # exact float64 check: each point lies inside some mesh triangle (open3d's distances are
    # float32, trimesh's closest_point errs by ~5e-5 m on some triangles)
    sub = cloud.p_S[np.random.default_rng(0).choice(len(cloud.p_S), 150, replace=False)]
    T = hub.vertices_H[hub.faces]
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    n = np.cross(e1, e2)
    keep = np.linalg.norm(n, axis=1) > 1e-14
    T, e1, e2, n = T[keep], e1[keep], e2[keep], n[keep]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    g11, g12, g22 = np.sum(e1 * e1, 1), np.sum(e1 * e2, 1), np.sum(e2 * e2, 1)
    det = g11 * g22 - g12 * g12
    for p in sub:
        w = p - T[:, 0]
        plane = np.abs(np.sum(w * n, axis=1))
        b1, b2 = np.sum(w * e1, 1), np.sum(w * e2, 1)
        u = (g22 * b1 - g12 * b2) / det
        v = (g11 * b2 - g12 * b1) / det
        inside = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9)
        assert inside.any() and plane[inside].min() < 1e-12
    n = cloud.n_S
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-9)
    # nothing facing away from the scanner (the back of the face, the barrel's outside)
    assert n[:, 2].min() > -0.2
    # the tilted views see the window walls (normals perpendicular to the axis)
    walls = np.abs(n[:, 2]) < 1e-6
    r = np.hypot(cloud.p_S[:, 0], cloud.p_S[:, 1])
    win_walls = walls & (r > hub.spec.window_inner_radius - 1e-3) & (
        r < hub.spec.window_outer_radius + 1e-3)
    assert win_walls.sum() > 200
    face_on = mut.simulate_scan(hub, mut.ScannerModel(sigma=0.0, n_tilted=0), spacing=4e-3,
                                seed=0, with_normals=True)
    r0 = np.hypot(face_on.p_S[:, 0], face_on.p_S[:, 1])
    walls0 = (np.abs(face_on.n_S[:, 2]) < 1e-6) & (r0 < hub.spec.window_outer_radius + 1e-3)
    assert walls0.sum() < 0.5 * win_walls.sum()  # face-on: only walls facing the axis


def test_deterministic_for_a_seed(hub):
    a = mut.simulate_scan(hub, spacing=5e-3, seed=3)
    b = mut.simulate_scan(hub, spacing=5e-3, seed=3)
    c = mut.simulate_scan(hub, spacing=5e-3, seed=4)
    np.testing.assert_array_equal(a.p_S, b.p_S)
    assert a.p_S.shape != c.p_S.shape or not np.array_equal(a.p_S, c.p_S)


def test_partial_sector_and_edge_band(hub):
    sector = (math.radians(-20.0), math.radians(80.0))
    cloud = mut.simulate_scan(hub, mut.ScannerModel(sigma=0.0), spacing=3e-3, partial=sector)
    th = np.arctan2(cloud.p_S[:, 1], cloud.p_S[:, 0])
    assert th.min() >= sector[0] - 1e-9 and th.max() <= sector[1] + 1e-9
    assert th.max() - th.min() > math.radians(95.0)
    from scipy.spatial import cKDTree

    band = mut.simulate_scan(hub, mut.ScannerModel(sigma=0.0), spacing=1e-3,
                             max_edge_distance=4e-3)
    edge = np.concatenate([w.p_HE for w in hub.windows])
    d, _ = cKDTree(edge).query(band.p_S)
    assert d.max() <= 4e-3 + 1e-9 and len(band.p_S) > 5000


def test_view_direction_is_respected(hub):
    back = mut.simulate_scan(hub, mut.ScannerModel(sigma=0.0, view_dir=(0, 0, -1), n_tilted=0),
                             spacing=5e-3, with_normals=True)
    assert back.n_S[:, 2].max() < 0.2  # nothing facing +Z_H
    assert back.n_S[:, 2].mean() < -0.3


def test_scan_in_a_moved_frame(hub):
    rng = np.random.default_rng(0)
    a = rng.uniform(-math.pi, math.pi)
    X = np.eye(4)
    X[:3, :3] = [[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]]
    X[:3, 3] = rng.uniform(-5e-3, 5e-3, 3)
    ref = mut.simulate_scan(hub, spacing=5e-3, seed=2, with_normals=True)
    moved = mut.simulate_scan(hub, spacing=5e-3, seed=2, with_normals=True, X_SH=X)
    np.testing.assert_allclose(moved.p_S, ref.p_S @ X[:3, :3].T + X[:3, 3], atol=1e-15)
    np.testing.assert_allclose(moved.n_S, ref.n_S @ X[:3, :3].T, atol=1e-15)
    assert moved.meta["frame"] == "S"


@pytest.mark.parametrize("kwargs, match", [
    ({"X_SH": np.diag([1.0, 1.0, -1.0, 1.0])}, "X_SH"),
    ({"scanner": mut.ScannerModel(sigma=-1.0)}, "sigma"),
    ({"spacing": 0.0}, "spacing"),
    ({"scanner": mut.ScannerModel(view_dir=(0, 0, 0))}, "view_dir"),
    ({"partial": (1.0, 0.5)}, "partial"),
])
def test_bad_arguments(hub, kwargs, match):
    with pytest.raises(InputError, match=match):
        mut.simulate_scan(hub, **kwargs)
