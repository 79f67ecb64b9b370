"""Test helpers: a generated hub's mesh written the way real CAD/game exports come.

``degraded_mesh`` turns a generated hub (mesh in H, metres) into the vertices and triangles of
a file a user might bring: scaled to mm, moved into a CAD pose, mirrored front to back, without
its barrel, with holes in the surface, split into unstitched parts.
"""

from __future__ import annotations

import numpy as np


def degraded_mesh(hub, rng, *, mm: bool = True, mirror: bool = False, no_barrel: bool = False,
                  holes: int = 0, split: bool = False, X_MH: np.ndarray | None = None):
    """(V_M (N, 3), F (M, 3), X_MH (4, 4) [m]) of a degraded copy of ``hub``'s mesh.

    Args:
        hub: a HubModel (generated: ``hub.spec`` is set).
        rng: numpy Generator (which triangles are removed).
        mm: scale the file to millimetres.
        mirror: the front face looks along -Z_M (a rotation by pi about X_H).
        no_barrel: drop every triangle outside the face plate (rim barrel and flanges).
        holes: remove this many patches of barrel triangles (the mesh is no longer closed).
        split: duplicate the vertices of the rim's triangles (face plate and rim unstitched).
        X_MH: pose of H in the file [m] (after the mirror); default identity.
    """
    V, F = hub.vertices_H.copy(), hub.faces.copy()
    spec = hub.spec
    c = V[F].mean(axis=1)
    r = np.hypot(c[:, 0], c[:, 1])
    barrel = r > spec.rim_barrel_inner_radius - 0.5e-3
    if no_barrel:
        F = F[~barrel]
    elif holes:
        idx = np.flatnonzero(barrel)
        for _ in range(holes):
            seed = V[F[rng.choice(idx)]].mean(axis=0)
            near = np.linalg.norm(V[F].mean(axis=1) - seed, axis=1) < 8e-3
            F = F[~near]
    if split and not no_barrel:
        c = V[F].mean(axis=1)
        rim = np.hypot(c[:, 0], c[:, 1]) > spec.rim_barrel_inner_radius - 0.5e-3
        used = np.unique(F[rim])
        new = np.arange(len(V), len(V) + len(used))
        remap = np.full(len(V), -1)
        remap[used] = new
        V = np.concatenate([V, V[used]])
        F = F.copy()
        F[rim] = remap[F[rim]]
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    V, F = V[used], remap[F]
    X = np.eye(4) if X_MH is None else np.array(X_MH, float)
    if mirror:  # front face now looks along -Z: rotate by pi about X_H (not a reflection)
        R = np.diag([1.0, -1.0, -1.0])
        X = X.copy()
        X[:3, :3] = X[:3, :3] @ R
    V_M = V @ X[:3, :3].T + X[:3, 3]
    return V_M * (1e3 if mm else 1.0), F, X


def narrow_slot_disc_stl(path, slot_width: float = 8e-3, slots: int = 6):
    """A 500 mm disc, 25 mm thick, with a 60 mm centre bore and ``slots`` radial slots
    ``slot_width`` wide and 80 mm long at r = 120-200 mm, written as a millimetre STL: a
    readable hub whose openings no burr of the tool library fits when the slots are narrower
    than the 6 mm burr's 10 mm (head + 2 x 2 mm clearance). Returns the path."""
    import manifold3d as m3d
    import trimesh

    disc = m3d.Manifold.cylinder(0.025, 0.25, 0.25, 128).translate([0, 0, -0.025])
    cut = m3d.Manifold.cylinder(0.05, 0.03, 0.03, 48).translate([0, 0, -0.04])
    for k in range(slots):
        a = 2 * np.pi * k / slots
        slot = m3d.Manifold.cube([0.08, slot_width, 0.05], center=True).translate(
            [0.16, 0.0, -0.0125]).rotate([0.0, 0.0, float(np.degrees(a))])
        cut = cut + slot
    mesh = (disc - cut).to_mesh()
    trimesh.Trimesh(np.asarray(mesh.vert_properties[:, :3]) * 1e3,
                    np.asarray(mesh.tri_verts)).export(path)
    return path
