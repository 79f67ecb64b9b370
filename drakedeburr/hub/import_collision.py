"""Convex collision pieces of an imported hub mesh (metres, frame H).

* **Closed meshes**: CoACD (approximate convex decomposition, Wei et al. 2022) on the solid
  simplified by ``simplify_tolerance``; then every piece that reaches more than
  ``window_reach`` into a window opening (probe points: edge points pushed into the opening and
  down the wall, kept where they are outside the solid) is replaced by the hulls of the solid
  inside it cut in two at an offending probe's edge point (across the edge, else along the
  wall plane, else across the longest extent), round after round. The same for pieces standing
  more than ``front_reach`` proud of the surface seen from the front within ``front_band`` of
  a window (``front_reach_far`` further out; probes on a plan-view grid; cut
  circumferentially, else radially).
* **Open meshes** (not watertight, several parts, inconsistent winding): inside and outside
  are undefined, so the pieces cover the *surface*: triangles are subdivided to at most
  ``shell_max_edge``, a plan-view quadtree groups them into cells, each connected group of a
  cell becomes the hull of its triangles and their copies offset along their normals, and a
  cell is split while a hull holds a probe (in a window opening, or above the front surface).
  A tool reaching the hub from outside must cross such a shell first. Where the front view
  tells the material's side (:func:`front_sides`: a connected part whose winding is
  consistent and whose triangles seen first from +Z_H all face the same way) the shell lies
  behind the surface, ``shell_thickness`` deep, so the pieces stand no higher than the surface
  itself; elsewhere it is ``shell_thickness``/2 either side. (Measured on the audibot rim, an
  open game mesh: the +-0.5 mm shell read the burr shank 0.49 mm (median) closer than the
  true mesh all along window 1, where the bundled hubs' solid pieces read 0.04 mm, and the
  shank passes only ~2.1 mm over the face against the IK's 2.05 mm bound.)
* **Closed meshes whose refinement does not converge** (a piece still holds a probe after
  ``max_refine_rounds``): each such piece is dropped and the mesh surface it covered is
  covered by shell pieces instead (:func:`shell_patch`). The solid's interior there is no
  longer covered, but a tool can only get into it through that surface.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

__all__ = ["front_probes", "front_sides", "solid_pieces", "shell_pieces", "shell_patch",
           "coacd_version"]

Progress = Callable[[int, int, str], None] | None


def front_probes(scene, face_normals: np.ndarray, options, closed: bool = True,
                 walls_xy: np.ndarray | None = None):
    """Probes above the surface seen along -Z_H (plan-view grid): ``front_reach`` above it
    within ``front_band`` (plan view) of a window's wall line (``walls_xy`` (K, 2)),
    ``front_reach_far`` further out or without walls; and their cut data (K, 9): surface
    point, circumferential and radial directions (cut planes that part a hull bridging a
    concave corner of the face or a ring; circumferential first: fewer pieces, measured)."""
    import open3d as o3d
    from scipy.spatial import cKDTree

    h = options.front_probe_spacing
    r_max = 0.35  # [m] half the largest wheel diameter the importer accepts
    g = np.arange(-r_max, r_max + h, h)
    gx, gy = np.meshgrid(g, g, indexing="ij")
    keep = np.hypot(gx, gy).ravel() <= r_max
    rays = np.zeros((int(keep.sum()), 6), np.float32)
    rays[:, 0], rays[:, 1] = gx.ravel()[keep], gy.ravel()[keep]
    rays[:, 2], rays[:, 5] = 1.0, -1.0
    ans = scene.cast_rays(o3d.core.Tensor(rays))
    t = ans["t_hit"].numpy()
    hit = np.isfinite(t)
    foot = rays[hit, :3].astype(float) - np.c_[np.zeros((hit.sum(), 2)), t[hit]]
    n = face_normals[ans["primitive_ids"].numpy()[hit].astype(np.int64)]
    n[n[:, 2] < 0] *= -1.0
    reach = np.full(len(foot), options.front_reach_far)
    if walls_xy is not None and len(walls_xy):
        near = cKDTree(walls_xy).query(foot[:, :2], distance_upper_bound=options.front_band)[0]
        reach[np.isfinite(near)] = options.front_reach
    q = foot + reach[:, None] * n
    er = np.c_[foot[:, :2], np.zeros(len(foot))]
    er /= np.maximum(np.linalg.norm(er, axis=1, keepdims=True), 1e-12)
    et = np.c_[-er[:, 1], er[:, 0], np.zeros(len(er))]
    qt = o3d.core.Tensor(q.astype(np.float32))
    d = (scene.compute_signed_distance(qt) if closed else scene.compute_distance(qt)).numpy()
    # a probe nearer the mesh than its simplification (closed) or the shell's half thickness
    # (open) may lie inside the solid the pieces are cut from: it could never be freed
    inner = options.simplify_tolerance if closed else 0.5 * options.shell_thickness
    ok = d > np.maximum(0.5 * reach, inner + 0.1e-3)
    return q[ok], np.c_[foot, et, er][ok]


# --------------------------------------------------------------------------- collision
def _coacd(V: np.ndarray, F: np.ndarray, threshold: float, options,
           max_hulls: int = -1) -> list[np.ndarray]:
    """CoACD pieces (hull vertex arrays, metres) of a closed mesh."""
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int32)),
        threshold=threshold, max_convex_hull=max_hulls, preprocess_mode="off",
        resolution=options.resolution, mcts_nodes=options.mcts_nodes,
        mcts_iterations=options.mcts_iterations, mcts_max_depth=options.mcts_max_depth,
        merge=True, seed=options.seed)
    return [np.asarray(v, float) for v, _ in parts if len(v) >= 4]


def _manifold_arrays(m) -> tuple[np.ndarray, np.ndarray]:
    mesh = m.to_mesh64()
    return np.asarray(mesh.vert_properties[:, :3], float), np.asarray(mesh.tri_verts, np.int64)


def _halves(part, point: np.ndarray | None = None, normals: tuple = ()) -> list:
    """Cut a manifold in two by the first plane through ``point`` with one of ``normals`` that
    leaves material on both sides; else across its longest bounding-box extent (middle)."""
    for normal in normals:
        a, b = part.split_by_plane(normal.tolist(), float(normal @ point))
        if a.volume() > 1e-9 and b.volume() > 1e-9:
            return [a, b]
    bb = np.asarray(part.bounding_box(), float)
    ext = bb[3:] - bb[:3]
    k = int(np.argmax(ext))
    normal = np.zeros(3)
    normal[k] = 1.0
    a, b = part.split_by_plane(normal.tolist(), float(0.5 * (bb[k] + bb[k + 3])))
    return [h for h in (a, b) if not h.is_empty()]


def solid_pieces(solid, probes, probe_edge: np.ndarray, options,
                      progress: Progress = None):
    """Convex pieces (list of (M, 3) hull vertices, metres, H) and refinement statistics.

    ``probe_edge`` (K, 9): for each probe the edge point it was pushed from, the wall normal
    and the edge tangent there. A piece holding probes is cut at the edge point of its middle
    probe: along the wall's tangent plane (separates a window's wall from material across the
    opening), else across the edge (halving a hull that bridges a window's concave corner
    shrinks the bridge about fourfold)."""
    from manifold3d import Manifold

    V, F = _manifold_arrays(solid)
    t0 = time.perf_counter()
    pieces = _coacd(V, F, options.threshold, options, options.max_convex_hull)
    stats = {"coacd_first_pass_pieces": len(pieces),
             "coacd_first_pass_seconds": round(time.perf_counter() - t0, 2),
             "refined_pieces": 0, "refine_rounds": 0}
    min_vol = 1e-9  # [m^3] parts smaller than 1 mm^3 are slivers of the boolean
    for rnd in range(options.max_refine_rounds):
        hits = {i: probes.inside(p) for i, p in enumerate(pieces)}
        bad = [i for i, h in hits.items() if len(h)]
        if progress is not None:
            progress(rnd, options.max_refine_rounds,
                     f"collision refinement {rnd + 1}: {len(bad)} pieces reach into a window")
        if not bad:
            break
        stats["refine_rounds"] = rnd + 1
        stats["refined_pieces"] += len(bad)
        keep = [p for i, p in enumerate(pieces) if i not in set(bad)]
        for i in bad:
            part = solid ^ Manifold.hull_points(pieces[i])
            for comp in part.decompose():
                if comp.volume() < min_vol:
                    continue
                if options.refine == "coacd":
                    sub = _coacd(*_manifold_arrays(comp), options.threshold * 0.5 ** (rnd + 1),
                                 options)
                else:
                    sub = []
                if len(sub) <= 1:  # cut it in two across the window edge
                    e = probe_edge[hits[i][len(hits[i]) // 2]]
                    sub = [_manifold_arrays(h.hull())[0]
                           for h in _halves(comp, e[:3], (e[6:], e[3:6]))
                           if h.volume() >= min_vol]
                keep.extend(sub)
        pieces = keep
    return pieces, stats


def coacd_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("coacd")
    except PackageNotFoundError:
        return "?"


def _components(faces: np.ndarray) -> np.ndarray:
    """(F,) connected-component label of each triangle (shared vertices)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n_v = int(faces.max()) + 1
    rows = np.repeat(np.arange(len(faces)), 3)
    g = coo_matrix((np.ones(len(rows)), (rows, faces.ravel())),
                   shape=(len(faces), n_v)).tocsr()
    adj = g @ g.T
    return connected_components(adj, directed=False)[1]


def front_sides(V: np.ndarray, F: np.ndarray, spacing: float = 2e-3,
                agree: float = 0.98) -> np.ndarray:
    """(M,) per triangle +1 / -1: its normal (by winding) points out of the material, or into
    it; 0: not known. Known for each connected part (shared vertices) whose winding is
    consistent and whose triangles met first by rays along -Z_H (plan grid ``spacing`` [m])
    face +Z_H (+1) or -Z_H (-1) in at least ``agree`` of the hits: the tool works from the
    front, so the side a front ray comes from is outside."""
    import open3d as o3d
    import trimesh

    from drakedeburr.hub.extract import ray_scene

    n = trimesh.Trimesh(V, F, process=False).face_normals
    lo, hi = V[:, :2].min(axis=0), V[:, :2].max(axis=0)
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0], spacing), np.arange(lo[1], hi[1], spacing),
                         indexing="ij")
    rays = np.zeros((gx.size, 6), np.float32)
    rays[:, 0], rays[:, 1] = gx.ravel(), gy.ravel()
    rays[:, 2], rays[:, 5] = float(V[:, 2].max()) + 0.01, -1.0
    ans = ray_scene(V, F).cast_rays(o3d.core.Tensor(rays))
    seen = ans["primitive_ids"].numpy()[np.isfinite(ans["t_hit"].numpy())].astype(np.int64)
    labels = _components(F)
    sides = np.zeros(len(F))
    for lab in np.unique(labels[seen]):
        up = n[seen[labels[seen] == lab], 2] > 0.0
        share = float(up.mean())
        part = np.flatnonzero(labels == lab)
        if max(share, 1.0 - share) < agree or not trimesh.Trimesh(
                V, F[part], process=False).is_winding_consistent:
            continue
        sides[part] = 1.0 if share >= agree else -1.0
    return sides


def _shell_hull(V: np.ndarray, faces: np.ndarray, normals: np.ndarray,
                offsets: np.ndarray) -> np.ndarray | None:
    """Hull of the triangles ``faces`` moved along their ``normals`` by each of their two
    ``offsets`` (k, 2) [m]."""
    from scipy.spatial import ConvexHull, QhullError

    tri = V[faces]  # (k, 3, 3)
    pts = np.concatenate([(tri + normals[:, None, :] * offsets[:, j, None, None]).reshape(-1, 3)
                          for j in (0, 1)])
    try:
        return pts[ConvexHull(pts).vertices]
    except QhullError:
        return None


def shell_pieces(V: np.ndarray, F: np.ndarray, probes, options,
                 progress: Progress = None,
                 sides: np.ndarray | None = None) -> tuple[list[np.ndarray], dict]:
    """Convex pieces covering the surface of an open mesh (module doc) and statistics.

    Args:
        V: (N, 3) vertices in H [m]; F: (M, 3) triangles.
        probes: :class:`~drakedeburr.hub.collision.WindowProbes` (metres) that must stay
            outside every piece.
        options: :class:`~drakedeburr.hub.import_options.ImportOptions`.
        sides: (M,) the material's side of each triangle (:func:`front_sides`; 0: both);
            None: :func:`front_sides` of (``V``, ``F``) if ``options.shell_behind``, else 0.
    """
    import trimesh

    t0 = time.perf_counter()
    if sides is None:
        sides = front_sides(V, F) if options.shell_behind else np.zeros(len(F))
    V, F, src = trimesh.remesh.subdivide_to_size(V, F, options.shell_max_edge,
                                                 return_index=True)
    tri = V[F]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    c = tri.mean(axis=1)
    half = 0.5 * options.shell_thickness
    s = np.asarray(sides, float)[src]
    # a known side: from the surface to shell_thickness behind it; else half either side
    offsets = np.where((s == 0.0)[:, None], [[half, -half]],
                       np.c_[np.zeros(len(s)), -options.shell_thickness * s])
    lo = c[:, :2].min(axis=0) - 1e-6
    size = float((c[:, :2].max(axis=0) - lo).max()) + 2e-6
    n0 = int(np.ceil(size / options.shell_cell))
    edge = size / n0
    stack = [(lo[0] + i * edge, lo[1] + j * edge, edge) for j in range(n0) for i in range(n0)]
    pieces, stats = [], {"triangles_subdivided": int(len(F)), "cells_split": 0,
                         "pieces_with_probes": 0}
    while stack:
        x0, y0, h = stack.pop()
        sel = np.flatnonzero((c[:, 0] >= x0) & (c[:, 0] < x0 + h) & (c[:, 1] >= y0)
                             & (c[:, 1] < y0 + h))
        if not len(sel):
            continue
        labels = _components(F[sel])
        hulls, split = [], False
        for lab in np.unique(labels):
            part = sel[labels == lab]
            hull = _shell_hull(V, F[part], n[part], offsets[part])
            if hull is None:
                continue
            if len(probes.inside(hull)):
                if h > options.shell_min_cell:
                    split = True
                    break
                stats["pieces_with_probes"] += 1
            hulls.append(hull)
        if split:
            stats["cells_split"] += 1
            g = h / 2
            stack.extend([(x0, y0, g), (x0 + g, y0, g), (x0, y0 + g, g), (x0 + g, y0 + g, g)])
            continue
        pieces.extend(hulls)
        if progress is not None:
            progress(len(pieces), len(pieces) + len(stack), "collision shell pieces")
    stats["pieces_before_merging"] = len(pieces)
    pieces = _merge_shell(pieces, probes, options.shell_thickness)
    stats["seconds"] = round(time.perf_counter() - t0, 2)
    return pieces, stats


def _merge_shell(pieces: list[np.ndarray], probes, thickness: float) -> list[np.ndarray]:
    """Greedy merging of touching shell pieces under the generator's rule (in mm): the merged
    hull holds no probe and adds at most 1 mm of average thickness to the shell it covers."""
    from scipy.spatial import ConvexHull

    from drakedeburr.hub.collision import Piece, WindowProbes, merge_pieces

    mm = [p * 1e3 for p in pieces]
    parts = [Piece(p, ConvexHull(p).volume, ConvexHull(p).volume) for p in mm]
    merged = merge_pieces(parts, thickness * 1e3, (WindowProbes(probes.pts * 1e3),))
    return [p.pts * 1e-3 for p in merged]


def _meets(tri: np.ndarray, eq: np.ndarray, grow: float) -> bool:
    """Whether triangle ``tri`` (3, 3) meets the convex hull of half-spaces ``eq`` (F, 4),
    unit normals as qhull gives them, grown by ``grow``: the triangle clipped by each
    half-space in turn (Sutherland-Hodgman) keeps a point. Exact for any triangle size; written
    by hand because trimesh/scipy offer no triangle-polytope test."""
    poly = [tuple(p) for p in tri]
    for a, b, c, d in eq:
        dist = [a * x + b * y + c * z + d - grow for x, y, z in poly]
        out = []
        for k, p in enumerate(poly):
            q, dp, dq = poly[k - 1], dist[k], dist[k - 1]
            if (dp <= 0.0) != (dq <= 0.0):  # the edge q -> p crosses the plane
                t = dq / (dq - dp)
                out.append(tuple(qi + t * (pi - qi) for pi, qi in zip(p, q, strict=True)))
            if dp <= 0.0:
                out.append(p)
        poly = out
        if not poly:
            return False
    return True


def shell_patch(pieces: list[np.ndarray], V: np.ndarray, F: np.ndarray, probes, options,
                progress: Progress = None) -> tuple[list[np.ndarray], dict]:
    """``pieces`` with every piece that holds a probe replaced by shell pieces (module doc).

    The surface a dropped piece covered: every triangle of (``V``, ``F``) (H, metres) that
    meets its hull grown by ``shell_thickness`` (:func:`_meets`, exact whatever the triangle's
    size). A tool outside the hub meets one of those triangles before it can enter the dropped
    piece's volume, and the shell holds them.
    """
    from scipy.spatial import ConvexHull

    bad = [i for i, p in enumerate(pieces) if len(probes.inside(p))]
    stats = {"pieces_replaced_by_shell": len(bad), "shell_patch_pieces": 0}
    if not bad:
        return pieces, stats
    grow = options.shell_thickness
    tri = V[F]
    tri_lo, tri_hi = tri.min(axis=1), tri.max(axis=1)
    chosen = np.zeros(len(F), bool)
    for i in bad:
        eq = ConvexHull(pieces[i]).equations
        lo, hi = pieces[i].min(axis=0) - grow, pieces[i].max(axis=0) + grow
        near = np.flatnonzero(np.all((tri_hi >= lo) & (tri_lo <= hi), axis=1) & ~chosen)
        for j in near:
            chosen[j] = _meets(tri[j], eq, grow)
    dropped = set(bad)
    keep = [p for i, p in enumerate(pieces) if i not in dropped]
    if chosen.any():
        patch, shell = shell_pieces(V, F[chosen], probes, options, progress,
                                    sides=np.zeros(int(chosen.sum())))
        keep.extend(patch)
        stats["shell_patch_pieces"] = len(patch)
        stats["shell_patch_pieces_with_probes"] = shell["pieces_with_probes"]
    stats["shell_patch_triangles"] = int(chosen.sum())
    return keep, stats
