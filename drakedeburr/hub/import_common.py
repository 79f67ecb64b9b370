"""The steps a mesh import (:mod:`drakedeburr.hub.import_mesh`) and a CAD import
(:mod:`drakedeburr.hub.import_cad`) share: the cache folder of an import, the wheel-size
check, the ray scene, the origin on the centre's front face, the collision pieces around the
windows' wall lines, and which burrs of the tool library an opening is judged by.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.extract import principal_axis, ray_scene
from drakedeburr.hub.openings import judged_burrs, narrow_reason

if TYPE_CHECKING:
    from drakedeburr.hub.import_options import ImportOptions

__all__ = ["ImportedHub", "Progress", "DIAMETER_RANGE", "file_hash", "options_json",
           "cache_key", "cache_slot", "hub_name", "from_cache", "front_origin_offset",
           "ray_scene", "across_axis", "wheel_diameter", "wall_line", "collision_pieces",
           "judged_burrs", "narrow_reason"]

log = logging.getLogger(__name__)

DIAMETER_RANGE = (0.150, 0.700)  # [m] plausible wheel diameter across the hub axis

Progress = Callable[[int, int, str], None] | None


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
        summary: the content of ``summary.json`` (``import.front``: the front side chosen and
            its evidence; ``import.not_windows``: openings that are no window, with reasons).
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


def file_hash(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def options_json(options: ImportOptions) -> dict:
    d = dataclasses.asdict(options)
    if d["axis_M"] is not None:
        d["axis_M"] = [float(v) for v in d["axis_M"]]
    return d


def cache_key(sha: str, options: ImportOptions, **versions) -> str:
    """Hash of the file's bytes (``sha``), the options and ``versions`` (what else decides the
    result: the import's version, a chordal tolerance)."""
    blob = json.dumps({"sha256": sha, "options": options_json(options), **versions},
                      sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def cache_slot(path: Path, out_root: Path, options: ImportOptions, t_start: float,
               **versions) -> tuple[str, str, str, Path, ImportedHub | None]:
    """(sha256, cache key, hub name, target folder, the cached ImportedHub or None) of an
    import of ``path`` under ``out_root``: the folder ``<name>_<key[:12]>``."""
    sha = file_hash(path)
    key = cache_key(sha, options, **versions)
    name = hub_name(path)
    target = Path(out_root) / f"{name}_{key[:12]}"
    return sha, key, name, target, from_cache(target, key, name, path, sha, t_start)


def hub_name(path: Path) -> str:
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


def front_origin_offset(scene, r_inner: float, z_top: float) -> float:
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


def across_axis(mesh, axis_M) -> tuple[float, np.ndarray, np.ndarray]:
    """(extent [m] across the hub axis, the axis z_M, the centre of that extent) - the axis
    is the principal axis unless given."""
    z_M = principal_axis(mesh)[0] if axis_M is None else np.asarray(axis_M, float)
    z_M = z_M / np.linalg.norm(z_M)
    v = mesh.vertices - mesh.vertices.mean(axis=0)
    across = v - np.outer(v @ z_M, z_M)
    basis = np.linalg.svd(across, full_matrices=False)[2][:2]
    span = across @ basis.T
    centre = mesh.vertices.mean(axis=0) + 0.5 * (span.min(axis=0) + span.max(axis=0)) @ basis
    return float(np.max(np.ptp(span, axis=0))), z_M, centre


def wheel_diameter(path: Path, mesh, axis_M, unit: str) -> float:
    """Extent [m] across the hub axis (principal axis unless given); InputError when it is not
    a wheel's."""
    diameter = across_axis(mesh, axis_M)[0]
    if not DIAMETER_RANGE[0] <= diameter <= DIAMETER_RANGE[1]:
        raise InputError(
            f"{path}: diameter across the hub axis {diameter * 1e3:.0f} mm (file read as "
            f"{unit}) is not a wheel hub's ({DIAMETER_RANGE[0] * 1e3:.0f}-"
            f"{DIAMETER_RANGE[1] * 1e3:.0f} mm); force the unit (unit='m'/'mm') or check the "
            f"file")
    return diameter


def wall_line(xy: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(M, 9) the opening's outline ``xy`` (M, 2) lifted to the height of the nearest edge
    point of ``p`` (N, 3), its horizontal normal into the opening and its tangent."""
    from scipy.spatial import cKDTree

    z = p[cKDTree(p[:, :2]).query(xy)[1], 2]
    tang = np.roll(xy, -1, axis=0) - np.roll(xy, 1, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    left = np.c_[-tang[:, 1], tang[:, 0]]
    zeros = np.zeros(len(xy))
    return np.c_[xy, z, left, zeros, tang, zeros]


def _opening_test(scene, closed: bool, reach: float, z_top: float):
    """Callable (K, 3) probes -> (K,) bool: the probe lies in a window opening (closed mesh:
    outside the solid by > reach / 2; open mesh: a ray along the axis through it misses)."""
    import open3d as o3d

    def in_opening(q: np.ndarray) -> np.ndarray:
        if closed:
            d = scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32))).numpy()
            return d > 0.5 * reach
        rays = np.zeros((len(q), 6), np.float32)
        rays[:, :2], rays[:, 2], rays[:, 5] = q[:, :2], z_top, -1.0
        return ~np.isfinite(scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy())

    return in_opening


def collision_pieces(path: Path, V_H, F, walls, closed: bool, options: ImportOptions,
                     progress: Progress, steps: int):
    """(pieces, statistics) of the collision model (import_collision). The opening probes
    start from each opening's innermost wall line (``walls``, see _frame_and_windows): an
    edge round or a draft sets the deburring edge back from it."""
    import trimesh
    from manifold3d import Manifold, Mesh64

    from drakedeburr.hub.collision import WindowProbes, window_intrusion
    from drakedeburr.hub.import_collision import (
        front_probes,
        shell_patch,
        shell_pieces,
        solid_pieces,
    )

    scene = ray_scene(V_H, F)
    normals = trimesh.Trimesh(V_H, F, process=False).face_normals
    in_opening = _opening_test(scene, closed, options.window_reach, float(V_H[:, 2].max()) + 0.01)
    probe_pts, probe_edge = [], []
    for wall in walls:
        # probes at most window_reach / 2 apart along the wall (closer on the outline)
        wall = wall[::max(1, int(0.5 * options.window_reach / options.edge_spacing))]
        q0 = wall[:, :3] + options.window_reach * wall[:, 3:6]
        for f in np.linspace(0.02, 0.98, 6):
            probe_pts.append(q0 - np.array([0.0, 0.0, f * options.probe_depth]))
            probe_edge.append(wall)
    probe_pts, probe_edge = np.concatenate(probe_pts), np.concatenate(probe_edge)
    ok = in_opening(probe_pts)
    face_pts, face_cut = front_probes(scene, normals, options, closed=closed,
                                      walls_xy=np.concatenate([w[:, :2] for w in walls]))
    probes = WindowProbes(np.concatenate([probe_pts[ok], face_pts]))
    t_coll = time.perf_counter()
    sub = None if progress is None else (lambda d, n, label: progress(2, steps, label))
    if closed:
        solid = Manifold(Mesh64(np.ascontiguousarray(V_H),
                                np.ascontiguousarray(F.astype(np.uint64))))
        if solid.status().name != "NoError" or solid.is_empty():
            raise InputError(f"{path}: the mesh is watertight but not a valid solid (manifold3d: "
                             f"{solid.status().name}); self-intersections or inverted faces?")
        pieces, stats = solid_pieces(solid.simplify(options.simplify_tolerance), probes,
                                     np.concatenate([probe_edge[ok], face_cut]), options, sub)
        pieces, patched = shell_patch(pieces, V_H, F, probes, options, sub)
        stats.update(patched)
    else:
        pieces, stats = shell_pieces(V_H, F, probes, options, sub)
    loops = [{"p_HE": wall[:, :3], "n_wall_H": wall[:, 3:6]} for wall in walls]
    stats.update(
        seconds=round(time.perf_counter() - t_coll, 2),
        max_window_intrusion_mm=round(window_intrusion(
            loops, pieces, options.probe_depth, keep=in_opening) * 1e3, 3),
        probes_in_openings=int(ok.sum()), front_probes=int(len(face_pts)),
        front_probes_inside_pieces=int(sum(len(WindowProbes(face_pts).inside(pv))
                                           for pv in pieces)))
    return pieces, stats


def from_cache(target: Path, key: str, name: str, path: Path, sha: str,
                t_start: float) -> ImportedHub | None:
    summary = _cached(target, key)
    if summary is None:
        return None
    log.info("%s: reusing %s (same mesh and options)", path, target)
    return ImportedHub(dir=target.resolve(), name=name, source=path, sha256=sha, cached=True,
                       X_MH=np.asarray(summary["import"]["X_MH"], float),
                       window_count=summary["window_count"],
                       piece_count=summary["collision"]["piece_count"],
                       max_window_intrusion=summary["collision"]["max_window_intrusion_mm"]
                       * 1e-3, seconds=time.perf_counter() - t_start, summary=summary)


