"""The deburring edge of one window, read off any hub mesh by ray casts from the front.

**Which line is deburred.** The edge where the front face ends at a window: on a sharp edge
the crease between face and wall; on a rounded or chamfered edge the line where the face
surface meets the round or chamfer (its face-side tangent line). This is the line the
generator stores as ground truth (``drakedeburr.hub.surface``) and the one extracted here, the
same way on every mesh.

**How.** The opening's plan-view outline (the boundary of the misses of rays along -Z_H,
refined by bisection) is walked outward, away from the opening, along its 2-D normal; rays
along -Z_H at ``step`` spacing sample the surface seen from the front: height z(s) and facet
normal n(s). From the outline outward a profile crosses, in this order: what is seen through
the opening's wider front part (a drafted wall, anything below), the edge band (round,
chamfer), then the face. A sample belongs to the face when its normal is less than
``WALL_ANGLE`` off the axis (walls are steeper) and it is not on a drafted flank (more than
``FLANK_ANGLE`` off the axis with the surface climbing by more than ``FLANK_RISE`` before it
turns gentler than that: a wall of the opening seen from the front, whose top is the front
boundary; a real rim's spoke flanks are drafted 12-14 deg, 76-78 deg off the axis), does not
differ by more than
``BAND_ANGLE`` from the normal ``lag`` further out where that one faces the front more or
the normal turns right here, within a quarter ``lag`` (the band turns faster, up into the
face; a flat stretch before a surface turning away is face before a crease, not the band),
and the profile
does not jump there (a step of more than ``JUMP`` between samples is a wall hidden from the
front). The edge point is the first sample of the first run of ``run`` face samples, unless
the profile steps *up* within ``ledge`` after it (a ledge inside the opening, seen through its
wider front part): then the first run after that step. It then steps on by up to
``REFINE_LENGTH`` (and sin(BAND_ANGLE) x the band's width) while the surface still turns
toward the front by more than ``FACE_ANGLE`` over ``lag`` (the BAND_ANGLE test stops
R sin(BAND_ANGLE) inside a round of radius R). A
profile goes ``FAR_REACH`` times ``reach`` out (a 40 mm tall drafted flank's top lies 10-12 mm
out); nearly every profile finds its face within the first millimetres.

**Noise.** A profile reads the face start on its own 0.1 mm grid from the facets of a
tessellated round, so neighbouring profiles can disagree by a facet. The band width (outline to
edge) is therefore filtered along the loop, a running median then a Gaussian of about a
millimetre, and the face read again there (:func:`_smoothed_edge`); the true band of a round or
chamfer changes over millimetres, not between profiles 0.5 mm apart.

**Where the edge leaves the face** (real wheels: the front boundary runs along the spoke face,
turns down a spoke flank, along the rim's lip): neighbouring edge points then differ in height
by more than their plan-view distance. Such a stretch is not an error: the points between them
are filled in along the straight segment and moved onto the nearest mesh surface
(:func:`_bridge`), so the loop follows the flank. A profile that finds no face within its length
takes the band of its neighbours (periodic interpolation along the loop) and reads the surface
there, or the outline point itself (where the surface seen from the front ends).

**Rejections** are only those a person looking at the model would accept, each naming where:
no front boundary (no profile found a front-visible surface), not closed (a filled stretch
keeps a gap wider than ``MAX_BRIDGE_GAP`` with no surface in it: a hole or a seam), or
self-intersecting (two stretches of the loop cross in plan view at the same height, within
``CROSS_DZ``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["EdgeLine", "opening_outline", "deburr_line", "BAND_ANGLE", "WALL_ANGLE"]

BAND_ANGLE = math.radians(8.0)  # a round/chamfer band turns more than this per lag
FACE_ANGLE = math.radians(1.5)  # past the band test, a surface still turning this much per
#                                 lag toward the front is the round's last facets
REFINE_LENGTH = 0.3e-3  # [m] how far the face start moves on by FACE_ANGLE
WALL_ANGLE = math.radians(80.0)  # surfaces steeper than this (off the axis) are walls
FLANK_ANGLE = math.radians(60.0)  # steeper (off the axis) and climbing FLANK_RISE: a flank
FLANK_RISE = 3e-3  # [m] a flank's climb to the next gentle sample that makes it a wall
FAR_REACH = 3.0  # a profile walks this many times its `reach` out (module doc)
JUMP = 0.8e-3  # [m] height step between two samples (0.1 mm apart) that is a hidden wall
MAX_BRIDGE_GAP = 10e-3  # [m] a gap this wide left in a filled stretch: the loop is not closed
CROSS_DZ = 1e-3  # [m] plan-view crossings closer than this in height are self-intersections
SWALLOWTAIL = 0.05  # a crossing cutting off at most this share of the loop is cut out
BAND_MEDIAN = 2.5e-3  # [m] running median of the band width along the loop ("Noise")
BAND_SIGMA = 1.0e-3  # [m] Gaussian smoothing of the band width along the loop ("Noise")


@dataclass(frozen=True, eq=False)
class EdgeLine:
    """The deburring edge of one opening, or why there is none.

    Attributes:
        p_H: (N, 3) edge points in H [m] (outline order, CCW seen from +Z_H), or None.
        band: (N,) distance [m] in plan view from the opening's outline to the edge point.
        outline_xy: (M, 2) the opening's refined outline [m].
        reason: "" or why the loop was rejected.
        figures: length [m], outline length [m], largest step [m], warp [m], missing share.
    """

    p_H: np.ndarray | None
    band: np.ndarray | None
    outline_xy: np.ndarray
    reason: str
    figures: dict


def _cast(scene, xy: np.ndarray, z0: float):
    import open3d as o3d

    r = np.zeros((len(xy), 6), np.float32)
    r[:, :2], r[:, 2], r[:, 5] = xy, z0, -1.0
    ans = scene.cast_rays(o3d.core.Tensor(r))
    return ans["t_hit"].numpy().astype(float), ans["primitive_normals"].numpy().astype(float)


def _area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _resample2(xy: np.ndarray, spacing: float) -> np.ndarray:
    q = np.vstack([xy, xy[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    n = max(16, int(round(s[-1] / spacing)))
    t = np.linspace(0.0, s[-1], n, endpoint=False)
    return np.column_stack([np.interp(t, s, q[:, 0]), np.interp(t, s, q[:, 1])])


def opening_outline(scene, mask: np.ndarray, grid: np.ndarray, pixel: float, z0: float,
                    spacing: float) -> np.ndarray:
    """(M, 2) outline of one opening in H [m], CCW, at ``spacing``, refined to ~1e-3 of a
    grid cell by bisection with rays along its normal (hit = material)."""
    import contourpy

    lines = contourpy.contour_generator(z=np.pad(mask.astype(float), 1)).lines(0.5)
    line = max(lines, key=len)
    ax = np.arange(len(grid))
    xy = np.c_[np.interp(line[:, 1] - 1, ax, grid), np.interp(line[:, 0] - 1, ax, grid)]
    if np.linalg.norm(xy[0] - xy[-1]) < 1e-12:
        xy = xy[:-1]
    if _area(xy) < 0:
        xy = xy[::-1]
    xy = _resample2(xy, spacing)
    out = _outward(xy)
    lo = np.full(len(xy), -2.0 * pixel)  # in the opening (miss)
    hi = np.full(len(xy), 2.0 * pixel)  # on material (hit)
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        h = np.isfinite(_cast(scene, xy + mid[:, None] * out, z0)[0])
        hi = np.where(h, mid, hi)
        lo = np.where(h, lo, mid)
    return xy + hi[:, None] * out


def _outward(xy: np.ndarray) -> np.ndarray:
    """Unit 2-D normals of a CCW outline pointing out of the opening (to its right)."""
    tang = np.roll(xy, -1, axis=0) - np.roll(xy, 1, axis=0)
    out = np.c_[tang[:, 1], -tang[:, 0]]
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _shifted(a: np.ndarray, k: int) -> np.ndarray:
    """a[:, j + k] along axis 1 (k < 0: behind), the end values repeated past the ends."""
    if k >= 0:
        return np.concatenate([a[:, k:], np.repeat(a[:, -1:], k, axis=1)], axis=1)
    return np.concatenate([np.repeat(a[:, :1], -k, axis=1), a[:, :k]], axis=1)


def _face_start(t: np.ndarray, n: np.ndarray, z0: float, step: float, lag: int,
                run: int, ledge: int, refine: int = 0) -> np.ndarray:
    """Per profile (rows) the index of the edge sample, or -1 (module doc).

    Args:
        t: (P, K) ray hit distances (inf: miss); n: (P, K, 3) facet normals.
        ledge: a face stretch followed within this many samples by a step *up* is a ledge
            inside the opening (seen through its wider front part): the edge is further out.
    """
    z = z0 - t
    hit = np.isfinite(t)
    steep = np.abs(n[..., 2]) < math.cos(WALL_ANGLE)
    # a drafted flank (FLANK_ANGLE..WALL_ANGLE off the axis) that the surface climbs by more
    # than FLANK_RISE before it turns gentle is a wall seen from the front, not the face: the
    # front boundary is the crease at its top (on the audibot rim the 14 deg draft of the
    # spoke flanks put 36-52 % of each loop at their foot, 25-47 mm below the spoke face). The
    # steep part of an edge round rises by far less than that to the face.
    gentle = hit & (np.abs(n[..., 2]) >= math.cos(FLANK_ANGLE))
    K = t.shape[1]
    nxt = np.minimum.accumulate(np.where(gentle, np.arange(K), K)[:, ::-1], axis=1)[:, ::-1]
    z_next = np.take_along_axis(np.where(hit, z, -np.inf), np.minimum(nxt, K - 1), axis=1)
    with np.errstate(invalid="ignore"):  # misses: -inf - -inf, masked by `hit`
        steep |= hit & ~gentle & (nxt < K) & (z_next - z > FLANK_RISE)
    # the band: the normal turns by more than BAND_ANGLE over `lag` samples (facets of a
    # non-watertight mesh may face either way: compare |n . n'|), toward the front or here.
    # A convex round or chamfer turns from the wall up into the face: the surface `lag` further
    # out faces the front at least as much, or (a round running into a concave face) the
    # normal turns right here, within a quarter lag. A flat stretch whose surface turns away
    # from the front only further out has crossed the band and meets a crease beyond the face
    # (the disc face of a CAD wheel is a 1.8 mm strip between a window's round and a 31 deg
    # slope: read as band, the edge went past the crease, 1.9 mm off)
    ahead, hit_ahead = _shifted(n, lag), _shifted(hit, lag)
    toward_front = ~hit_ahead | (np.abs(ahead[..., 2]) >= np.abs(n[..., 2]))
    m = max(1, lag // 4)
    here = ((np.abs(np.einsum("pkd,pkd->pk", n, _shifted(n, m))) < math.cos(FACE_ANGLE))
            | (np.abs(np.einsum("pkd,pkd->pk", n, _shifted(n, -m))) < math.cos(FACE_ANGLE)))
    turning = ((np.abs(np.einsum("pkd,pkd->pk", n, ahead)) < math.cos(BAND_ANGLE))
               & (toward_front | here))
    with np.errstate(invalid="ignore"):  # between two misses: nan, never a jump
        dz = np.diff(z, axis=1, prepend=z[:, :1])
    jump_tol = JUMP * step / 1e-4
    up = hit & (dz > jump_tol)
    face = hit & ~steep & ~turning & ~(np.abs(dz) > jump_tol)
    face[:, -lag:] = False
    win = np.lib.stride_tricks.sliding_window_view(face, run, axis=1).all(axis=2)
    K = win.shape[1]
    cols = np.arange(K)
    first = np.where(win.any(axis=1), np.argmax(win, axis=1), -1)
    for _ in range(4):  # move past ledges (a step up shortly after the chosen stretch)
        lo = first[:, None]
        near_up = up[:, :K] & (cols > lo) & (cols <= lo + ledge) & (lo >= 0)
        if not near_up.any():
            break
        last_up = np.where(near_up.any(axis=1), K - 1 - np.argmax(near_up[:, ::-1], axis=1), -1)
        moved = last_up >= 0
        later = win & (cols >= last_up[:, None])
        first = np.where(moved, np.where(later.any(axis=1), np.argmax(later, axis=1), -1), first)
    # the band test stops where the round is within BAND_ANGLE of the face: R sin(BAND_ANGLE)
    # before its face-side line (0.14 mm on a 1 mm round, whose band reads about R wide). Step
    # on while the surface still turns toward the front by more than FACE_ANGLE over `lag`, by
    # at most sin(BAND_ANGLE) x the band's width read before the face start (the round's own
    # error: a convex face beyond the round turns toward the front too; the random catalogue's
    # loops moved 0.10-0.15 -> 0.14-0.22 mm from the generator's with the step, the CAD
    # wheel's fine STL 0.189 -> 0.103 mm from its B-rep edges) and at most `refine` samples
    settling = (np.abs(np.einsum("pkd,pkd->pk", n, ahead)) < math.cos(FACE_ANGLE)) \
        & toward_front & face
    rows = np.arange(len(first))
    k = np.arange(turning.shape[1])
    last_flat = np.maximum.accumulate(np.where(turning, -1, k), axis=1)  # last non-band index
    band = np.where(first > 0, first - 1 - last_flat[rows, np.maximum(first - 1, 0)], 0)
    cap = np.minimum(np.ceil(band * math.sin(BAND_ANGLE)), refine)
    for j in range(refine):
        step_on = (first >= 0) & (j < cap) & settling[rows, np.maximum(first, 0)]
        if not step_on.any():
            break
        first = np.where(step_on, first + 1, first)
    return first


def deburr_line(scene, outline_xy: np.ndarray, z0: float, *, step: float = 0.1e-3,
                reach: float = 10e-3, lag_length: float = 1.0e-3,
                run_length: float = 1.0e-3, ledge_length: float = 5.0e-3) -> EdgeLine:
    """The deburring edge beside one opening's outline (module doc).

    Args:
        scene: open3d RaycastingScene of the mesh in H [m].
        outline_xy: (M, 2) refined CCW outline of the opening [m].
        z0: ray origin height above the mesh [m].
        step: profile sample spacing [m]; reach: how far out the profile goes, times
            ``FAR_REACH`` [m].
        lag_length: the band test compares normals this far apart [m].
        run_length: the face must continue this far past the edge point [m].
        ledge_length: a face stretch this close before a step up is a ledge [m].
    """
    out = _outward(outline_xy)
    lag, run = max(1, int(round(lag_length / step))), max(2, int(round(run_length / step)))
    xy, t, first = _profiles(scene, outline_xy, out, z0, step, reach,
                             (lag, run, int(round(ledge_length / step)),
                              int(round(REFINE_LENGTH / step))))
    s = 0.02e-3 + np.arange(xy.shape[1]) * step
    P = len(outline_xy)
    ok = first >= 0
    figures = {"outline_length": float(np.linalg.norm(
        np.roll(outline_xy, -1, axis=0) - outline_xy, axis=1).sum()),
        "missing": float(1.0 - ok.mean())}
    band = np.full(P, np.nan)
    if ok.sum() < max(4, P // 20):
        c = outline_xy.mean(axis=0)
        return EdgeLine(None, band, outline_xy,
                        f"no front boundary: no surface seen from the front within "
                        f"{FAR_REACH * reach * 1e3:.0f} mm of the opening's outline (around "
                        f"({c[0] * 1e3:.0f}, {c[1] * 1e3:.0f}) mm)", figures)
    rows = np.flatnonzero(ok)
    band[rows] = s[first[ok]]
    p_rows = np.column_stack([xy[rows, first[ok]], z0 - t[rows, first[ok]]])
    if len(rows) >= 16:
        p_rows = _smoothed_edge(scene, p_rows, outline_xy[rows], out[rows], band[rows], z0,
                                step)
    p = np.full((P, 3), np.nan)
    p[rows] = p_rows
    if not ok.all():
        p = _fill_missing(scene, p, band, ok, outline_xy, out, z0)
    p, gap = _bridge(scene, p, float(np.median(np.linalg.norm(
        np.diff(outline_xy, axis=0), axis=1))))
    figures["largest_bridge_gap"] = gap[0]
    p = _forward_only(p, outline_xy)
    p, crossings = _untangle(p)
    reason = _implausible(p, figures, gap, crossings)
    return EdgeLine(None if reason else p, band, outline_xy, reason, figures)


def _profiles(scene, outline_xy: np.ndarray, out: np.ndarray, z0: float, step: float,
              reach: float, samples: tuple[int, int, int, int]):
    """The profiles and their face starts (module doc), ``FAR_REACH`` times ``reach`` long
    (``samples``: the band lag, face run, ledge and refinement of :func:`_face_start` in
    samples):
    a drafted flank's top (where the flank rule of :func:`_face_start` needs to see the
    gentle surface) can lie further out than ``reach`` (mkz13 rim: 39 mm tall flanks 78 deg
    off the axis reach 10.5-12 mm out).

    Returns:
        xy (P, K, 2) sample points, t (P, K) hit distances, first (P,) face-start index or -1.
    """
    P = len(outline_xy)
    s = 0.02e-3 + np.arange(int(round(FAR_REACH * reach / step)) + 1) * step
    xy = outline_xy[:, None, :] + s[None, :, None] * out[:, None, :]
    t, n = _cast(scene, xy.reshape(-1, 2), z0)
    t, n = t.reshape(P, len(s)), n.reshape(P, len(s), 3)
    return xy, t, _face_start(t, n, z0, step, *samples)


def _fill_missing(scene, p: np.ndarray, band: np.ndarray, ok: np.ndarray,
                  outline_xy: np.ndarray, out: np.ndarray, z0: float) -> np.ndarray:
    """Edge points of the profiles without a face (module doc): the band of the neighbours
    (periodic interpolation along the loop), read on the surface there; where that ray misses,
    the outline point (a ray just outside the opening)."""
    P = len(p)
    idx = np.arange(P)
    rows = np.flatnonzero(ok)
    b = np.interp(idx, rows, band[rows], period=P)
    miss = np.flatnonzero(~ok)
    q = p.copy()
    for bb in (b[miss], np.full(len(miss), 0.02e-3)):
        xy = outline_xy[miss] + bb[:, None] * out[miss]
        t, _ = _cast(scene, xy, z0)
        hit = np.isfinite(t)
        q[miss[hit]] = np.column_stack([xy[hit], z0 - t[hit]])
        miss = miss[~hit]
        if not len(miss):
            break
    # still nothing under the outline (a gap in an open mesh): neighbours' heights
    if len(miss):
        have = np.flatnonzero(np.isfinite(q[:, 2]))
        xy = outline_xy[miss] + b[miss, None] * out[miss]
        q[miss] = np.column_stack([xy, np.interp(miss, have, q[have, 2], period=P)])
    return q


def _bridge(scene, p: np.ndarray, spacing: float) -> tuple[np.ndarray, tuple]:
    """Fill the stretches where the loop leaves the face (module doc): between neighbours
    more than 2 ``spacing`` apart in 3-D, points every ``spacing`` on the segment, moved to
    the nearest point of the mesh (open3d ``compute_closest_points``); where two of those
    land far apart (on two surfaces), the same again between them (3 levels).

    Returns:
        (M, 3) the loop with the filled points; (the largest distance [m] left between
        neighbours of a filled stretch, its midpoint (3,) in H or None).
    """
    import open3d as o3d

    def closest(q: np.ndarray) -> np.ndarray:
        res = scene.compute_closest_points(o3d.core.Tensor(q.astype(np.float32)))
        return res["points"].numpy().astype(float)

    def fill(a: np.ndarray, b: np.ndarray, depth: int) -> list[np.ndarray]:
        m = int(np.ceil(np.linalg.norm(b - a) / spacing)) - 1
        q = closest(a + (np.arange(1, m + 1) / (m + 1))[:, None] * (b - a))
        chain, out = np.vstack([a, q, b]), []
        for k in range(len(chain) - 1):
            out.append(chain[k:k + 1])
            if depth and np.linalg.norm(chain[k + 1] - chain[k]) > 2.0 * spacing:
                out += fill(chain[k], chain[k + 1], depth - 1)[1:]
        return out

    nxt = np.roll(p, -1, axis=0)
    far = np.linalg.norm(nxt - p, axis=1) > 2.0 * spacing
    if not far.any():
        return p, (0.0, None)
    parts, gap, where = [], 0.0, None
    for i in range(len(p)):
        if not far[i]:
            parts.append(p[i:i + 1])
            continue
        chain = np.concatenate(fill(p[i], nxt[i], 3) + [nxt[i][None]])
        d = np.linalg.norm(np.diff(chain, axis=0), axis=1)
        k = int(np.argmax(d))
        if d[k] > gap:
            gap, where = float(d[k]), 0.5 * (chain[k] + chain[k + 1])
        parts.append(chain[:-1])
    return np.concatenate(parts), (gap, where)


def _smoothed_edge(scene, p: np.ndarray, outline_xy: np.ndarray, out: np.ndarray,
                   band: np.ndarray, z0: float, step: float) -> np.ndarray:
    """The edge points with the band width filtered along the loop (module doc, "Noise").

    Each profile reads the face start on its own ``step`` grid, from the facets of a
    tessellated round: neighbouring profiles 0.5 mm apart can differ by a facet (0.1-0.3 mm)
    where the true band changes by microns, which zig-zags the loop (turns of 30-70 deg between
    0.5 mm chords on a real CAD export; the CL stage then follows the zig-zag with hundreds of
    points and the wrist with it). The band is filtered as a periodic signal along the loop:
    a running median over ``BAND_MEDIAN`` (drops single-profile jumps), then a Gaussian of
    ``BAND_SIGMA`` (averages the grid steps), both with scipy.ndimage. The face is then read
    again at the filtered band (a ray cast); a point whose ray misses, lands on a wall, or whose
    height differs from the raw one by more than the profile's hidden-wall step (``JUMP`` per
    0.1 mm moved) keeps its raw position.
    """
    from scipy.ndimage import gaussian_filter1d, median_filter

    spacing = float(np.median(np.linalg.norm(np.diff(outline_xy, axis=0), axis=1)))
    size = max(1, int(round(BAND_MEDIAN / spacing))) | 1
    b = median_filter(band, size=size, mode="wrap")
    b = gaussian_filter1d(b, BAND_SIGMA / spacing, mode="wrap")
    xy = outline_xy + b[:, None] * out
    t, n = _cast(scene, xy, z0)
    z = z0 - t
    # the profile's own tests over the distance moved: no hidden wall (JUMP per 0.1 mm), not
    # on a wall (facets of either winding: |n_z|)
    tol = JUMP * np.maximum(np.abs(b - band), step) / 1e-4
    keep = (np.isfinite(t) & (np.abs(z - p[:, 2]) <= tol)
            & (np.abs(n[:, 2]) >= math.cos(WALL_ANGLE)))
    q = p.copy()
    q[keep] = np.column_stack([xy[keep], z[keep]])
    return q


def _forward_only(p: np.ndarray, outline_xy: np.ndarray) -> np.ndarray:
    """The loop without its back-tracking spikes: each point's place along the opening's
    outline (the arc position of its nearest outline point, scipy cKDTree) must not go back
    by more than 1 mm from the furthest reached so far (a filled stretch snapped onto a wall
    beside a corner can run back and forth; a climb keeps its place). Points that go back
    are dropped; the loop keeps its order."""
    from scipy.spatial import cKDTree

    seg = np.linalg.norm(np.roll(outline_xy, -1, axis=0) - outline_xy, axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    L = float(seg.sum())
    pos = s[cKDTree(outline_xy).query(p[:, :2])[1]]
    pos = pos - pos[0]
    pos = np.where(pos < -0.5 * L, pos + L, pos)
    out = np.unwrap(pos * (2 * np.pi / L)) * (L / (2 * np.pi))
    keep = out >= np.maximum.accumulate(out) - 1e-3
    return p[keep] if keep.sum() >= 16 else p


def _crossings(p: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """Plan-view crossings of two non-neighbouring segments (i, i+1), (j, j+1), i < j, of the
    closed loop ``p`` (N, 3) whose heights there differ by less than ``CROSS_DZ`` (3-D
    self-intersections): [(i, j, (x, y, z) [m])]."""
    a, b = p, np.roll(p, -1, axis=0)
    n = len(p)
    lo, hi = np.minimum(a[:, :2], b[:, :2]), np.maximum(a[:, :2], b[:, :2])
    found = []
    for s0 in range(0, n, 512):  # blocks: (512, N) pair tests
        i = np.arange(s0, min(n, s0 + 512))
        cand = ((lo[i, None, 0] <= hi[None, :, 0]) & (lo[None, :, 0] <= hi[i, None, 0])
                & (lo[i, None, 1] <= hi[None, :, 1]) & (lo[None, :, 1] <= hi[i, None, 1]))
        gap = np.arange(n)[None, :] - i[:, None]
        cand &= (gap > 1) & ~((i[:, None] == 0) & (np.arange(n)[None, :] == n - 1))
        ii, jj = np.nonzero(cand)
        ii = i[ii]
        if not len(ii):
            continue
        d1, d2 = b[ii, :2] - a[ii, :2], b[jj, :2] - a[jj, :2]
        w = a[jj, :2] - a[ii, :2]
        den = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
        good = np.abs(den) > 1e-18
        den = np.where(good, den, 1.0)
        u = (w[:, 0] * d2[:, 1] - w[:, 1] * d2[:, 0]) / den
        v = (w[:, 0] * d1[:, 1] - w[:, 1] * d1[:, 0]) / den
        za = a[ii, 2] + u * (b[ii, 2] - a[ii, 2])
        zb = a[jj, 2] + v * (b[jj, 2] - a[jj, 2])
        hit = good & (u > 0) & (u < 1) & (v > 0) & (v < 1) & (np.abs(za - zb) < CROSS_DZ)
        found += [(int(ii[k]), int(jj[k]), np.r_[a[ii[k], :2] + u[k] * d1[k], za[k]])
                  for k in np.flatnonzero(hit)]
    return found


def _untangle(p: np.ndarray, max_share: float = SWALLOWTAIL) -> tuple[np.ndarray, list]:
    """The loop with its small self-intersection loops cut out (the "swallowtails" of an
    offset curve at a corner, where neighbouring profiles' face starts cross): a crossing
    whose smaller side holds at most ``max_share`` of the points is replaced by the crossing
    point. Returns the loop and the crossings left (the first of them names a real one)."""
    for _ in range(64):
        found = _crossings(p)
        if not found:
            return p, []
        n = len(p)
        small = [(min(j - i, n - (j - i)), i, j, x) for i, j, x in found]
        size, i, j, x = min(small, key=lambda t: t[0])
        if size > max_share * n:
            return p, found
        if j - i <= n - (j - i):
            p = np.vstack([p[:i + 1], x[None], p[j + 1:]])
        else:  # the small side runs over the seam
            p = np.vstack([x[None], p[i + 1:j + 1]])
    return p, _crossings(p)


def _implausible(p: np.ndarray, fig: dict, gap: tuple, crossings: list) -> str:
    """'' or why the loop is not a window's front boundary (module doc); fills ``fig``."""
    if len(p) < 16:
        return "no front boundary: fewer than 16 edge points"
    d = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    fig["length"] = float(d.sum())
    dz = np.abs(np.roll(p[:, 2], -1) - p[:, 2])
    fig["max_step"] = float(dz.max())
    fig["height_range"] = float(np.ptp(p[:, 2]))
    # where the loop climbs: stretches steeper than 60 deg to the face plane (their length)
    dzs = np.roll(p[:, 2], -1) - p[:, 2]
    steep = np.abs(dzs) > np.sin(np.radians(60.0)) * np.maximum(d, 1e-12)
    fig["steep_length"] = float(d[steep].sum())
    if gap[0] > MAX_BRIDGE_GAP:
        w = gap[1]
        return (f"not closed: at ({w[0] * 1e3:.0f}, {w[1] * 1e3:.0f}, {w[2] * 1e3:.0f}) mm "
                f"the front boundary has a {gap[0] * 1e3:.1f} mm gap with no surface in it "
                f"(a hole or a seam between parts of the mesh)")
    if crossings:
        x = crossings[0][2]
        return (f"self-intersecting: the loop crosses itself at ({x[0] * 1e3:.0f}, "
                f"{x[1] * 1e3:.0f}, {x[2] * 1e3:.0f}) mm")
    return ""
