"""Mesh file (STL/OBJ/PLY) -> hub model folder that the cell, planner and verifier load like a
bundled hub (``hub.yaml``, ``hub.obj``, ``edges.npz``, ``summary.json``, ``hub.sdf``,
``collision/piece_NNN.obj``; see docs/hub.md).

Any triangle mesh of a wheel is accepted: closed or open (not watertight), one part or many,
in metres or millimetres. Steps:

1. Load and validate (:func:`drakedeburr.hub.mesh_io.load_hub_mesh`: suffix, triangles, finite
   vertices, mm/m detection) and a wheel-sized diameter across the hub axis
   (``DIAMETER_RANGE``).
2. Hub frame H, front side and window edges (:func:`drakedeburr.hub.extract.extract_window_edges`:
   axis estimated unless given, the front decided from lug seats, barrel, mounting face and
   dish unless ``front`` says, openings that are not windows listed with their reasons). The
   origin is then moved along the axis onto the front face of the centre (median height of the
   surface seen along -Z_H inside the innermost window radius).
3. Edge normals from the mesh (:mod:`drakedeburr.hub.edge_normals`).
4. Convex collision pieces (:mod:`drakedeburr.hub.import_collision`): CoACD plus targeted cuts
   for a closed mesh, a probe-checked surface shell for an open one.
5. Files are written into a temporary folder next to the target and renamed into place. The
   folder name carries a hash of the mesh bytes and the options, so importing the same file
   again returns the cached folder.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np

from drakedeburr.errors import (
    InputError,
    NoCuttableWindow,
    describe_numerical_error,
    numerical_errors,
)
from drakedeburr.hub.edge_normals import edge_normals as _edge_normals
from drakedeburr.hub.import_common import (
    DIAMETER_RANGE,
    ImportedHub,
    Progress,
    across_axis,
    cache_slot,
    collision_pieces,
    front_origin_offset,
    ray_scene,
    wall_line,
    wheel_diameter,
)
from drakedeburr.hub.import_options import IMPORT_VERSION, ImportOptions
from drakedeburr.hub.types import WindowEdge

__all__ = ["ImportOptions", "ImportedHub", "import_mesh", "IMPORT_VERSION", "DIAMETER_RANGE"]

log = logging.getLogger(__name__)




def _without_tyre(path: Path, mesh, axis_M):
    """(mesh, note): a wheel exported with its tyre (a ROS robot description's wheel.dae) is
    too large for a hub; where the parts that make it so lie wholly outside the rest - a ring
    whose inner radius is at least 0.85 of the rest's outer radius, the rest then hub-sized -
    they are the tyre: dropped, and said (a WARNING and the note). Anything else is left
    as it is (the size check then names the diameter)."""
    diameter, z_M, c = across_axis(mesh, axis_M)
    if diameter <= DIAMETER_RANGE[1]:
        return mesh, None
    import trimesh

    parts = trimesh.graph.connected_components(  # faces joined by edges; scipy (no networkx)
        mesh.face_adjacency, nodes=np.arange(len(mesh.faces)), engine="scipy")
    radii = []
    for faces in parts:
        v = mesh.vertices[np.unique(mesh.faces[faces])] - c
        r = np.linalg.norm(v - np.outer(v @ z_M, z_M), axis=1)
        radii.append((float(r.min()), float(r.max())))
    outer = [i for i, (_, r1) in enumerate(radii) if r1 > 0.5 * DIAMETER_RANGE[1]]
    rest = [i for i in range(len(parts)) if i not in outer]
    if not outer or not rest:
        return mesh, None
    r_rest = max(radii[i][1] for i in rest)
    if (min(radii[i][0] for i in outer) < 0.85 * r_rest
            or not DIAMETER_RANGE[0] <= 2.0 * r_rest <= DIAMETER_RANGE[1]):
        return mesh, None
    kept = trimesh.Trimesh(mesh.vertices, mesh.faces[np.concatenate([parts[i] for i in rest])],
                           process=True)
    n_faces = sum(len(parts[i]) for i in outer)
    note = (f"tyre dropped: {len(outer)} part(s), {n_faces} faces, a ring "
            f"{2e3 * min(radii[i][0] for i in outer):.0f}-{diameter * 1e3:.0f} mm across the "
            f"hub axis around the rest ({2e3 * r_rest:.0f} mm)")
    log.warning("%s: %s", path, note)
    return kept, note


def _frame_and_windows(path: Path, mesh, options: ImportOptions):
    """(X_MH, V_H, F, windows, extraction notes, wall lines): the frame with its origin on the
    centre's front face, the mesh in H, the windows with normals read off the mesh, and per
    window its opening's outline (the innermost wall) at the edge's height with the outline's
    normal into the opening and its tangent ((M, 9): point, normal, tangent in H)."""
    import trimesh

    from drakedeburr.hub.extract import extract_window_edges
    from drakedeburr.hub.openings import OpeningSearch

    search = OpeningSearch.of(options.burr_diameter, options.burr_diameters,
                              options.clearance, options.min_window_width)
    ext = extract_window_edges(mesh, source=str(path), axis_M=options.axis_M,
                               front=options.front, spacing=options.edge_spacing,
                               search=search, expected_windows=options.expected_windows)
    X_MH = np.array(ext.X_MH, float)
    X_HM = np.linalg.inv(X_MH)
    V_H = mesh.vertices @ X_HM[:3, :3].T + X_HM[:3, 3]
    F = np.asarray(mesh.faces, np.int64)
    r_inner = min(float(np.linalg.norm(w.p_HE[:, :2], axis=1).min()) for w in ext.windows)
    dz = front_origin_offset(ray_scene(V_H, F), r_inner, float(V_H[:, 2].max()) + 0.01)
    X_MH[:3, 3] += dz * X_MH[:3, 2]
    V_H[:, 2] -= dz
    V_H = np.round(V_H, 7) + 0.0  # the OBJ precision (0.1 um): files and memory agree
    scene = ray_scene(V_H, F)
    normals = trimesh.Trimesh(V_H, F, process=False).face_normals
    windows, walls = [], []
    for w, xy in zip(ext.windows, ext.outlines_xy, strict=True):
        p = w.p_HE - np.array([0.0, 0.0, dz])
        try:
            n_wall, n_face, t = _edge_normals(scene, normals, p, xy)
        except numerical_errors() as exc:  # this window, named; the others go on
            c = p.mean(axis=0)
            why = f"numerical failure reading its normals: {describe_numerical_error(exc)}"
            log.warning("%s: window at (%.0f, %.0f) mm dropped: %s", path, c[0] * 1e3,
                        c[1] * 1e3, why)
            ext.notes["rejected"].append({"center_xy_mm": [round(float(c[0]) * 1e3, 2),
                                                           round(float(c[1]) * 1e3, 2)],
                                          "reason": why})
            continue
        windows.append(WindowEdge(index=len(windows), kind=w.kind, p_HE=p, t_H=t,
                                  n_wall_H=n_wall, n_face_H=n_face))
        walls.append(wall_line(xy, p))
    if not windows:
        raise NoCuttableWindow(f"{path}: no window left: "
                               + "; ".join(r["reason"] for r in ext.notes["rejected"]),
                               source=str(path), axis=X_MH[:3, 2],
                               openings=ext.notes["not_windows"], rejected=ext.notes["rejected"])
    return X_MH, V_H, F, windows, ext.notes, walls


def _mass_properties(path: Path, V_H, F, hulls, closed: bool, density: float):
    """(mass [kg], com (3,) [m], inertia about the com (3, 3) [kg m^2], volume [m^3], how):
    of the solid for a closed mesh; of the union of the surface shell pieces for an open one
    (whose solid is unknown: the real part is heavier, which the summary says)."""
    import trimesh
    from manifold3d import Manifold, OpType

    if closed:
        mp = trimesh.Trimesh(V_H, F, process=False).mass_properties
        how = "the closed mesh"
    else:
        union = Manifold.batch_boolean(hulls, OpType.Add)
        mesh = union.to_mesh64()
        mp = trimesh.Trimesh(np.asarray(mesh.vert_properties[:, :3]),
                             np.asarray(mesh.tri_verts), process=False).mass_properties
        how = ("the union of the surface shell pieces (open mesh: the solid's volume is "
               "unknown; the real part is heavier)")
    if mp.volume <= 0:
        raise InputError(f"{path}: the mesh encloses no volume (faces inside out?)")
    I_com = np.asarray(mp.inertia) * density
    return (float(mp.volume * density), np.asarray(mp.center_mass), 0.5 * (I_com + I_com.T),
            float(mp.volume), how)


def _warn_pieces(path: Path, coll: dict, options: ImportOptions) -> None:
    """WARNINGs for pieces that reach into an opening or stand proud of the front."""
    if coll["max_window_intrusion_mm"] > options.window_reach * 1e3:
        log.warning("%s: collision pieces reach %.2f mm into a window opening (allowed %.2f mm)",
                    path, coll["max_window_intrusion_mm"], options.window_reach * 1e3)
    if coll["front_probes_inside_pieces"]:
        log.warning("%s: %d probes above the front surface lie inside collision pieces (pieces "
                    "stand more than %.1f mm proud within %.0f mm of a window, %.1f mm further "
                    "out): the planner may find the tool blocked there", path,
                    coll["front_probes_inside_pieces"], options.front_reach * 1e3,
                    options.front_band * 1e3, options.front_reach_far * 1e3)


# --------------------------------------------------------------------------- main
def import_mesh(path: str | Path, out_root: str | Path, *,
                options: ImportOptions | None = None,
                progress: Progress = None) -> ImportedHub:
    """Turn a hub mesh file into a hub model folder under ``out_root`` (see module doc).

    Args:
        path: mesh file of one hub (closed or not, m or mm; a tyre around it is dropped); a
            STEP/IGES file goes to :func:`drakedeburr.hub.import_cad.import_cad`.
        out_root: parent folder; the hub folder is ``out_root/<name>_<hash12>``.
        options: import settings. progress: optional callback (done, total, label).

    Returns: the ImportedHub (``cached`` when the folder already existed for this file +
        options).

    Raises: FileNotFoundError (no such file); InputError: not a readable mesh, not
        wheel-sized, or no window found (the message names the file, each opening and why).
    """
    from manifold3d import Manifold

    from drakedeburr.hub.cad import CAD_SUFFIXES
    from drakedeburr.hub.import_output import ImportRecord, import_summary, write_folder
    from drakedeburr.hub.mesh_io import check_mesh_file, load_hub_mesh

    options = options if options is not None else ImportOptions()
    if Path(path).suffix.lower() in CAD_SUFFIXES:  # STEP/IGES: the B-rep's exact edges
        from drakedeburr.hub.import_cad import import_cad  # noqa: I001 (OCP only for CAD)
        return import_cad(path, out_root, options=options, progress=progress)
    t_start = time.perf_counter()
    if options.refine not in ("cut", "coacd"):
        raise InputError(f"ImportOptions.refine must be 'cut' or 'coacd', got {options.refine!r}")
    if not 0 < options.front_reach <= options.front_reach_far or not options.front_band >= 0:
        raise InputError(f"ImportOptions: need 0 < front_reach <= front_reach_far and "
                         f"front_band >= 0, got {options.front_reach!r}, "
                         f"{options.front_reach_far!r}, {options.front_band!r}")
    path = Path(path)
    check_mesh_file(path)  # before hashing: a regular file within the mesh read limit
    out_root = Path(out_root)
    sha, key, name, target, cached = cache_slot(path, out_root, options, t_start,
                                                version=IMPORT_VERSION)
    if cached is not None:
        return cached
    steps = 5
    if progress is not None:
        progress(0, steps, "load mesh")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")
    lm = load_hub_mesh(path, unit=options.unit)
    mesh, tyre = _without_tyre(path, lm.mesh, options.axis_M)
    diameter = wheel_diameter(path, mesh, options.axis_M, lm.unit)
    closed = bool(mesh.is_watertight)
    if progress is not None:
        progress(1, steps, "hub frame and window edges")
    try:
        X_MH, V_H, F, windows, notes, walls = _frame_and_windows(path, mesh, options)
    except NoCuttableWindow as exc:
        exc.notes += [tyre] if tyre else []
        raise
    notes["dropped"] = tyre
    if progress is not None:
        progress(2, steps, "collision pieces (CoACD)" if closed else "collision pieces (shell)")
    try:
        pieces, coll = collision_pieces(path, V_H, F, walls, closed, options, progress, steps)
    except InputError:
        raise
    except numerical_errors() as exc:  # CoACD / Qhull / manifold3d on degenerate pieces
        raise NoCuttableWindow(
            f"{path}: {len(windows)} windows found, but the collision model could not be "
            f"built ({'CoACD pieces' if closed else 'surface shell pieces'}: "
            f"{describe_numerical_error(exc)})", source=str(path), axis=X_MH[:3, 2],
            openings=notes["not_windows"], rejected=notes["rejected"]) from exc
    _warn_pieces(path, coll, options)
    progress is not None and progress(3, steps, "write folder")
    try:
        hulls = [Manifold.hull_points(pv) for pv in pieces]
        mass, com, I_com, volume, how = _mass_properties(path, V_H, F, hulls, closed,
                                                         options.density)
    except numerical_errors() as exc:
        if isinstance(exc, InputError):  # an InputError (a ValueError) passes as it is
            raise
        raise NoCuttableWindow(
            f"{path}: the mass properties of the collision pieces could not be computed "
            f"({describe_numerical_error(exc)})", source=str(path), axis=X_MH[:3, 2],
            openings=notes["not_windows"], rejected=notes["rejected"]) from exc
    rec = ImportRecord(name, path, sha, key, lm.unit, closed, X_MH, options, notes, V_H, F,
                       windows, mass, com, I_com, volume, how, diameter, pieces, hulls, coll)
    summary = import_summary(rec)
    write_folder(target, out_root, rec, summary)
    if progress is not None:
        progress(steps, steps, "done")
    seconds = time.perf_counter() - t_start
    log.info("%s -> %s: %d windows, %d pieces (max reach into a window %.2f mm) in %.1f s",
             path, target, len(windows), len(pieces), coll["max_window_intrusion_mm"], seconds)
    return ImportedHub(dir=target.resolve(), name=name, source=path, sha256=sha, cached=False,
                       X_MH=X_MH, window_count=len(windows), piece_count=len(pieces),
                       max_window_intrusion=coll["max_window_intrusion_mm"] * 1e-3,
                       seconds=seconds, summary=summary)
