"""Window edge-loop extraction from any hub mesh.

Steps (each failure raises an InputError that says which step and what was found):

1. Hub axis and frame H. Given (``axis_M``, ``origin_M``) or estimated: the principal axis of
   the area-weighted surface whose moment differs most from the other two (a wheel is a
   body of revolution), centred on the surface centroid; the front side is the side toward
   which the spoke disc is offset from the mid-plane (override with ``axis_M``'s sign).
   H: +Z_H along the axis out of the front face, origin on the axis at the frontmost point of
   the spoke region, X_H = the mesh X axis projected (or Y when X is along the axis).
2. Windows = through-openings: rays cast along -Z_H on a plan-view grid (open3d
   RaycastingScene); connected regions of misses (scipy.ndimage) that neither touch the grid
   border (outside the wheel) nor contain the axis (centre bore), larger than
   ``min_window_area``.
3. Edge loop of each window: the front face is the set of faces whose normal is within
   ``front_angle`` of +Z_H; the boundary edges of that face set (sharp dihedral edges on a
   closed mesh, also open boundaries on a non-watertight one) are chained into closed loops;
   each window takes the smallest loop whose plan view encloses the window's opening.
4. Loops are oriented counter-clockwise seen from +Z_H and resampled at equal arc length
   (the source's "initial CL points"); ``t_H`` holds chord tangents (central differences),
   the wall and face normals are left None (the frames stage estimates them from the scan).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.types import WindowEdge

__all__ = ["HubFrameEstimate", "ExtractionResult", "extract_window_edges", "resample_loop",
           "hub_frame_from_mesh"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class HubFrameEstimate:
    """X_MH: (4, 4) pose of hub frame H in the mesh frame M; ``estimated``: not given."""

    X_MH: np.ndarray
    estimated: bool


@dataclass(frozen=True, eq=False)
class ExtractionResult:
    """Windows found on a mesh.

    Attributes:
        windows: WindowEdge per window, in H [m], index CCW about +Z_H from +X_H.
        X_MH: (4, 4) hub frame in the mesh frame (metres).
        source: file or description.
        notes: what was detected (units, axis, loops) for reports.
    """

    windows: list[WindowEdge]
    X_MH: np.ndarray
    source: str = ""
    notes: dict = field(default_factory=dict)


def hub_frame_from_mesh(mesh, axis_M: np.ndarray | None = None,
                        origin_M: np.ndarray | None = None) -> HubFrameEstimate:
    """Hub frame H in the mesh frame M (see module doc, step 1).

    Args:
        mesh: trimesh.Trimesh in metres.
        axis_M: (3,) +Z_H in M (out of the front face), or None to estimate.
        origin_M: (3,) a point on the axis in M, or None (surface centroid projected).
    """
    c = mesh.triangles_center
    w = mesh.area_faces
    centroid = (c * w[:, None]).sum(0) / w.sum()
    estimated = axis_M is None
    if axis_M is None:
        d = c - centroid
        cov = (d * w[:, None]).T @ d / w.sum()
        lam, vec = np.linalg.eigh(cov)
        # the symmetry axis: the eigenvalue farthest from the other two
        score = [abs(lam[i] - np.mean(np.delete(lam, i))) for i in range(3)]
        z = vec[:, int(np.argmax(score))]
        # front: toward the axial offset of the spoke disc (area-weighted, inner radii)
        a = d @ z
        r = np.linalg.norm(d - np.outer(a, z), axis=1)
        inner = r < 0.6 * r.max()
        if inner.any():
            mid = 0.5 * (a.min() + a.max())
            offset = float((a[inner] * w[inner]).sum() / w[inner].sum()) - mid
            if offset < 0:
                z = -z
            log.info("hub axis estimated: %s (spoke disc offset %.1f mm toward front)",
                     np.round(z, 4), abs(offset) * 1e3)
    else:
        z = np.asarray(axis_M, float)
        z = z / np.linalg.norm(z)
    o = centroid if origin_M is None else np.asarray(origin_M, float)
    if origin_M is None:
        # move the origin along the axis to the frontmost point of the spoke region
        d = mesh.vertices - o
        a = d @ z
        r = np.linalg.norm(d - np.outer(a, z), axis=1)
        inner = r < 0.75 * r.max()
        o = o + z * float(a[inner].max() if inner.any() else a.max())
    ref = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    X = np.eye(4)
    X[:3, :3] = np.c_[x, y, z]
    X[:3, 3] = o
    return HubFrameEstimate(X_MH=X, estimated=estimated)


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


def _chain_loops(edges: np.ndarray) -> tuple[list[np.ndarray], int]:
    """Chain undirected edges (E, 2) into closed vertex loops; returns loops and the number of
    edges that could not be chained (open chains or branch points)."""
    from collections import defaultdict

    adj = defaultdict(list)
    for a, b in edges:
        adj[a].append(b)
        adj[b].append(a)
    used = set()
    loops, loose = [], 0
    for start in list(adj):
        if len(adj[start]) != 2:
            continue
        for nxt in adj[start]:
            key = (min(start, nxt), max(start, nxt))
            if key in used:
                continue
            loop, prev, cur = [start], start, nxt
            path_edges = [key]
            ok = True
            while cur != start:
                if len(adj[cur]) != 2:
                    ok = False
                    break
                loop.append(cur)
                a, b = adj[cur]
                prev, cur = cur, (b if a == prev else a)
                path_edges.append((min(prev, cur), max(prev, cur)))
            used.update(path_edges)
            if ok:
                loops.append(np.array(loop))
            else:
                loose += len(path_edges)
    return loops, loose


def _point_in_polygon(pts: np.ndarray, poly: np.ndarray) -> np.ndarray:
    from matplotlib.path import Path as MplPath

    return MplPath(poly).contains_points(pts)


def _polygon_area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _silhouette_loop(scene, mask: np.ndarray, g: np.ndarray, pixel: float, z0: float,
                     spacing: float) -> np.ndarray:
    """The outline of one opening (plan view), refined to ~1e-3 px by bisection with ray casts
    along its normal, lifted onto the front surface just outside the opening. (N, 3) in H,
    CCW seen from +Z_H."""
    import contourpy
    import open3d as o3d

    pad = np.pad(mask.astype(float), 1)
    lines = contourpy.contour_generator(z=pad).lines(0.5)
    line = max(lines, key=len)
    xy = np.c_[np.interp(line[:, 1] - 1, np.arange(len(g)), g),
               np.interp(line[:, 0] - 1, np.arange(len(g)), g)]
    if np.linalg.norm(xy[0] - xy[-1]) < 1e-12:
        xy = xy[:-1]
    if _polygon_area(xy) < 0:
        xy = xy[::-1]
    xy = resample_loop(np.c_[xy, np.zeros(len(xy))], spacing / 2)[:, :2]
    tang = np.roll(xy, -1, 0) - np.roll(xy, 1, 0)
    nrm = np.c_[tang[:, 1], -tang[:, 0]]  # right of a CCW outline = out of the opening
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)

    def cast(p2):
        r = np.zeros((len(p2), 6), np.float32)
        r[:, :2], r[:, 2], r[:, 5] = p2, z0, -1.0
        t = scene.cast_rays(o3d.core.Tensor(r))["t_hit"].numpy()
        return t

    lo = np.full(len(xy), -2.0 * pixel)  # inside the opening (miss)
    hi = np.full(len(xy), 2.0 * pixel)  # on material (hit)
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        h = np.isfinite(cast(xy + mid[:, None] * nrm))
        hi = np.where(h, mid, hi)
        lo = np.where(h, lo, mid)
    edge = xy + hi[:, None] * nrm
    t = cast(edge + 0.02e-3 * nrm)
    ok = np.isfinite(t)
    edge, t = edge[ok], t[ok]
    return np.c_[edge, z0 - t]


def extract_window_edges(
    mesh,
    *,
    source: str = "mesh",
    axis_M: np.ndarray | None = None,
    origin_M: np.ndarray | None = None,
    spacing: float = 2.0e-3,
    pixel: float = 0.5e-3,
    front_angle_deg: float = 60.0,
    min_window_area: float = 2.0e-4,
    min_window_width: float = 30e-3,
    expected_windows: int | None = None,
    edge_source: str = "auto",
) -> ExtractionResult:
    """Find the window edge loops of a hub mesh (see module doc).

    Args:
        mesh: trimesh.Trimesh in metres (e.g. ``load_hub_mesh(path).mesh``).
        source: name for messages.
        axis_M, origin_M: hub axis (+Z_H, out of the front face) and a point on it in the
            mesh frame; None estimates them. For a mesh already in H pass (0, 0, 1), (0, 0, 0).
        spacing: arc-length spacing of the returned loop points [m].
        pixel: plan-view grid step for finding openings [m].
        front_angle_deg: faces within this angle of +Z_H belong to the front face.
        min_window_area: smaller openings (bolt holes, noise) are ignored [m^2].
        min_window_width: openings whose largest inscribed circle is narrower than this
            (slits between twin spokes, bolt holes) are not windows [m]; they are logged.
        expected_windows: if given, a different count is an error.
        edge_source: "mesh" (front-face boundary loops only), "silhouette" (the opening's
            plan-view outline, refined by ray casts and lifted onto the front surface), or
            "auto": mesh loops where they exist, else the silhouette (for meshes whose parts
            are not stitched, e.g. low-poly game models); the choice is logged per window.

    Returns:
        ExtractionResult with one WindowEdge per window (points in H).

    Raises:
        InputError: no opening found, an opening without a closed front-face loop, or the
            wrong number of windows; the message names the window and what was found.
    """
    import open3d as o3d
    from scipy import ndimage

    if edge_source not in ("auto", "mesh", "silhouette"):
        raise InputError(f"edge_source must be auto, mesh or silhouette, got {edge_source!r}")
    frame = hub_frame_from_mesh(mesh, axis_M, origin_M)
    X_HM = np.linalg.inv(frame.X_MH)
    v_H = mesh.vertices @ X_HM[:3, :3].T + X_HM[:3, 3]
    f = np.asarray(mesh.faces)
    r_max = float(np.linalg.norm(v_H[:, :2], axis=1).max())

    # --- 2. openings by plan-view ray casting --------------------------------------------
    n_px = int(np.ceil(2 * r_max / pixel)) + 3
    g = (np.arange(n_px) - (n_px - 1) / 2) * pixel
    gx, gy = np.meshgrid(g, g, indexing="ij")
    z0 = float(v_H[:, 2].max()) + 0.01
    rays = np.zeros((n_px * n_px, 6), np.float32)
    rays[:, 0], rays[:, 1], rays[:, 2], rays[:, 5] = gx.ravel(), gy.ravel(), z0, -1.0
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v_H.astype(np.float32)),
                        o3d.core.Tensor(f.astype(np.uint32)))
    hit = np.isfinite(scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()).reshape(n_px, n_px)
    labels, n_lab = ndimage.label(~hit)
    border = set(np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    centre = labels[n_px // 2, n_px // 2]
    openings, skipped = [], []
    for lab in range(1, n_lab + 1):
        if lab in border or lab == centre:
            continue
        mask = labels == lab
        area = mask.sum() * pixel**2
        if area < min_window_area:
            continue
        dist = ndimage.distance_transform_edt(mask)
        i, j = np.unravel_index(np.argmax(dist), mask.shape)
        width = 2 * dist[i, j] * pixel
        if width < min_window_width:
            log.info("%s: opening of %.0f mm^2 at r = %.0f mm skipped: %.1f mm wide < "
                     "min_window_width %.1f mm", source, area * 1e6,
                     np.hypot(g[i], g[j]) * 1e3, width * 1e3, min_window_width * 1e3)
            skipped.append({"area_mm2": area * 1e6, "width_mm": width * 1e3})
            continue
        openings.append({"mask": mask, "area": area, "inner": np.array([g[i], g[j]]),
                         "pts": np.c_[gx[mask], gy[mask]]})
    notes = {"axis_estimated": frame.estimated, "openings": len(openings),
             "skipped_openings": skipped,
             "watertight": bool(mesh.is_watertight)}
    if not openings:
        raise InputError(
            f"{source}: no through-opening larger than {min_window_area * 1e6:.0f} mm^2 found "
            f"looking along the hub axis {np.round(frame.X_MH[:3, 2], 4)} (estimated="
            f"{frame.estimated}); pass the axis if it is wrong"
        )

    # --- 3. front-face boundary loops ----------------------------------------------------
    n_H = mesh.face_normals @ X_HM[:3, :3].T
    front = n_H[:, 2] > np.cos(np.radians(front_angle_deg))
    fe = np.sort(np.stack([f[front][:, [0, 1]], f[front][:, [1, 2]], f[front][:, [2, 0]]],
                          axis=1).reshape(-1, 2), axis=1)
    uniq, counts = np.unique(fe, axis=0, return_counts=True)
    loops, loose = _chain_loops(uniq[counts == 1])
    notes.update(front_faces=int(front.sum()), front_loops=len(loops), loose_edges=int(loose))

    windows = []
    for k, op in enumerate(openings):
        best = None
        sample = op["pts"][:: max(1, len(op["pts"]) // 200)]
        for loop in loops:
            xy = v_H[loop, :2]
            area = abs(_polygon_area(xy))
            # the front edge encloses the opening's silhouette, but not much more
            if not 0.9 * op["area"] <= area <= 2.0 * op["area"]:
                continue
            if best is not None and area >= best[0]:
                continue
            if not _point_in_polygon(op["inner"][None], xy)[0]:
                continue
            if _point_in_polygon(sample, xy).mean() < 0.95:
                continue
            best = (area, loop)
        if edge_source == "silhouette" or (best is None and edge_source == "auto"):
            p = _silhouette_loop(scene, op["mask"], g, pixel, z0, spacing)
            if edge_source == "auto":
                log.warning("%s: opening %d: no closed front-face edge loop in the mesh; using "
                            "the opening's silhouette lifted onto the front surface", source, k)
            notes.setdefault("edge_source", {})[k] = "silhouette"
            windows.append((np.arctan2(*op["inner"][::-1]) % (2 * np.pi), op["area"], p))
            continue
        if best is None:
            ang = np.degrees(np.arctan2(op["inner"][1], op["inner"][0]))
            raise InputError(
                f"{source}: opening {k} (area {op['area'] * 1e6:.0f} mm^2, at r = "
                f"{np.linalg.norm(op['inner']) * 1e3:.0f} mm, {ang:.0f} deg about +Z_H) has no "
                f"closed front-face edge loop around it: the front face ({int(front.sum())} "
                f"faces within {front_angle_deg:.0f} deg of the axis) has {len(loops)} closed "
                f"boundary loops and {loose} edges in open chains or branches"
                + ("" if mesh.is_watertight else "; the mesh is not watertight")
            )
        p = v_H[best[1]]
        if _polygon_area(p[:, :2]) < 0:
            p = p[::-1]
        notes.setdefault("edge_source", {})[k] = "mesh"
        windows.append((np.arctan2(*op["inner"][::-1]) % (2 * np.pi), best[0], p))

    if expected_windows is not None and len(windows) != expected_windows:
        raise InputError(f"{source}: found {len(windows)} windows, expected {expected_windows}")
    windows.sort(key=lambda t: t[0])
    a_max = max(w[1] for w in windows)
    out = []
    for idx, (_, area, p) in enumerate(windows):
        q = resample_loop(p, spacing)
        kind = "large" if area >= 0.6 * a_max else "small"
        t = np.roll(q, -1, axis=0) - np.roll(q, 1, axis=0)  # central differences, loop order
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        out.append(WindowEdge(index=idx, kind=kind, p_HE=q, t_H=t))
    log.info("%s: %d windows, loop lengths %s mm", source, len(out),
             [round(float(np.linalg.norm(np.diff(np.vstack([w.p_HE, w.p_HE[:1]]), axis=0),
                                         axis=1).sum() * 1e3), 1) for w in out])
    return ExtractionResult(windows=out, X_MH=frame.X_MH, source=source, notes=notes)
