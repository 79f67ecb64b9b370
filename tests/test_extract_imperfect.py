"""Imperfect meshes never crash (issue 42 item 3): a low-poly hub (30-facet window outlines)
given as a triangle soup - every triangle its own three vertices (duplicated vertices, no
connectivity: as many parts as triangles), a copy of some triangles moved by 0.1 um (nearly
coincident vertices), the back face left out (open shell) - yields every window with its loop
on the true sharp edge; degenerate input to the numerical steps ends in a named failure.

The truth is the construction: a flat front face at z = 0 with prismatic windows, so the front
boundary is the window polygon at z = 0 (its facets are the polygon's sides)."""

from __future__ import annotations

import numpy as np
import pytest

import drakedeburr.hub.extract as mut
from drakedeburr.errors import InputError, NoCuttableWindow


def _window_polygon(angle: float, n: int) -> np.ndarray:
    """A convex window of n facets: an annulus sector 100-190 mm, 50 deg wide, its corners
    cut off, as a polygon of n vertices (CCW) [m]."""
    a0, a1 = angle - np.radians(25), angle + np.radians(25)
    m = n // 4
    outer = [(0.19 * np.cos(t), 0.19 * np.sin(t)) for t in np.linspace(a0, a1, m + 1)]
    inner = [(0.10 * np.cos(t), 0.10 * np.sin(t)) for t in np.linspace(a1, a0, n - m - 1)]
    return np.array(outer + inner)


def _soup_hub(n_facets: int = 30):
    """(trimesh soup, truth loops (5 x (n, 3))): disc R 0.25 m, 20 mm thick, front face z = 0,
    5 windows of ``n_facets`` facets; back face dropped; duplicated and jittered triangles."""
    import manifold3d as m3d
    import trimesh

    disc = m3d.Manifold.cylinder(0.02, 0.25, 0.25, 64).translate([0, 0, -0.02])
    truth, cut = [], m3d.Manifold.cylinder(0.06, 0.03, 0.03, 24).translate([0, 0, -0.04])
    for k in range(5):
        xy = _window_polygon(2 * np.pi * k / 5 + 0.3, n_facets)
        truth.append(np.c_[xy, np.zeros(len(xy))])
        cut = cut + m3d.Manifold.extrude(m3d.CrossSection([xy.tolist()]), 0.06).translate(
            [0, 0, -0.04])
    mesh = (disc - cut).to_mesh()
    V, F = np.asarray(mesh.vert_properties[:, :3], float), np.asarray(mesh.tri_verts)
    tri = V[F]
    n_z = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2]
    back = (np.abs(tri[:, :, 2] + 0.02).max(axis=1) < 1e-9) & (n_z < 0)
    tri = tri[~back]  # open shell: no back face
    rng = np.random.default_rng(0)
    extra = tri[rng.choice(len(tri), len(tri) // 10, replace=False)] + 1e-7  # near copies
    soup = np.concatenate([tri, extra])
    faces = np.arange(3 * len(soup)).reshape(-1, 3)
    return trimesh.Trimesh(soup.reshape(-1, 3), faces, process=False), truth


def _distance_to_polygon(p: np.ndarray, poly: np.ndarray) -> np.ndarray:
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    d = p[:, None, :] - a[None]
    t = np.clip(np.einsum("kij,ij->ki", d, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    return np.linalg.norm(d - t[..., None] * ab[None], axis=2).min(axis=1)


@pytest.mark.parametrize("n_facets", [20, 60])
def test_low_poly_soup_hub_gives_every_window_on_its_sharp_edge(n_facets):
    mesh, truth = _soup_hub(n_facets)
    assert not mesh.is_watertight and len(mesh.vertices) == 3 * len(mesh.faces)
    res = mut.extract_window_edges(mesh, source="soup", axis_M=np.array([0.0, 0.0, 1.0]),
                                   origin_M=np.zeros(3))
    assert len(res.windows) == 5 and res.notes["rejected"] == []
    for w in res.windows:
        c = w.p_HE.mean(axis=0)
        poly = min(truth, key=lambda t: np.linalg.norm(t.mean(axis=0)[:2] - c[:2]))
        d = _distance_to_polygon(w.p_HE, poly)
        # the sharp edge of a prismatic window: the loop runs on it (ray-cast profiles on a
        # 0.1 mm grid, bisected outline): within 0.2 mm, on the face (z = 0)
        assert d.max() < 0.2e-3, d.max()
        assert np.abs(w.p_HE[:, 2]).max() < 1e-5


def test_degenerate_meshes_end_in_named_failures():
    import trimesh

    # all vertices on one line: no hub frame, no opening (LAPACK/Qhull would choke on it)
    V = np.c_[np.linspace(0, 0.3, 30), np.zeros(30), np.zeros(30)]
    F = np.array([[i, i + 1, i + 2] for i in range(28)])
    flat = trimesh.Trimesh(V, F, process=False)
    with pytest.raises(InputError) as err:
        mut.extract_window_edges(flat, source="line.stl")
    assert str(err.value).startswith("line.stl:")
    # non-finite coordinates reach the numerical steps: a named failure, not a crash
    mesh, _ = _soup_hub(20)
    bad = trimesh.Trimesh(np.where(np.arange(len(mesh.vertices))[:, None] == 7, np.nan,
                                   mesh.vertices), mesh.faces, process=False)
    with pytest.raises(InputError) as err:
        mut.extract_window_edges(bad, source="nan.stl")
    assert str(err.value).startswith("nan.stl:")
    assert isinstance(err.value, (NoCuttableWindow, InputError))
