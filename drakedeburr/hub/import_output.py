"""What ``hub import`` writes: the summary (``summary.json``) and the hub folder (atomically:
a temporary folder renamed into place)."""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drakedeburr._io import atomic_write_text, temp_folder_beside
from drakedeburr.hub.types import WindowEdge

__all__ = ["ImportRecord", "window_summary", "import_summary", "write_folder"]


@dataclass(frozen=True)
class ImportRecord:
    """What an import (mesh or CAD) made, in the hub frame H [m, kg], for the summary and the
    folder: the source (``name``, ``path``, ``sha`` of the file, cache ``key``, file ``unit``,
    ``closed`` solid, ``X_MH`` file -> H, ``options`` ImportOptions, ``notes`` of the window
    search), the tessellation ``V_H`` (N, 3) / ``F`` (M, 3), the ``windows`` (WindowEdge), the
    mass properties (``mass``, ``com`` (3,), ``I_com`` (3, 3) about the centre of mass,
    ``volume`` [m^3] and ``how`` it was computed), ``diameter``, and the collision model
    (``pieces`` point sets, their convex ``hulls``, ``coll`` figures)."""

    name: str
    path: Path
    sha: str
    key: str
    unit: str
    closed: bool
    X_MH: np.ndarray
    options: Any
    notes: dict
    V_H: np.ndarray
    F: np.ndarray
    windows: list
    mass: float
    com: np.ndarray
    I_com: np.ndarray
    volume: float
    how: str
    diameter: float
    pieces: list
    hulls: list = field(default_factory=list)
    coll: dict = field(default_factory=dict)


def window_summary(windows: list[WindowEdge], spacing: float) -> list[dict]:
    from drakedeburr.hub.outline import window_center_xy
    from drakedeburr.hub.truth import loop_curvature

    out = []
    for w in windows:
        p = w.p_HE
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        kappa = loop_curvature(p, max(2, int(round(2e-3 / spacing))))
        c_xy = window_center_xy(p[:, :2])
        u = c_xy / np.linalg.norm(c_xy)
        out.append({
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
    return out


def write_folder(target: Path, out_root: Path, rec: ImportRecord, summary: dict) -> None:
    """Write the hub folder of ``rec`` (with ``summary`` as summary.json) into a temporary
    folder and rename it into place."""
    import yaml

    from drakedeburr.hub.files import obj_text, sdf_text, write_npz
    from drakedeburr.hub.solid import mesh_arrays

    name, path, sha, windows, hulls = rec.name, rec.path, rec.sha, rec.windows, rec.hulls
    V_H, F, mass, com, I_com = rec.V_H, rec.F, rec.mass, rec.com, rec.I_com
    out_root.mkdir(parents=True, exist_ok=True)
    # the user's umask (mkdtemp makes 0700); a killed import's leftovers are removed
    tmp = temp_folder_beside(target)
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
            hv, hf = mesh_arrays(hull)
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


def import_summary(rec: ImportRecord) -> dict:
    """The content of summary.json of ``rec`` (the bundled hubs' keys plus ``import``)."""
    from drakedeburr.hub.import_collision import coacd_version
    from drakedeburr.hub.import_common import options_json
    from drakedeburr.hub.import_options import IMPORT_VERSION

    name, path, sha, key, unit, closed = rec.name, rec.path, rec.sha, rec.key, rec.unit, rec.closed
    X_MH, options, notes, V_H, F, windows = (rec.X_MH, rec.options, rec.notes, rec.V_H, rec.F,
                                             rec.windows)
    volume, how, diameter, mass, com = rec.volume, rec.how, rec.diameter, rec.mass, rec.com
    pieces, coll = rec.pieces, rec.coll
    hull_volume = float(sum(h.volume() for h in rec.hulls))
    return {
        "name": name,
        "import": {"source": str(path.resolve()), "sha256": sha, "cache_key": key,
                   "version": IMPORT_VERSION, "unit": unit, "closed_mesh": closed,
                   "axis_estimated": bool(options.axis_M is None),
                   "X_MH": np.round(X_MH, 9).tolist(), "options": options_json(options),
                   "front": notes.get("front"),
                   "min_window_width_mm": notes["min_window_width_mm"],
                   "burrs_mm": notes.get("burrs_mm"),
                   "not_windows": notes["not_windows"], "rejected": notes["rejected"],
                   "loops": notes["loops"], "dropped": notes.get("dropped")},
        "frame": "H: origin on the hub axis at the front face of the centre, +Z out of the "
                 "visible face",
        "units": "metres in every data file; mm in this summary",
        "mesh": {"vertices": int(len(V_H)), "triangles": int(len(F)),
                 "watertight": closed, "volume_m3": round(volume, 9),
                 "volume_from": how, "diameter_mm": round(diameter * 1e3, 2)},
        "mass_kg": round(mass, 4),
        "center_of_mass_m": [round(float(c), 6) for c in com],
        "window_count": len(windows), "windows": window_summary(windows, options.edge_spacing),
        "collision": {
            "method": (f"CoACD {coacd_version()} on the solid simplified within "
                       f"{options.simplify_tolerance * 1e3:g} mm (threshold "
                       f"{options.threshold:g}), pieces reaching into a window or proud of "
                       f"the front cut at the offending probe ({options.refine})" if closed
                       else "surface shell (open mesh): hulls of the triangles in plan-view "
                            f"cells, {options.shell_thickness * 1e3:g} mm thick, cells split "
                            "while a hull holds a probe in a window opening or above the front"),
            "piece_count": len(pieces),
            "hull_volume_over_solid": round(hull_volume / volume, 4),
            "window_reach_allowed_mm": round(options.window_reach * 1e3, 3),
            "front_reach_allowed_mm": round(options.front_reach * 1e3, 3),
            "front_reach_far_allowed_mm": round(options.front_reach_far * 1e3, 3),
            "front_band_mm": round(options.front_band * 1e3, 3), **coll,
        },
    }
