"""Load a generated hub model folder: spec, mesh, ground-truth window edges, collision, SDF.

A hub folder (``models/hubs/<name>/`` or one written by ``drakedeburr hub generate --out``)
holds ``hub.yaml``, ``hub.obj``, ``edges.npz``, ``summary.json``, ``hub.sdf`` and
``collision/piece_NNN.obj``. See docs/hub.md.
"""

from __future__ import annotations

import functools
import json
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.spec import HubSpec, load_spec
from drakedeburr.hub.types import WindowEdge

__all__ = ["HubModel", "load_hub", "resolve_hub_dir", "read_obj"]


@dataclass(frozen=True, eq=False)
class HubModel:
    """A generated hub, everything in the hub frame H, metres.

    Attributes:
        name: hub name (folder name / spec name).
        dir: the hub folder.
        spec: the HubSpec it was generated from; None for a hub imported from a mesh
            (``drakedeburr hub import``: its ``hub.yaml`` names the source file instead).
        vertices_H: (V, 3) mesh vertices [m] in H.
        faces: (F, 3) int triangle indices, outward (counter-clockwise) winding.
        windows: ground-truth window edges, index order (CCW about +Z_H from +X_H).
        collision_paths: the convex collision pieces (OBJ, metres, frame H).
        sdf_path: ``hub.sdf`` (model ``hub``, link ``hub`` whose body frame is H).
        mesh_path: ``hub.obj``.
        summary: the generator's summary (``summary.json``: mass, window sizes, collision
            quality).
    """

    name: str
    dir: Path
    spec: HubSpec | None
    vertices_H: np.ndarray
    faces: np.ndarray
    windows: tuple[WindowEdge, ...]
    collision_paths: tuple[Path, ...]
    sdf_path: Path
    mesh_path: Path
    summary: dict

    @functools.cached_property
    def trimesh(self):
        """The mesh as a ``trimesh.Trimesh`` (not processed: vertex order kept)."""
        import trimesh

        return trimesh.Trimesh(self.vertices_H, self.faces, process=False)

    @functools.cached_property
    def process(self):
        """The hub's process parameters (``process.yaml`` in its folder over the defaults:
        :func:`drakedeburr.config.process_parameters`)."""
        from drakedeburr.config import process_parameters

        return process_parameters(self.dir)

    @property
    def large_windows(self) -> tuple[WindowEdge, ...]:
        return tuple(w for w in self.windows if w.kind == "large")

    @property
    def small_windows(self) -> tuple[WindowEdge, ...]:
        return tuple(w for w in self.windows if w.kind == "small")

    def window_center_H(self, index: int) -> np.ndarray:
        """(3,) a point [m] on the axis-parallel line through the middle of window ``index``:
        the point of the window's outline plane farthest from its edge, at the edge's mean z."""
        info = self.summary["windows"][index]
        xy = np.asarray(info["center_xy_mm"], float) * 1e-3
        return np.array([xy[0], xy[1], float(np.mean(self.windows[index].p_HE[:, 2]))])


def read_obj(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (F, 3) of a triangle-only OBJ (as written by the generator).

    Written by hand: trimesh's loader merges/reorders vertices, the ground-truth loops refer to
    the exact vertex coordinates.
    """
    from drakedeburr._io import read_text_bounded

    text = read_text_bounded(path, "hub mesh", "mesh")  # a regular file within READ_LIMITS
    v_lines = [ln[2:] for ln in text.splitlines() if ln.startswith("v ")]
    f_lines = [ln[2:] for ln in text.splitlines() if ln.startswith("f ")]
    V = np.array(" ".join(v_lines).split(), float).reshape(-1, 3)
    try:
        F = np.array(" ".join(f_lines).split(), np.int64).reshape(-1, 3) - 1
    except ValueError as exc:
        raise InputError(f"{path}: only plain triangle faces 'f a b c' are supported") from exc
    return V, F


def resolve_hub_dir(name_or_dir: str | Path) -> Path:
    """A hub folder from a bundled name (``h5_split``), a folder, or a file inside it."""
    from drakedeburr.resources import resolve_hub_dir as _resolve

    return _resolve(name_or_dir)


#: the arrays of a hub's ``edges.npz`` (a CAD import adds each loop's NURBS)
_EDGE_ARRAYS = re.compile(
    r"kinds|w\d{1,4}_(?:p_HE|t_H|n_wall_H|n_face_H|nurbs_(?:poles|weights|knots|degree))")


def _read_edges(path: Path, n_windows: int) -> tuple[WindowEdge, ...]:
    from drakedeburr._io import check_npz_members

    # from the headers, before anything is decompressed: names, dtypes, sizes, 256 MiB in all
    check_npz_members(path, _EDGE_ARRAYS, 256 << 20, "hub edges", "kinds, w<i>_p_HE, ...",
                      kinds="fU")
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())

    data = np.load(path, allow_pickle=False)
    kinds = [str(k) for k in data["kinds"]]
    if len(kinds) != n_windows:
        raise InputError(f"{path}: {len(kinds)} windows, the hub says {n_windows}")
    out = []
    for i, kind in enumerate(kinds):
        keys = [f"w{i}_{k}" for k in ("p_HE", "t_H", "n_wall_H", "n_face_H")]
        missing = [k for k in keys if k + ".npy" not in names]
        if missing:
            raise InputError(f"{path}: window {i}: missing arrays {missing}")
        out.append(WindowEdge(index=i, kind=kind, p_HE=data[keys[0]], t_H=data[keys[1]],
                              n_wall_H=data[keys[2]], n_face_H=data[keys[3]]))
    return tuple(out)


def _imported_from(path: Path) -> dict | None:
    """The mapping of an imported hub's ``hub.yaml`` (key ``imported_from``), else None."""
    from drakedeburr._io import load_yaml

    data = load_yaml(path, "hub description")  # bounded: size, aliases, duplicate keys
    if isinstance(data, dict) and "imported_from" in data:
        if not isinstance(data.get("name"), str):
            raise InputError(f"{path}: imported hub without a 'name'")
        return data
    return None


def load_hub(name_or_dir: str | Path) -> HubModel:
    """Load a generated hub model.

    Args:
        name_or_dir: a bundled hub name (see ``drakedeburr hub list``), a hub folder, or a file
            in it (``hub.yaml``, ``hub.sdf``).

    Returns:
        The HubModel (mesh, ground-truth windows, collision pieces, SDF path).

    Raises:
        FileNotFoundError: no such hub, or its generated files are missing (message says how to
            generate them).
        InputError: a file is malformed.
    """
    d = resolve_hub_dir(name_or_dir)
    imported = _imported_from(d / "hub.yaml")
    spec = None if imported else load_spec(d / "hub.yaml")
    name = imported["name"] if imported else spec.name
    needed = ("hub.obj", "edges.npz", "summary.json", "hub.sdf")
    missing = [f for f in needed if not (d / f).is_file()]
    if missing:
        how = (f"drakedeburr hub import {imported['imported_from']} --out {d.parent}" if imported
               else f"drakedeburr hub generate {spec.name} --out {d.parent}")
        raise FileNotFoundError(f"{d}: hub model not generated ({', '.join(missing)} missing); "
                                f"run: {how}")
    V, F = read_obj(d / "hub.obj")
    from drakedeburr._io import read_bounded

    summary = json.loads(read_bounded(d / "summary.json", "hub summary", "json"))
    windows = _read_edges(d / "edges.npz",
                          int(summary["window_count"]) if imported else spec.window_count)
    pieces = tuple(sorted((d / "collision").glob("piece_*.obj")))
    return HubModel(name=name, dir=d, spec=spec, vertices_H=V, faces=F, windows=windows,
                    collision_paths=pieces, sdf_path=d / "hub.sdf", mesh_path=d / "hub.obj",
                    summary=summary)
