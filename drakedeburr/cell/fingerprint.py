"""A content hash of everything a cell is built from: the scenario file, the arm, tool and
fixture models, and the hub model folder. A verification report carries it, so a report is
accepted only for the cell it checked (``drakedeburr export`` refuses otherwise)."""

from __future__ import annotations

import hashlib
from pathlib import Path

from drakedeburr.cell.tools import DEFAULT_TOOL
from drakedeburr.resources import models_dir, resolve_hub_dir, scenario_path

__all__ = ["cell_fingerprint", "hub_digest"]

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
