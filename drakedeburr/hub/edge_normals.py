"""Edge normals of an imported hub's window loops, read off the mesh (docs/hub.md, step 7).

``n_face_H`` = normal of the surface just outside the loop, ``n_wall_H`` = normal of the wall
just below it (outward = into the opening; facets are oriented by the side they must face, so
an inconsistent winding does not matter), a few neighbours averaged; ``t_H`` = the loop's own
chord direction (also where the loop climbs a flank: a 3-D loop), ``n_wall_H`` made
perpendicular to it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["edge_normals"]

_NORMAL_PROBE = 1.5e-3  # [m] how far from the edge the face/wall normals are sampled
_NORMAL_SIDE = 0.3e-3  # [m] sideways offset of those samples off the corner
_WALL_TILT = np.radians(30.0)  # a wall normal at most this far from the constructed one
_STEEP = np.radians(45.0)  # a loop tangent steeper than this: 'into the opening' from the outline


def _smooth(v: np.ndarray, k: int = 3) -> np.ndarray:
    """Average each row with its k neighbours on both sides (closed loop) and normalise."""
    out = sum(np.roll(v, s, axis=0) for s in range(-k, k + 1))
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def edge_normals(scene, face_normals: np.ndarray, p: np.ndarray,
                  outline_xy: np.ndarray | None = None):
    """(n_wall, n_face, t) (N, 3) each for a CCW loop ``p`` (N, 3) in H (see module doc).

    The loop may leave the face (down a spoke flank, along the rim's lip): its tangent is the
    3-D chord, "into the opening" is the horizontal direction across it to its left
    (Z_H x t; where t is steeper than 45 deg, down a flank, the plan-view inward normal of the
    opening's outline ``outline_xy`` (M, 2) at the nearest point, of the loop's own plan view
    when None, made perpendicular to t), and
    "out of the front surface" completes them
    (t x into-the-opening: +Z_H on a flat stretch). The wall is probed below the edge along
    the latter, the face beside it; a probe that finds a facet not facing its side (less than
    0.3), or a wall probe whose facet faces the front more than the opening, keeps the
    constructed direction. The tangent returned is the loop's chord direction,
    the wall normal is made perpendicular to it."""
    import open3d as o3d
    from scipy.spatial import cKDTree

    chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
    t0 = chord / np.maximum(np.linalg.norm(chord, axis=1, keepdims=True), 1e-12)
    ref = p[:, :2] if outline_xy is None else np.asarray(outline_xy, float)
    tang = np.roll(ref, -1, axis=0) - np.roll(ref, 1, axis=0)
    inward = np.c_[-tang[:, 1], tang[:, 0]]
    inward /= np.maximum(np.linalg.norm(inward, axis=1, keepdims=True), 1e-12)
    inward3 = np.c_[inward[cKDTree(ref).query(p[:, :2])[1]], np.zeros(len(p))]
    # into the opening: the horizontal direction across t to its left (Z_H x t: into the
    # opening of a CCW loop, and the frame's upright t x left then has Z_H >= 0 even where a
    # low-poly corner makes the loop run back a little); for a tangent along the axis the
    # outline's inward normal
    left = np.cross([0.0, 0.0, 1.0], t0)
    ln = np.linalg.norm(left, axis=1)
    # where the loop runs down a flank (steeper than _STEEP) the plan direction of its tangent
    # is noise (a low-poly flank's chords wander sideways by a fraction of a millimetre), and
    # Z_H x t with it: on the audibot rim's window 0 it pointed away from the opening's plan
    # centroid at 91 of 218 such points (0 of 632 gentler ones), tilting the tool into the
    # spoke. There the outline's inward normal, made perpendicular to t, says where the
    # opening is.
    along = inward3 - np.einsum("ij,ij->i", inward3, t0)[:, None] * t0
    an = np.linalg.norm(along, axis=1)
    steep = (np.abs(t0[:, 2]) > np.sin(_STEEP)) & (an > 0.2)
    left = np.where((ln > 1e-3)[:, None] & ~steep[:, None],
                    left / np.maximum(ln, 1e-12)[:, None],
                    np.where(steep[:, None], along / np.maximum(an, 1e-12)[:, None], inward3))
    up = np.cross(t0, left)  # out of the front surface

    def normal_at(q: np.ndarray) -> np.ndarray:
        res = scene.compute_closest_points(o3d.core.Tensor(q.astype(np.float32)))
        return face_normals[res["primitive_ids"].numpy().astype(np.int64)]

    # facets of an open mesh may face either way: orient by the side they must face
    n_wall = normal_at(p + _NORMAL_SIDE * left - _NORMAL_PROBE * up)
    n_wall *= np.where(np.einsum("ij,ij->i", n_wall, left) < 0, -1.0, 1.0)[:, None]
    # a wall faces the opening more than it faces the front (else the probe found a face or
    # a flank below the edge: its normal is not the inner-side one)
    along = np.einsum("ij,ij->i", n_wall, left)
    bad = (along < 0.3) | (np.einsum("ij,ij->i", n_wall, up) > along)
    n_wall[bad] = left[bad]
    n_face = normal_at(p - _NORMAL_PROBE * left + _NORMAL_SIDE * up)
    n_face *= np.where(np.einsum("ij,ij->i", n_face, up) < 0, -1.0, 1.0)[:, None]
    bad = np.einsum("ij,ij->i", n_face, up) < 0.3
    n_face[bad] = up[bad]
    n_wall, n_face = _smooth(n_wall), _smooth(n_face)
    # the tangent is the loop's own (a 3-D loop's facets beside a flank give normals whose
    # cross product strays from it); the wall normal is made perpendicular to it
    n_wall -= np.einsum("ij,ij->i", n_wall, t0)[:, None] * t0
    norm = np.linalg.norm(n_wall, axis=1)
    n_wall = np.where((norm > 0.2)[:, None], n_wall / np.maximum(norm, 1e-12)[:, None], left)
    # a window wall stands within WALL_TILT of the constructed direction (drafts are a few
    # degrees); a facet tilted further is a flank below a climbing stretch, not the wall
    off = np.einsum("ij,ij->i", n_wall, left) < np.cos(_WALL_TILT)
    n_wall[off] = left[off]
    return n_wall, n_face, t0
