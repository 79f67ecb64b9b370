"""Window edge loops from any hub mesh: closed or not, one part or many, mm or m.

Steps (each refusal raises an InputError that says which step and what was found):

1. Hub axis: given (``axis_M``) or the principal axis of the area-weighted surface whose
   moment differs most from the other two (a wheel is a body of revolution); a provisional
   origin on it at the surface centroid.
2. Front side (:mod:`drakedeburr.hub.front`): lug seats, barrel, mounting face and dish vote;
   the choice and its evidence are returned; ``front`` (a file axis such as "-y") or the
   sign of a given ``axis_M`` override it. H: +Z_H out of the front face, origin on the axis
   at the front-most point of the spoke region (``origin_M`` overrides), X_H = the mesh X axis
   projected (or Y when X is along the axis).
3. Openings (:mod:`drakedeburr.hub.openings`): plan-view rays along -Z_H; windows, centre
   bore, lug holes and openings no burr of the tool library fits (each burr's need: head +
   2 x clearance, the small burr tried before an opening is refused) are told apart, every
   opening that is not a window is reported with its reason and the measured width.
4. Edge of each window (:mod:`drakedeburr.hub.edgeline`): where the front face ends at the
   opening (the face side of a round or chamfer), by profiles of ray casts from the front,
   following the boundary where it leaves the face (down a spoke flank, along the rim's
   lip): a 3-D loop. It is rejected only when there is no front boundary, it is not closed
   or it intersects itself, and the reason says where.
5. Loops are oriented counter-clockwise seen from +Z_H, resampled at equal arc length
   (``spacing``, the source's "initial CL points") and numbered CCW from +X_H; ``t_H``
   holds chord tangents, the wall and face normals are left None (the importer reads them off
   the mesh; the frames stage estimates them from a scan).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import (
    InputError,
    NoCuttableWindow,
    describe_numerical_error,
    numerical_errors,
)
from drakedeburr.hub.front import FrontDecision, decide_front, front_from_user
from drakedeburr.hub.openings import OpeningSearch, find_openings
from drakedeburr.hub.types import WindowEdge

__all__ = ["HubFrameEstimate", "ExtractionResult", "extract_window_edges", "resample_loop",
           "hub_frame_from_mesh", "principal_axis", "frame_from_axis", "ray_scene"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class HubFrameEstimate:
    """X_MH: (4, 4) pose of hub frame H in the mesh frame M; ``estimated``: not given;
    ``front``: how the side of the axis was chosen (None when the axis was given)."""

    X_MH: np.ndarray
    estimated: bool
    front: FrontDecision | None = None


@dataclass(frozen=True, eq=False)
class ExtractionResult:
    """Windows found on a mesh.

    Attributes:
        windows: WindowEdge per window, in H [m], index CCW about +Z_H from +X_H.
        X_MH: (4, 4) hub frame in the mesh frame (metres).
        source: file or description.
        notes: what was detected for reports: ``axis_estimated``, ``front`` (decided_by,
            evidence), ``not_windows`` (openings that are no window, with reasons),
            ``rejected`` (openings whose edge loop was implausible, with reasons),
            ``min_window_width_mm``, ``watertight``, per window ``loops`` figures.
        outlines_xy: per window (M, 2) its opening's outline in the plan view of H [m], CCW:
            the narrowest section of the opening (where the walls are innermost).
    """

    windows: list[WindowEdge]
    X_MH: np.ndarray
    source: str = ""
    notes: dict = field(default_factory=dict)
    outlines_xy: list[np.ndarray] = field(default_factory=list)


def principal_axis(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(axis (3,), centroid (3,)) in M: the axis of the area-weighted surface's second moment
    that differs most from the other two (its sign is arbitrary)."""
    c = mesh.triangles_center
    w = mesh.area_faces
    centroid = (c * w[:, None]).sum(0) / w.sum()
    d = c - centroid
    cov = (d * w[:, None]).T @ d / w.sum()
    lam, vec = np.linalg.eigh(cov)
    score = [abs(lam[i] - np.mean(np.delete(lam, i))) for i in range(3)]
    z = vec[:, int(np.argmax(score))]
    # a deterministic sign: toward the larger file coordinate
    k = int(np.argmax(np.abs(z)))
    return (z if z[k] > 0 else -z), centroid


def frame_from_axis(z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(4, 4) X_MH with +Z_H = ``z``, X_H = the mesh X axis projected (or Y when X is along
    the axis), origin ``origin``."""
    z = np.asarray(z, float) / np.linalg.norm(z)
    ref = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, :3] = np.c_[x, np.cross(z, x), z]
    X[:3, 3] = origin
    return X


def _to_frame(mesh, X_MH: np.ndarray) -> np.ndarray:
    X_HM = np.linalg.inv(X_MH)
    return mesh.vertices @ X_HM[:3, :3].T + X_HM[:3, 3]


def ray_scene(V: np.ndarray, F: np.ndarray):
    """open3d RaycastingScene of the triangles F (T, 3) over the vertices V (N, 3) [m]."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)),
                        o3d.core.Tensor(np.asarray(F).astype(np.uint32)))
    return scene


def hub_frame_from_mesh(mesh, axis_M: np.ndarray | None = None,
                        origin_M: np.ndarray | None = None, *, front: str = "auto",
                        pixel: float = 1.0e-3, min_width: float | None = None,
                        source: str = "mesh") -> HubFrameEstimate:
    """Hub frame H in the mesh frame M (module doc, steps 1-2).

    Args:
        mesh: trimesh.Trimesh in metres.
        axis_M: (3,) +Z_H in M (out of the front face), or None to estimate (its side from
            ``front``).
        origin_M: (3,) a point on the axis in M, or None (front-most point of the spokes).
        front: "auto" (cues) or a file axis "+x", "-x", ..., "-z" the front faces.
        pixel: plan-view grid of the front cues' opening scan [m].
    """
    decision = None
    if axis_M is not None:
        z = np.asarray(axis_M, float) / np.linalg.norm(axis_M)
        centroid = principal_axis(mesh)[1]
        if front not in (None, "auto"):
            decision = front_from_user(front, z)
            z = z * decision.sign
    else:
        z, centroid = principal_axis(mesh)
        decision = front_from_user(front, z)
        if decision is None:
            X0 = frame_from_axis(z, centroid)
            V0 = _to_frame(mesh, X0)
            scene = ray_scene(V0, mesh.faces)
            r_max = float(np.hypot(V0[:, 0], V0[:, 1]).max())
            scan = find_openings(scene, r_max, float(V0[:, 2].max()) + 0.01,
                                 search=OpeningSearch(min_width=min_width, pixel=pixel),
                                 source=f"{source} (front cues)", quiet=True)
            decision = decide_front(scene, V0, scan, source=source)
        z = z * decision.sign
    o = centroid if origin_M is None else np.asarray(origin_M, float)
    if origin_M is None:
        # move the origin along the axis to the frontmost point of the spoke region
        d = mesh.vertices - o
        a = d @ z
        r = np.linalg.norm(d - np.outer(a, z), axis=1)
        inner = r < 0.75 * r.max()
        o = o + z * float(a[inner].max() if inner.any() else a.max())
    return HubFrameEstimate(frame_from_axis(z, o), axis_M is None, decision)


def resample_loop(p: np.ndarray, spacing: float | None = None, n: int | None = None):
    """Resample a closed polyline at equal arc length.

    Args:
        p: (N, 3) loop, first point not repeated.
        spacing: target spacing [m] (the count is rounded), or
        n: exact number of points.

    Returns:
        (n, 3) points, the first one at p[0].
    """
    q = np.vstack([p, p[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    if n is None:
        n = max(8, int(round(s[-1] / spacing)))
    t = np.linspace(0.0, s[-1], n, endpoint=False)
    return np.stack([np.interp(t, s, q[:, k]) for k in range(3)], axis=1)


def _polygon_area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _window_edges(scene, scan, spacing: float, source: str):
    """(kept: [(angle, area, p (N, 3))], rejected: [dict], figures: [dict])."""
    from drakedeburr.hub.edgeline import deburr_line, opening_outline

    kept, rejected, figures = [], [], []
    for op in scan.windows:
        ang = float(np.arctan2(op.center_xy[1], op.center_xy[0]) % (2 * np.pi))
        entry = {"center_xy_mm": [round(float(v) * 1e3, 2) for v in op.center_xy],
                 "width_mm": round(op.width * 1e3, 2)}
        try:
            outline = opening_outline(scene, op.mask, scan.grid, scan.pixel, scan.z0,
                                      min(spacing, 0.5e-3))
            line = deburr_line(scene, outline, scan.z0)
        except InputError:
            raise
        except numerical_errors() as exc:  # degenerate geometry: this window, named
            why = ("numerical failure while tracing the front boundary: "
                   + describe_numerical_error(exc))
            log.warning("%s: opening at (%.0f, %.0f) mm rejected as a window: %s", source,
                        op.center_xy[0] * 1e3, op.center_xy[1] * 1e3, why)
            rejected.append({**entry, "reason": why})
            continue
        entry.update({k: round(v * (1e3 if k != "missing" else 1.0), 3)
                      for k, v in line.figures.items()})
        if line.reason:
            log.warning("%s: opening at (%.0f, %.0f) mm rejected as a window: %s", source,
                        op.center_xy[0] * 1e3, op.center_xy[1] * 1e3, line.reason)
            rejected.append({**entry, "reason": line.reason})
            continue
        p = line.p_H
        if _polygon_area(p[:, :2]) < 0:
            p = p[::-1]
        band = line.band[np.isfinite(line.band)]
        entry["edge_band_mm"] = [round(float(band.min()) * 1e3, 2),
                                 round(float(np.median(band)) * 1e3, 2),
                                 round(float(band.max()) * 1e3, 2)]
        kept.append((ang, op.area, p, outline))
        figures.append((ang, entry))
    return kept, rejected, [f for _, f in sorted(figures, key=lambda t: t[0])]


def extract_window_edges(
    mesh,
    *,
    source: str = "mesh",
    axis_M: np.ndarray | None = None,
    origin_M: np.ndarray | None = None,
    front: str = "auto",
    spacing: float = 2.0e-3,
    search: OpeningSearch | None = None,
    expected_windows: int | None = None,
) -> ExtractionResult:
    """Find the window edge loops of a hub mesh (see module doc).

    Args:
        mesh: trimesh.Trimesh in metres (e.g. ``load_hub_mesh(path).mesh``).
        source: name for messages.
        axis_M, origin_M: hub axis (+Z_H, out of the front face) and a point on it in the
            mesh frame; None estimates them. For a mesh already in H pass (0, 0, 1), (0, 0, 0).
        front: "auto" or the file axis the front faces ("+z", "-y", ...).
        spacing: arc-length spacing of the returned loop points [m].
        search: how openings are found and judged
            (:class:`drakedeburr.hub.openings.OpeningSearch`: the plan-view grid step, every
            burr that may cut, the clearance each needs, the narrowest window). Default: the
            tool library's burrs (``OpeningSearch.of()``): an opening is a window candidate
            when one of them fits (:func:`drakedeburr.hub.openings.min_window_width`).
        expected_windows: if given, a different count is an error.

    Returns:
        ExtractionResult with one WindowEdge per window (points in H).

    Raises:
        InputError: no opening, no plausible window edge, or the wrong number of windows;
            the message names the openings and why each was not used.
    """
    search = OpeningSearch.of() if search is None else search
    min_w = search.window_width
    try:
        frame = hub_frame_from_mesh(mesh, axis_M, origin_M, front=front, min_width=min_w,
                                    source=source)
        v_H = _to_frame(mesh, frame.X_MH)
        scene = ray_scene(v_H, mesh.faces)
        r_max = float(np.linalg.norm(v_H[:, :2], axis=1).max())
        scan = find_openings(scene, r_max, float(v_H[:, 2].max()) + 0.01, search=search,
                             source=source)
    except InputError:
        raise
    except numerical_errors() as exc:  # degenerate geometry: a named result, not a crash
        axis = np.asarray(axis_M if axis_M is not None else [0.0, 0.0, 1.0], float)
        raise NoCuttableWindow(
            f"{source}: the hub frame and the through-openings could not be measured "
            f"(numerical failure: {describe_numerical_error(exc)})", source=str(source),
            axis=axis, openings=[], rejected=[]) from exc
    notes = {"axis_estimated": frame.estimated,
             "front": None if frame.front is None else frame.front.as_dict(frame.X_MH[:3, 2]),
             "min_window_width_mm": round(min_w * 1e3, 3),
             "burrs_mm": [round(b * 1e3, 3) for b in search.burrs],
             "not_windows": [o.as_dict() for o in scan.not_windows],
             "watertight": bool(mesh.is_watertight)}
    kept, rejected, figures = _window_edges(scene, scan, spacing, source)
    notes.update(rejected=rejected, loops=figures)
    if not kept:
        why = "; ".join(f"{o['kind']} at r = {o['radius_mm']:.0f} mm: {o['reason']}"
                        for o in notes["not_windows"][:30])
        why += "".join(f"; rejected edge at {r['center_xy_mm']} mm: {r['reason']}"
                       for r in rejected[:30])
        msg = (f"{source}: no window found looking along the hub axis "
               f"{np.round(frame.X_MH[:3, 2], 4)} (estimated={frame.estimated}); "
               f"{len(scan.openings)} through-openings: {why or 'none'}; pass the axis or "
               f"--front if they are wrong")
        if not scan.openings:  # no through-opening at all: not a hub with windows
            raise InputError(msg)
        raise NoCuttableWindow(msg, source=str(source), axis=frame.X_MH[:3, 2],
                               openings=notes["not_windows"], rejected=rejected)
    if expected_windows is not None and len(kept) != expected_windows:
        raise InputError(f"{source}: found {len(kept)} windows, expected {expected_windows}"
                         + "".join(f"; {o['kind']}: {o['reason']}"
                                   for o in notes["not_windows"] + rejected if o.get("reason")))
    kept.sort(key=lambda t: t[0])
    a_max = max(w[1] for w in kept)
    out = []
    for idx, (_, area, p, _) in enumerate(kept):
        q = resample_loop(p, spacing)
        kind = "large" if area >= 0.6 * a_max else "small"
        t = np.roll(q, -1, axis=0) - np.roll(q, 1, axis=0)  # central differences, loop order
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        out.append(WindowEdge(index=idx, kind=kind, p_HE=q, t_H=t))
    log.info("%s: %d windows, loop lengths %s mm", source, len(out),
             [round(float(np.linalg.norm(np.diff(np.vstack([w.p_HE, w.p_HE[:1]]), axis=0),
                                         axis=1).sum() * 1e3), 1) for w in out])
    return ExtractionResult(windows=out, X_MH=frame.X_MH, source=source, notes=notes,
                            outlines_xy=[w[3] for w in kept])
