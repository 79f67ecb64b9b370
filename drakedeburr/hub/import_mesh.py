"""Mesh file (STL/OBJ/PLY) -> hub model folder that the cell, planner and verifier load like a
bundled hub (``hub.yaml``, ``hub.obj``, ``edges.npz``, ``summary.json``, ``hub.sdf``,
``collision/piece_NNN.obj``; see docs/hub.md).

Steps:

1. Load and validate (:func:`drakedeburr.hub.mesh_io.load_hub_mesh`: suffix, triangles, finite
   vertices, mm/m detection); then require a closed solid (watertight, a valid manifold: the
   collision model and the probes need inside/outside) and a wheel-sized diameter across the
   hub axis (``DIAMETER_RANGE``).
2. Hub frame H and window edges (:func:`drakedeburr.hub.extract.extract_window_edges`, axis
   estimated unless given). The origin is then moved along the axis onto the front face of the
   centre (median height of the surface seen along -Z_H inside the innermost window radius;
   for a generated hub that is the flat face around the pad, z = 0, as in the bundled hubs).
3. Edge normals from the mesh: ``n_face_H`` = normal of the surface just outside the loop,
   ``n_wall_H`` = normal of the window wall just below it (outward = into the opening),
   ``t_H = n_wall_H x n_face_H`` (loop direction); a few neighbours averaged.
4. Convex collision pieces: CoACD (approximate convex decomposition, Wei et al. 2022) on the
   solid simplified by ``simplify_tolerance``; then every piece that reaches more than
   ``window_reach`` into a window opening (probe points: edge points pushed into the opening and
   down the wall, kept where they are outside the solid; the generator's ``WindowProbes``) is
   replaced by the hulls of the solid inside it cut in two at an offending probe's edge point
   (across the edge, else along the wall plane, else across the longest extent), round after
   round. The same for pieces standing more than ``front_reach`` proud of the surface seen
   from the front (probes on a plan-view grid; cut circumferentially, else radially): CoACD's
   coarse hulls bridge the dish and the corner where the face meets the rim lip by up to
   12 mm otherwise. Pieces still reaching into a window after ``max_refine_rounds`` are kept
   and reported (``summary.json``: ``collision.max_window_intrusion_mm``), not hidden.
5. Files are written into a temporary folder next to the target and renamed into place. The
   folder name carries a hash of the mesh bytes and the options, so importing the same file
   again returns the cached folder without running CoACD.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.hub.types import WindowEdge

__all__ = ["ImportOptions", "ImportedHub", "import_mesh", "IMPORT_VERSION", "DIAMETER_RANGE"]

log = logging.getLogger(__name__)

IMPORT_VERSION = 1
DIAMETER_RANGE = (0.150, 0.700)  # [m] plausible wheel diameter across the hub axis
_NORMAL_PROBE = 1.5e-3  # [m] how far from the edge the face/wall normals are sampled
_NORMAL_SIDE = 0.3e-3  # [m] sideways offset of those samples off the corner

Progress = Callable[[int, int, str], None] | None


@dataclass(frozen=True)
class ImportOptions:
    """Settings of :func:`import_mesh` (all part of the cache key).

    Attributes:
        unit: "m" or "mm" to force the file's unit; None detects it from the size.
        axis_M: (3,) hub axis (+Z_H, out of the visible face) in the file's frame, or None to
            estimate it.
        expected_windows: fail unless this many windows are found (None: any number >= 1).
        edge_spacing: arc-length spacing of the stored edge points [m].
        simplify_tolerance: the solid is simplified within this distance before decomposition
            [m] (CoACD's time grows with the triangle count).
        threshold: CoACD concavity threshold (relative to the part's size). Deliberately
            coarse: CoACD's time grows steeply with a finer threshold (0.05 with the search
            below took 70 s on a 17 in hub, 0.1 takes 4 s) and a fine threshold still bridges
            window corners; the targeted refinement below does the rest.
        max_convex_hull: CoACD's piece limit of the first pass (-1: none).
        resolution: CoACD surface sampling resolution.
        mcts_iterations, mcts_nodes, mcts_max_depth: CoACD's tree search effort.
        seed: CoACD random seed (deterministic output for a given mesh).
        window_reach: a piece may reach at most this far into a window opening [m]. The
            generator holds 0.5 mm (which ``Tolerances.collision_model_excess`` assumes); at
            1 mm the full-hub verification of h5_straight's mesh failed ``burr_contact`` by
            0.03 mm and the planner lost 7 IK targets of window 4, at 0.5 mm it passed like the
            bundled hub but took 1108 pieces, 53 s, and did not converge within
            ``max_refine_rounds`` on the same mesh in another pose (known weakness).
        probe_depth: the opening probes span this depth below the edge [m].
        max_refine_rounds: refinement rounds for pieces that reach into an opening.
        front_reach: a piece may stand at most this far proud of the surface seen from the
            front (+Z_H, where the tool works) [m]; probes on a plan-view grid of
            ``front_probe_spacing`` [m]. (Surfaces the front view does not see, e.g. the tyre
            well and the barrel's inside, are not probed: their pieces may bridge concave
            regions, a conservative model where no tool goes.)
        refine: how such a piece's part is split: "cut" (in two at the offending probe,
            see the module doc; fast) or "coacd" (CoACD again with the threshold halved per
            round, the cut when CoACD keeps the part whole; slower).
        density: material density for the inertia in hub.sdf [kg/m^3] (aluminium).
    """

    unit: str | None = None
    axis_M: tuple[float, float, float] | None = None
    expected_windows: int | None = None
    edge_spacing: float = 0.5e-3
    simplify_tolerance: float = 0.5e-3
    threshold: float = 0.1
    max_convex_hull: int = -1
    resolution: int = 500
    mcts_iterations: int = 20
    mcts_nodes: int = 20
    mcts_max_depth: int = 1
    seed: int = 0
    window_reach: float = 1.0e-3
    probe_depth: float = 20e-3
    max_refine_rounds: int = 40
    front_reach: float = 3.0e-3
    front_probe_spacing: float = 4.0e-3
    refine: str = "cut"
    density: float = 2700.0


@dataclass(frozen=True, eq=False)
class ImportedHub:
    """What :func:`import_mesh` produced.

    Attributes:
        dir: the hub model folder (load it with ``load_hub(dir)`` / ``load_cell(s, dir)``).
        name: hub name (from the file name).
        source: the mesh file.
        sha256: hash of the mesh file's bytes.
        cached: True when an existing folder was reused (no work done).
        X_MH: (4, 4) pose of the hub frame H in the file's frame M [m].
        window_count: windows found.
        piece_count: convex collision pieces.
        max_window_intrusion: largest reach of a piece into a window opening [m].
        seconds: wall time of this call [s].
        summary: the content of ``summary.json``.
    """

    dir: Path
    name: str
    source: Path
    sha256: str
    cached: bool
    X_MH: np.ndarray
    window_count: int
    piece_count: int
    max_window_intrusion: float
    seconds: float
    summary: dict


# --------------------------------------------------------------------------- helpers
def _file_hash(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _options_json(options: ImportOptions) -> dict:
    d = dataclasses.asdict(options)
    if d["axis_M"] is not None:
        d["axis_M"] = [float(v) for v in d["axis_M"]]
    return d


def _cache_key(sha: str, options: ImportOptions) -> str:
    blob = json.dumps({"sha256": sha, "options": _options_json(options),
                       "version": IMPORT_VERSION}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def _hub_name(path: Path) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", path.stem).strip("._") or "hub"


def _cached(folder: Path, key: str) -> dict | None:
    try:
        summary = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return None
    if summary.get("import", {}).get("cache_key") != key:
        return None
    if not all((folder / f).is_file() for f in ("hub.yaml", "hub.obj", "edges.npz", "hub.sdf")):
        return None
    return summary


def _front_origin_offset(scene, r_inner: float, z_top: float) -> float:
    """Height [m] (in the extraction's H) of the centre's front face: median of the surface
    seen along -Z_H on a polar grid inside ``r_inner``; 0 when nothing is hit."""
    import open3d as o3d

    r = np.arange(2e-3, max(r_inner - 3e-3, 3e-3), 1e-3)
    a = np.linspace(0.0, 2 * np.pi, 120, endpoint=False)
    rr, aa = np.meshgrid(r, a)
    rays = np.zeros((rr.size, 6), np.float32)
    rays[:, 0], rays[:, 1] = (rr * np.cos(aa)).ravel(), (rr * np.sin(aa)).ravel()
    rays[:, 2], rays[:, 5] = z_top, -1.0
    t = scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()
    t = t[np.isfinite(t)]
    return float(np.median(z_top - t)) if len(t) else 0.0


def _smooth(v: np.ndarray, k: int = 3) -> np.ndarray:
    """Average each row with its k neighbours on both sides (closed loop) and normalise."""
    out = sum(np.roll(v, s, axis=0) for s in range(-k, k + 1))
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _edge_normals(scene, face_normals: np.ndarray, p: np.ndarray):
    """(n_wall, n_face, t) (N, 3) each for a CCW loop ``p`` (N, 3) in H (see module doc)."""
    import open3d as o3d

    chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
    left = np.c_[-chord[:, 1], chord[:, 0], np.zeros(len(p))]  # into the opening (plan view)
    left /= np.linalg.norm(left, axis=1, keepdims=True)
    z = np.array([0.0, 0.0, 1.0])

    def normal_at(q: np.ndarray) -> np.ndarray:
        res = scene.compute_closest_points(o3d.core.Tensor(q.astype(np.float32)))
        return face_normals[res["primitive_ids"].numpy().astype(np.int64)]

    n_wall = normal_at(p + _NORMAL_SIDE * left - _NORMAL_PROBE * z)
    bad = np.einsum("ij,ij->i", n_wall, left) < 0.3
    n_wall[bad] = left[bad]
    n_face = normal_at(p - _NORMAL_PROBE * left + _NORMAL_SIDE * z)
    bad = n_face[:, 2] < 0.3
    n_face[bad] = z
    n_wall, n_face = _smooth(n_wall), _smooth(n_face)
    t = np.cross(n_wall, n_face)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    flip = np.einsum("ij,ij->i", t, chord) < 0
    t[flip] *= -1.0
    return n_wall, n_face, t


def _front_probes(scene, face_normals: np.ndarray, options: ImportOptions):
    """Probes ``front_reach`` above the surface seen along -Z_H (plan-view grid) and their cut
    data (K, 9): surface point, circumferential and radial directions (cut planes that part
    a hull bridging a concave corner of the face or a ring; circumferential first: fewer
    pieces, measured)."""
    import open3d as o3d

    h = options.front_probe_spacing
    r_max = 0.5 * DIAMETER_RANGE[1]
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
    q = foot + options.front_reach * n
    er = np.c_[foot[:, :2], np.zeros(len(foot))]
    er /= np.maximum(np.linalg.norm(er, axis=1, keepdims=True), 1e-12)
    et = np.c_[-er[:, 1], er[:, 0], np.zeros(len(er))]
    d = scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32))).numpy()
    ok = d > 0.5 * options.front_reach
    return q[ok], np.c_[foot, et, er][ok]


# --------------------------------------------------------------------------- collision
def _coacd(V: np.ndarray, F: np.ndarray, threshold: float, options: ImportOptions,
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


def _collision_pieces(solid, probes, probe_edge: np.ndarray, options: ImportOptions,
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


# --------------------------------------------------------------------------- main
def import_mesh(path: str | Path, out_root: str | Path, *,
                options: ImportOptions = ImportOptions(),
                progress: Progress = None) -> ImportedHub:
    """Turn a hub mesh file into a hub model folder under ``out_root`` (see module doc).

    Args:
        path: STL, OBJ or PLY file of one wheel hub (closed solid, metres or millimetres).
        out_root: parent folder; the hub folder is ``out_root/<name>_<hash12>``.
        options: import settings.
        progress: optional callback (done, total, label).

    Returns:
        The ImportedHub (``cached`` when the folder already existed for this file + options).

    Raises:
        FileNotFoundError: no such file.
        InputError: not a readable mesh, not a closed solid, not wheel-sized, or no windows
            found (the message names the file and what was wrong).
    """
    import trimesh
    import yaml
    from manifold3d import Manifold, Mesh64

    from drakedeburr.hub.extract import extract_window_edges, hub_frame_from_mesh
    from drakedeburr.hub.generate import (
        WindowProbes,
        loop_curvature,
        obj_text,
        sdf_text,
        window_center_xy,
        window_intrusion,
        write_npz,
    )
    from drakedeburr.hub.mesh_io import load_hub_mesh

    t_start = time.perf_counter()
    if options.refine not in ("cut", "coacd"):
        raise InputError(f"ImportOptions.refine must be 'cut' or 'coacd', got {options.refine!r}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"hub mesh {path} does not exist")
    sha = _file_hash(path)
    key = _cache_key(sha, options)
    name = _hub_name(path)
    out_root = Path(out_root)
    target = out_root / f"{name}_{key[:12]}"
    summary = _cached(target, key)
    if summary is not None:
        log.info("%s: reusing %s (same mesh and options)", path, target)
        imp = summary["import"]
        return ImportedHub(dir=target.resolve(), name=name, source=path, sha256=sha, cached=True,
                           X_MH=np.asarray(imp["X_MH"], float),
                           window_count=summary["window_count"],
                           piece_count=summary["collision"]["piece_count"],
                           max_window_intrusion=summary["collision"]["max_window_intrusion_mm"]
                           * 1e-3, seconds=time.perf_counter() - t_start, summary=summary)

    steps = 5
    if progress is not None:
        progress(0, steps, "load mesh")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")
    lm = load_hub_mesh(path, unit=options.unit)
    mesh = lm.mesh
    if not lm.watertight:
        open_edges = int(len(mesh.edges_unique) - np.sum(
            np.bincount(mesh.edges_unique_inverse, minlength=len(mesh.edges_unique)) == 2))
        raise InputError(
            f"{path}: the mesh is not a closed solid ({open_edges} edges not shared by exactly "
            f"two triangles): convex collision pieces and the window probes need inside and "
            f"outside; close the holes / stitch the parts in the CAD export")

    if progress is not None:
        progress(1, steps, "hub frame and window edges")
    z_M = hub_frame_from_mesh(mesh, options.axis_M).X_MH[:3, 2]
    v = mesh.vertices - mesh.vertices.mean(axis=0)
    across = v - np.outer(v @ z_M, z_M)
    span = across @ np.linalg.svd(across, full_matrices=False)[2][:2].T
    diameter = float(np.max(np.ptp(span, axis=0)))  # extent across the axis
    if not DIAMETER_RANGE[0] <= diameter <= DIAMETER_RANGE[1]:
        raise InputError(
            f"{path}: diameter across the hub axis {diameter * 1e3:.0f} mm (file read as "
            f"{lm.unit}) is not a wheel hub's ({DIAMETER_RANGE[0] * 1e3:.0f}-"
            f"{DIAMETER_RANGE[1] * 1e3:.0f} mm); force the unit (unit='m'/'mm') or check the "
            f"file")
    ext = extract_window_edges(mesh, source=str(path), axis_M=options.axis_M,
                               spacing=options.edge_spacing,
                               expected_windows=options.expected_windows)
    X_MH = np.array(ext.X_MH, float)
    X_HM = np.linalg.inv(X_MH)
    V_H = mesh.vertices @ X_HM[:3, :3].T + X_HM[:3, 3]
    F = np.asarray(mesh.faces, np.int64)

    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V_H.astype(np.float32)),
                        o3d.core.Tensor(F.astype(np.uint32)))
    r_inner = min(float(np.linalg.norm(w.p_HE[:, :2], axis=1).min()) for w in ext.windows)
    dz = _front_origin_offset(scene, r_inner, float(V_H[:, 2].max()) + 0.01)
    X_MH[:3, 3] += dz * X_MH[:3, 2]
    V_H[:, 2] -= dz
    V_H = np.round(V_H, 7) + 0.0  # the OBJ precision (0.1 um): files and memory agree
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V_H.astype(np.float32)),
                        o3d.core.Tensor(F.astype(np.uint32)))
    tm = trimesh.Trimesh(V_H, F, process=False)
    windows, loops = [], []
    for w in ext.windows:
        p = w.p_HE - np.array([0.0, 0.0, dz])
        n_wall, n_face, t = _edge_normals(scene, tm.face_normals, p)
        windows.append(WindowEdge(index=w.index, kind=w.kind, p_HE=p, t_H=t, n_wall_H=n_wall,
                                  n_face_H=n_face))
        loops.append({"p_HE": p, "n_wall_H": n_wall})

    if progress is not None:
        progress(2, steps, "collision pieces (CoACD)")
    solid = Manifold(Mesh64(np.ascontiguousarray(V_H), np.ascontiguousarray(F.astype(np.uint64))))
    if solid.status().name != "NoError" or solid.is_empty():
        raise InputError(f"{path}: the mesh is watertight but not a valid solid (manifold3d: "
                         f"{solid.status().name}); self-intersections or inverted faces?")
    simple = solid.simplify(options.simplify_tolerance)

    def in_opening(q: np.ndarray) -> np.ndarray:
        d = scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32))).numpy()
        return d > 0.5 * options.window_reach

    probe_pts, probe_edge = [], []
    for w in windows:
        q0 = w.p_HE + options.window_reach * w.n_wall_H
        for f in np.linspace(0.02, 0.98, 6):
            probe_pts.append(q0 - np.array([0.0, 0.0, f * options.probe_depth]))
            probe_edge.append(np.c_[w.p_HE, w.n_wall_H, w.t_H])
    probe_pts, probe_edge = np.concatenate(probe_pts), np.concatenate(probe_edge)
    ok = in_opening(probe_pts)
    face_pts, face_cut = _front_probes(scene, tm.face_normals, options)
    n_window_probes = int(ok.sum())
    probes = WindowProbes(np.concatenate([probe_pts[ok], face_pts]))
    t_coll = time.perf_counter()
    sub = None if progress is None else (lambda d, n, label: progress(2, steps, label))
    pieces, coll_stats = _collision_pieces(simple, probes,
                                           np.concatenate([probe_edge[ok], face_cut]), options,
                                           sub)
    coll_seconds = time.perf_counter() - t_coll
    intrusion = window_intrusion(loops, pieces, options.probe_depth, keep=in_opening)
    proud = WindowProbes(face_pts)
    face_hits = sum(len(proud.inside(pv)) for pv in pieces)
    hulls = [Manifold.hull_points(pv) for pv in pieces]
    hull_volume = float(sum(h.volume() for h in hulls))

    if progress is not None:
        progress(3, steps, "write folder")
    mp = tm.mass_properties
    if mp.volume <= 0:
        raise InputError(f"{path}: the mesh encloses no volume (faces inside out?)")
    mass = float(mp.volume * options.density)
    com = np.asarray(mp.center_mass)
    I_com = np.asarray(mp.inertia) * options.density
    I_com = 0.5 * (I_com + I_com.T)
    win_summary = []
    for w in windows:
        p = w.p_HE
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        kappa = loop_curvature(p, max(2, int(round(2e-3 / options.edge_spacing))))
        c_xy = window_center_xy(p[:, :2])
        u = c_xy / np.linalg.norm(c_xy)
        win_summary.append({
            "index": w.index, "kind": w.kind, "points": int(len(p)),
            "length_mm": round(float(seg.sum()) * 1e3, 3),
            "max_spacing_mm": round(float(seg.max()) * 1e3, 4),
            "fillet_mm": round(1e-3 / max(float(np.percentile(kappa, 99.5)) * 1e-3, 1e-9), 3),
            "max_curvature_per_mm": round(float(np.percentile(kappa, 99.5)) * 1e-3, 4),
            "z_range_mm": [round(float(p[:, 2].min()) * 1e3, 3),
                           round(float(p[:, 2].max()) * 1e3, 3)],
            "center_xy_mm": [round(float(c_xy[0]) * 1e3, 3), round(float(c_xy[1]) * 1e3, 3)],
            "width_mm": round(float(np.ptp(p[:, :2] @ np.array([-u[1], u[0]]))) * 1e3, 2),
            "radial_size_mm": round(float(np.ptp(p[:, :2] @ u)) * 1e3, 2),
        })
    summary = {
        "name": name,
        "import": {"source": str(path.resolve()), "sha256": sha, "cache_key": key,
                   "version": IMPORT_VERSION, "unit": lm.unit,
                   "axis_estimated": bool(options.axis_M is None),
                   "X_MH": np.round(X_MH, 9).tolist(), "options": _options_json(options),
                   "extraction": {k: v for k, v in ext.notes.items() if k != "edge_source"}},
        "frame": "H: origin on the hub axis at the front face of the centre, +Z out of the "
                 "visible face",
        "units": "metres in every data file; mm in this summary",
        "mesh": {"vertices": int(len(V_H)), "triangles": int(len(F)),
                 "genus": int(solid.genus()), "watertight": True,
                 "volume_m3": round(float(mp.volume), 9),
                 "diameter_mm": round(diameter * 1e3, 2)},
        "mass_kg": round(mass, 4),
        "center_of_mass_m": [round(float(c), 6) for c in com],
        "window_count": len(windows), "windows": win_summary,
        "collision": {
            "method": f"CoACD {_coacd_version()} on the solid simplified within "
                      f"{options.simplify_tolerance * 1e3:g} mm (threshold "
                      f"{options.threshold:g}); pieces reaching > "
                      f"{options.window_reach * 1e3:g} mm into a window opening or > "
                      f"{options.front_reach * 1e3:g} mm proud of the front surface cut in two "
                      f"at the offending probe ({options.refine})",
            "piece_count": len(pieces),
            "hull_volume_over_solid": round(hull_volume / float(mp.volume), 4),
            "max_window_intrusion_mm": round(intrusion * 1e3, 3),
            "window_reach_allowed_mm": round(options.window_reach * 1e3, 3),
            "probes_in_openings": n_window_probes,
            "front_probes": int(len(face_pts)),
            "front_probes_inside_pieces": int(face_hits),
            "front_reach_allowed_mm": round(options.front_reach * 1e3, 3),
            "seconds": round(coll_seconds, 2), **coll_stats,
        },
    }
    if intrusion > options.window_reach:
        log.warning("%s: collision pieces reach %.2f mm into a window opening (allowed %.2f mm) "
                    "after %d refinement rounds", path, intrusion * 1e3,
                    options.window_reach * 1e3, options.max_refine_rounds)

    out_root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=out_root))
    try:
        atomic_write_text(tmp / "hub.yaml", (
            "# drakedeburr hub imported from a mesh by `drakedeburr hub import` (see "
            "docs/hub.md); do not edit.\n"
            + yaml.safe_dump({"name": name, "imported_from": str(path.resolve()),
                              "mesh_sha256": sha}, sort_keys=False)))
        atomic_write_text(tmp / "hub.obj", obj_text(V_H, F, f"drakedeburr hub {name} "
                                                     f"(imported from {path.name})"))
        arrays: dict[str, np.ndarray] = {"kinds": np.array([w.kind for w in windows])}
        for w in windows:
            for k in ("p_HE", "t_H", "n_wall_H", "n_face_H"):
                arrays[f"w{w.index}_{k}"] = getattr(w, k)
        write_npz(tmp / "edges.npz", arrays)
        (tmp / "collision").mkdir()
        piece_files = []
        for i, hull in enumerate(hulls):
            hv, hf = _manifold_arrays(hull)
            rel = f"collision/piece_{i:03d}.obj"
            atomic_write_text(tmp / rel, obj_text(hv, hf, f"hub {name} convex piece {i}"))
            piece_files.append(rel)
        atomic_write_text(tmp / "hub.sdf", sdf_text(
            name, mass, com, I_com, piece_files,
            origin="hub {name} imported from a mesh by `drakedeburr hub import`"))
        atomic_write_text(tmp / "summary.json", json.dumps(summary, indent=2) + "\n")
        if target.exists():  # a stale or incomplete import with the same key
            shutil.rmtree(target)
        os.rename(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if progress is not None:
        progress(steps, steps, "done")
    seconds = time.perf_counter() - t_start
    log.info("%s -> %s: %d windows, %d pieces (max reach into a window %.2f mm) in %.1f s",
             path, target, len(windows), len(pieces), intrusion * 1e3, seconds)
    return ImportedHub(dir=target.resolve(), name=name, source=path, sha256=sha, cached=False,
                       X_MH=X_MH, window_count=len(windows), piece_count=len(pieces),
                       max_window_intrusion=intrusion, seconds=seconds, summary=summary)


def _coacd_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("coacd")
    except PackageNotFoundError:
        return "?"
