"""HubSpec -> watertight hub mesh, ground-truth window edges, convex collision pieces, SDF.

Construction (manifold3d, robust booleans; everything in millimetres inside the geometry
modules, metres in every file written):

1. 2-D window outlines (:mod:`drakedeburr.hub.outline`).
2. The face plate (front and back height fields, window walls with draft and edge round,
   :mod:`drakedeburr.hub.surface`), united with the hub pad and the rim, minus the centre bore
   and the bolt holes with their lug seats (:mod:`drakedeburr.hub.solid`). The result is
   checked: watertight volume, genus = windows + bolt holes + 1.
3. Vertices are rounded to 0.1 um (the OBJ precision); the ground-truth edge loops are read
   from the final mesh (:mod:`drakedeburr.hub.truth`).
4. Collision pieces (:mod:`drakedeburr.hub.collision`): hulls covering the material, split
   until none reaches into a window opening; the reach is measured and recorded
   (``summary.json``: ``collision.max_window_intrusion_mm``).
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.hub.collision import (
    COLL_FRONT_BAND_MM,
    COLL_FRONT_REACH_MM,
    COLL_SAG_MM,
    COLL_TOL_MM,
    COLL_WINDOW_REACH_MM,
    WindowProbes,
    collision_pieces,
    window_intrusion,
)
from drakedeburr.hub.files import OBJ_DECIMALS, obj_text, sdf_text, write_npz
from drakedeburr.hub.outline import (
    LINE_STEP_MM,
    Window,
    build_window_outlines,
    inscribed_width,
    window_center_xy,
)
from drakedeburr.hub.solid import PlateGeometry, build_solid, mesh_arrays, plate_geometry
from drakedeburr.hub.spec import HubSpec, spec_to_yaml
from drakedeburr.hub.truth import ground_truth_loops, loop_curvature

__all__ = ["GeneratedHub", "generate_hub", "build_window_outlines", "build_solid",
           "write_npz", "window_intrusion", "sdf_text", "obj_text", "loop_curvature",
           "window_center_xy", "WindowProbes", "GENERATOR_VERSION", "LINE_STEP_MM"]

log = logging.getLogger(__name__)

#: recorded in every hub's summary.json; 2: the plate's collision pieces keep within 1 mm of
#: the front face near the windows (front probes, session 12)
GENERATOR_VERSION = 2

Progress = Callable[[int, int, str], None] | None


@dataclass(frozen=True)
class GeneratedHub:
    """What :func:`generate_hub` wrote.

    Attributes:
        dir: the hub folder.
        files: every file written (relative to ``dir``), sorted.
        seconds: generation wall time [s].
        summary: the content of ``summary.json``.
    """

    dir: Path
    files: tuple[str, ...]
    seconds: float
    summary: dict


def _intrusion_loops(spec: HubSpec, windows: list[Window], geom: PlateGeometry,
                     loops: list[dict]) -> tuple[list[dict], float]:
    """Edge points and wall normals from which the reach of the pieces into the openings is
    measured, and the wall's drift per unit depth: the ground-truth loops, or with a draft or
    an edge round the sharp outline on the front face (the wall's top line)."""
    if not (spec.wall_draft or spec.edge_round_radius):
        return loops, 0.0
    out = []
    for w, e in zip(windows, geom.edges, strict=True):
        p = np.column_stack([w.poly_mm, geom.surface.front(w.poly_mm)]) * 1e-3
        out.append({"p_HE": p, "n_wall_H": np.column_stack([e.normals2d,
                                                            np.zeros(len(p))])})
    return out, math.tan(spec.wall_draft)


def _write_collision(spec: HubSpec, windows: list[Window], geom: PlateGeometry,
                     loops: list[dict], out: Path, solid_volume: float) -> tuple[list, dict]:
    """Write ``collision/piece_NNN.obj`` (stale pieces removed); (files, summary entry)."""
    from manifold3d import Manifold

    pieces = collision_pieces(spec, windows, geom)
    coll_dir = out / "collision"
    coll_dir.mkdir(exist_ok=True)
    piece_V, piece_files = [], []
    hull_vol = 0.0
    for i, piece in enumerate(pieces):
        hull = Manifold.hull_points(piece)
        hull_vol += hull.volume() * 1e-9
        pv, pf = mesh_arrays(hull)
        pv_m = np.round(pv * 1e-3, OBJ_DECIMALS) + 0.0
        piece_V.append(pv_m)
        name = f"collision/piece_{i:03d}.obj"
        atomic_write_text(out / name, obj_text(pv_m, pf, f"hub {spec.name} convex piece {i}"))
        piece_files.append(name)
    for stale in sorted(coll_dir.glob("piece_*.obj")):
        if f"collision/{stale.name}" not in piece_files:
            stale.unlink()
    probe_loops, drift = _intrusion_loops(spec, windows, geom, loops)
    intrusion = window_intrusion(probe_loops, piece_V, spec.face_thickness, drift=drift)
    info = {
        "method": "face plate: quadtree of square cells, convex hull of each connected "
                  f"part, split while the hull adds > {COLL_TOL_MM} mm average thickness or "
                  f"reaches > {COLL_WINDOW_REACH_MM} mm into a window or stands > "
                  f"{COLL_FRONT_REACH_MM} mm proud of the front face within "
                  f"{COLL_FRONT_BAND_MM:.0f} mm of a window, then greedy merging "
                  "of touching pieces under the same rule; pad and rim: hulls of annular "
                  f"sectors (chord sag <= {COLL_SAG_MM} mm)",
        "piece_count": len(pieces),
        "hull_volume_over_solid": round(hull_vol / solid_volume, 4),
        "max_window_intrusion_mm": round(intrusion * 1e3, 3),
        "bolt_holes_filled": True,
    }
    return piece_files, info


def _window_summary(spec: HubSpec, loops: list[dict]) -> list[dict]:
    out = []
    for lp in loops:
        p = lp["p_HE"]
        # curvature over chords of ~0.6 of the smallest radius (fillet or blend): consecutive
        # points are collinear between outline vertices and would give spikes
        r_min = min(lp["fillet_m"], spec.blend_radius)
        kappa = loop_curvature(p, max(2, int(0.3 * r_min / spec.edge_sample_spacing)))
        c_xy = window_center_xy(lp["poly_xy_m"])
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        entry = {
            "index": lp["index"], "kind": lp["kind"], "points": int(len(p)),
            "length_mm": round(float(seg.sum()) * 1e3, 3),
            "max_spacing_mm": round(float(seg.max()) * 1e3, 4),
            "fillet_mm": round(lp["fillet_m"] * 1e3, 3),
            "max_curvature_per_mm": round(float(np.percentile(kappa, 99.5)) * 1e-3, 4),
            "z_range_mm": [round(float(p[:, 2].min()) * 1e3, 3),
                           round(float(p[:, 2].max()) * 1e3, 3)],
            "center_xy_mm": [round(float(c_xy[0]) * 1e3, 3), round(float(c_xy[1]) * 1e3, 3)],
            "width_mm": round(float(np.ptp(lp["poly_xy_m"] @ np.array(
                [-c_xy[1], c_xy[0]]) / np.linalg.norm(c_xy))) * 1e3, 2),
            "radial_size_mm": round(float(np.ptp(lp["poly_xy_m"] @ (c_xy / np.linalg.norm(
                c_xy)))) * 1e3, 2),
        }
        if spec.uses_optional_features():
            # the burr's passage: largest inscribed circle of the opening at the back (the
            # narrowest section with a draft), as the importer measures it
            shrink = spec.face_thickness * math.tan(spec.wall_draft)
            entry["inscribed_width_mm"] = round(
                inscribed_width(lp["poly_xy_m"]) * 1e3 - 2 * shrink * 1e3, 2)
        out.append(entry)
    return out


def generate_hub(spec: HubSpec, out_dir: str | Path, *, progress: Progress = None,
                 with_collision: bool = True) -> GeneratedHub:
    """Generate every asset of one hub into ``out_dir`` (the hub's folder).

    Writes ``hub.yaml`` (the spec), ``hub.obj`` (watertight mesh, metres, frame H),
    ``edges.npz`` (ground-truth loops: ``w{i}_p_HE``, ``w{i}_t_H``, ``w{i}_n_wall_H``,
    ``w{i}_n_face_H`` (N, 3) and ``kinds``), ``summary.json`` (human-readable: windows, mass,
    collision quality), ``collision/piece_NNN.obj`` and ``hub.sdf``. Deterministic: the same
    spec gives byte-identical files. Stale pieces in ``collision/`` are removed.

    Raises:
        InputError: the spec is invalid (names the field).
    """
    import trimesh

    t_start = time.perf_counter()
    spec.validate()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    steps = 5
    if progress:
        progress(0, steps, "outlines")
    windows = build_window_outlines(spec)
    geom = plate_geometry(spec, windows)
    if progress:
        progress(1, steps, "solid")
    solid = build_solid(spec, windows, geom=geom)
    V_mm, F = mesh_arrays(solid)
    V_m = np.round(V_mm * 1e-3, OBJ_DECIMALS) + 0.0
    genus = solid.genus()
    expected_genus = spec.window_count + spec.bolt_count + 1
    if genus != expected_genus:
        raise RuntimeError(f"hub {spec.name!r}: genus {genus}, expected {expected_genus}")
    if progress:
        progress(2, steps, "edges")
    loops = ground_truth_loops(spec, windows, geom, V_m, F)
    tm = trimesh.Trimesh(V_m, F, process=False)
    if not (tm.is_watertight and tm.is_volume):
        raise RuntimeError(f"hub {spec.name!r}: mesh is not a watertight volume")
    mp = tm.mass_properties
    mass = float(mp.volume * spec.density)
    com = np.asarray(mp.center_mass)
    I_com = np.asarray(mp.inertia) * spec.density  # about the centre of mass, axes of H
    I_com = 0.5 * (I_com + I_com.T)

    files = ["hub.yaml", "hub.obj", "edges.npz"]
    atomic_write_text(out / "hub.yaml", spec_to_yaml(spec))
    atomic_write_text(out / "hub.obj", obj_text(V_m, F, f"drakedeburr hub {spec.name}"))
    arrays: dict[str, np.ndarray] = {"kinds": np.array([lp["kind"] for lp in loops])}
    for lp in loops:
        for key in ("p_HE", "t_H", "n_wall_H", "n_face_H"):
            arrays[f"w{lp['index']}_{key}"] = lp[key]
    write_npz(out / "edges.npz", arrays)

    if progress:
        progress(3, steps, "collision pieces")
    piece_files, collision_info = [], {}
    if with_collision:
        piece_files, collision_info = _write_collision(spec, windows, geom, loops, out,
                                                       float(mp.volume))
        files.extend(piece_files)
    atomic_write_text(out / "hub.sdf", sdf_text(spec.name, mass, com, I_com, piece_files))
    files.append("hub.sdf")

    if progress:
        progress(4, steps, "summary")
    summary = {
        "name": spec.name, "generator_version": GENERATOR_VERSION,
        "frame": "H: origin on the hub axis at the front face centre, +Z out of the visible face",
        "units": "metres in every data file; mm in this summary",
        "mesh": {"vertices": int(len(V_m)), "triangles": int(len(F)), "genus": int(genus),
                 "watertight": True, "volume_m3": round(float(mp.volume), 9)},
        "mass_kg": round(mass, 4),
        "center_of_mass_m": [round(float(c), 6) for c in com],
        "window_count": len(loops), "windows": _window_summary(spec, loops),
        "collision": collision_info,
    }
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    files.append("summary.json")
    if progress:
        progress(steps, steps, "done")
    seconds = time.perf_counter() - t_start
    log.info("hub %s: %d vertices, %d triangles, %d windows, %d pieces in %.1f s", spec.name,
             len(V_m), len(F), len(loops), len(piece_files), seconds)
    return GeneratedHub(out, tuple(sorted(files)), seconds, summary)
