"""The burr head read against a triangle mesh (verify.true_surface): the cone's signed
distance against its analytic values, the branch and bound against a dense brute-force
reading (a second implementation) and against planes whose answer is known, the in-centre
guard, and burr_contact on a hub whose collision pieces stand proud of its surface."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.cell.true_surface import (
    burr_cone,
    cone_signed_distance,
    true_surface_distances,
)

CONE = burr_cone()


def _pose(R=None, p=None) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = np.eye(3) if R is None else R
    X[:3, 3] = np.zeros(3) if p is None else p
    return X


def _plane(origin, normal, half=0.05, n=1):
    """A square of side 2*half through ``origin`` normal to ``normal``: (n x n) quads, two
    triangles each (coarse on purpose: the bound splits them)."""
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    g = np.linspace(-half, half, n + 1)
    V = np.array([origin + a * u + b * v for a in g for b in g])
    F = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, \
                i * (n + 1) + j + 1
            F += [(a, b, c), (a, c, d)]
    return V, np.array(F)


def _hub(V, F, pieces=()):
    return SimpleNamespace(vertices_H=V, faces=F, collision_paths=tuple(pieces))


def test_cone_signed_distance_matches_its_analytic_values():
    c = CONE
    zb, za, a = c.z_base, c.z_apex, c.alpha
    z = np.linspace(zb + 1e-4, za - 1e-4, 50)
    on_axis = np.stack([np.zeros_like(z), np.zeros_like(z), z], axis=1)
    expect = -np.minimum(z - zb, (za - z) * math.sin(a))
    assert np.allclose(cone_signed_distance(c, on_axis), expect, atol=1e-12)
    # beyond the apex on the axis: the distance to the apex; below the base: to the base
    assert cone_signed_distance(c, np.array([[0, 0, za + 2e-3]]))[0] == pytest.approx(2e-3)
    assert cone_signed_distance(c, np.array([[1e-3, 0, zb - 3e-3]]))[0] == pytest.approx(3e-3)
    # off the flank along its outward normal, at any azimuth
    for phi in np.linspace(0, 2 * math.pi, 7):
        zm = 0.5 * (zb + za)
        r = (za - zm) * math.tan(a)
        nrm = np.array([math.cos(a) * math.cos(phi), math.cos(a) * math.sin(phi), math.sin(a)])
        p = np.array([r * math.cos(phi), r * math.sin(phi), zm]) + 1.5e-3 * nrm
        assert cone_signed_distance(c, p[None])[0] == pytest.approx(1.5e-3, abs=1e-12)
    # in-centre: depth = in-radius, equal to base and flank
    assert -cone_signed_distance(c, c.incentre_T[None])[0] == pytest.approx(c.inradius)


@pytest.mark.parametrize("height", [-1e-3, 0.5e-3, 2.0e-3])
def test_a_plane_across_the_axis_reads_its_depth_on_the_axis(height):
    """A plane normal to the axis at z = height cuts the cone; its deepest point is on the
    axis: depth min(z - z_b, (z_a - z) sin alpha) (the plane's two triangles are 100 mm
    wide: the bound has to split them)."""
    c = CONE
    V, F = _plane(np.array([0.0, 0.0, height]), [0, 0, 1])
    r = true_surface_distances(_hub(V, F), _pose()[None], [0], reach=0.0, cone=c)
    expect = -min(height - c.z_base, (c.z_apex - height) * math.sin(c.alpha))
    assert r.value[0] <= expect + 1e-12  # a lower bound of the signed distance
    assert r.value[0] >= expect - 2 * r.resolution
    assert not r.engulfed[0]


def test_the_bound_agrees_with_a_dense_brute_force_reading():
    """Tilted planes and a fine mesh: the branch and bound's reading against the largest
    depth of 0.02 mm-spaced surface points (a second implementation); the dense reading can
    only be shallower, by at most its spacing."""
    rng = np.random.default_rng(7)
    c = CONE
    for _ in range(6):
        normal = rng.normal(size=3)
        origin = np.array([0.0, 0.0, 0.5 * (c.z_base + c.z_apex)]) + rng.normal(scale=1e-3,
                                                                             size=3)
        V, F = _plane(origin, normal, half=0.012, n=3)
        angle = rng.uniform(0, 2 * math.pi)
        Rz = np.array([[math.cos(angle), -math.sin(angle), 0],
                       [math.sin(angle), math.cos(angle), 0], [0, 0, 1]])
        p = rng.normal(scale=2e-3, size=3)
        X = _pose(Rz, p)
        r = true_surface_distances(_hub(V, F), X[None], [0], reach=3e-3, cone=c)
        # dense: barycentric grid on every triangle, into T
        pts = []
        m = 600
        ii, jj = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
        keep = ii + jj <= m
        u, v = ii[keep] / m, jj[keep] / m
        for f in F:
            a, b, cc = V[f]
            pts.append(a + u[:, None] * (b - a) + v[:, None] * (cc - a))
        P = np.concatenate(pts)
        dense = min(3e-3, float(cone_signed_distance(c, (P - p) @ Rz).min()))
        assert r.value[0] <= dense + 1e-12
        assert r.value[0] >= dense - 0.02e-3 - 2 * r.resolution


def test_a_burr_inside_a_piece_is_marked_engulfed(tmp_path):
    """The in-centre guard: with the burr's in-centre inside a collision piece the reading
    is marked (the material may hold the cone's deepest point, which no surface point
    shows); outside every piece it is not."""
    import trimesh

    box = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    path = tmp_path / "piece.obj"
    box.export(path)
    V, F = np.asarray(box.vertices), np.asarray(box.faces)
    inside = _pose(p=-CONE.incentre_T)  # in-centre at the box centre
    outside = _pose(p=np.array([0.0, 0.0, 0.03]))
    r = true_surface_distances(_hub(V, F, [path]), np.stack([inside, outside]), [0, 1],
                               reach=2e-3)
    assert r.engulfed.tolist() == [True, False]
    # the surface alone (the cone within the box: no face point inside it) reads nothing
    assert r.value[0] == pytest.approx(2e-3, abs=1e-9)


def test_burr_contact_reads_the_true_surface_where_the_pieces_stand_proud(tmp_path):
    """burr_contact on a hub of one flat face whose collision piece stands 2 mm proud of
    it: the burr 1.0 mm deep into the face fails against the piece (3.0 mm > 1.5 + 0.17 +
    0.5 mm) and passes against the true face (limit: depth of cut + edge tolerance); 2.0 mm
    deep it fails against both."""
    import trimesh

    from drakedeburr.config import Config, ProcessParameters, Recipe, default_tolerances
    from drakedeburr.verify import checks_distance
    from drakedeburr.verify.types import KIND_CODE

    c = CONE
    V, F = _plane(np.zeros(3), [0, 0, 1], half=0.05)
    piece = trimesh.creation.box(extents=(0.1, 0.1, 0.022))
    piece.apply_translation([0, 0, -0.009])  # top at z = +2 mm, the face at 0
    path = tmp_path / "piece.obj"
    piece.export(path)
    hub = _hub(V, F, [path])
    tol = default_tolerances()
    proc = ProcessParameters()
    depth_of_cut = proc.depth_of_cut("large")
    flip = np.diag([1.0, -1.0, -1.0])  # tool axis +Z_T pointing down at the face
    # apex reaches `pen` below the face: the face's depth in the cone is pen * sin(alpha)
    # at the axis (flank) or less; place the apex at -pen/sin(alpha)
    results = {}
    for pen in (1.0e-3, 2.0e-3):
        apex_below = pen / math.sin(c.alpha)
        X = _pose(flip, np.array([0.0, 0.0, c.z_apex - apex_below]))
        X_HT = X[None]
        piece_reading = -(pen + 2e-3)  # what the scene graph would read against the piece
        sp = SimpleNamespace(
            hub_model=hub,
            samples=SimpleNamespace(kind=np.array([KIND_CODE["cut"]]), window=np.array([0]),
                                    X_HT=X_HT),
            distances=SimpleNamespace(burr=np.array([piece_reading]),
                                      burr_pair=[("spindle::burr/burr_head", "hub::hub/p")]),
            depth_of_cut=lambda w: depth_of_cut,
            where=lambda i: {},
            _memo={},
        )
        sp.memo = lambda key, f, sp=sp: sp._memo.setdefault(key, f())
        cfg = Config("tool_in_hand", "h5_straight", Recipe(process=proc), tol)
        results[pen] = checks_distance.burr_contact(sp, cfg)
    ok, bad = results[1.0e-3], results[2.0e-3]
    assert ok.passed and ok.limit == pytest.approx(-(depth_of_cut + tol.edge_deviation))
    assert "re-read against the true surface" in ok.detail
    # the face normal to the axis: its depth is the apex's depth along the flank normal
    assert -1.0e-3 - 2 * 2e-6 <= ok.value <= -1.0e-3 + 1e-12
    assert not bad.passed and bad.value < bad.limit


def _l_block():
    """An L-shaped block (two 40 x 20 x 20 mm bars, closed and outward oriented) and the
    convex hull of it, a collision piece that bridges the concave corner: the square
    x, y in [20, 40] mm is inside the piece and outside the material."""
    import manifold3d

    bar_x = manifold3d.Manifold.cube([0.04, 0.02, 0.02])
    bar_y = manifold3d.Manifold.cube([0.02, 0.04, 0.02])
    mesh = (bar_x + bar_y).to_mesh()
    return np.asarray(mesh.vert_properties, float)[:, :3], np.asarray(mesh.tri_verts, int)


def test_an_in_centre_inside_a_piece_but_outside_a_closed_mesh_is_read(tmp_path):
    """The in-centre in the corner a piece bridges: with the closed mesh the winding number
    finds it outside the material and the surface reading stands (nothing within reach);
    with the mesh opened (inside undefined) or the in-centre in the material, the pieces'
    reading is kept."""
    import trimesh

    V, F = _l_block()
    hull = trimesh.Trimesh(V, F).convex_hull
    path = tmp_path / "piece.obj"
    hull.export(path)
    corner = _pose(p=np.array([0.03, 0.03, 0.01]) - CONE.incentre_T)  # 10 mm from each wall
    solid = _pose(p=np.array([0.01, 0.01, 0.01]) - CONE.incentre_T)
    X = np.stack([corner, solid])
    closed = true_surface_distances(_hub(V, F, [path]), X, [0, 1], reach=2e-3)
    assert closed.engulfed.tolist() == [False, True]
    assert closed.value[0] == pytest.approx(2e-3, abs=1e-9)
    opened = true_surface_distances(_hub(V, F[2:], [path]), X, [0, 1], reach=2e-3)
    assert opened.engulfed.tolist() == [True, True]
    # the closed mesh is kept per mesh content: the same arrays (copies) give the kept
    # answer, the opened mesh read after it its own
    from drakedeburr.cell.true_surface import _closed_mesh

    assert _closed_mesh(_hub(V.copy(), F.copy())) is _closed_mesh(_hub(V, F))
    assert _closed_mesh(_hub(V, F[2:])) is None


def test_the_depth_lies_below_its_tangent_plane_everywhere():
    """The concave bound the branch and bound settles triangles with: at random points y
    inside, outside and on the axis, depth(x) <= depth(y) + g(y) . (x - y) for random x, and
    the depth equals minus the cone's signed distance."""
    from drakedeburr.cell.true_surface import _depth_supergradient

    rng = np.random.default_rng(11)
    c = CONE
    y = rng.uniform([-8e-3, -8e-3, -6e-3], [8e-3, 8e-3, 6e-3], size=(4000, 3))
    y[:200, :2] = 0.0  # on the axis (the supergradient's ambiguous meridian)
    x = y + rng.normal(scale=3e-3, size=y.shape)
    f_y, g_y = _depth_supergradient(c, y)
    f_x, _ = _depth_supergradient(c, x)
    assert np.allclose(f_y, -cone_signed_distance(c, y), atol=1e-15)
    assert np.allclose(np.linalg.norm(g_y, axis=1), 1.0)
    assert np.all(f_x <= f_y + np.einsum("ni,ni->n", g_y, x - y) + 1e-12)
