"""hub.import_collision's surface shell of an open mesh: behind the surface where the front view
tells the material's side (front_sides), half either side where it does not."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from drakedeburr.hub import import_collision as mut
from drakedeburr.hub.collision import WindowProbes

TOP = 0.01  # [m] height of the plate's front face
HALF_WINDOW = 0.01  # [m] the window is 20 x 20 mm


def _open_face_with_window():
    """The front face (z = 10 mm) of a 60 x 60 mm plate and the four walls of its 20 x 20 mm
    window, nothing else: an open mesh, consistently wound (outward) [m]."""
    from manifold3d import Manifold

    plate = Manifold.cube([0.06, 0.06, TOP]).translate([-0.03, -0.03, 0.0])
    hole = Manifold.cube([0.02, 0.02, 0.02]).translate([-HALF_WINDOW, -HALF_WINDOW, -0.005])
    m = (plate - hole).to_mesh()
    V, F = np.asarray(m.vert_properties)[:, :3].astype(float), np.asarray(m.tri_verts)
    n = trimesh.Trimesh(V, F, process=False).face_normals
    c = V[F].mean(axis=1)
    wall = (np.abs(n[:, 2]) < 0.1) & np.all(np.abs(c[:, :2]) < HALF_WINDOW + 1e-6, axis=1)
    keep = (n[:, 2] > 0.5) | wall
    return V, F[keep]


def _wall_probes(off: float) -> WindowProbes:
    """Points ``off`` inside the window from its four walls, through the face's height."""
    s = np.linspace(-0.008, 0.008, 9)
    z = np.linspace(0.001, 0.009, 5)
    e = HALF_WINDOW - off
    pts = [[a, b, h] for h in z for t in s for a, b in ((e, t), (-e, t), (t, e), (t, -e))]
    return WindowProbes(np.array(pts))


def _options(**kw):
    base = dict(shell_thickness=1e-3, shell_max_edge=8e-3, shell_cell=0.04,
                shell_min_cell=2.5e-3, shell_behind=True)
    base.update(kw)
    return SimpleNamespace(**base)


def _covered(pieces, pts) -> np.ndarray:
    inside = np.zeros(len(pts), bool)
    for p in pieces:
        eq = ConvexHull(p).equations
        inside |= np.all(pts @ eq[:, :3].T + eq[:, 3] <= 1e-9, axis=1)
    return inside


def test_front_sides_reads_the_winding_from_the_front_view():
    V, F = _open_face_with_window()
    assert np.all(mut.front_sides(V, F) == 1.0)
    assert np.all(mut.front_sides(V, F[:, ::-1]) == -1.0)
    bad = F.copy()
    bad[::2] = bad[::2, ::-1]  # inconsistent winding: the side is not known
    assert np.all(mut.front_sides(V, bad) == 0.0)


def test_shell_lies_behind_the_surface_and_covers_it():
    """Known side: no piece stands above the front face or reaches into the window (probes
    0.2 mm off the walls: the cells split until none holds one), and every sampled surface
    point lies in a piece; the same with the winding flipped. Unknown side: the shell is half
    either side (0.5 mm above the face), and the walls' shell holds probes 0.2 mm into the
    window whatever the cell size."""
    V, F = _open_face_with_window()
    near = _wall_probes(0.2e-3)
    surface = trimesh.Trimesh(V, F, process=False).sample(4000, seed=2)
    for faces in (F, F[:, ::-1]):
        pieces, stats = mut.shell_pieces(V, faces, near, _options())
        top = max(float(p[:, 2].max()) for p in pieces)
        assert top <= TOP + 1e-9, top
        assert stats["pieces_with_probes"] == 0
        assert sum(len(near.inside(p)) for p in pieces) == 0
        assert _covered(pieces, surface).all()
        # the shell is shell_thickness deep behind the face: a point 0.9 mm below it is held
        below = surface[surface[:, 2] > TOP - 1e-9] - [0.0, 0.0, 0.9e-3]
        assert _covered(pieces, below).all()
    pieces, stats = mut.shell_pieces(V, F, near, _options(shell_behind=False))
    top = max(float(p[:, 2].max()) for p in pieces)
    assert abs(top - (TOP + 0.5e-3)) < 1e-9, top
    assert stats["pieces_with_probes"] > 0
