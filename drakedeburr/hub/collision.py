"""Convex collision pieces of a generated hub (a Drake Mesh collides as its convex hull, which
would fill the windows).

The face plate is cut into square cells (quadtree, start ``COLL_CELL_MM``); each connected part
of a cell is replaced by its convex hull, and a cell is split while the hull adds more than
``COLL_TOL_MM`` of average thickness to its part or contains a *probe point* (points
``COLL_WINDOW_REACH_MM`` inside the window openings, through the face thickness, and points
``COLL_FRONT_REACH_MM`` above the front face within ``COLL_FRONT_BAND_MM`` of a window). Touching
pieces are then merged greedily while the merged hull passes the same test. The pad, barrel and
flanges are hulls of annular sectors. Bolt holes are filled (conservative; no tool goes
there); the bore stays open.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.hub.outline import Window, densify
from drakedeburr.hub.solid import PlateGeometry, mesh_arrays, plate_manifold, rings, tube
from drakedeburr.hub.spec import HubSpec

__all__ = ["WindowProbes", "collision_pieces", "window_intrusion", "COLL_CELL_MM",
           "COLL_TOL_MM", "COLL_WINDOW_REACH_MM", "COLL_SAG_MM", "COLL_FRONT_REACH_MM",
           "COLL_FRONT_BAND_MM", "MIN_CELL_MM", "front_probes"]

COLL_CELL_MM = 60.0  # initial quadtree cell of the plate's collision pieces [mm]
COLL_TOL_MM = 1.0  # allowed average extra thickness of a plate hull [mm]
COLL_WINDOW_REACH_MM = 0.5  # a hull may reach at most this far into a window opening [mm]
COLL_SAG_MM = 0.5  # chord sag of the rim's and pad's annular-sector pieces [mm]
#: a plate hull may stand at most this far proud of the front face (normal to it) within
#: COLL_FRONT_BAND_MM of a window, where the burr, its shank and the collet work [mm]
COLL_FRONT_REACH_MM = 1.0
COLL_FRONT_BAND_MM = 30.0
MIN_CELL_MM = 2.5  # smallest quadtree cell [mm]

Progress = Callable[[int, int, str], None] | None


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
        out.append(mesh_arrays(Manifold.hull_points(pts))[0])
    return out


class WindowProbes:
    """Points just inside the window openings [mm]: a collision hull containing one reaches
    more than ``COLL_WINDOW_REACH_MM`` into an opening."""

    def __init__(self, pts: np.ndarray):
        self.pts = np.asarray(pts, float)
        # sorted along x so a hull's bounding box selects its candidates by bisection
        self._order = np.argsort(self.pts[:, 0], kind="stable") if len(self.pts) else \
            np.zeros(0, np.int64)
        self._x = self.pts[self._order, 0] if len(self.pts) else np.zeros(0)

    @classmethod
    def from_spec(cls, spec: HubSpec, windows: list[Window],
                  geom: PlateGeometry | None = None) -> WindowProbes:
        """Probes ``COLL_WINDOW_REACH_MM`` off each wall at six depths through the face (off
        the drafted wall at that depth)."""
        from drakedeburr.hub.solid import plate_geometry

        geom = geom or plate_geometry(spec, windows)
        surf = geom.surface
        tan_d = math.tan(spec.wall_draft)
        pts = []
        t = spec.face_thickness * 1e3
        for w in windows:
            p = densify(w.poly_mm, 1.0)
            seg = np.roll(p, -1, axis=0) - p
            seg /= np.linalg.norm(seg, axis=1, keepdims=True)
            nrm = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
            nrm = nrm + np.roll(nrm, 1, axis=0)
            nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
            q = p + COLL_WINDOW_REACH_MM * nrm
            z = surf.front(q)
            for f in np.linspace(0.02, 0.98, 6):
                if tan_d:
                    qd = q + (f * t * tan_d) * nrm
                    pts.append(np.column_stack([qd, surf.front(qd) - f * t]))
                else:
                    pts.append(np.column_stack([q, z - f * t]))
        return cls(np.concatenate(pts))

    def inside(self, hull_pts: np.ndarray, equations: np.ndarray | None = None) -> np.ndarray:
        """Indices of the probes inside the convex hull of ``hull_pts`` (its half-space
        ``equations`` (F, 4) when already known)."""
        from scipy.spatial import ConvexHull

        lo, hi = hull_pts.min(axis=0), hull_pts.max(axis=0)
        a = np.searchsorted(self._x, lo[0], side="left")
        b = np.searchsorted(self._x, hi[0], side="right")
        cand = self._order[a:b]
        box = np.all((self.pts[cand] >= lo) & (self.pts[cand] <= hi), axis=1)
        m = np.sort(cand[box])  # ascending, as a full scan would give them
        if not len(m):
            return m
        eq = ConvexHull(hull_pts).equations if equations is None else equations
        return m[np.all(self.pts[m] @ eq[:, :3].T + eq[:, 3] <= 0.0, axis=1)]

    def hit(self, hull_pts: np.ndarray, equations: np.ndarray | None = None) -> bool:
        return bool(len(self.inside(hull_pts, equations)))


def front_probes(spec: HubSpec, windows: list[Window], geom: PlateGeometry) -> np.ndarray:
    """Points ``COLL_FRONT_REACH_MM`` above the front face (normal to it) on rings 1 to
    ``COLL_FRONT_BAND_MM`` out from each window outline, 2 mm apart [mm]: a plate hull that
    contains one stands further proud of the face where the tool works. Without them the
    average-thickness rule lets a hull on a dished face bridge its curvature (by up to 3.9 mm
    seen 3 mm from a CL point), and the burr shank meets that phantom material in planning and
    verification (0.22 mm read where the true face is some 4 mm away)."""
    surf = geom.surface
    pts = []
    for w in windows:
        p = densify(w.poly_mm, 2.0)
        seg = np.roll(p, -1, axis=0) - p
        seg /= np.linalg.norm(seg, axis=1, keepdims=True)
        nrm = np.stack([-seg[:, 1], seg[:, 0]], axis=1)  # into the opening (CCW outline)
        nrm = nrm + np.roll(nrm, 1, axis=0)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        for off in np.geomspace(1.0, COLL_FRONT_BAND_MM, 10):
            q = p - off * nrm
            g = surf.gradient(q)
            lift = COLL_FRONT_REACH_MM * np.sqrt(1.0 + np.sum(g * g, axis=1))
            pts.append(np.column_stack([q, surf.front(q) + lift]))
    return np.concatenate(pts)


@dataclass
class Piece:
    pts: np.ndarray  # hull vertices [mm]
    vol: float  # volume of the material part(s) it covers [mm^3]
    hull_vol: float


def _piece_ok(pc: Piece, t: float, probes: tuple[WindowProbes, ...],
              equations: np.ndarray | None = None) -> bool:
    excess = (pc.hull_vol - pc.vol) / max(pc.vol / t, 1.0)
    return excess <= COLL_TOL_MM and not any(p.hit(pc.pts, equations) for p in probes)


def _quadtree_pieces(plate, t: float, probes: tuple[WindowProbes, ...],
                     progress: Progress) -> list[Piece]:
    """Hulls of the plate's parts in quadtree cells, split until each passes ``_piece_ok``."""
    from manifold3d import CrossSection

    bb = plate.bounding_box()
    z0, z1 = bb[2] - 1.0, bb[5] + 1.0
    half = max(abs(bb[0]), abs(bb[1]), abs(bb[3]), abs(bb[4])) + 1.0
    n0 = int(math.ceil(2 * half / COLL_CELL_MM))
    edge = 2 * half / n0
    stack = [(-half + i * edge, -half + j * edge, edge) for j in range(n0) for i in range(n0)]
    pieces: list[Piece] = []
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
            pc = Piece(mesh_arrays(hull)[0], vol, hull.volume())
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
    return pieces


def merge_pieces(pieces: list[Piece], t: float,
                  probes: tuple[WindowProbes, ...]) -> list[Piece]:
    """Greedy merge of touching pieces while the merged hull passes ``_piece_ok``."""
    from scipy.spatial import ConvexHull

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
                pc = Piece(pts[hull.vertices], pieces[i].vol + pieces[j].vol, hull.volume)
                if _piece_ok(pc, t, probes, hull.equations):
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
    return pieces


def collision_pieces(spec: HubSpec, windows: list[Window], geom: PlateGeometry,
                     progress: Progress = None) -> list[np.ndarray]:
    """Convex pieces (hull vertex arrays [mm]) covering the hub: plate by quadtree + merging,
    pad and rim by construction (annular sectors). Bolt holes are filled; the bore is open."""
    bore_r = 0.5 * spec.center_bore_diameter * 1e3
    plate = plate_manifold(spec, windows, geom) - tube(0.0, bore_r, -1e3, 1e3)
    probes = (WindowProbes.from_spec(spec, windows, geom),
              WindowProbes(front_probes(spec, windows, geom)))
    t = spec.face_thickness * 1e3
    pieces = [p.pts for p in merge_pieces(_quadtree_pieces(plate, t, probes, progress), t,
                                           probes)]
    pad, rims = rings(spec)
    if pad is not None:
        pieces += _sector_hulls(bore_r, *pad, COLL_SAG_MM, spec.spoke_phase)
    for ring in rims:
        pieces += _sector_hulls(*ring, COLL_SAG_MM, 0.0)
    return pieces


def _hull_equations(V: np.ndarray) -> np.ndarray:
    from scipy.spatial import ConvexHull

    return ConvexHull(V).equations  # (F, 4): n.x + d <= 0 inside


def window_intrusion(loops: list[dict], piece_vertices: list[np.ndarray],
                     face_thickness: float, keep=None, drift: float = 0.0) -> float:
    """Largest distance [m] from the window wall into the opening that a piece reaches.

    Probes: each edge point moved into the opening by s along n_wall, at 5 depths through the
    face thickness; the largest s of a probe inside any piece is returned (0 if none).

    Args:
        loops: per window a mapping with ``p_HE`` and ``n_wall_H`` (N, 3) in H [m].
        piece_vertices: convex pieces, each (M, 3) hull vertices in H [m].
        face_thickness: depth [m] below the edge (along -Z_H) that the probes span.
        keep: optional callable (K, 3) probes -> (K,) bool: which probes really lie in the
            opening (for a mesh whose walls are not parallel to the axis); default all.
        drift: the wall moves this far into the opening per unit depth (tan of a draft
            angle): the probes at depth d start d * drift off the edge point [-].
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
            if drift:
                nh = n * [1.0, 1.0, 0.0]
                nh /= np.linalg.norm(nh, axis=1, keepdims=True)
                q = np.concatenate([p + s * n + d * drift * nh - np.array([0, 0, d])
                                    for d in depths])
            else:
                q = np.concatenate([p + s * n - np.array([0, 0, d]) for d in depths])
            if keep is not None:
                q = q[keep(q)]
            if _any_inside(q, eqs, lo, hi):
                worst = s
                break
    return float(worst)


def _any_inside(q: np.ndarray, eqs, lo, hi) -> bool:
    for e, a, b in zip(eqs, lo, hi, strict=True):
        m = np.all((q >= a - 1e-9) & (q <= b + 1e-9), axis=1)
        if m.any() and np.all(q[m] @ e[:, :3].T + e[:, 3] <= -1e-7, axis=1).any():
            return True
    return False
