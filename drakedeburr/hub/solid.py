"""The hub solid from its window outlines (manifold3d; millimetres inside this module, frame H).

1. The face plate is written by hand (not extrude + refine: manifold's refine subdivides the
   long slivers of an extrusion's triangulation into ~10^5 triangles): the front face is a
   Delaunay triangulation of the edge points plus a hexagonal grid graded by the distance to
   the window edges (1.5 mm / 3 mm / ``mesh_edge_length``), the back face a coarse one; both
   are lifted onto their height fields (:class:`drakedeburr.hub.surface.FaceSurface`) and the
   window walls join them through the edge profile's rings (draft, round).
2. Union with the hub pad (boss) and the rim (barrel, front and back flange); the centre bore
   and the bolt holes (with their lug seats) are cut through.
"""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.hub.outline import Window, segments_per_circle
from drakedeburr.hub.spec import LUG_SEAT_HALF_ANGLE, HubSpec
from drakedeburr.hub.surface import EdgeRings, FaceSurface, edge_rings

__all__ = ["PlateGeometry", "plate_geometry", "plate_manifold", "build_solid", "tube", "rings",
           "mesh_arrays", "edge_set", "RIM_SAG_MM", "FACE_STEPS_MM"]

RIM_SAG_MM = 0.02  # chord sag of the rim, pad, bore and bolt-hole circles [mm]
# face triangulation: grid step [mm] by distance [mm] from the nearest window edge (top face);
# the back face uses mesh_edge_length everywhere
FACE_STEPS_MM = ((4.0, 1.5), (12.0, 3.0))


def tube(r_in: float, r_out: float, z0: float, z1: float):
    """A cylinder (r_in = 0) or tube [mm] between z0 and z1 as a Manifold."""
    from manifold3d import Manifold

    outer = Manifold.cylinder(z1 - z0, r_out, -1.0, segments_per_circle(r_out, RIM_SAG_MM))
    if r_in <= 0:
        return outer.translate((0, 0, z0))
    inner = Manifold.cylinder(z1 - z0 + 2.0, r_in, -1.0,
                              segments_per_circle(r_in, RIM_SAG_MM)).translate((0, 0, -1.0))
    return (outer - inner).translate((0, 0, z0))


def _hex_grid(lo: np.ndarray, hi: np.ndarray, h: float) -> np.ndarray:
    ys = np.arange(lo[1], hi[1] + h, h * math.sqrt(3) / 2)
    pts = []
    for j, y in enumerate(ys):
        xs = np.arange(lo[0] + (h / 2 if j % 2 else 0.0), hi[0] + h, h)
        pts.append(np.column_stack([xs, np.full(len(xs), y)]))
    return np.concatenate(pts)


def edge_set(faces: np.ndarray) -> set[tuple[int, int]]:
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = np.sort(e, axis=1)
    return set(map(tuple, np.unique(e, axis=0).tolist()))


def _graded_grid(spec: HubSpec, polys: list[np.ndarray], r_plate: float,
                 graded: bool) -> tuple[np.ndarray, np.ndarray]:
    """Grid points (K, 2) of the plate region outside the windows and their grid step (K,)."""
    from matplotlib.path import Path as MplPath
    from scipy.spatial import cKDTree

    wtree = cKDTree(np.concatenate(polys))
    lo, hi = np.array([-r_plate, -r_plate]), np.array([r_plate, r_plate])
    coarse = spec.mesh_edge_length * 1e3
    bands = list(FACE_STEPS_MM) if graded else []
    grids, steps = [], []
    inner = 0.0
    for outer_d, h in [*bands, (np.inf, coarse)]:
        g = _hex_grid(lo, hi, h)
        d = wtree.query(g)[0]
        g = g[(d > inner) & (d <= outer_d)]
        grids.append(g)
        steps.append(np.full(len(g), h))
        inner = outer_d
    grid, step = np.concatenate(grids), np.concatenate(steps)
    keep = np.hypot(grid[:, 0], grid[:, 1]) < r_plate - 1.0
    for poly in polys:
        keep &= ~MplPath(poly).contains_points(grid)
    return grid[keep], step[keep]


def _triangulate(spec: HubSpec, loops: list[np.ndarray], polys: list[np.ndarray],
                 r_plate: float, graded: bool):
    """Delaunay triangulation (T, 3) of the plate region: boundary points (indices first, in
    ``loops`` order) plus a hexagonal grid; every boundary segment checked to be an edge.
    ``polys`` are the window openings (CCW) of this face."""
    from matplotlib.path import Path as MplPath
    from scipy.spatial import Delaunay, cKDTree

    bpts = np.concatenate(loops)
    grid, step = _graded_grid(spec, polys, r_plate, graded)
    grid = grid[cKDTree(bpts).query(grid)[0] > 0.6 * step]
    pts = np.concatenate([bpts, grid])
    tri = Delaunay(pts).simplices
    cen = pts[tri].mean(axis=1)
    inside = np.hypot(cen[:, 0], cen[:, 1]) < r_plate
    for poly in polys:
        inside &= ~MplPath(poly).contains_points(cen)
    tri = tri[inside]
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    cw = ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])) < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]  # CCW seen from +Z
    edges = edge_set(tri)
    offs = np.cumsum([0] + [len(lp) for lp in loops])
    for k in range(len(loops)):
        idx = np.arange(offs[k], offs[k + 1])
        nxt = np.roll(idx, -1)
        missing = sum((min(i, j), max(i, j)) not in edges for i, j in zip(idx, nxt, strict=True))
        if missing:
            raise RuntimeError(f"hub {spec.name!r}: face triangulation misses {missing} "
                               f"outline segments of loop {k}")
    return pts, tri


class PlateGeometry:
    """The face plate's surfaces and window edge rings (see :func:`plate_geometry`).

    Attributes:
        surface: the height field.
        edges: per window its :class:`EdgeRings` (CCW, index order).
        r_plate: plate radius [mm] (to the middle of the barrel wall).
    """

    def __init__(self, surface: FaceSurface, edges: list[EdgeRings], r_plate: float):
        self.surface, self.edges, self.r_plate = surface, edges, r_plate


def plate_geometry(spec: HubSpec, windows: list[Window]) -> PlateGeometry:
    """Height fields and edge rings of the face plate of ``spec`` with ``windows``."""
    surf = FaceSurface(spec, windows)
    a_max = 0.5 * spec.blend_radius * 1e3
    edges = [edge_rings(spec, surf, w.poly_mm, a_max) for w in windows]
    r_plate = (spec.rim_barrel_inner_radius + 0.5 * spec.rim_thickness) * 1e3
    return PlateGeometry(surf, edges, r_plate)


def plate_manifold(spec: HubSpec, windows: list[Window], geom: PlateGeometry | None = None):
    """The face plate (disc minus windows, dished) as a Manifold [mm] (module doc, step 1)."""
    from manifold3d import Manifold, Mesh64

    geom = geom or plate_geometry(spec, windows)
    r_plate = geom.r_plate
    n_out = segments_per_circle(r_plate, RIM_SAG_MM)
    ang = 2 * math.pi * np.arange(n_out) / n_out
    outer = np.column_stack([r_plate * np.cos(ang), r_plate * np.sin(ang)])  # CCW, material left
    top_polys = [e.rings[0][:, :2] for e in geom.edges]
    bot_polys = [e.rings[-1][:, :2] for e in geom.edges]
    # windows reversed: material on the left
    top_pts, top_tri = _triangulate(spec, [outer] + [p[::-1] for p in top_polys], top_polys,
                                    r_plate, graded=True)
    bot_pts, bot_tri = _triangulate(spec, [outer] + [p[::-1] for p in bot_polys], bot_polys,
                                    r_plate, graded=False)
    n_top, n_bot = len(top_pts), len(bot_pts)
    surf = geom.surface
    V = [np.column_stack([top_pts, surf.front(top_pts)]),
         np.column_stack([bot_pts, surf.back(bot_pts)])]
    # the boundary points keep the exact ring heights (the same functions evaluated)
    F = [top_tri, bot_tri[:, [0, 2, 1]] + n_top]
    offs = np.cumsum([0] + [n_out] + [len(p) for p in top_polys])
    n_v = n_top + n_bot
    walls = [_ring_quads(np.arange(n_out), np.arange(n_out) + n_top)]
    for k, e in enumerate(geom.edges):
        idx_top = np.arange(offs[k + 1], offs[k + 2])  # reversed loop's indices
        ring_idx = [idx_top]
        for ring in e.rings[1:-1]:
            V.append(ring[::-1])
            ring_idx.append(np.arange(n_v, n_v + len(ring)))
            n_v += len(ring)
        ring_idx.append(idx_top + n_top)
        walls.extend(_ring_quads(a, b) for a, b in zip(ring_idx[:-1], ring_idx[1:], strict=True))
    V = np.concatenate(V)
    F = np.concatenate([*F, *walls])
    plate = Manifold(Mesh64(np.ascontiguousarray(V), np.ascontiguousarray(F.astype(np.uint64))))
    if plate.status().name != "NoError" or plate.is_empty():
        raise RuntimeError(f"hub {spec.name!r}: face plate mesh invalid: {plate.status()}")
    return plate


def _ring_quads(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Triangles joining ring ``a`` to the ring ``b`` below it (same length, same order)."""
    na, nb = np.roll(a, -1), np.roll(b, -1)
    return np.concatenate([np.column_stack([a, b, nb]), np.column_stack([a, nb, na])])


def rings(spec: HubSpec):
    """The axisymmetric parts [mm]: hub pad ``(r_out, z0, z1)`` (None without a pad) and the rim
    rings ``(r_in, r_out, z0, z1)``: barrel, front flange (lip) and back flange."""
    t = spec.face_thickness * 1e3
    pad_depth = spec.hub_pad_depth * 1e3
    pad = (spec.hub_pad_radius * 1e3, -t - pad_depth, -t + 0.5) if pad_depth > 0 else None
    z_lip = (spec.z_face(spec.dish_outer_radius) + spec.rim_lip_height) * 1e3
    z_back = z_lip - spec.rim_width * 1e3
    rb_out = 0.5 * spec.rim_barrel_diameter * 1e3
    rb_in = spec.rim_barrel_inner_radius * 1e3
    rf = 0.5 * spec.rim_outer_diameter * 1e3
    tf = spec.rim_flange_thickness * 1e3
    rims = [(rb_in, rb_out, z_back, z_lip), (rb_out - 0.5, rf, z_lip - tf, z_lip),
            (rb_out - 0.5, rf, z_back, z_back + tf)]
    return pad, rims


def _hole_cutters(spec: HubSpec) -> list:
    """Centre bore and bolt holes (with 60 deg lug seats opening to the front) [mm]."""
    from manifold3d import Manifold

    t = spec.face_thickness * 1e3
    pad_depth = spec.hub_pad_depth * 1e3
    cutters = [tube(0.0, 0.5 * spec.center_bore_diameter * 1e3, -t - pad_depth - 5.0, 5.0)]
    rb = 0.5 * spec.bolt_circle_diameter * 1e3
    r_hole = 0.5 * spec.bolt_hole_diameter * 1e3
    r_seat = 0.5 * spec.bolt_seat_diameter * 1e3
    for k in range(spec.bolt_count):
        a = 2 * math.pi * (k + 0.5) / spec.bolt_count + spec.spoke_phase
        c = tube(0.0, r_hole, -t - pad_depth - 5.0, 5.0)
        if r_seat > r_hole:  # the seat: a cone from the pad face (z = 0) down to the hole
            depth = (r_seat - r_hole) / math.tan(LUG_SEAT_HALF_ANGLE)
            n = segments_per_circle(r_seat, RIM_SAG_MM)
            cone = Manifold.cylinder(depth, r_hole, r_seat, n).translate((0, 0, -depth))
            c = c + cone + tube(0.0, r_seat, 0.0, 5.0)
        cutters.append(c.translate((rb * math.cos(a), rb * math.sin(a), 0.0)))
    return cutters


def build_solid(spec: HubSpec, windows: list[Window], *, holes: bool = True,
                geom: PlateGeometry | None = None):
    """The hub solid as a manifold3d Manifold in millimetres (frame H)."""
    from manifold3d import Manifold, OpType

    parts = [plate_manifold(spec, windows, geom)]
    pad, rims = rings(spec)
    if pad is not None:
        parts.append(tube(0.0, *pad))
    parts.extend(tube(*ring) for ring in rims)
    solid = Manifold.batch_boolean(parts, OpType.Add)
    if holes:
        solid = Manifold.batch_boolean([solid, *_hole_cutters(spec)], OpType.Subtract)
    if solid.status().name != "NoError" or solid.is_empty():
        raise RuntimeError(f"hub {spec.name!r}: manifold construction failed: {solid.status()}")
    return solid


def mesh_arrays(solid) -> tuple[np.ndarray, np.ndarray]:
    mesh = solid.to_mesh64()
    return np.asarray(mesh.vert_properties[:, :3], float), np.asarray(mesh.tri_verts, np.int64)
