"""Hub mesh import (STL, OBJ, PLY, OFF, COLLADA, glTF via trimesh) with unit detection and
validation.

A car wheel is 0.3-0.9 m across. A mesh whose largest extent is above ``_MM_THRESHOLD`` is
read as millimetres and scaled to metres; the choice is logged and returned.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["LoadedMesh", "load_hub_mesh", "MESH_SUFFIXES", "OTHER_MESH_SUFFIXES",
           "CAD_SUFFIXES",
           "MESH_TARGET_SUFFIXES", "READABLE_FORMATS", "check_mesh_file"]

log = logging.getLogger(__name__)

#: triangle-mesh files trimesh reads: a CAD export (STL, OBJ, PLY, OFF), a ROS robot
#: description's COLLADA (``.dae``, through pycollada) or a glTF export; a file of several
#: parts (a tyre and a rim, a scene graph) is read as one mesh with every part placed
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".dae", ".glb")
READABLE_FORMATS = "STL, OBJ, PLY, OFF, COLLADA (.dae) or binary glTF (.glb)"
#: STEP/IGES solids are read by drakedeburr.hub.cad (exact B-rep edges), not as a mesh;
#: native CAD formats and other mesh formats are refused with what to export instead
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")
_CAD = (".x_t", ".sldprt", ".prt")
OTHER_MESH_SUFFIXES = CAD_SUFFIXES + _CAD + (".3mf", ".fbx", ".3ds", ".blend", ".dxf", ".usd",
                                             ".usdz", ".gltf")
#: a command's file argument with one of these is a mesh: read, or refused by name when read
MESH_TARGET_SUFFIXES = MESH_SUFFIXES + OTHER_MESH_SUFFIXES
_WHY_NOT = {".gltf": "its geometry may sit in separate buffer files, which the import's cache "
                     "cannot follow; export binary glTF (.glb)"}
_MM_THRESHOLD = 5.0  # a wheel larger than 5 "units" is in millimetres (5 m wheels don't exist)
_PLAUSIBLE_SIZE_M = (0.05, 2.0)  # [m] largest extent after conversion


@dataclass(frozen=True, eq=False)
class LoadedMesh:
    """A triangle mesh in metres.

    Attributes:
        mesh: trimesh.Trimesh with merged vertices, in metres, in the file's own frame M.
        source: the file path.
        unit: "m" or "mm": what the file was detected to be in.
        watertight: whether the mesh is closed.
    """

    mesh: object
    source: Path
    unit: str
    watertight: bool


def check_mesh_file(path: Path) -> int:
    """FileNotFoundError for a missing mesh file; InputError for anything but a regular file
    (``/dev/zero``, a pipe, a folder) or one over ``READ_LIMITS["mesh"]``, named with the
    limit. Returns its size. Call it before reading or hashing a mesh a user hands in."""
    from drakedeburr._io import check_regular_file

    if not Path(path).exists():
        raise FileNotFoundError(f"hub mesh {path} does not exist")
    return check_regular_file(path, "hub mesh", "mesh")


def _check_not_degenerate(mesh, path: Path) -> None:
    """Refuse a mesh with no area or no extent in some direction (every triangle collinear,
    or all on one line): nothing downstream (the axis estimate's eigenvectors, the window
    search) has a solid to work on."""
    areas = np.asarray(mesh.area_faces, float) if len(mesh.faces) else np.zeros(0)
    scale = float(np.ptp(mesh.vertices, axis=0).max()) if len(mesh.vertices) else 0.0
    if scale <= 0 or not (areas > 1e-12 * scale**2).any():
        raise InputError(f"{path}: every triangle is degenerate (collinear vertices, no area): "
                         "not a surface")
    centred = mesh.vertices - mesh.vertices.mean(axis=0)
    rank = np.linalg.matrix_rank(centred, tol=1e-9 * scale) if np.isfinite(centred).all() else 0
    if rank < 2:
        raise InputError(f"{path}: all vertices lie on one line: not a surface")


def load_hub_mesh(path: str | Path, unit: str | None = None) -> LoadedMesh:
    """Load a hub mesh and convert it to metres.

    Args:
        path: a mesh file (:data:`MESH_SUFFIXES`).
        unit: "m" or "mm" to force the unit; None detects it from the size.

    Raises:
        FileNotFoundError: no such file.
        InputError: unsupported suffix, unreadable file, no triangles, non-finite vertices,
            or an implausible size for a wheel.
    """
    import trimesh

    path = Path(path)
    check_mesh_file(path)
    suffix = path.suffix.lower()
    if suffix in CAD_SUFFIXES:
        raise InputError(f"{path}: a CAD solid (B-rep), not a triangle mesh: read it with "
                         "drakedeburr.hub.cad (`hub import`, `verify` and `cl` do)")
    if suffix not in MESH_SUFFIXES:
        what = _WHY_NOT.get(suffix, "a native CAD file; export STEP or IGES (read here) or "
                            "a mesh" if suffix in _CAD
                            else "not a format read here")
        raise InputError(f"{path}: unsupported mesh type {path.suffix!r} ({what}); export the "
                         f"hub as {READABLE_FORMATS}")
    try:
        # unprocessed first: trimesh's processing drops non-finite vertices silently
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds; name the file
        raise InputError(f"{path}: cannot read mesh: {exc}") from exc
    stated = _collada_unit(path) if suffix == ".dae" else None
    if unit is None and stated is not None:
        unit = stated
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError(f"{path}: no triangles found")
    if not np.isfinite(mesh.vertices).all():
        bad = int(np.flatnonzero(~np.isfinite(mesh.vertices).all(axis=1))[0])
        where = f"facet {bad // 3}" if path.suffix.lower() == ".stl" else f"vertex {bad}"
        raise InputError(f"{path}: {where}: a vertex is not finite "
                         f"({mesh.vertices[bad].tolist()}); every vertex needs finite "
                         "coordinates")
    if len(mesh.faces) and (mesh.faces.min() < 0 or mesh.faces.max() >= len(mesh.vertices)):
        raise InputError(f"{path}: a face refers to a vertex the file does not have")
    mesh.process()
    mesh.merge_vertices()
    _check_not_degenerate(mesh, path)
    size = float(mesh.extents.max())
    if stated is not None and unit == stated:
        log.info("%s: the file states its unit: %s", path.name,
                 "metres" if unit == "m" else "millimetres")
    elif unit is None:
        unit = "mm" if size > _MM_THRESHOLD else "m"
        log.info("%s: largest extent %.4g -> read as %s", path.name, size,
                 "millimetres" if unit == "mm" else "metres")
    elif unit not in ("m", "mm"):
        raise InputError(f"unit must be 'm' or 'mm', got {unit!r}")
    if unit == "mm":
        mesh.apply_scale(1e-3)
    size_m = float(mesh.extents.max())
    if not _PLAUSIBLE_SIZE_M[0] <= size_m <= _PLAUSIBLE_SIZE_M[1]:
        raise InputError(
            f"{path}: largest extent {size_m:.4g} m (read as {unit}) is not a wheel's size "
            f"({_PLAUSIBLE_SIZE_M[0]}-{_PLAUSIBLE_SIZE_M[1]} m); pass unit='m' or 'mm'"
        )
    watertight = bool(mesh.is_watertight)
    if not watertight:
        log.info("%s: mesh is not watertight (%d faces)", path.name, len(mesh.faces))
    return LoadedMesh(mesh=mesh, source=path, unit=unit, watertight=watertight)


def _collada_unit(path: Path) -> str | None:
    """The unit a COLLADA file states (``<asset><unit meter=...>``; trimesh keeps it as
    metadata and does not scale): "m", "mm", or None when it states none; InputError for
    any other (a SketchUp export in inches, centimetres): its coordinates would be read as
    millimetres by size."""
    import collada

    meter = collada.Collada(str(path), ignore=[collada.common.DaeUnsupportedError,
                                               collada.common.DaeBrokenRefError]
                            ).assetInfo.unitmeter
    if meter is None:
        return None
    for name, value in (("m", 1.0), ("mm", 1e-3)):
        if abs(meter - value) <= 1e-9 * value:
            return name
    raise InputError(f"{path}: the file states its unit as {meter:g} m (<unit meter=...>), "
                     "neither metres nor millimetres; export the hub in metres or millimetres")
