"""The window loops of a B-rep on its exact edges (docs/hub.md "CAD solids", steps 2-3 of
:mod:`drakedeburr.hub.cad`): front-boundary edges chained into closed loops, each sampled on
its own curve at equal arc length with the exact face and wall normals, and joined into one
NURBS (``GeomConvert_CompCurveToBSplineCurve``: exact for lines and arcs)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.hub.cad import CadSolid, face_at, xyz

__all__ = ["CadLoop", "cad_loops", "boundary_chains", "join_nurbs", "nurbs_arrays",
           "continuous_frames", "SMOOTH_HALF_LENGTH"]


@dataclass(frozen=True, eq=False)
class CadLoop:
    """One closed front-boundary loop of the B-rep, in the file frame M [m].

    Attributes:
        p: (N, 3) points on the edges (loop order, not closed), t: (N, 3) unit tangents.
        n_face, n_wall: (N, 3) exact normals of the front face and of the wall (out of the
            material into the opening; beyond the blend on a rounded edge).
        edges: the loop's TopoDS_Edges in order; faces: the front/other face index per edge.
        blended: per edge, whether the other face is a fillet/chamfer (the edge is rounded).
        nurbs: the loop joined into one Geom_BSplineCurve (shape units, mm).
    """

    p: np.ndarray
    t: np.ndarray
    n_face: np.ndarray
    n_wall: np.ndarray
    edges: list
    faces: list
    blended: list
    nurbs: object
    info: dict = field(default_factory=dict)


def _edge_faces(shape):
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as EdgeFaces,
    )
    from OCP.collections import (
        IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape,
    )
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
    from OCP.TopExp import TopExp

    emap = EdgeFaces()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, emap)
    vmap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_VERTEX, vmap)
    return emap, vmap


def boundary_chains(cad: CadSolid, fmap, cls: dict):
    """Closed chains of front-boundary edges: list of (edges [(edge, forward, front face
    index, other face index)], problem or None)."""
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS

    emap, vmap = _edge_faces(cad.shape)
    links: dict[int, list[int]] = {}
    items = []
    for i in range(1, emap.Extent() + 1):
        edge = TopoDS.Edge(emap.FindKey(i))
        idx = sorted({fmap.FindIndex(f) - 1 for f in emap.FindFromIndex(i)})
        if len(idx) != 2 or cls[idx[0]]["front"] == cls[idx[1]]["front"]:
            continue
        fi, oi = (idx[0], idx[1]) if cls[idx[0]]["front"] else (idx[1], idx[0])
        # the vertices at the curve's first and last parameter (not the edge's orientation)
        v0 = vmap.FindIndex(TopExp.FirstVertex_s(edge, False))
        v1 = vmap.FindIndex(TopExp.LastVertex_s(edge, False))
        k = len(items)
        items.append((edge, v0, v1, fi, oi))
        for v in {v0, v1}:
            links.setdefault(v, []).append(k)
    used = [False] * len(items)
    chains = []
    for start in range(len(items)):
        if used[start]:
            continue
        chain, problem = [], None
        k, v = start, items[start][1]
        while True:
            used[k] = True
            edge, v0, v1, fi, oi = items[k]
            forward = v0 == v
            chain.append((edge, forward, fi, oi))
            v = v1 if forward else v0
            nxt = [j for j in links[v] if not used[j]]
            if len(links[v]) > 2 and problem is None:
                problem = f"{len(links[v])} boundary edges meet at one vertex"
            if not nxt:
                if v != items[start][1] and problem is None:
                    problem = "the boundary does not close"
                break
            k = nxt[0]
        chains.append((chain, problem))
    return chains


def _face_normal(face, edge, t: float, p_mm) -> np.ndarray:
    """Outward unit normal of ``face`` at the point of ``edge`` at parameter ``t`` (the
    edge's p-curve on the face), falling back to a projection of ``p_mm``."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d
    from OCP.BRepGProp import BRepGProp_Face
    from OCP.gp import gp_Pnt, gp_Vec

    pf = BRepGProp_Face(face)
    try:
        uv = BRepAdaptor_Curve2d(edge, face).Value(t)
        u, v = uv.X(), uv.Y()
    except Exception:
        u, v = _project_uv(face, p_mm)
    pnt, vec = gp_Pnt(), gp_Vec()
    pf.Normal(u, v, pnt, vec)
    n = np.array(xyz(vec))
    return n / max(np.linalg.norm(n), 1e-30)


def _project_uv(face, p_mm) -> tuple[float, float]:
    from OCP.BRep import BRep_Tool
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*p_mm), BRep_Tool.Surface_s(face))
    return proj.LowerDistanceParameters()


def _wall_normal(fmap, cls, neighbours, blend_i: int, front_i: int, p_mm,
                 tangent) -> np.ndarray:
    """Normal of the wall beyond a blend face at ``p_mm``: of the faces next to the blend (or
    next to a neighbouring blend) that are neither front nor blend, the one whose nearest
    point lies across the loop (square to its ``tangent``), the nearer at a tie (at a
    window's corner both walls are near)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.BRepGProp import BRepGProp_Face
    from OCP.gp import gp_Pnt, gp_Vec

    vtx = BRepBuilderAPI_MakeVertex(gp_Pnt(*p_mm)).Vertex()
    best, best_d = None, math.inf
    ring = set(neighbours.get(blend_i, ()))
    for j in list(ring):  # a corner patch: the wall lies beyond the neighbouring rounds
        if cls[j]["blend"]:
            ring |= neighbours.get(j, set())
    for j in sorted(ring):
        if j == front_i or cls[j]["front"] or cls[j]["blend"]:
            continue
        d = BRepExtrema_DistShapeShape(vtx, face_at(fmap, j + 1))
        if not d.IsDone():
            continue
        q = np.array(xyz(d.PointOnShape2(1))) - np.asarray(p_mm)
        along = abs(float(q @ tangent)) / max(float(np.linalg.norm(q)), 1e-9)
        score = along + 0.1 * d.Value()  # [mm]: 0.1 of the cosine per mm farther
        if score < best_d:
            best, best_d = j, score
    if best is None:
        return None
    u, v = _project_uv(face_at(fmap, best + 1), p_mm)
    pnt, vec = gp_Pnt(), gp_Vec()
    BRepGProp_Face(face_at(fmap, best + 1)).Normal(u, v, pnt, vec)
    n = np.array(xyz(vec))
    return n / max(np.linalg.norm(n), 1e-30)


def face_neighbours(cad: CadSolid, fmap) -> dict[int, set[int]]:
    """Face index -> indices of the faces sharing an edge with it."""
    emap, _ = _edge_faces(cad.shape)
    out: dict[int, set[int]] = {}
    for i in range(1, emap.Extent() + 1):
        idx = {fmap.FindIndex(f) - 1 for f in emap.FindFromIndex(i)}
        for a in idx:
            out.setdefault(a, set()).update(idx - {a})
    return out


def cad_loops(cad: CadSolid, fmap, cls: dict, spacing: float) -> list:
    """Every closed front-boundary chain as a :class:`CadLoop` (file frame, metres), or a
    ``(problem, point (3,) [m])`` tuple for a chain that is not one simple closed loop."""
    neighbours = face_neighbours(cad, fmap)
    out = []
    for chain, problem in boundary_chains(cad, fmap, cls):
        if problem is not None:
            out.append((problem, _chain_point(chain) * cad.scale))
            continue
        out.append(_sample_chain(cad, fmap, cls, neighbours, chain, spacing))
    return out


def _chain_point(chain) -> np.ndarray:
    from OCP.BRepAdaptor import BRepAdaptor_Curve

    c = BRepAdaptor_Curve(chain[0][0])
    return np.array(xyz(c.Value(0.5 * (c.FirstParameter() + c.LastParameter()))))


def _sample_chain(cad, fmap, cls, neighbours, chain, spacing: float) -> CadLoop:
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.GCPnts import GCPnts_AbscissaPoint, GCPnts_UniformAbscissa
    from OCP.gp import gp_Pnt, gp_Vec

    pts, tans, nf, nw = [], [], [], []
    step = spacing / cad.scale
    for edge, forward, fi, oi in chain:
        c = BRepAdaptor_Curve(edge)
        a, b = c.FirstParameter(), c.LastParameter()
        length = GCPnts_AbscissaPoint.Length_s(c, a, b)
        n = max(2, int(math.ceil(length / step)) + 1)
        ua = GCPnts_UniformAbscissa(c, n, a, b)
        ts = [ua.Parameter(j) for j in range(1, ua.NbPoints() + 1)] if ua.IsDone() \
            else list(np.linspace(a, b, n))
        if not forward:
            ts = ts[::-1]
        face, other = face_at(fmap, fi + 1), face_at(fmap, oi + 1)
        for t in ts[:-1]:
            p, d = gp_Pnt(), gp_Vec()
            c.D1(t, p, d)
            pm = xyz(p)
            tan = np.array(xyz(d)) * (1.0 if forward else -1.0)
            n_face = _face_normal(face, edge, t, pm)
            if cls[oi]["blend"]:
                n_wall = _wall_normal(fmap, cls, neighbours, oi, fi, pm,
                                      tan / max(np.linalg.norm(tan), 1e-30))
                if n_wall is None:
                    n_wall = _face_normal(other, edge, t, pm)
            else:
                n_wall = _face_normal(other, edge, t, pm)
            pts.append(pm)
            tans.append(tan / max(np.linalg.norm(tan), 1e-30))
            nf.append(n_face)
            nw.append(n_wall)
    pts, tans, nf, nw = (np.array(a) for a in (pts, tans, nf, nw))
    keep = np.linalg.norm(pts - np.roll(pts, 1, axis=0), axis=1) > 1e-4  # [mm] (tiny edges)
    pts, tans, nf, nw = pts[keep], tans[keep], nf[keep], nw[keep]
    exact_t = tans
    nw, nf, tans = continuous_frames(pts * cad.scale, tans, nw, nf, spacing)
    return CadLoop(p=np.array(pts) * cad.scale, t=np.array(tans), n_face=np.array(nf),
                   n_wall=np.array(nw), edges=[e for e, *_ in chain],
                   info={"exact_t": exact_t},
                   faces=[(fi, oi) for _, _, fi, oi in chain],
                   blended=[bool(cls[oi]["blend"]) for *_, oi in chain],
                   nurbs=join_nurbs(chain))


#: [m] half-length of the running mean of the normals along a loop: the mesh import's
#: (``import_mesh``: each normal averaged with 3 neighbours either side at its 0.5 mm spacing)
SMOOTH_HALF_LENGTH = 1.5e-3


def _unit_rows(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-30)


def continuous_frames(p: np.ndarray, t: np.ndarray, n_wall: np.ndarray, n_face: np.ndarray,
                      spacing: float, half_length: float = SMOOTH_HALF_LENGTH):
    """(n_wall, n_face, t) (N, 3) of a closed loop ``p`` [m], continuous along it as the mesh
    import's: the exact B-rep normals jump where the loop passes from one face pair to the
    next (a crease of the front surface, a window corner where the walls of two sides meet,
    the wall chosen beyond a corner patch of rounds), and the planner's frames, which turn the
    tool with them, would jump too. Per point the wall normal is first made square to the
    loop's exact tangent ``t`` (a wall normal nearly along the tangent is the wall of the next
    side: the direction across the loop in the face stands in for it); both normals are then
    averaged over ``half_length`` either side and ``t = n_wall x n_face``, turned along the
    loop, as a mesh import's."""
    from scipy.ndimage import uniform_filter1d

    t = _unit_rows(np.asarray(t, float))
    n_face = _unit_rows(np.asarray(n_face, float))
    n_wall = np.asarray(n_wall, float)
    across = _unit_rows(np.cross(n_face, t))  # in the face, square to the loop
    across *= 1.0 if float(np.einsum("ij,ij->i", across, n_wall).sum()) >= 0 else -1.0
    along = np.einsum("ij,ij->i", n_wall, t)
    square = n_wall - along[:, None] * t
    wrong = np.linalg.norm(square, axis=1) < 0.5  # within 30 deg of the tangent
    square[wrong] = across[wrong]
    size = 2 * max(1, int(round(half_length / spacing))) + 1
    n_wall = _unit_rows(uniform_filter1d(_unit_rows(square), size, axis=0, mode="wrap"))
    n_face = _unit_rows(uniform_filter1d(n_face, size, axis=0, mode="wrap"))
    t_new = _unit_rows(np.cross(n_wall, n_face))
    chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
    t_new[np.einsum("ij,ij->i", t_new, chord) < 0] *= -1.0
    return n_wall, n_face, t_new


def join_nurbs(chain):
    """The chain's edges joined into one Geom_BSplineCurve (exact conversion of lines,
    circles and B-splines, joined at the shared vertices), or None if OpenCASCADE refuses."""
    from OCP.BRep import BRep_Tool
    from OCP.Geom import Geom_TrimmedCurve
    from OCP.GeomConvert import GeomConvert, GeomConvert_CompCurveToBSplineCurve

    comp = None
    try:
        for edge, forward, _, _ in chain:
            curve, a, b = BRep_Tool.Curve_s(edge, 0.0, 1.0), *BRep_Tool.Range_s(edge)
            bs = GeomConvert.CurveToBSplineCurve_s(Geom_TrimmedCurve(curve, a, b))
            if not forward:
                bs.Reverse()
            if comp is None:
                comp = GeomConvert_CompCurveToBSplineCurve(bs)
            elif not comp.Add(bs, 1e-4, True):
                return None
        return comp.BSplineCurve()
    except Exception:
        return None


def nurbs_arrays(curve, scale: float, X_HM: np.ndarray) -> dict[str, np.ndarray]:
    """Poles (in H [m]), weights, flat knots and degree of a Geom_BSplineCurve."""
    poles = np.array([xyz(curve.Pole(i)) for i in range(1, curve.NbPoles() + 1)]) * scale
    poles = poles @ X_HM[:3, :3].T + X_HM[:3, 3]
    weights = np.array([curve.Weight(i) for i in range(1, curve.NbPoles() + 1)])
    knots = []
    for i in range(1, curve.NbKnots() + 1):
        knots += [curve.Knot(i)] * curve.Multiplicity(i)
    return {"poles": poles, "weights": weights, "knots": np.array(knots),
            # a float: the hub loader takes float and text arrays only
            "degree": np.array(float(curve.Degree()))}
