"""CAD file (STEP/IGES) -> hub model folder, the same files as a mesh import
(:mod:`drakedeburr.hub.import_mesh`; docs/hub.md "CAD solids").

1. Read and check the B-rep (:func:`drakedeburr.hub.cad.read_cad`; units from the file).
2. Tessellate it at a stated chordal tolerance (``BRepMesh_IncrementalMesh``): the mesh the
   collision pipeline, the front decision and the ray tests use.
3. Hub axis: the axis of the largest cylindrical face (the barrel), else the mesh's principal
   axis (or the given one); the front side as for a mesh (``--front`` or the cues of
   :mod:`drakedeburr.hub.front` on the tessellation). The origin moves onto the centre's front
   face as for a mesh.
4. Window loops on the exact edges (:func:`drakedeburr.hub.cad.cad_loops`); every other loop is
   listed with what it is (centre bore, the rim's outer edge, a blind pocket, a lug hole (one
   cylindrical wall), an opening no burr of the tool library fits with the clearance (its
   width and each burr's need), not a simple closed loop).
5. Collision pieces and the folder exactly as for a closed mesh
   (:func:`drakedeburr.hub.import_common.collision_pieces`, ``import_output.write_folder``);
   mass properties from the B-rep; the loops' NURBS are stored in ``edges.npz`` too
   (``w{i}_nurbs_poles/weights/knots/degree``, in H [m]).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError, NoCuttableWindow
from drakedeburr.hub.cad import DEFAULT_CHORDAL_TOLERANCE
from drakedeburr.hub.import_common import (
    ImportedHub,
    cache_slot,
    collision_pieces,
    front_origin_offset,
    judged_burrs,
    narrow_reason,
    ray_scene,
    wall_line,
    wheel_diameter,
)
from drakedeburr.hub.types import WindowEdge

__all__ = ["import_cad", "cad_windows", "CAD_IMPORT_VERSION"]

log = logging.getLogger(__name__)

# 6: openings judged by every burr of the tool library, lug holes by their geometry;
# 5: normals square to the loop and continuous along it (cad_loops.continuous_frames);
# 4: the wall across the loop at corners; 3: the wall beyond a corner patch; 2: corner
# patches are blends
CAD_IMPORT_VERSION = 6
#: [m] widest round hole (one cylindrical wall, within half the wheel's radius of the axis)
#: that is a lug hole, as a mesh import's bolt pattern (hub.openings)
LUG_MAX_WIDTH = 35e-3


def _frame(cad, mesh, options):
    """(X_MH, front decision dict) with +Z_H out of the front."""
    from drakedeburr.hub.cad import barrel_axis
    from drakedeburr.hub.extract import frame_from_axis, hub_frame_from_mesh, principal_axis
    from drakedeburr.hub.front import front_from_user

    if options.axis_M is not None:
        z = np.asarray(options.axis_M, float)
        z /= np.linalg.norm(z)
        est = hub_frame_from_mesh(mesh, z, front=options.front, source=str(cad.source))
        how = {"decided_by": "user (axis given)", "axis_in_file": z.round(6).tolist()}
        if est.front is not None:
            how = est.front.as_dict(est.X_MH[:3, 2])
        return est.X_MH, how, "given"
    barrel = barrel_axis(cad)
    axis_from = "the barrel's cylinder (B-rep)" if barrel else "principal axis of the surface"
    z0, point = barrel if barrel else principal_axis(mesh)
    decision = front_from_user(options.front, z0)
    if decision is None:  # the cues of a mesh import on the tessellation
        est = hub_frame_from_mesh(mesh, None, front="auto", source=str(cad.source))
        decision = est.front
        sign = 1 if float(est.X_MH[:3, 2] @ z0) > 0 else -1
    else:
        sign = decision.sign
    z = sign * z0
    X = frame_from_axis(z, point)
    return X, decision.as_dict(z), axis_from


def _raster(xy: np.ndarray, pixel: float = 0.25e-3):
    """(inscribed width [m], the point deepest inside (2,), area [m^2]) of a plan polygon."""
    from matplotlib.path import Path as MPath
    from scipy.ndimage import distance_transform_edt

    lo, hi = xy.min(axis=0) - 2 * pixel, xy.max(axis=0) + 2 * pixel
    gx = np.arange(lo[0], hi[0], pixel)
    gy = np.arange(lo[1], hi[1], pixel)
    X, Y = np.meshgrid(gx, gy)
    inside = MPath(xy).contains_points(np.c_[X.ravel(), Y.ravel()]).reshape(X.shape)
    if not inside.any():
        return 0.0, xy.mean(axis=0), 0.0
    d = distance_transform_edt(inside) * pixel
    k = np.unravel_index(int(np.argmax(d)), d.shape)
    return 2.0 * float(d.max()), np.array([gx[k[1]], gy[k[0]]]), float(inside.sum()) * pixel ** 2


def _describe(loop_H, scene, z_top, judge, r_outer) -> tuple[str, str, dict]:
    """(kind, reason, figures) of one loop in H: kind "window" or what else it is; ``judge``
    is (burrs [m], clearance [m], narrowest window [m])."""
    import open3d as o3d
    from matplotlib.path import Path as MPath

    p = loop_H["p"]
    xy = p[:, :2]
    centre = xy.mean(axis=0)
    figures = {"center_xy_mm": [round(float(v) * 1e3, 2) for v in centre],
               "radius_mm": round(float(np.linalg.norm(centre)) * 1e3, 2),
               "z_range_mm": [round(float(p[:, 2].min()) * 1e3, 2),
                              round(float(p[:, 2].max()) * 1e3, 2)]}
    r = np.linalg.norm(xy, axis=1)
    if MPath(xy).contains_point((0.0, 0.0)):
        if r.max() >= 0.98 * r_outer:
            return "outer edge", "the rim's outer edge (encloses the axis)", figures
        return "centre bore", f"encloses the hub axis (radius {r.min() * 1e3:.1f} mm)", figures
    width, deep, area = _raster(xy)
    figures.update(width_mm=round(width * 1e3, 2), area_mm2=round(area * 1e6, 1))
    ray = np.array([[deep[0], deep[1], z_top, 0, 0, -1]], np.float32)
    t = scene.cast_rays(o3d.core.Tensor(ray))["t_hit"].numpy()[0]
    if np.isfinite(t):
        return ("blind", f"not a through-opening: a ray along the axis through it meets the "
                f"solid {(z_top - t) * 1e3:.1f} mm above the origin (pocket or recess)",
                figures)
    radius = float(np.linalg.norm(centre))
    if loop_H.get("cylinder") and width <= LUG_MAX_WIDTH and radius <= 0.5 * r_outer:
        return "lug hole", (f"round {width * 1e3:.1f} mm hole (one cylindrical wall) on a "
                            f"{2 * radius * 1e3:.1f} mm circle: a lug hole"), figures
    burrs, clearance, min_w = judge
    if width < min_w:
        u = np.linalg.svd(xy - centre, full_matrices=False)[2][0]
        what = "vent slot" if np.ptp((xy - centre) @ u) > 3.0 * width else "opening"
        return "too narrow", narrow_reason(width, burrs, clearance, min_w, what), figures
    return "window", "", figures


def innermost_outline(scene, p: np.ndarray, reach: float = 10e-3,
                      step: float = 0.1e-3) -> np.ndarray:
    """(N, 2) per loop point the first plan point inward (horizontal, into the opening) where
    a ray along -Z_H passes the whole wheel: the opening's innermost section, below a draft
    that narrows the opening towards the back or an edge round (what the collision probes of
    a mesh import start from)."""
    import open3d as o3d

    chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
    left = np.c_[-chord[:, 1], chord[:, 0]]
    left /= np.maximum(np.linalg.norm(left, axis=1, keepdims=True), 1e-12)
    s = np.arange(0.0, reach + step, step)
    q = p[:, None, :2] + s[None, :, None] * left[:, None, :]
    rays = np.zeros((q.shape[0] * q.shape[1], 6), np.float32)
    rays[:, :2] = q.reshape(-1, 2)
    rays[:, 2], rays[:, 5] = float(p[:, 2].max()) + 0.5, -1.0
    miss = ~np.isfinite(scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy())
    miss = miss.reshape(q.shape[:2])
    first = np.where(miss.any(axis=1), np.argmax(miss, axis=1), 0)
    xy = q[np.arange(len(p)), first]
    keep = np.linalg.norm(xy - np.roll(xy, 1, axis=0), axis=1) > 1e-6
    return xy[keep]


def _to_H(X_HM, v):
    return v @ X_HM[:3, :3].T


def cad_windows(cad, V_H, F, owner, fmap, X_MH, options, judge):
    """(windows [WindowEdge in H], loops kept (dicts with the NURBS), notes): the B-rep's
    front-boundary loops sorted into windows and the rest (see module doc); ``judge`` is
    (burrs [m], clearance [m], narrowest window [m]) (:func:`_judge`)."""
    from drakedeburr.hub.cad import classify_faces
    from drakedeburr.hub.cad_loops import cad_loops

    X_HM = np.linalg.inv(X_MH)
    cls = classify_faces(cad, V_H, F, owner, fmap)
    scene = ray_scene(V_H, F)
    z_top = float(V_H[:, 2].max()) + 0.01
    r_outer = float(np.linalg.norm(V_H[:, :2], axis=1).max())
    kept, not_windows, rejected = [], [], []
    for loop in cad_loops(cad, fmap, cls, options.edge_spacing):
        if isinstance(loop, tuple):
            q = _to_H(X_HM, loop[1]) + X_HM[:3, 3]
            rejected.append({"center_xy_mm": [round(float(v) * 1e3, 2) for v in q[:2]],
                             "reason": f"{loop[0]} at ({', '.join(f'{v * 1e3:.1f}' for v in q)})"
                                       " mm: not one closed front boundary"})
            continue
        p = _to_H(X_HM, loop.p) + X_HM[:3, 3]
        d = {"p": p, "faces": loop.faces, "cylinder": _single_cylinder(fmap, loop)}
        kind, reason, figures = _describe(d, scene, z_top, judge, r_outer)
        if kind != "window":
            if kind != "outer edge":
                not_windows.append({"kind": kind, "reason": reason, **figures})
            continue
        t, nw, nf = (_to_H(X_HM, a) for a in (loop.t, loop.n_wall, loop.n_face))
        if _signed_area(p[:, :2]) < 0:  # counter-clockwise seen from +Z_H
            p, nw, nf, t = p[::-1], nw[::-1], nf[::-1], -t[::-1]
        kept.append({"p": p, "t": t, "n_wall": nw, "n_face": nf, "loop": loop,
                     "figures": figures, "angle": float(np.arctan2(*p[:, :2].mean(0)[::-1])
                                                        % (2 * np.pi))})
    kept.sort(key=lambda k: k["angle"])
    areas = [k["figures"]["area_mm2"] for k in kept]
    windows = []
    for i, k in enumerate(kept):
        kind = "large" if k["figures"]["area_mm2"] >= 0.6 * max(areas) else "small"
        windows.append(WindowEdge(index=i, kind=kind, p_HE=k["p"], t_H=k["t"],
                                  n_wall_H=k["n_wall"], n_face_H=k["n_face"]))
    notes = {"not_windows": not_windows, "rejected": rejected,
             "loops": [{"index": i, "edges": len(k["loop"].edges),
                        "rounded_edges": int(sum(k["loop"].blended)),
                        "nurbs": k["loop"].nurbs is not None, **k["figures"]}
                       for i, k in enumerate(kept)],
             "faces": {"front": sum(c["front"] for c in cls.values()),
                       "blend": sum(c["blend"] for c in cls.values()), "total": len(cls)}}
    return windows, kept, notes


def _single_cylinder(fmap, loop) -> bool:
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Cylinder

    from drakedeburr.hub.cad import face_at

    others = {o for _, o in loop.faces}
    return len(others) == 1 and BRepAdaptor_Surface(
        face_at(fmap, next(iter(others)) + 1)).GetType() == GeomAbs_Cylinder


def _signed_area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _mass(cad, X_HM, density: float):
    """(mass [kg], com in H (3,), inertia about the com in H (3, 3), volume [m^3]) of the
    B-rep (exact, OpenCASCADE BRepGProp)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(cad.shape, props)
    vol = props.Mass() * cad.scale ** 3
    if vol <= 0:
        raise InputError(f"{cad.source}: the B-rep encloses no volume (not a solid, or "
                         "faces inside out)")
    c = props.CentreOfMass()
    com_M = np.array([c.X(), c.Y(), c.Z()]) * cad.scale
    m = props.MatrixOfInertia()
    I_M = np.array([[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)]) * cad.scale ** 5
    R = X_HM[:3, :3]
    I_H = R @ I_M @ R.T * density
    return vol * density, R @ com_M + X_HM[:3, 3], 0.5 * (I_H + I_H.T), vol


def _judge(options) -> tuple[tuple[float, ...], float, float]:
    """(burrs [m] smallest first, clearance [m], narrowest window [m]) an opening is judged by:
    every burr of the tool library (:func:`drakedeburr.hub.import_common.judged_burrs`), the
    smallest need unless ``options.min_window_width`` is given."""
    from drakedeburr.hub.openings import min_window_width

    burrs = judged_burrs(options.burr_diameter, options.burr_diameters)
    min_w = (options.min_window_width if options.min_window_width is not None
             else min_window_width(burrs, options.clearance))
    return burrs, options.clearance, min_w


def read_cad_windows(path, options, chordal_tolerance: float = DEFAULT_CHORDAL_TOLERANCE):
    """Steps 1-4 of the module doc (no collision pieces): a dict with ``cad``, the
    tessellation ``V_H``/``F`` in H [m], ``X_MH`` (origin on the centre's front face),
    ``windows`` (WindowEdge in H), ``kept`` (their loops), ``notes``, ``closed``,
    ``diameter`` [m], ``min_w`` [m] and ``front`` (the decision)."""
    import trimesh

    from drakedeburr.hub.cad import read_cad, tessellate

    path = Path(path)
    cad = read_cad(path)
    V, F, owner, fmap = tessellate(cad, chordal_tolerance)
    mesh = trimesh.Trimesh(V, F, process=False)
    diameter = wheel_diameter(path, mesh, options.axis_M, f"{cad.unit}, converted to mm")
    X_MH, front, axis_from = _frame(cad, mesh, options)
    X_HM = np.linalg.inv(X_MH)
    V_H = V @ X_HM[:3, :3].T + X_HM[:3, 3]
    judge = _judge(options)
    min_w = judge[2]
    windows, kept, notes = cad_windows(cad, V_H, F, owner, fmap, X_MH, options, judge)
    notes.update(front={**front, "axis_from": axis_from},
                 min_window_width_mm=round(min_w * 1e3, 3),
                 burrs_mm=[round(b * 1e3, 3) for b in judge[0]], dropped=None)
    if not windows:
        why = "; ".join(f"{o.get('kind', 'loop')} at r = {o.get('radius_mm', 0):.0f} mm: "
                        f"{o['reason']}"
                        for o in notes["not_windows"] + notes["rejected"])
        raise NoCuttableWindow(f"{path}: no window in the B-rep: {why or 'no opening'}",
                               source=str(path), axis=X_MH[:3, 2],
                               openings=notes["not_windows"], rejected=notes["rejected"])
    if options.expected_windows is not None and len(windows) != options.expected_windows:
        raise InputError(f"{path}: found {len(windows)} windows, expected "
                         f"{options.expected_windows}")
    r_inner = min(float(np.linalg.norm(w.p_HE[:, :2], axis=1).min()) for w in windows)
    dz = front_origin_offset(ray_scene(V_H, F), r_inner, float(V_H[:, 2].max()) + 0.01)
    X_MH[:3, 3] += dz * X_MH[:3, 2]
    V_H = np.round(V_H - [0.0, 0.0, dz], 7) + 0.0
    windows = [WindowEdge(index=w.index, kind=w.kind, p_HE=w.p_HE - [0.0, 0.0, dz],
                          t_H=w.t_H, n_wall_H=w.n_wall_H, n_face_H=w.n_face_H) for w in windows]
    return {"cad": cad, "V_H": V_H, "F": F, "X_MH": X_MH, "windows": windows, "kept": kept,
            "notes": notes, "closed": bool(mesh.is_watertight), "diameter": diameter,
            "min_w": min_w}


def _write_nurbs(target: Path, kept, cad, X_HM) -> None:
    """Add each loop's NURBS to ``edges.npz`` (rewritten atomically)."""
    from drakedeburr.hub.cad_loops import nurbs_arrays
    from drakedeburr.hub.files import write_npz

    with np.load(target / "edges.npz", allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    for i, k in enumerate(kept):
        if k["loop"].nurbs is not None:
            for name, a in nurbs_arrays(k["loop"].nurbs, cad.scale, X_HM).items():
                arrays[f"w{i}_nurbs_{name}"] = a
    write_npz(target / "edges.npz", arrays)


def import_cad(path: str | Path, out_root: str | Path, *, options=None, progress=None,
               chordal_tolerance: float = DEFAULT_CHORDAL_TOLERANCE):
    """Turn a STEP/IGES wheel into a hub model folder under ``out_root`` (module doc); the
    same result type and folder as :func:`drakedeburr.hub.import_mesh.import_mesh`.

    Raises:
        FileNotFoundError: no such file.
        InputError: an unreadable or invalid file (the entity or face named), not wheel-sized.
        NoCuttableWindow: read, but no through-opening is a window (each one listed).
    """
    from manifold3d import Manifold

    from drakedeburr._io import check_regular_file
    from drakedeburr.hub.import_options import ImportOptions
    from drakedeburr.hub.import_output import ImportRecord, import_summary, write_folder

    t_start = time.perf_counter()
    options = options or ImportOptions()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"CAD file {path} does not exist")
    check_regular_file(path, "CAD file", "mesh")  # before hashing: no device, pipe or folder
    out_root = Path(out_root)
    sha, key, name, target, cached = cache_slot(path, out_root, options, t_start,
                                                chordal=chordal_tolerance,
                                                cad_version=CAD_IMPORT_VERSION)
    if cached is not None:
        return cached
    steps = 5
    if progress is not None:
        progress(0, steps, "read CAD, hub frame and window loops (B-rep edges)")
    cw = read_cad_windows(path, options, chordal_tolerance)
    cad, V_H, F, X_MH, windows, kept, notes = (cw[k] for k in (
        "cad", "V_H", "F", "X_MH", "windows", "kept", "notes"))
    X_HM = np.linalg.inv(X_MH)
    closed, diameter = cw["closed"], cw["diameter"]
    scene = ray_scene(V_H, F)
    walls = [wall_line(innermost_outline(scene, w.p_HE), w.p_HE) for w in windows]
    if progress is not None:
        progress(2, steps, "collision pieces (CoACD)" if closed else "collision pieces (shell)")
    pieces, coll = collision_pieces(path, V_H, F, walls, closed, options, progress, steps)
    if progress is not None:
        progress(3, steps, "write folder")
    hulls = [Manifold.hull_points(pv) for pv in pieces]
    mass, com, I_com, volume = _mass(cad, X_HM, options.density)
    rec = ImportRecord(name, path, sha, key, "mm", closed, X_MH, options, notes, V_H, F,
                       windows, mass, com, I_com, volume, "the B-rep (OpenCASCADE BRepGProp)",
                       diameter, pieces, hulls, coll)
    summary = import_summary(rec)
    summary["import"]["cad"] = {
        "format": "STEP" if path.suffix.lower() in (".step", ".stp") else "IGES",
        "file_unit": cad.unit, "solids": cad.solids,
        "chordal_tolerance_mm": chordal_tolerance * 1e3, "faces": notes["faces"],
        "loops": "exact B-rep edges (lines, arcs, B-splines), one NURBS per loop in edges.npz",
        "version": CAD_IMPORT_VERSION}
    write_folder(target, out_root, rec, summary)
    _write_nurbs(target, kept, cad, X_HM)
    if progress is not None:
        progress(steps, steps, "done")
    seconds = time.perf_counter() - t_start
    log.info("%s -> %s: %d windows (B-rep), %d pieces in %.1f s", path, target, len(windows),
             len(pieces), seconds)
    return ImportedHub(dir=target.resolve(), name=name, source=path, sha256=sha, cached=False,
                       X_MH=X_MH, window_count=len(windows), piece_count=len(pieces),
                       max_window_intrusion=coll["max_window_intrusion_mm"] * 1e-3,
                       seconds=seconds, summary=summary)
