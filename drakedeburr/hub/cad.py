"""CAD solids (STEP, IGES) through OpenCASCADE (the ``cadquery-ocp`` binding, module ``OCP``):
read, check, tessellate, and find the window loops on the B-rep's exact edges.

Units come from the file: OpenCASCADE's readers convert the file's length unit (STEP
``LENGTH_UNIT``/``SI_UNIT``, IGES global section) to millimetres; :func:`read_cad` scales that
to metres and records the file's own unit name.

Window loops (docs/hub.md, "CAD solids"): with the hub axis +Z_H known,

1. every B-rep face is classified from its tessellation (area-weighted outward normal, share
   seen from the front along -Z_H) and its exact surface: a **blend** (fillet or chamfer) is
   a narrow face (2 area / perimeter <= :data:`BLEND_MAX_WIDTH`) that is convex (its principal
   curvature bends away from the outward normal), a plane at 20-70 deg to the axis, or a
   patch that faces the front on average but turns down to the wall (normals below 60 deg
   from the axis: where two rounds meet); a
   **front** face is not a blend, faces the front (normal within 60 deg of +Z_H) and is seen
   from the front over at least half its area;
2. the **front boundary** is every edge between a front face and a face that is not: on a
   sharp edge the crease between face and wall, on a rounded or chamfered edge the line where
   the face meets the blend (the face-side tangent line, as docs/hub.md defines the deburred
   line);
3. those edges are chained into closed loops through shared vertices; a loop that encloses
   the axis is the centre bore or the rim's outer edge, a loop whose inside a ray along the
   axis cannot pass is blind (a pocket, a recess), a loop narrower than the burr needs is
   named with its width; the rest are the windows.

Every loop is the exact edge curves: each edge is sampled on its own curve (line, circle,
B-spline) at equal arc length, and the loop's edges are also joined into one NURBS
(``GeomConvert_CompCurveToBSplineCurve``, exact for lines and arcs). Face and wall normals are
the exact surface normals at the sample points.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.mesh_io import CAD_SUFFIXES

__all__ = ["CAD_SUFFIXES", "CadSolid", "read_cad", "tessellate", "barrel_axis", "classify_faces",
           "BLEND_MAX_WIDTH", "DEFAULT_CHORDAL_TOLERANCE", "face_at", "xyz"]

log = logging.getLogger(__name__)

BLEND_MAX_WIDTH = 6.0e-3  # [m] widest fillet/chamfer strip taken for an edge blend
DEFAULT_CHORDAL_TOLERANCE = 0.1e-3  # [m] tessellation of the collision geometry
DEFAULT_ANGULAR_TOLERANCE = 0.2  # [rad]
_FRONT_COS = 0.5  # a front face's mean normal lies within 60 deg of +Z_H
_SEEN_SHARE = 0.5  # ... and at least this share of its area is seen from the front


@dataclass(frozen=True, eq=False)
class CadSolid:
    """A B-rep read from a CAD file.

    Attributes:
        shape: the OCP TopoDS_Shape (coordinates in millimetres, OpenCASCADE's session unit).
        source: the file.
        unit: the file's length unit as it states it (e.g. "millimetre", "INCH").
        scale: metres per shape unit (1e-3).
        solids: number of solids in the file.
    """

    shape: object
    source: Path
    unit: str
    scale: float
    solids: int


def _quiet() -> None:
    """OpenCASCADE's readers print progress to stdout; the library only logs."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    for i in range(1, printers.Length() + 1):
        printers.Value(i).SetTraceLevel(Message_Gravity.Message_Fail)


def _captured(fn):
    """(fn(), what OpenCASCADE wrote to stdout/stderr meanwhile): its readers write parse
    errors straight to the process's file descriptors; the library only logs."""
    import os
    import sys
    import tempfile

    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            result = fn()
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
        tmp.seek(0)
        said = tmp.read().decode("utf-8", "replace")
    for line in said.splitlines():
        if line.strip():
            log.debug("OpenCASCADE: %s", line.strip())
    return result, said


def _said_errors(said: str, limit: int = 2) -> list[str]:
    """The reader's error lines (ANSI colours and stars stripped)."""
    import re

    out = []
    for line in said.splitlines():
        line = re.sub(r"\x1b\[[0-9;]*m", "", line).strip(" *")
        if "ERR" in line or "rror" in line:
            out.append(re.sub(r"^ERR\s*", "", line))
    return out[:limit]


def _failed_entities(reader, limit: int = 3) -> list[str]:
    """'#N TYPE: message' of the entities the reader could not load (the STEP/IGES check)."""
    out = []
    try:
        model = reader.Model()
        checks = reader.WS().ModelCheckList()
        checks.Start()
        while checks.More() and len(out) < limit:
            ch = checks.Value()
            ent = ch.Entity()
            if ch.HasFailed() and ent is not None and model.Number(ent) > 0:
                msg = ch.CFail(1, True) if ch.NbFails() else ""
                out.append(f"entity #{model.Number(ent)} {model.TypeName(ent, False)}: "
                           f"{msg}".strip(" :"))
            checks.Next()
    except Exception:  # the check list is a diagnosis only
        pass
    return out


def _file_unit(reader, suffix: str) -> str:
    if suffix in (".step", ".stp"):
        from OCP.collections import Sequence_TCollection_AsciiString as Seq

        lengths, angles, solid_angles = Seq(), Seq(), Seq()
        reader.FileUnits(lengths, angles, solid_angles)
        names = sorted({lengths.Value(i + 1).ToCString() for i in range(lengths.Length())})
        return ", ".join(names) or "unstated (read as millimetre)"
    try:
        return reader.IGESModel().GlobalSection().UnitName().ToCString()
    except Exception:
        return "unstated (read as millimetre)"


def read_cad(path: str | Path) -> CadSolid:
    """Read a STEP or IGES file into one B-rep solid (or several, kept together).

    Raises:
        FileNotFoundError: no such file.
        InputError: not readable, entities that fail to load (named by their number and
            type), no solid or closed shell, or an invalid B-rep (the face named).
    """
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.STEPControl import STEPControl_Reader

    from drakedeburr._io import check_regular_file

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"CAD file {path} does not exist")
    suffix = path.suffix.lower()
    if suffix not in CAD_SUFFIXES:
        raise InputError(f"{path}: not a STEP or IGES file ({', '.join(CAD_SUFFIXES)})")
    # a device, pipe or folder is never handed to the parser; the size bounded like a mesh's
    if check_regular_file(path, "CAD file", "mesh") == 0:
        raise InputError(f"{path}: the file is empty")
    _quiet()  # and _captured below: the parsers write to the file descriptors
    reader = STEPControl_Reader() if suffix in (".step", ".stp") else IGESControl_Reader()
    kind = "STEP" if suffix in (".step", ".stp") else "IGES"
    status, said = _captured(lambda: reader.ReadFile(str(path)))
    if status != IFSelect_RetDone:
        bad = _failed_entities(reader) + _said_errors(said)
        raise InputError(f"{path}: not a readable {kind} file ({status.name})"
                         + (f": {'; '.join(bad)}" if bad else ""))
    unit = _file_unit(reader, suffix)
    n_roots, said = _captured(reader.TransferRoots)
    if n_roots == 0:
        raise InputError(f"{path}: no {kind} entity could be turned into a shape"
                         + "".join(f"; {b}" for b in _failed_entities(reader)
                                   + _said_errors(said)))
    for b in _failed_entities(reader):
        log.warning("%s: %s", path, b)
    shape = reader.OneShape()
    if kind == "STEP":
        _all_faces_transferred(path, reader, shape, said)
    return _checked(path, shape, unit, kind)


def _all_faces_transferred(path: Path, reader, shape, said: str) -> None:
    """InputError naming the STEP face entities that did not become faces (a face whose
    surface reference is missing or of the wrong type is dropped by the reader)."""
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    model = reader.Model()
    faces = [i for i in range(1, model.NbEntities() + 1)
             if model.Value(i).DynamicType().Name() == "StepShape_AdvancedFace"]
    n_shape, exp = 0, TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        n_shape += 1
        exp.Next()
    if n_shape >= len(faces):
        return
    bad = [f"entity #{i} ADVANCED_FACE: its surface reference is "
           "missing or not a surface" for i in faces if model.Value(i).FaceGeometry() is None]
    why = "; ".join(bad[:3]) or "; ".join(_said_errors(said)) or "see the file's faces"
    raise InputError(f"{path}: {len(faces) - n_shape} of {len(faces)} faces did not transfer: "
                     f"{why}")


def _checked(path: Path, shape, unit: str, kind: str) -> CadSolid:
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.collections import (
        IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape,
    )
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID
    from OCP.TopExp import TopExp

    solids, shells, faces = (TopTools_IndexedMapOfShape() for _ in range(3))
    TopExp.MapShapes_s(shape, TopAbs_SOLID, solids)
    TopExp.MapShapes_s(shape, TopAbs_SHELL, shells)
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    if faces.Extent() == 0:
        raise InputError(f"{path}: the {kind} file holds no surface (no face, no solid): "
                         "export the wheel as a solid")
    if solids.Extent() == 0:
        log.warning("%s: no solid in the file, %d faces in %d shells: read as surfaces",
                    path, faces.Extent(), shells.Extent())
    if not BRepCheck_Analyzer(shape).IsValid():
        for i in range(1, faces.Extent() + 1):
            if not BRepCheck_Analyzer(face_at(faces, i)).IsValid():
                raise InputError(f"{path}: face {i} of {faces.Extent()} is not a valid "
                                 "B-rep face (OpenCASCADE BRepCheck); repair the model")
        raise InputError(f"{path}: the B-rep is not valid (OpenCASCADE BRepCheck: edges or "
                         "shells do not join); repair the model")
    return CadSolid(shape=shape, source=path, unit=unit, scale=1e-3,
                    solids=int(solids.Extent()))


# --------------------------------------------------------------------------- tessellation
def tessellate(cad: CadSolid, chordal: float = DEFAULT_CHORDAL_TOLERANCE,
               angular: float = DEFAULT_ANGULAR_TOLERANCE):
    """(V (n, 3) [m], F (m, 3), face_of_triangle (m,), faces map) of the B-rep meshed by
    ``BRepMesh_IncrementalMesh`` at the chordal tolerance ``chordal`` [m]; triangles wound
    by the face orientation (outward), vertices on shared edges merged."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.collections import (
        IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape,
    )
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp
    from OCP.TopLoc import TopLoc_Location

    mesher = BRepMesh_IncrementalMesh(cad.shape, chordal / cad.scale, False, angular, True)
    mesher.Perform()
    fmap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(cad.shape, TopAbs_FACE, fmap)
    V, F, owner, base = [], [], [], 0
    for i in range(1, fmap.Extent() + 1):
        face = face_at(fmap, i)
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is None:
            raise InputError(f"{cad.source}: face {i} could not be meshed at "
                             f"{chordal * 1e3:g} mm (OpenCASCADE BRepMesh)")
        trsf = loc.Transformation()
        nodes = np.array([xyz(tri.Node(j).Transformed(trsf))
                          for j in range(1, tri.NbNodes() + 1)])
        tris = np.array([tri.Triangle(j).Get() for j in range(1, tri.NbTriangles() + 1)]) - 1
        if face.Orientation() == TopAbs_REVERSED:
            tris = tris[:, [0, 2, 1]]
        V.append(nodes)
        F.append(tris + base)
        owner.append(np.full(len(tris), i - 1))
        base += len(nodes)
    V = np.concatenate(V) * cad.scale
    F = np.concatenate(F)
    owner = np.concatenate(owner)
    # nodes on a shared edge are the same 3-D points in both faces' triangulations
    key = np.round(V / 1e-9).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V, F = V[first], inverse.reshape(-1)[F]
    ok = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
    return V, F[ok], owner[ok], fmap


def face_at(fmap, i: int):
    """The i-th (1-based) face of an indexed map, as a TopoDS_Face."""
    from OCP.TopoDS import TopoDS

    return TopoDS.Face(fmap.FindKey(i))


def xyz(p) -> tuple[float, float, float]:
    """The coordinates of an OpenCASCADE point or vector (gp_Pnt, gp_Vec, gp_Dir)."""
    return (p.X(), p.Y(), p.Z())


def barrel_axis(cad: CadSolid) -> tuple[np.ndarray, np.ndarray] | None:
    """(direction (3,), a point (3,) [m]) of the largest cylindrical face (a wheel's barrel),
    or None when the B-rep has none."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepGProp import BRepGProp
    from OCP.GeomAbs import GeomAbs_Cylinder
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    best, best_area = None, 0.0
    exp = TopExp_Explorer(cad.shape, TopAbs_FACE)
    while exp.More():
        face = TopoDS.Face(exp.Current())
        exp.Next()
        surf = BRepAdaptor_Surface(face)
        if surf.GetType() != GeomAbs_Cylinder:
            continue
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(face, props)
        if props.Mass() > best_area:
            ax = surf.Cylinder().Axis()
            best_area, best = props.Mass(), (np.array(xyz(ax.Direction())),
                                             np.array(xyz(ax.Location())) * cad.scale)
    return best


# --------------------------------------------------------------------------- faces
def _convex(face) -> bool | None:
    """True when the face bends away from its outward normal (a convex blend), False when
    towards it, None for a plane."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools
    from OCP.GeomAbs import GeomAbs_Plane
    from OCP.TopAbs import TopAbs_REVERSED

    surf = BRepAdaptor_Surface(face)
    if surf.GetType() == GeomAbs_Plane:
        return None
    u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
    props = BRepLProp_SLProps(surf, 0.5 * (u0 + u1), 0.5 * (v0 + v1), 2, 1e-9)
    if not props.IsCurvatureDefined():
        return None
    k = max((props.MaxCurvature(), props.MinCurvature()), key=abs)
    if face.Orientation() == TopAbs_REVERSED:
        k = -k
    return bool(k < 0)


def classify_faces(cad: CadSolid, V_H, F, owner, fmap) -> dict:
    """Per face (0-based index in ``fmap``): ``front``, ``blend`` flags and figures (see the
    module doc); ``V_H``: the tessellation in H [m]."""
    import open3d as o3d
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    tri = V_H[F]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    c = tri.mean(axis=1)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V_H.astype(np.float32)),
                        o3d.core.Tensor(F.astype(np.uint32)))
    rays = np.zeros((len(F), 6), np.float32)
    rays[:, :2], rays[:, 2], rays[:, 5] = c[:, :2], float(V_H[:, 2].max()) + 0.01, -1.0
    ans = scene.cast_rays(o3d.core.Tensor(rays))
    t_hit = ans["t_hit"].numpy()
    hit = np.where(np.isfinite(t_hit), ans["primitive_ids"].numpy().astype(np.int64), -1)
    z_hit = rays[:, 2] - t_hit
    seen = (hit >= 0) & (np.abs(z_hit - c[:, 2]) < 2e-5)
    seen |= (hit >= 0) & (owner[np.clip(hit, 0, None)] == owner)
    n = len(fmap)
    a_face = np.bincount(owner, area, n)
    nz = np.bincount(owner, 0.5 * cross[:, 2], n) / np.maximum(a_face, 1e-30)
    seen_share = np.bincount(owner, area * seen, n) / np.maximum(a_face, 1e-30)
    nz_min = np.ones(n)  # lowest triangle normal of each face: a blend reaches the wall's
    np.minimum.at(nz_min, owner, cross[:, 2] / np.maximum(2.0 * area, 1e-30))
    out = {}
    for i in range(n):
        face = face_at(fmap, i + 1)
        props = GProp_GProps()
        BRepGProp.LinearProperties_s(face, props)
        width = 2.0 * a_face[i] / max(props.Mass() * cad.scale, 1e-12)
        convex = _convex(face)
        # narrow, and convex, or a chamfer plane, or turning from the front down to the
        # wall (the corner patches where a round meets a round)
        blend = width <= BLEND_MAX_WIDTH and (
            convex is True or (convex is None and 0.34 < nz[i] < 0.94)
            or (nz[i] >= _FRONT_COS > nz_min[i]))
        front = (not blend and nz[i] >= _FRONT_COS and seen_share[i] >= _SEEN_SHARE)
        out[i] = {"front": bool(front), "blend": bool(blend), "nz": float(nz[i]),
                  "width": float(width), "area": float(a_face[i]),
                  "seen": float(seen_share[i])}
    return out
