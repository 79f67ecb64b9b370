"""HubSpec -> watertight hub mesh, ground-truth window edges, convex collision pieces, SDF.

Construction (manifold3d, robust booleans; everything in millimetres inside this module, metres
in every file written):

1. 2-D window outlines (``CrossSection``): the annulus between the window radii minus the spoke
   bands; each connected component is one window. Its convex corners are rounded by an
   opening (offset by -f then +f with round joins), which gives exact circular fillets; a
   closing with ``blend_radius`` then rounds reflex corners (tangent-continuous outline).
   Straight stretches are subdivided so that no outline segment exceeds ~1 mm; arcs are
   segmented so that their chord sag stays below 2 um.
2. The face plate (disc minus windows) is extruded as a 1 mm slab, refined to
   ``mesh_edge_length`` (the outline segments are shorter and stay intact), then warped: the
   slab is stretched to ``face_thickness`` and every vertex is lifted by the dish profile
   ``z_face(r)``. Window side walls therefore stay parallel to the hub axis, and the edge where
   the front face meets a window is a polyline of mesh vertices.
3. Union with the hub pad (boss) and the rim (barrel, front and back flange); the centre bore
   and the bolt holes are cut through.
4. Vertices are rounded to 0.1 um (the OBJ precision); the ground-truth edge loops are read
   from the final mesh (lifted outline vertices, checked to be joined by mesh edges) and
   resampled along those mesh edges to <= ``edge_sample_spacing``, so every loop point lies on
   the mesh. Normals are analytic: the wall normal is the 2-D outline normal (pointing into the
   opening), the face normal is that of ``z = z_face(r)``; the tangent is their cross product.
5. Collision pieces: the solid is cut into polar cells (rings x sectors); each connected part of
   a cell is replaced by its convex hull, and a cell is split further (in radius or angle)
   while the hull adds more than ``HULL_EXCESS_MM`` of average thickness to the part. The
   hulls cover the material (each covers its own part); how far they reach into the window
   openings is measured and recorded (``summary.json``: ``collision.max_window_intrusion_mm``).
   Bolt holes are filled in the collision model (conservative; no tool goes there).
"""

from __future__ import annotations

import io
import json
import logging
import math
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_bytes, atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.hub.spec import HubSpec, spec_to_yaml

__all__ = ["GeneratedHub", "generate_hub", "build_window_outlines", "build_solid",
           "write_npz", "window_intrusion", "sdf_text", "obj_text", "loop_curvature",
           "WindowProbes", "GENERATOR_VERSION"]

log = logging.getLogger(__name__)

GENERATOR_VERSION = 1
ARC_SAG_MM = 0.002  # chord sag of arcs in the window outlines [mm]
ARC_MAX_STEP = math.radians(2.0)  # and at most this angle per arc segment
MAX_TURN = math.radians(2.5)  # largest turn between consecutive outline segments
RIM_SAG_MM = 0.02  # chord sag of the rim, pad, bore and bolt-hole circles [mm]
LINE_STEP_MM = 1.0  # max outline segment on straight stretches [mm]
COLL_CELL_MM = 60.0  # initial quadtree cell of the plate's collision pieces [mm]
COLL_TOL_MM = 1.0  # allowed average extra thickness of a plate hull [mm]
COLL_WINDOW_REACH_MM = 0.5  # a hull may reach at most this far into a window opening [mm]
COLL_SAG_MM = 0.5  # chord sag of the rim's and pad's annular-sector pieces [mm]
MIN_CELL_MM = 2.5  # smallest quadtree cell [mm]
OBJ_DECIMALS = 7  # 0.1 um in metres

Progress = Callable[[int, int, str], None] | None


@dataclass(frozen=True)
class GeneratedHub:
    """What :func:`generate_hub` wrote.

    Attributes:
        dir: the hub folder.
        files: every file written (relative to ``dir``), sorted.
        seconds: generation wall time [s].
        summary: the content of ``summary.json``.
    """

    dir: Path
    files: tuple[str, ...]
    seconds: float
    summary: dict


# --------------------------------------------------------------------------- 2-D outlines
def _segments(radius_mm: float, sag_mm: float = ARC_SAG_MM) -> int:
    """Circular segments per full circle so that the chord sag is <= ``sag_mm``."""
    dtheta = min(2.0 * math.sqrt(2.0 * sag_mm / max(radius_mm, 1e-9)), ARC_MAX_STEP)
    return int(math.ceil(2.0 * math.pi / dtheta))


def _densify(poly: np.ndarray, step: float) -> np.ndarray:
    """Insert collinear points so that no segment of the closed polygon exceeds ``step``."""
    out = []
    nxt = np.roll(poly, -1, axis=0)
    for a, b in zip(poly, nxt, strict=True):
        n = max(1, int(math.ceil(np.linalg.norm(b - a) / step - 1e-9)))
        t = np.arange(n)[:, None] / n
        out.append(a + (b - a) * t)
    return np.concatenate(out)


def _dedupe(poly: np.ndarray, tol: float = 0.01) -> np.ndarray:
    """Drop vertices closer than ``tol`` [mm] to the previously kept one (Clipper's offsets
    leave near-duplicates that would become sliver triangles)."""
    keep = [0]
    for i in range(1, len(poly)):
        if np.linalg.norm(poly[i] - poly[keep[-1]]) >= tol:
            keep.append(i)
    if len(keep) > 1 and np.linalg.norm(poly[keep[-1]] - poly[0]) < tol:
        keep.pop()
    return poly[keep]


def _band(center: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Polygon (CCW) of a band of varying width about a 2-D centre line (M, 2)."""
    d = np.gradient(center, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    nrm = np.stack([-d[:, 1], d[:, 0]], axis=1)
    left = center + nrm * (width[:, None] / 2)
    right = center - nrm * (width[:, None] / 2)
    poly = np.concatenate([right, left[::-1]])
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    return poly if area > 0 else poly[::-1]


def _spoke_polygons(spec: HubSpec) -> list[np.ndarray]:
    """Spoke bands in mm (they overhang the window annulus on both sides)."""
    r_in, r_out = spec.window_inner_radius * 1e3, spec.window_outer_radius * 1e3
    ext = 15.0
    w_in, w_out = spec.spoke_width * 1e3, spec.spoke_width_outer * 1e3
    polys = []
    for k in range(spec.spoke_count):
        th = spec.spoke_phase + 2.0 * math.pi * k / spec.spoke_count
        if spec.spoke_style in ("straight", "curved"):
            r = np.linspace(r_in - ext, r_out + ext, 121)
            s = (r - r_in) / (r_out - r_in)
            sc = np.clip(s, 0.0, None)
            ang = th + spec.spoke_sweep * sc * sc
            center = np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)
            width = w_in + (w_out - w_in) * np.clip(s, 0.0, 1.0)
            polys.append(_band(center, width))
        else:  # split: a stem and two straight arms
            u = np.array([math.cos(th), math.sin(th)])
            r_split = spec.split_radius * 1e3
            stem = np.stack([u * (r_in - ext), u * (r_split + 0.5 * w_out)])
            polys.append(_band(stem, np.array([w_in, w_in])))
            a = u * r_split
            for sgn in (-1.0, 1.0):
                c = r_out * np.array([math.cos(th + sgn * spec.split_angle),
                                      math.sin(th + sgn * spec.split_angle)])
                d = (c - a) / np.linalg.norm(c - a)
                polys.append(_band(np.stack([a, c + d * ext]), np.array([w_out, w_out])))
    return polys


@dataclass(frozen=True)
class _Window:
    index: int
    kind: str
    poly_mm: np.ndarray  # (N, 2) CCW outline [mm]
    fillet_mm: float


def build_window_outlines(spec: HubSpec) -> list[_Window]:
    """The windows' 2-D outlines [mm], CCW, sorted CCW about +Z from +X; validated."""
    from manifold3d import CrossSection, JoinType

    r_in, r_out = spec.window_inner_radius * 1e3, spec.window_outer_radius * 1e3
    annulus = (CrossSection.circle(r_out, _segments(r_out))
               - CrossSection.circle(r_in, _segments(r_in)))
    spokes = CrossSection(_spoke_polygons(spec))
    raw = (annulus - spokes).decompose()
    n_expected = spec.window_count
    if len(raw) != n_expected:
        raise InputError(
            f"hub {spec.name!r}: field 'spoke_width': the spokes leave {len(raw)} openings in "
            f"the window annulus, expected {n_expected} (spokes too wide or overlapping?)")
    pitch = 2 * math.pi / spec.spoke_count
    windows = []
    for comp in raw:
        pts = np.concatenate(comp.to_polygons())
        c = pts.mean(axis=0)
        ang = math.atan2(c[1], c[0]) - spec.spoke_phase
        # distance of the window's angle from the nearest spoke angle, in pitches
        frac = abs(((ang / pitch) + 0.5) % 1.0 - 0.5)
        kind = "small" if spec.spoke_style == "split" and frac < 0.25 else "large"
        f = (spec.fillet_radius_small if kind == "small" else spec.fillet_radius) * 1e3
        seg = _segments(f)
        opened = comp.offset(-f, JoinType.Round, 2.0, seg)
        if opened.is_empty():
            field = "fillet_radius_small" if kind == "small" else "fillet_radius"
            raise InputError(f"hub {spec.name!r}: field {field!r}: fillet {f:.1f} mm is larger "
                             f"than a {kind} window can hold")
        opened = opened.offset(f, JoinType.Round, 2.0, seg)
        # closing rounds the reflex corners that the opening keeps (e.g. where a curved spoke's
        # side meets the fillet), so the whole edge is tangent-continuous
        c = min(f, spec.blend_radius * 1e3)
        opened = opened.offset(c, JoinType.Round, 2.0, _segments(c)).offset(
            -c, JoinType.Round, 2.0, _segments(c))
        polys = opened.to_polygons()
        if len(polys) != 1:
            field = "fillet_radius_small" if kind == "small" else "fillet_radius"
            raise InputError(f"hub {spec.name!r}: field {field!r}: rounding a {kind} window "
                             f"splits it into {len(polys)} parts")
        poly = _dedupe(np.asarray(polys[0], float))
        area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1)
                            - np.roll(poly[:, 0], -1) * poly[:, 1])
        if area < 0:
            poly = poly[::-1]
        # start the loop at the point of smallest angle about the window centre seen from H's
        # origin direction: deterministic, independent of Clipper's start vertex
        c = poly.mean(axis=0)
        rel = poly - c
        radial = c / np.linalg.norm(c)
        start = int(np.argmax(rel @ radial))  # outermost point
        poly = np.roll(poly, -start, axis=0)
        seg_v = np.roll(poly, -1, axis=0) - poly
        heading = np.arctan2(seg_v[:, 1], seg_v[:, 0])
        turn = np.abs((np.roll(heading, -1) - heading + np.pi) % (2 * np.pi) - np.pi)
        if turn.max() > MAX_TURN:
            raise RuntimeError(f"hub {spec.name!r}: window outline has a corner of "
                               f"{math.degrees(turn.max()):.1f} deg at "
                               f"{poly[int(np.argmax(turn)) + 1]} mm")
        windows.append((math.atan2(c[1], c[0]) % (2 * math.pi), kind, _densify(poly, LINE_STEP_MM),
                        f))
    windows.sort(key=lambda w: w[0])
    return [_Window(i, kind, poly, f) for i, (_, kind, poly, f) in enumerate(windows)]


# --------------------------------------------------------------------------- 3-D solid
def _tube(r_in: float, r_out: float, z0: float, z1: float):
    from manifold3d import Manifold

    outer = Manifold.cylinder(z1 - z0, r_out, -1.0, _segments(r_out, RIM_SAG_MM))
    if r_in <= 0:
        return outer.translate((0, 0, z0))
    inner = Manifold.cylinder(z1 - z0 + 2.0, r_in, -1.0, _segments(r_in, RIM_SAG_MM)).translate(
        (0, 0, -1.0))
    return (outer - inner).translate((0, 0, z0))


def _hex_grid(lo: np.ndarray, hi: np.ndarray, h: float) -> np.ndarray:
    ys = np.arange(lo[1], hi[1] + h, h * math.sqrt(3) / 2)
    pts = []
    for j, y in enumerate(ys):
        xs = np.arange(lo[0] + (h / 2 if j % 2 else 0.0), hi[0] + h, h)
        pts.append(np.column_stack([xs, np.full(len(xs), y)]))
    return np.concatenate(pts)


# face triangulation: grid step [mm] by distance [mm] from the nearest window edge (top face);
# the back face uses mesh_edge_length everywhere
FACE_STEPS_MM = ((4.0, 1.5), (12.0, 3.0))


def _triangulate(spec: HubSpec, loops: list[np.ndarray], windows: list[_Window], r_plate: float,
                 graded: bool) -> np.ndarray:
    """Delaunay triangulation (T, 3) of the plate region: outline points (indices first, in
    ``loops`` order) plus a hexagonal grid; every outline segment checked to be an edge."""
    from matplotlib.path import Path as MplPath
    from scipy.spatial import Delaunay, cKDTree

    bpts = np.concatenate(loops)
    win_paths = [MplPath(w.poly_mm) for w in windows]
    wtree = cKDTree(np.concatenate([w.poly_mm for w in windows]))
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
    for path in win_paths:
        keep &= ~path.contains_points(grid)
    grid, step = grid[keep], step[keep]
    grid = grid[cKDTree(bpts).query(grid)[0] > 0.6 * step]
    pts = np.concatenate([bpts, grid])
    tri = Delaunay(pts).simplices
    cen = pts[tri].mean(axis=1)
    inside = np.hypot(cen[:, 0], cen[:, 1]) < r_plate
    for path in win_paths:
        inside &= ~path.contains_points(cen)
    tri = tri[inside]
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    cw = ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])) < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]  # CCW seen from +Z
    edges = _edge_set(tri)
    offs = np.cumsum([0] + [len(lp) for lp in loops])
    for k in range(len(loops)):
        idx = np.arange(offs[k], offs[k + 1])
        nxt = np.roll(idx, -1)
        missing = sum((min(i, j), max(i, j)) not in edges for i, j in zip(idx, nxt, strict=True))
        if missing:
            raise RuntimeError(f"hub {spec.name!r}: face triangulation misses {missing} "
                               f"outline segments of loop {k}")
    return pts, tri


def _dished_plate(spec: HubSpec, windows: list[_Window]):
    """The face plate (disc minus windows, dished) as a Manifold [mm].

    Written by hand instead of extrude + refine: manifold's refine subdivides the long slivers of
    the extrusion's triangulation into ~10^5 triangles. The front face is a Delaunay
    triangulation of the outline points plus a hexagonal grid graded by the distance to the
    window edges (1.5 mm / 3 mm / ``mesh_edge_length``), the back face a coarse one; the window
    walls join the two copies of each outline.
    """
    from manifold3d import Manifold, Mesh64

    t = spec.face_thickness * 1e3
    r_plate = (spec.rim_barrel_inner_radius + 0.5 * spec.rim_thickness) * 1e3
    n_out = _segments(r_plate, RIM_SAG_MM)
    ang = 2 * math.pi * np.arange(n_out) / n_out
    outer = np.column_stack([r_plate * np.cos(ang), r_plate * np.sin(ang)])  # CCW, material left
    loops = [outer] + [w.poly_mm[::-1] for w in windows]  # windows reversed: material left
    nb = sum(len(lp) for lp in loops)
    top_pts, top_tri = _triangulate(spec, loops, windows, r_plate, graded=True)
    bot_pts, bot_tri = _triangulate(spec, loops, windows, r_plate, graded=False)
    n_top = len(top_pts)
    offs = np.cumsum([0] + [len(lp) for lp in loops])
    walls = []
    for k in range(len(loops)):
        idx = np.arange(offs[k], offs[k + 1])
        nxt = np.roll(idx, -1)
        walls.append(np.column_stack([idx, idx + n_top, nxt + n_top]))
        walls.append(np.column_stack([idx, nxt + n_top, nxt]))
    assert np.array_equal(top_pts[:nb], bot_pts[:nb])

    def lift(pts: np.ndarray, dz: float) -> np.ndarray:
        r = np.hypot(pts[:, 0], pts[:, 1]) * 1e-3
        return np.column_stack([pts, spec.z_face(r) * 1e3 + dz])

    V = np.concatenate([lift(top_pts, 0.0), lift(bot_pts, -t)])
    F = np.concatenate([top_tri, bot_tri[:, [0, 2, 1]] + n_top, *walls])
    plate = Manifold(Mesh64(np.ascontiguousarray(V), np.ascontiguousarray(F.astype(np.uint64))))
    if plate.status().name != "NoError" or plate.is_empty():
        raise RuntimeError(f"hub {spec.name!r}: face plate mesh invalid: {plate.status()}")
    return plate


def _rings(spec: HubSpec):
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


def build_solid(spec: HubSpec, windows: list[_Window], *, holes: bool = True):
    """The hub solid as a manifold3d Manifold in millimetres (frame H)."""
    from manifold3d import Manifold

    t = spec.face_thickness * 1e3
    plate = _dished_plate(spec, windows)
    pad_depth = spec.hub_pad_depth * 1e3
    parts = [plate]
    pad, rims = _rings(spec)
    if pad is not None:
        parts.append(_tube(0.0, *pad))
    parts.extend(_tube(*ring) for ring in rims)
    from manifold3d import OpType

    solid = Manifold.batch_boolean(parts, OpType.Add)
    if holes:
        cutters = [_tube(0.0, 0.5 * spec.center_bore_diameter * 1e3, -t - pad_depth - 5.0, 5.0)]
        rb = 0.5 * spec.bolt_circle_diameter * 1e3
        for k in range(spec.bolt_count):
            a = 2 * math.pi * (k + 0.5) / spec.bolt_count + spec.spoke_phase
            cutters.append(_tube(0.0, 0.5 * spec.bolt_hole_diameter * 1e3, -t - pad_depth - 5.0,
                                 5.0).translate((rb * math.cos(a), rb * math.sin(a), 0.0)))
        solid = Manifold.batch_boolean([solid, *cutters], OpType.Subtract)
    if solid.status().name != "NoError" or solid.is_empty():
        raise RuntimeError(f"hub {spec.name!r}: manifold construction failed: {solid.status()}")
    return solid


def _mesh_arrays(solid) -> tuple[np.ndarray, np.ndarray]:
    mesh = solid.to_mesh64()
    return np.asarray(mesh.vert_properties[:, :3], float), np.asarray(mesh.tri_verts, np.int64)


# --------------------------------------------------------------------------- edge loops
def _edge_set(faces: np.ndarray) -> set[tuple[int, int]]:
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = np.sort(e, axis=1)
    return set(map(tuple, np.unique(e, axis=0).tolist()))


def _loops_from_mesh(spec: HubSpec, windows: list[_Window], V_m: np.ndarray,
                     faces: np.ndarray) -> list[dict]:
    """Ground-truth loops (metres) read from the final, rounded mesh vertices."""
    from scipy.spatial import cKDTree

    tree = cKDTree(V_m)
    edges = _edge_set(faces)
    out = []
    for w in windows:
        xy = w.poly_mm * 1e-3
        z = spec.z_face(np.hypot(xy[:, 0], xy[:, 1]))
        target = np.column_stack([xy, z])
        dist, idx = tree.query(target)
        if dist.max() > 1e-6:
            raise RuntimeError(f"hub {spec.name!r} window {w.index}: outline vertex not in the "
                               f"mesh (off by {dist.max():.2e} m)")
        nxt = np.roll(idx, -1)
        missing = [i for i, (a, b) in enumerate(zip(idx, nxt, strict=True))
                   if (min(a, b), max(a, b)) not in edges]
        if missing:
            raise RuntimeError(f"hub {spec.name!r} window {w.index}: {len(missing)} outline "
                               f"segments are not mesh edges")
        P = V_m[idx]  # exact mesh vertices
        # wall normals at the vertices: mean of the adjacent outline-segment normals (2-D)
        seg = np.roll(xy, -1, axis=0) - xy
        seg /= np.linalg.norm(seg, axis=1, keepdims=True)
        seg_n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)  # left of CCW = into the opening
        vert_n = seg_n + np.roll(seg_n, 1, axis=0)
        vert_n /= np.linalg.norm(vert_n, axis=1, keepdims=True)
        # resample along the mesh edges
        P_next = np.roll(P, -1, axis=0)
        n_next = np.roll(vert_n, -1, axis=0)
        L = np.linalg.norm(P_next - P, axis=1)
        counts = np.maximum(1, np.ceil(L / spec.edge_sample_spacing - 1e-9).astype(int))
        seg_id = np.repeat(np.arange(len(P)), counts)
        frac = np.concatenate([np.arange(c) / c for c in counts])[:, None]
        p = P[seg_id] + (P_next[seg_id] - P[seg_id]) * frac
        n2 = vert_n[seg_id] * (1 - frac) + n_next[seg_id] * frac
        n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
        n_wall = np.column_stack([n2, np.zeros(len(n2))])
        r = np.hypot(p[:, 0], p[:, 1])
        g = spec.dz_face_dr(r)
        with np.errstate(invalid="ignore", divide="ignore"):
            ex = np.where(r > 0, p[:, 0] / r, 0.0)
            ey = np.where(r > 0, p[:, 1] / r, 0.0)
        n_face = np.column_stack([-g * ex, -g * ey, np.ones(len(p))])
        n_face /= np.linalg.norm(n_face, axis=1, keepdims=True)
        tan = np.cross(n_wall, n_face)
        chord = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
        sgn = np.sign(np.sum(tan * chord, axis=1))
        if np.any(sgn <= 0):
            raise RuntimeError(f"hub {spec.name!r} window {w.index}: tangent sign inconsistent")
        tan /= np.linalg.norm(tan, axis=1, keepdims=True)
        out.append({"index": w.index, "kind": w.kind, "p_HE": p, "t_H": tan,
                    "n_wall_H": n_wall, "n_face_H": n_face, "fillet_m": w.fillet_mm * 1e-3,
                    "poly_xy_m": xy, "vertices_m": P})
    return out


def window_center_xy(poly_xy: np.ndarray, grid: int = 80) -> np.ndarray:
    """The point inside a closed 2-D polygon (N, 2) farthest from its boundary (grid search)."""
    from matplotlib.path import Path as MplPath
    from scipy.spatial import cKDTree

    lo, hi = poly_xy.min(axis=0), poly_xy.max(axis=0)
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], grid), np.linspace(lo[1], hi[1], grid))
    cand = np.column_stack([gx.ravel(), gy.ravel()])
    inside = MplPath(poly_xy).contains_points(cand)
    cand = cand[inside]
    d, _ = cKDTree(_densify(poly_xy, (hi - lo).max() / 400)).query(cand)
    return cand[int(np.argmax(d))]


def loop_curvature(p: np.ndarray, k: int = 1) -> np.ndarray:
    """Discrete curvature [1/m] of a closed polyline: circle through points i-k, i, i+k."""
    a = np.roll(p, k, axis=0)
    c = np.roll(p, -k, axis=0)
    ab, bc, ca = np.linalg.norm(p - a, axis=1), np.linalg.norm(c - p, axis=1), np.linalg.norm(
        a - c, axis=1)
    cross = np.linalg.norm(np.cross(p - a, c - a), axis=1)
    return 2 * cross / np.maximum(ab * bc * ca, 1e-300)


# --------------------------------------------------------------------------- collision
def _sector_hulls(r0: float, r1: float, z0: float, z1: float, sag: float, phase: float) -> list:
    """Convex pieces covering the tube r0..r1, z0..z1 [mm]: hulls of annular sectors whose
    inner chord sags at most ``sag`` [mm] into the tube's hole."""
    from manifold3d import Manifold

    n = max(3, int(math.ceil(2 * math.pi / (2 * math.sqrt(2 * sag / r0))))) if r0 > 0 else 1
    out = []
    for k in range(n):
        a0 = phase + 2 * math.pi * k / n
        a1 = phase + 2 * math.pi * (k + 1) / n
        m = max(2, int(math.ceil((a1 - a0) / 0.02)) + 1)
        ang = np.linspace(a0, a1, m)
        ring = []
        for r in ((r0, r1) if r0 > 0 else (r1,)):
            ring.append(np.column_stack([r * np.cos(ang), r * np.sin(ang)]))
        pts2 = np.concatenate(ring + ([] if r0 > 0 else [np.zeros((1, 2))]))
        pts = np.concatenate([np.column_stack([pts2, np.full(len(pts2), z)]) for z in (z0, z1)])
        out.append(_mesh_arrays(Manifold.hull_points(pts))[0])
    return out


class WindowProbes:
    """Points just inside the window openings [mm]: a collision hull containing one reaches
    more than ``COLL_WINDOW_REACH_MM`` into an opening."""

    def __init__(self, pts: np.ndarray):
        self.pts = np.asarray(pts, float)

    @classmethod
    def from_spec(cls, spec: HubSpec, windows: list[_Window]) -> WindowProbes:
        pts = []
        t = spec.face_thickness * 1e3
        for w in windows:
            p = _densify(w.poly_mm, 1.0)
            seg = np.roll(p, -1, axis=0) - p
            seg /= np.linalg.norm(seg, axis=1, keepdims=True)
            nrm = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
            nrm = nrm + np.roll(nrm, 1, axis=0)
            nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
            q = p + COLL_WINDOW_REACH_MM * nrm
            z = spec.z_face(np.hypot(q[:, 0], q[:, 1]) * 1e-3) * 1e3
            for f in np.linspace(0.02, 0.98, 6):
                pts.append(np.column_stack([q, z - f * t]))
        return cls(np.concatenate(pts))

    def inside(self, hull_pts: np.ndarray) -> np.ndarray:
        """Indices of the probes inside the convex hull of ``hull_pts``."""
        from scipy.spatial import ConvexHull

        lo, hi = hull_pts.min(axis=0), hull_pts.max(axis=0)
        m = np.flatnonzero(np.all((self.pts >= lo) & (self.pts <= hi), axis=1))
        if not len(m):
            return m
        eq = ConvexHull(hull_pts).equations
        return m[np.all(self.pts[m] @ eq[:, :3].T + eq[:, 3] <= 0.0, axis=1)]

    def hit(self, hull_pts: np.ndarray) -> bool:
        return bool(len(self.inside(hull_pts)))


@dataclass
class _Piece:
    pts: np.ndarray  # hull vertices [mm]
    vol: float  # volume of the material part(s) it covers [mm^3]
    hull_vol: float


def _piece_ok(pc: _Piece, t: float, probes: WindowProbes) -> bool:
    excess = (pc.hull_vol - pc.vol) / max(pc.vol / t, 1.0)
    return excess <= COLL_TOL_MM and not probes.hit(pc.pts)


def _plate_pieces(spec: HubSpec, plate, probes: WindowProbes, progress: Progress = None) -> list:
    """Convex pieces [mm] of the plate: quadtree of square cells, then greedy merging of
    neighbours (see module doc)."""
    from manifold3d import CrossSection
    from scipy.spatial import ConvexHull

    t = spec.face_thickness * 1e3
    bb = plate.bounding_box()
    z0, z1 = bb[2] - 1.0, bb[5] + 1.0
    half = max(abs(bb[0]), abs(bb[1]), abs(bb[3]), abs(bb[4])) + 1.0
    n0 = int(math.ceil(2 * half / COLL_CELL_MM))
    edge = 2 * half / n0
    stack = [(-half + i * edge, -half + j * edge, edge) for j in range(n0) for i in range(n0)]
    pieces: list[_Piece] = []
    done, total = 0, len(stack)
    while stack:
        x0, y0, c = stack.pop()
        done += 1
        if progress is not None:
            progress(done, total, "collision cells")
        box2 = CrossSection.square((c, c)).translate((x0, y0))
        cell = plate ^ box2.extrude(z1 - z0).translate((0, 0, z0))
        if cell.is_empty():
            continue
        parts = []
        split = False
        for comp in cell.decompose():
            vol = comp.volume()
            if vol < 1e-6:
                continue
            hull = comp.hull()
            pc = _Piece(_mesh_arrays(hull)[0], vol, hull.volume())
            if c > MIN_CELL_MM and not _piece_ok(pc, t, probes):
                split = True
                break
            parts.append(pc)
        if split:
            h = c / 2
            stack.extend([(x0, y0, h), (x0 + h, y0, h), (x0, y0 + h, h), (x0 + h, y0 + h, h)])
            total += 4
            continue
        pieces.extend(parts)
    # greedy merge of touching pieces while the merged hull stays acceptable
    changed = True
    while changed:
        changed = False
        lo = np.array([p.pts.min(axis=0) for p in pieces])
        hi = np.array([p.pts.max(axis=0) for p in pieces])
        i = 0
        while i < len(pieces):
            touch = np.flatnonzero(np.all((lo[i] <= hi + 1e-6) & (hi[i] >= lo - 1e-6), axis=1))
            best = None
            for j in touch:
                if j <= i:
                    continue
                pts = np.concatenate([pieces[i].pts, pieces[j].pts])
                hull = ConvexHull(pts)
                pc = _Piece(pts[hull.vertices], pieces[i].vol + pieces[j].vol, hull.volume)
                if _piece_ok(pc, t, probes):
                    score = pc.hull_vol - pc.vol
                    if best is None or score < best[0]:
                        best = (score, j, pc)
            if best is None:
                i += 1
                continue
            _, j, pc = best
            pieces[i] = pc
            del pieces[j]
            lo = np.delete(lo, j, axis=0)
            hi = np.delete(hi, j, axis=0)
            lo[i], hi[i] = pc.pts.min(axis=0), pc.pts.max(axis=0)
            changed = True
    return [p.pts for p in pieces]


def _collision_pieces(spec: HubSpec, windows: list[_Window], progress: Progress = None) -> list:
    """Convex pieces (hull vertex arrays [mm]) covering the hub: plate by quadtree + merging,
    pad and rim by construction (annular sectors). Bolt holes are filled; the bore is open."""
    bore_r = 0.5 * spec.center_bore_diameter * 1e3
    plate = _dished_plate(spec, windows) - _tube(0.0, bore_r, -1e3, 1e3)
    pieces = _plate_pieces(spec, plate, WindowProbes.from_spec(spec, windows), progress)
    pad, rims = _rings(spec)
    if pad is not None:
        pieces += _sector_hulls(bore_r, *pad, COLL_SAG_MM, spec.spoke_phase)
    for ring in rims:
        pieces += _sector_hulls(*ring, COLL_SAG_MM, 0.0)
    return pieces


def _hull_equations(V: np.ndarray) -> np.ndarray:
    from scipy.spatial import ConvexHull

    return ConvexHull(V).equations  # (F, 4): n.x + d <= 0 inside


def window_intrusion(loops: list[dict], piece_vertices: list[np.ndarray],
                     face_thickness: float, keep=None) -> float:
    """Largest distance [m] from the window wall into the opening that a piece reaches.

    Probes: each edge point moved into the opening by s along n_wall, at 5 depths through the
    face thickness; the largest s of a probe inside any piece is returned (0 if none).

    Args:
        loops: per window a mapping with ``p_HE`` and ``n_wall_H`` (N, 3) in H [m].
        piece_vertices: convex pieces, each (M, 3) hull vertices in H [m].
        face_thickness: depth [m] below the edge (along -Z_H) that the probes span.
        keep: optional callable (K, 3) probes -> (K,) bool: which probes really lie in the
            opening (for a mesh whose walls are not parallel to the axis); default all.
    """
    eqs = [_hull_equations(v) for v in piece_vertices]
    lo = np.array([v.min(axis=0) for v in piece_vertices])
    hi = np.array([v.max(axis=0) for v in piece_vertices])
    steps = np.array([0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0]) * 1e-3
    depths = np.linspace(0.05, 0.95, 5) * face_thickness
    worst = 0.0
    for lp in loops:
        p, n = lp["p_HE"][::4], lp["n_wall_H"][::4]
        for s in steps[::-1]:
            if s <= worst:
                break
            q = np.concatenate([p + s * n - np.array([0, 0, d]) for d in depths])
            if keep is not None:
                q = q[keep(q)]
            hit = False
            for e, a, b in zip(eqs, lo, hi, strict=True):
                m = np.all((q >= a - 1e-9) & (q <= b + 1e-9), axis=1)
                if not m.any():
                    continue
                inside = np.all(q[m] @ e[:, :3].T + e[:, 3] <= -1e-7, axis=1)
                if inside.any():
                    hit = True
                    break
            if hit:
                worst = s
                break
    return float(worst)


# --------------------------------------------------------------------------- files
def obj_text(V_m: np.ndarray, faces: np.ndarray, header: str) -> str:
    Vr = np.round(V_m, OBJ_DECIMALS) + 0.0
    buf = io.StringIO()
    buf.write(f"# {header}\n# units: metres, frame H\n")
    np.savetxt(buf, Vr, fmt=f"v %.{OBJ_DECIMALS}f %.{OBJ_DECIMALS}f %.{OBJ_DECIMALS}f")
    np.savetxt(buf, faces + 1, fmt="f %d %d %d")
    return buf.getvalue()


def write_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Deterministic compressed .npz (fixed zip timestamps; numpy.savez stamps the clock)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key in sorted(arrays):
            arr = io.BytesIO()
            np.lib.format.write_array(arr, np.ascontiguousarray(arrays[key]), allow_pickle=False)
            info = zipfile.ZipInfo(key + ".npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, arr.getvalue())
    atomic_write_bytes(path, buf.getvalue())


def sdf_text(name: str, mass: float, com: np.ndarray, I: np.ndarray,
             piece_files: list[str], *,
             origin: str = "parametric hub {name}: generated by `drakedeburr hub generate`") -> str:
    """``hub.sdf``: link ``hub`` (body frame H), visual ``hub.obj``, one declared-convex
    collision mesh per piece file. ``mass`` [kg], ``com`` (3,) [m] in H, ``I`` (3, 3) [kg m^2]
    about the centre of mass, axes of H."""
    cols = "\n".join(
        f"""      <collision name="{Path(f).stem}">
        <geometry><mesh><uri>{f}</uri><drake:declare_convex/></mesh></geometry>
      </collision>""" for f in piece_files)
    return f"""<?xml version="1.0"?>
<!-- drakedeburr {origin.format(name=repr(name))}, do not
     edit. Body frame of link `hub` = hub frame H (origin on the axis at the front face, +Z out of
     the visible face). Units: metres, kg. Visual: the watertight mesh; collision: convex pieces
     (a Drake Mesh collides as its convex hull, which would fill the windows). -->
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
  <model name="hub">
    <link name="hub">
      <inertial>
        <pose>{com[0]:.9f} {com[1]:.9f} {com[2]:.9f} 0 0 0</pose>
        <mass>{mass:.6f}</mass>
        <inertia>
          <ixx>{I[0, 0]:.9f}</ixx><ixy>{I[0, 1]:.9f}</ixy><ixz>{I[0, 2]:.9f}</ixz>
          <iyy>{I[1, 1]:.9f}</iyy><iyz>{I[1, 2]:.9f}</iyz><izz>{I[2, 2]:.9f}</izz>
        </inertia>
      </inertial>
      <visual name="visual">
        <geometry><mesh><uri>hub.obj</uri></mesh></geometry>
        <material><diffuse>0.78 0.79 0.81 1</diffuse></material>
      </visual>
{cols}
    </link>
  </model>
</sdf>
"""


def generate_hub(spec: HubSpec, out_dir: str | Path, *, progress: Progress = None,
                 with_collision: bool = True) -> GeneratedHub:
    """Generate every asset of one hub into ``out_dir`` (the hub's folder).

    Writes ``hub.yaml`` (the spec), ``hub.obj`` (watertight mesh, metres, frame H),
    ``edges.npz`` (ground-truth loops: ``w{i}_p_HE``, ``w{i}_t_H``, ``w{i}_n_wall_H``,
    ``w{i}_n_face_H`` (N, 3) and ``kinds``), ``summary.json`` (human-readable: windows, mass,
    collision quality), ``collision/piece_NNN.obj`` and ``hub.sdf``. Deterministic: the same
    spec gives byte-identical files. Stale pieces in ``collision/`` are removed.

    Raises:
        InputError: the spec is invalid (names the field).
    """
    import trimesh

    t_start = time.perf_counter()
    spec.validate()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    steps = 5
    if progress:
        progress(0, steps, "outlines")
    windows = build_window_outlines(spec)
    if progress:
        progress(1, steps, "solid")
    solid = build_solid(spec, windows)
    V_mm, F = _mesh_arrays(solid)
    V_m = np.round(V_mm * 1e-3, OBJ_DECIMALS) + 0.0
    genus = solid.genus()
    expected_genus = spec.window_count + spec.bolt_count + 1
    if genus != expected_genus:
        raise RuntimeError(f"hub {spec.name!r}: genus {genus}, expected {expected_genus}")
    if progress:
        progress(2, steps, "edges")
    loops = _loops_from_mesh(spec, windows, V_m, F)
    tm = trimesh.Trimesh(V_m, F, process=False)
    if not (tm.is_watertight and tm.is_volume):
        raise RuntimeError(f"hub {spec.name!r}: mesh is not a watertight volume")
    mp = tm.mass_properties
    mass = float(mp.volume * spec.density)
    com = np.asarray(mp.center_mass)
    I_com = np.asarray(mp.inertia) * spec.density  # about the centre of mass, axes of H
    I_com = 0.5 * (I_com + I_com.T)

    files = []
    atomic_write_text(out / "hub.yaml", spec_to_yaml(spec))
    files.append("hub.yaml")
    atomic_write_text(out / "hub.obj", obj_text(V_m, F, f"drakedeburr hub {spec.name}"))
    files.append("hub.obj")
    arrays: dict[str, np.ndarray] = {"kinds": np.array([lp["kind"] for lp in loops])}
    for lp in loops:
        for key in ("p_HE", "t_H", "n_wall_H", "n_face_H"):
            arrays[f"w{lp['index']}_{key}"] = lp[key]
    write_npz(out / "edges.npz", arrays)
    files.append("edges.npz")

    if progress:
        progress(3, steps, "collision pieces")
    piece_files: list[str] = []
    collision_info: dict = {}
    coll_dir = out / "collision"
    if with_collision:
        pieces = _collision_pieces(spec, windows)
        coll_dir.mkdir(exist_ok=True)
        piece_V = []
        from manifold3d import Manifold

        hull_vol = 0.0
        for i, piece in enumerate(pieces):
            hull = Manifold.hull_points(piece)
            hull_vol += hull.volume() * 1e-9
            pv, pf = _mesh_arrays(hull)
            pv_m = np.round(pv * 1e-3, OBJ_DECIMALS) + 0.0
            piece_V.append(pv_m)
            name = f"collision/piece_{i:03d}.obj"
            atomic_write_text(out / name, obj_text(pv_m, pf, f"hub {spec.name} convex piece {i}"))
            piece_files.append(name)
        for stale in sorted(coll_dir.glob("piece_*.obj")):
            if f"collision/{stale.name}" not in piece_files:
                stale.unlink()
        files.extend(piece_files)
        intrusion = window_intrusion(loops, piece_V, spec.face_thickness)
        collision_info = {
            "method": "face plate: quadtree of square cells, convex hull of each connected "
                      f"part, split while the hull adds > {COLL_TOL_MM} mm average thickness or "
                      f"reaches > {COLL_WINDOW_REACH_MM} mm into a window, then greedy merging "
                      "of touching pieces under the same rule; pad and rim: hulls of annular "
                      f"sectors (chord sag <= {COLL_SAG_MM} mm)",
            "piece_count": len(pieces),
            "hull_volume_over_solid": round(hull_vol / float(mp.volume), 4),
            "max_window_intrusion_mm": round(intrusion * 1e3, 3),
            "bolt_holes_filled": True,
        }
    atomic_write_text(out / "hub.sdf", sdf_text(spec.name, mass, com, I_com, piece_files))
    files.append("hub.sdf")

    if progress:
        progress(4, steps, "summary")
    win_summary = []
    for lp in loops:
        p = lp["p_HE"]
        # curvature over chords of ~0.6 of the smallest radius (fillet or blend): consecutive
        # points are collinear between outline vertices and would give spikes
        r_min = min(lp["fillet_m"], spec.blend_radius)
        kappa = loop_curvature(p, max(2, int(0.3 * r_min / spec.edge_sample_spacing)))
        c_xy = window_center_xy(lp["poly_xy_m"])
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        win_summary.append({
            "index": lp["index"], "kind": lp["kind"], "points": int(len(p)),
            "length_mm": round(float(seg.sum()) * 1e3, 3),
            "max_spacing_mm": round(float(seg.max()) * 1e3, 4),
            "fillet_mm": round(lp["fillet_m"] * 1e3, 3),
            "max_curvature_per_mm": round(float(np.percentile(kappa, 99.5)) * 1e-3, 4),
            "z_range_mm": [round(float(p[:, 2].min()) * 1e3, 3),
                           round(float(p[:, 2].max()) * 1e3, 3)],
            "center_xy_mm": [round(float(c_xy[0]) * 1e3, 3), round(float(c_xy[1]) * 1e3, 3)],
            "width_mm": round(float(np.ptp(lp["poly_xy_m"] @ np.array(
                [-c_xy[1], c_xy[0]]) / np.linalg.norm(c_xy))) * 1e3, 2),
            "radial_size_mm": round(float(np.ptp(lp["poly_xy_m"] @ (c_xy / np.linalg.norm(
                c_xy)))) * 1e3, 2),
        })
    summary = {
        "name": spec.name, "generator_version": GENERATOR_VERSION,
        "frame": "H: origin on the hub axis at the front face centre, +Z out of the visible face",
        "units": "metres in every data file; mm in this summary",
        "mesh": {"vertices": int(len(V_m)), "triangles": int(len(F)), "genus": int(genus),
                 "watertight": True, "volume_m3": round(float(mp.volume), 9)},
        "mass_kg": round(mass, 4),
        "center_of_mass_m": [round(float(c), 6) for c in com],
        "window_count": len(loops), "windows": win_summary, "collision": collision_info,
    }
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    files.append("summary.json")
    if progress:
        progress(steps, steps, "done")
    seconds = time.perf_counter() - t_start
    log.info("hub %s: %d vertices, %d triangles, %d windows, %d pieces in %.1f s", spec.name,
             len(V_m), len(F), len(loops), len(piece_files), seconds)
    return GeneratedHub(out, tuple(sorted(files)), seconds, summary)
