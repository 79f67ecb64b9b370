"""hub.import_collision's shell merge under the generator's rule: two touching boxes merge
into one hull; a probe point in the gap their hull would fill keeps them apart."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from drakedeburr.hub import import_collision as mut


def _box(x0: float, x1: float) -> np.ndarray:
    """Corners of a 10 x 10 mm box of 1 mm height from x0 to x1 [m]."""
    return np.array([[x, y, z] for x in (x0, x1) for y in (0.0, 0.01) for z in (0.0, 0.001)])


def test_touching_pieces_merge_unless_a_probe_lies_in_their_hull():
    pieces = [_box(0.0, 0.01), _box(0.01, 0.02)]
    none = SimpleNamespace(pts=np.zeros((0, 3)))
    merged = mut._merge_shell(pieces, none, 0.001)
    assert len(merged) == 1
    lo, hi = merged[0].min(axis=0), merged[0].max(axis=0)
    assert np.allclose(lo, [0, 0, 0]) and np.allclose(hi, [0.02, 0.01, 0.001])
    # a probe inside the merged hull (on the seam) forbids the merge
    probe = SimpleNamespace(pts=np.array([[0.01, 0.005, 0.0005]]))
    assert len(mut._merge_shell(pieces, probe, 0.001)) == 2


def _plate_with_window():
    """A closed 60 x 60 x 10 mm plate with a 20 x 20 mm window through its centre [m]."""
    from manifold3d import Manifold

    plate = Manifold.cube([0.06, 0.06, 0.01]).translate([-0.03, -0.03, 0.0])
    hole = Manifold.cube([0.02, 0.02, 0.02]).translate([-0.01, -0.01, -0.005])
    m = (plate - hole).to_mesh()
    return np.asarray(m.vert_properties)[:, :3].astype(float), np.asarray(m.tri_verts)


def _slab(x0, x1, y0, y1) -> np.ndarray:
    return np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (0.0, 0.01)])


def test_a_piece_left_in_a_window_is_replaced_by_a_shell_of_the_surface_it_covered():
    """A convex piece that still reaches 5 mm into the window after the refinement (here: by
    construction) is dropped; shell pieces of the surface it covered replace it. None of them
    holds a probe, the other pieces are kept as they were, and every point of the plate's
    surface inside the dropped piece lies in a shell piece (re-checked on surface samples with
    each hull's own half-spaces)."""
    import trimesh
    from scipy.spatial import ConvexHull

    from drakedeburr.hub.collision import WindowProbes

    V, F = _plate_with_window()
    good = [_slab(-0.03, -0.01, -0.03, 0.03), _slab(0.01, 0.03, -0.03, 0.03),
            _slab(-0.01, 0.01, 0.01, 0.03)]
    # 5 mm into the window; no vertex and no triangle centre of the mesh in it (grown by 1 mm)
    bad = _slab(0.005, 0.008, -0.025, -0.005)
    xs, zs = np.linspace(0.0055, 0.0075, 5), np.linspace(0.001, 0.009, 5)
    probes = WindowProbes(np.array([[x, -0.009, z] for x in xs for z in zs]))
    assert len(probes.inside(bad)) == len(probes.pts)
    options = SimpleNamespace(shell_thickness=1e-3, shell_max_edge=8e-3, shell_cell=0.04,
                              shell_min_cell=2.5e-3)
    out, stats = mut.shell_patch([*good, bad], V, F, probes, options)
    assert stats["pieces_replaced_by_shell"] == 1 and stats["shell_patch_pieces"] >= 1
    assert all(np.array_equal(a, b) for a, b in zip(out[:3], good, strict=True))
    patch = out[3:]
    assert all(len(probes.inside(p)) == 0 for p in patch)
    pts = trimesh.Trimesh(V, F).sample(20000, seed=1)
    eq_bad = ConvexHull(bad).equations
    covered = pts[np.all(pts @ eq_bad[:, :3].T + eq_bad[:, 3] <= 0.0, axis=1)]
    assert len(covered) > 100
    inside_any = np.zeros(len(covered), bool)
    for p in patch:
        eq = ConvexHull(p).equations
        inside_any |= np.all(covered @ eq[:, :3].T + eq[:, 3] <= 1e-12, axis=1)
    assert inside_any.all(), (~inside_any).sum()


def test_a_triangle_meets_a_piece_whatever_its_size():
    """The exact triangle-against-hull test of the shell patch: a 300 mm sliver through a 4 mm
    box meets it (no vertex is near; subdividing it to 0.25 mm would take 2^11 splits an edge),
    one 0.5 mm beside it meets the box grown by 1 mm, one 1.5 mm beside it does not."""
    from scipy.spatial import ConvexHull

    box = np.array([[x, y, z] for x in (0.0, 0.004) for y in (0.0, 0.004) for z in (0.0, 0.004)])
    eq = ConvexHull(box).equations

    def sliver(y):
        return np.array([[-0.15, y, 0.002], [0.15, y, 0.002], [0.15, y, 0.0021]])

    assert mut._meets(sliver(0.002), eq, 1e-3)
    assert mut._meets(sliver(0.0045), eq, 1e-3)
    assert not mut._meets(sliver(0.0055), eq, 1e-3)
    assert not mut._meets(sliver(0.002) + [0, 0, 0.01], eq, 1e-3)
