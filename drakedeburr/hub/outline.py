"""2-D window outlines of a parametric hub (plan view, millimetres inside this module).

The annulus between the window radii minus the spoke bands (manifold3d ``CrossSection``); each
connected part is one window. Convex corners are rounded by an opening (offset -f, then +f with
round joins: exact circular fillets), reflex corners by a closing with ``blend_radius``; arcs are
segmented at <= 2 um chord sag and <= 2 deg, straight stretches at <= 1 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.spec import HubSpec

__all__ = ["Window", "build_window_outlines", "window_center_xy", "inscribed_width",
           "segments_per_circle", "densify", "outline_normals",
           "ARC_SAG_MM", "ARC_MAX_STEP", "MAX_TURN", "LINE_STEP_MM"]

ARC_SAG_MM = 0.002  # chord sag of arcs in the window outlines [mm]
ARC_MAX_STEP = math.radians(2.0)  # and at most this angle per arc segment
MAX_TURN = math.radians(2.5)  # largest turn between consecutive outline segments
LINE_STEP_MM = 1.0  # max outline segment on straight stretches [mm]
SPOKE_OVERHANG_MM = 15.0  # spoke bands reach this far past the window annulus [mm]


@dataclass(frozen=True)
class Window:
    """One window's plan-view outline.

    Attributes:
        index: window number, CCW about +Z_H from +X_H.
        kind: "large" or "small".
        poly_mm: (N, 2) outline [mm], CCW (opening on the left); the sharp edge where the
            front face would meet the wall (before any edge round).
        fillet_mm: corner fillet radius [mm].
    """

    index: int
    kind: str
    poly_mm: np.ndarray
    fillet_mm: float


def segments_per_circle(radius_mm: float, sag_mm: float = ARC_SAG_MM) -> int:
    """Circular segments per full circle so that the chord sag is <= ``sag_mm``."""
    dtheta = min(2.0 * math.sqrt(2.0 * sag_mm / max(radius_mm, 1e-9)), ARC_MAX_STEP)
    return int(math.ceil(2.0 * math.pi / dtheta))


def densify(poly: np.ndarray, step: float) -> np.ndarray:
    """Insert collinear points so that no segment of the closed polygon exceeds ``step``."""
    nxt = np.roll(poly, -1, axis=0)
    n = np.maximum(1, np.ceil(np.linalg.norm(nxt - poly, axis=1) / step - 1e-9).astype(int))
    seg = np.repeat(np.arange(len(poly)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    t = ((np.arange(len(seg)) - start) / n[seg])[:, None]
    return poly[seg] + (nxt[seg] - poly[seg]) * t


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


def outline_normals(poly: np.ndarray) -> np.ndarray:
    """(N, 2) unit vertex normals of a CCW outline pointing to its left (into the opening):
    the mean of the two adjacent segment normals."""
    seg = np.roll(poly, -1, axis=0) - poly
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    seg_n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    vert_n = seg_n + np.roll(seg_n, 1, axis=0)
    return vert_n / np.linalg.norm(vert_n, axis=1, keepdims=True)


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


def _disc(center: np.ndarray, radius: float) -> np.ndarray:
    n = segments_per_circle(radius, 0.01)
    a = 2 * math.pi * np.arange(n) / n
    return center + radius * np.column_stack([np.cos(a), np.sin(a)])


def _forked_arms(spec: HubSpec, th: float, r_split: float, r_out: float, w_out: float,
                 ext: float) -> list[np.ndarray]:
    """The two arms of a split (Y: to +-split_angle at r_out) or twin spoke (parallel arms
    ``twin_gap`` apart after a short fork) [mm]."""
    u = np.array([math.cos(th), math.sin(th)])
    v = np.array([-u[1], u[0]])
    a = u * r_split
    polys = []
    for sgn in (-1.0, 1.0):
        if spec.spoke_style == "split":
            c = r_out * np.array([math.cos(th + sgn * spec.split_angle),
                                  math.sin(th + sgn * spec.split_angle)])
            d = (c - a) / np.linalg.norm(c - a)
            polys.append(_band(np.stack([a, c + d * ext]), np.array([w_out, w_out])))
        else:  # twin: a 45 deg fork, then parallel to the spoke axis
            off = 0.5 * (spec.twin_gap * 1e3 + w_out)
            b = a + u * off + sgn * off * v  # 45 deg fork
            c = (r_out + ext) * u + sgn * off * v
            polys.append(_band(np.stack([a, b]), np.array([w_out, w_out])))
            polys.append(_band(np.stack([b, c]), np.array([w_out, w_out])))
            polys.append(_disc(b, 0.5 * w_out))
    return polys


def _spoke_polygons(spec: HubSpec) -> list[np.ndarray]:
    """Spoke bands in mm (they overhang the window annulus on both sides)."""
    r_in, r_out = spec.window_inner_radius * 1e3, spec.window_outer_radius * 1e3
    ext = SPOKE_OVERHANG_MM
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
        else:  # split / twin: a stem and two arms
            u = np.array([math.cos(th), math.sin(th)])
            r_split = spec.split_radius * 1e3
            stem = np.stack([u * (r_in - ext), u * (r_split + 0.5 * w_out)])
            polys.append(_band(stem, np.array([w_in, w_in])))
            polys.extend(_forked_arms(spec, th, r_split, r_out, w_out, ext))
    return polys


def _round_window(spec: HubSpec, comp, kind: str, f: float):
    """Opening (fillets) then closing (reflex blends) of one raw window; one polygon [mm]."""
    from manifold3d import JoinType

    seg = segments_per_circle(f)
    field = "fillet_radius_small" if kind == "small" else "fillet_radius"
    opened = comp.offset(-f, JoinType.Round, 2.0, seg)
    if opened.is_empty():
        raise InputError(f"hub {spec.name!r}: field {field!r}: fillet {f:.1f} mm is larger "
                         f"than a {kind} window can hold")
    opened = opened.offset(f, JoinType.Round, 2.0, seg)
    # closing rounds the reflex corners that the opening keeps (e.g. where a curved spoke's
    # side meets the fillet), so the whole edge is tangent-continuous
    c = min(f, spec.blend_radius * 1e3)
    opened = opened.offset(c, JoinType.Round, 2.0, segments_per_circle(c)).offset(
        -c, JoinType.Round, 2.0, segments_per_circle(c))
    polys = opened.to_polygons()
    if len(polys) != 1:
        raise InputError(f"hub {spec.name!r}: field {field!r}: rounding a {kind} window "
                         f"splits it into {len(polys)} parts")
    poly = _dedupe(np.asarray(polys[0], float))
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1)
                        - np.roll(poly[:, 0], -1) * poly[:, 1])
    return poly[::-1] if area < 0 else poly


def _start_and_check(spec: HubSpec, poly: np.ndarray) -> np.ndarray:
    """Start the loop at its outermost point (deterministic, independent of Clipper's start
    vertex) and refuse a corner sharper than ``MAX_TURN``."""
    c = poly.mean(axis=0)
    radial = c / np.linalg.norm(c)
    start = int(np.argmax((poly - c) @ radial))
    poly = np.roll(poly, -start, axis=0)
    seg_v = np.roll(poly, -1, axis=0) - poly
    heading = np.arctan2(seg_v[:, 1], seg_v[:, 0])
    turn = np.abs((np.roll(heading, -1) - heading + np.pi) % (2 * np.pi) - np.pi)
    if turn.max() > MAX_TURN:
        raise RuntimeError(f"hub {spec.name!r}: window outline has a corner of "
                           f"{math.degrees(turn.max()):.1f} deg at "
                           f"{poly[int(np.argmax(turn)) + 1]} mm")
    return poly


def build_window_outlines(spec: HubSpec) -> list[Window]:
    """The windows' 2-D outlines [mm], CCW, sorted CCW about +Z from +X; validated."""
    from manifold3d import CrossSection

    r_in, r_out = spec.window_inner_radius * 1e3, spec.window_outer_radius * 1e3
    annulus = (CrossSection.circle(r_out, segments_per_circle(r_out))
               - CrossSection.circle(r_in, segments_per_circle(r_in)))
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
        kind = "small" if spec.spoke_style in ("split", "twin") and frac < 0.25 else "large"
        f = (spec.fillet_radius_small if kind == "small" else spec.fillet_radius) * 1e3
        poly = _start_and_check(spec, _round_window(spec, comp, kind, f))
        c = poly.mean(axis=0)
        windows.append((math.atan2(c[1], c[0]) % (2 * math.pi), kind,
                        densify(poly, LINE_STEP_MM), f))
    windows.sort(key=lambda w: w[0])
    return [Window(i, kind, poly, f) for i, (_, kind, poly, f) in enumerate(windows)]


def window_center_xy(poly_xy: np.ndarray, grid: int = 80) -> np.ndarray:
    """The point inside a closed 2-D polygon (N, 2) farthest from its boundary (grid search)."""
    from matplotlib.path import Path as MplPath
    from scipy.spatial import cKDTree

    lo, hi = poly_xy.min(axis=0), poly_xy.max(axis=0)
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], grid), np.linspace(lo[1], hi[1], grid))
    cand = np.column_stack([gx.ravel(), gy.ravel()])
    inside = MplPath(poly_xy).contains_points(cand)
    cand = cand[inside]
    d, _ = cKDTree(densify(poly_xy, (hi - lo).max() / 400)).query(cand)
    return cand[int(np.argmax(d))]


def _distance_to_outline(q: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """(K,) distance of points q (K, 2) to the closed polyline ``poly`` (N, 2)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty(len(q))
    for s in range(0, len(q), 256):
        d = q[s:s + 256, None, :] - a[None]
        t = np.clip(np.einsum("kij,ij->ki", d, ab) / L2, 0.0, 1.0)
        out[s:s + 256] = np.linalg.norm(d - t[..., None] * ab[None], axis=2).min(axis=1)
    return out


def inscribed_width(poly_xy: np.ndarray, cells: int = 64) -> float:
    """Diameter of the largest circle inside a closed 2-D polygon (N, 2), same unit: the
    window's width for a tool that must pass it. A distance transform of a raster of
    ``cells`` across (scipy.ndimage) finds the centre, exact point-to-outline distances on a
    local grid around it refine the radius."""
    from matplotlib.path import Path as MplPath
    from scipy import ndimage

    lo, hi = poly_xy.min(axis=0), poly_xy.max(axis=0)
    h = float((hi - lo).max()) / cells
    gx = np.arange(lo[0] - h, hi[0] + 2 * h, h)
    gy = np.arange(lo[1] - h, hi[1] + 2 * h, h)
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    path = MplPath(poly_xy)
    mask = path.contains_points(np.column_stack([X.ravel(), Y.ravel()])).reshape(X.shape)
    if not mask.any():
        return 0.0
    edt = ndimage.distance_transform_edt(mask)
    i, j = np.unravel_index(int(np.argmax(edt)), mask.shape)
    best, centre = 0.0, np.array([gx[i], gy[j]])
    for step in (h, 0.25 * h, 0.0625 * h):
        g = np.linspace(-2 * step, 2 * step, 9)
        cand = centre + np.array(np.meshgrid(g, g)).reshape(2, -1).T
        cand = cand[path.contains_points(cand)]
        if not len(cand):
            break
        d = _distance_to_outline(cand, poly_xy)
        k = int(np.argmax(d))
        if d[k] > best:
            best, centre = float(d[k]), cand[k]
    return 2.0 * best
