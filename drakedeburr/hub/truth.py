"""Ground-truth window edge loops of a generated hub, read from its final mesh.

The deburring edge of a window is ring 0 of its edge profile (:mod:`drakedeburr.hub.surface`):
the line where the front face ends, i.e. where it meets the wall (sharp edge) or the wall's
round. Its points are mesh vertices (the lifted boundary of the front face's triangulation),
checked to be joined by mesh edges, and resampled along those edges at
<= ``edge_sample_spacing``, so every loop point lies on the mesh. Normals are analytic:
``n_wall_H`` is the outline normal (into the opening) tilted up by the wall draft,
``n_face_H`` the front face's normal, ``t_H = n_wall_H x n_face_H`` (loop direction).
"""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.hub.outline import Window
from drakedeburr.hub.solid import PlateGeometry, edge_set
from drakedeburr.hub.spec import HubSpec

__all__ = ["ground_truth_loops", "loop_curvature"]


def _wall_normals_2d(xy: np.ndarray) -> np.ndarray:
    """Vertex normals [-] of the CCW outline ``xy`` [m]: mean of the adjacent segment normals
    (left of CCW = into the opening)."""
    seg = np.roll(xy, -1, axis=0) - xy
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    seg_n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    vert_n = seg_n + np.roll(seg_n, 1, axis=0)
    return vert_n / np.linalg.norm(vert_n, axis=1, keepdims=True)


def _face_normals(spec: HubSpec, geom: PlateGeometry, p: np.ndarray) -> np.ndarray:
    """(N, 3) front face normals at loop points ``p`` [m]."""
    if geom.surface.has_twist or geom.surface.has_rise:
        return geom.surface.normal(p[:, :2] * 1e3)
    r = np.hypot(p[:, 0], p[:, 1])
    g = spec.dz_face_dr(r)
    with np.errstate(invalid="ignore", divide="ignore"):
        ex = np.where(r > 0, p[:, 0] / r, 0.0)
        ey = np.where(r > 0, p[:, 1] / r, 0.0)
    n_face = np.column_stack([-g * ex, -g * ey, np.ones(len(p))])
    return n_face / np.linalg.norm(n_face, axis=1, keepdims=True)


def _mesh_loop(spec: HubSpec, w: Window, target: np.ndarray, tree, edges, V_m: np.ndarray):
    """The mesh vertices (N, 3) [m] at ``target`` (N, 3), checked to be a chain of edges."""
    dist, idx = tree.query(target)
    if dist.max() > 1e-6:
        raise RuntimeError(f"hub {spec.name!r} window {w.index}: outline vertex not in the "
                           f"mesh (off by {dist.max():.2e} m)")
    nxt = np.roll(idx, -1)
    missing = [i for i, (a, b) in enumerate(zip(idx, nxt, strict=True))
               if (min(a, b), max(a, b)) not in edges]
    if missing:
        raise RuntimeError(f"hub {spec.name!r} window {w.index}: {len(missing)} outline "
                           f"segments are not mesh edges")
    return V_m[idx]


def ground_truth_loops(spec: HubSpec, windows: list[Window], geom: PlateGeometry,
                       V_m: np.ndarray, faces: np.ndarray) -> list[dict]:
    """Ground-truth loops (metres) read from the final, rounded mesh vertices.

    Returns per window a dict: index, kind, p_HE, t_H, n_wall_H, n_face_H (N, 3), fillet_m,
    poly_xy_m (the sharp outline, (M, 2) [m]) and vertices_m (the loop's mesh vertices)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(V_m)
    edges = edge_set(faces)
    draft = spec.wall_draft
    out = []
    for w, e in zip(windows, geom.edges, strict=True):
        xy = w.poly_mm * 1e-3
        P = _mesh_loop(spec, w, e.rings[0] * 1e-3, tree, edges, V_m)  # exact mesh vertices
        vert_n = _wall_normals_2d(xy)
        # resample along the mesh edges
        P_next = np.roll(P, -1, axis=0)
        n_next = np.roll(vert_n, -1, axis=0)
        L = np.linalg.norm(P_next - P, axis=1)
        counts = np.maximum(1, np.ceil(L / spec.edge_sample_spacing - 1e-9).astype(int))
        seg_id = np.repeat(np.arange(len(P)), counts)
        frac = np.concatenate([np.arange(c) / c for c in counts])[:, None]
        p = P[seg_id] + (P_next[seg_id] - P[seg_id]) * frac
        n2 = vert_n[seg_id] * (1 - frac) + n_next[seg_id] * frac
        n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
        if draft:
            n_wall = np.column_stack([n2 * math.cos(draft), np.full(len(n2), math.sin(draft))])
        else:
            n_wall = np.column_stack([n2, np.zeros(len(n2))])
        n_face = _face_normals(spec, geom, p)
        tan = np.cross(n_wall, n_face)
        chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
        sgn = np.sign(np.sum(tan * chord, axis=1))
        if np.any(sgn <= 0):
            raise RuntimeError(f"hub {spec.name!r} window {w.index}: tangent sign inconsistent")
        tan /= np.linalg.norm(tan, axis=1, keepdims=True)
        out.append({"index": w.index, "kind": w.kind, "p_HE": p, "t_H": tan,
                    "n_wall_H": n_wall, "n_face_H": n_face, "fillet_m": w.fillet_mm * 1e-3,
                    "poly_xy_m": xy, "vertices_m": P})
    return out


def loop_curvature(p: np.ndarray, k: int = 1) -> np.ndarray:
    """Discrete curvature [1/m] of a closed polyline: circle through points i-k, i, i+k."""
    a = np.roll(p, k, axis=0)
    c = np.roll(p, -k, axis=0)
    ab, bc, ca = np.linalg.norm(p - a, axis=1), np.linalg.norm(c - p, axis=1), np.linalg.norm(
        a - c, axis=1)
    cross = np.linalg.norm(np.cross(p - a, c - a), axis=1)
    return 2 * cross / np.maximum(ab * bc * ca, 1e-300)
