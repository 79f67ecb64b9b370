"""Two digests of a cell. :func:`cell_fingerprint`: a content hash of everything a cell is built
from (the scenario file, the arm, tool and fixture models, and the hub model folder); a
verification report carries it, so a report is accepted only for the cell it checked
(``drakedeburr export`` refuses otherwise). :func:`geometry_digest`: a hash of a loaded cell's
geometry, by which a pool worker's cell is checked to be the caller's."""

from __future__ import annotations

import hashlib
from pathlib import Path

from drakedeburr.cell.tools import DEFAULT_TOOL
from drakedeburr.resources import models_dir, resolve_hub_dir, scenario_path

__all__ = ["cell_fingerprint", "geometry_digest", "hub_digest"]

#: model folders every cell draws from (each file hashed with its path inside ``models/``)
_MODEL_FOLDERS = ("robots", "tools", "fixtures")


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def cell_fingerprint(scenario: str | Path, hub: str | Path, robot: str | None,
                     tool: str | None = None) -> str:
    """SHA-256 (hex) of the scenario file, the arm/tool/fixture models, the hub folder's files
    (its own ``summary.json`` aside: statistics, not geometry), the arm's name and the burr
    variant's (None and the standard burr's name hash alike: the same cell)."""
    h = hashlib.sha256()

    def add(name: str, path: Path) -> None:
        data = path.read_bytes()
        h.update(f"{name}\0{len(data)}\0".encode())
        h.update(data)

    add("scenario", scenario_path(scenario))
    root = models_dir()
    for sub in _MODEL_FOLDERS:
        for f in _files(root / sub):
            add(str(f.relative_to(root)), f)
    hub_dir = resolve_hub_dir(hub)
    for f in _files(hub_dir):
        if f.name != "summary.json":
            add("hub/" + str(f.relative_to(hub_dir)), f)
    h.update(f"robot\0{robot or ''}".encode())
    if tool not in (None, DEFAULT_TOOL):
        h.update(f"tool\0{tool}".encode())
    return h.hexdigest()


def hub_digest(hub: str | Path) -> str:
    """SHA-256 (hex) of a hub model folder's files (their paths inside it and their bytes;
    ``summary.json`` aside: statistics, not geometry): what a plan records of the hub it was
    made for (``plan.json`` ``hub_ref``), so verify and export can refuse a changed hub."""
    h = hashlib.sha256()
    hub_dir = resolve_hub_dir(hub)
    for f in _files(hub_dir):
        if f.name != "summary.json":
            data = f.read_bytes()
            h.update(f"{f.relative_to(hub_dir)}\0{len(data)}\0".encode())
            h.update(data)
    return h.hexdigest()


def geometry_digest(cell) -> str:
    """A digest of a cell's geometry (~30 ms, kept in ``cell.memo``): every proximity
    geometry's name, shape kind, hull or bounding points in its frame and world pose at the
    default configuration, and the cell's home and joint limits. Two processes that built the
    same cell agree on it; a model rewritten at the same path (a hub regenerated) changes it,
    so a worker's cell kept from an earlier run is never taken for the caller's."""
    fp = cell.memo.geometry_digest
    if fp is None:
        import hashlib

        import numpy as np
        from pydrake.geometry import Role

        from drakedeburr.cell.narrowphase import box_points

        plant, inspector = cell.plant, cell.scene_graph.model_inspector()
        pc = plant.CreateDefaultContext()
        h = hashlib.sha256()
        for g in sorted(inspector.GetAllGeometryIds(Role.kProximity), key=lambda g: g.get_value()):
            shape = inspector.GetShape(g)
            X = plant.EvalBodyPoseInWorld(pc, plant.GetBodyFromFrameId(inspector.GetFrameId(
                g))).multiply(inspector.GetPoseInFrame(g)).GetAsMatrix4()
            h.update(f"{inspector.GetName(g)}|{type(shape).__name__}".encode())
            h.update(np.ascontiguousarray(box_points(shape)).tobytes() + X.tobytes())
        for arr in (cell.q_home, cell.q_lower, cell.q_upper):
            h.update(np.ascontiguousarray(arr, float).tobytes())
        fp = cell.memo.geometry_digest = h.hexdigest()
    return fp
