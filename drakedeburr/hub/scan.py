"""Simulated structured-light scan of a hub's visible surfaces (front face, window walls, lip).

Model of the sensor: a structured-light scanner looks at the hub along ``view_dir`` from
``distance``; the cell merges ``1 + n_tilted`` views (one along the axis, the others tilted by
``tilt`` about it, evenly spread) so that the window side walls are seen too, as a real
multi-view scan does. Surface points are drawn uniformly by area (mean spacing ``spacing``),
kept if at least one view sees them (not occluded, incidence below ``max_incidence``), and
displaced by isotropic Gaussian noise of standard deviation ``sigma`` per axis (so the distance
to the surface along its normal has standard deviation ``sigma``). Deterministic for a seed.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.hub.model import HubModel
from drakedeburr.hub.types import ScanCloud

__all__ = ["ScannerModel", "simulate_scan", "scanner_origins_H"]

log = logging.getLogger(__name__)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float).reshape(3)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n < 1e-12:
        raise InputError(f"view_dir must be a non-zero 3-vector, got {v}")
    return v / n


def scanner_origins_H(view_dir: Sequence[float] = (0.0, 0.0, 1.0), *, distance: float = 0.8,
                      tilt: float = math.radians(25.0), n_tilted: int = 4,
                      target_H: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """(1 + n_tilted, 3) positions [m] in H of the merged scanner views."""
    d = _unit(view_dir)
    a = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(d, a)
    dirs = [d]
    for k in range(n_tilted):
        phi = 2 * math.pi * k / max(n_tilted, 1)
        dirs.append(math.cos(tilt) * d + math.sin(tilt) * (math.cos(phi) * a + math.sin(phi) * b))
    return np.asarray(target_H, float) + distance * np.array(dirs)


@dataclass(frozen=True)
class ScannerModel:
    """The simulated sensor (module docstring).

    Attributes:
        sigma: noise standard deviation per axis [m] (0.05 mm default).
        view_dir: unit direction in H from the hub towards the scanner (+Z_H: face-on).
        distance: scanner distance from the hub origin [m].
        tilt: tilt of the extra views about ``view_dir`` [rad].
        n_tilted: number of tilted views (0: a single face-on view, window walls unseen).
        max_incidence: a view sees a point only if the angle between the surface normal and the
            direction to the scanner is below this [rad].
    """

    sigma: float = 5e-5
    view_dir: Sequence[float] = (0.0, 0.0, 1.0)
    distance: float = 0.8
    tilt: float = math.radians(25.0)
    n_tilted: int = 4
    max_incidence: float = math.radians(80.0)


def simulate_scan(hub: HubModel, scanner: ScannerModel = ScannerModel(), *,
                  spacing: float = 1e-3, seed: int = 0,
                  partial: tuple[float, float] | None = None,
                  max_edge_distance: float | None = None,
                  with_normals: bool = False, X_SH: np.ndarray | None = None) -> ScanCloud:
    """Simulate a merged multi-view structured-light scan of ``hub`` in its frame H.

    Args:
        hub: the hub model (see :func:`drakedeburr.hub.load_hub`).
        scanner: noise, view direction, distance, tilted views and incidence limit
            (:class:`ScannerModel`).
        spacing: mean point spacing on the surface [m]; the count is area / spacing^2.
        seed: random seed (sampling and noise); same seed, same cloud.
        partial: optional sector ``(theta_min, theta_max)`` [rad] about +Z_H (measured from
            +X_H, CCW); only points whose polar angle lies in it are kept.
        max_edge_distance: optional [m]: keep only points within this distance of a window edge
            (cheap dense clouds for normal estimation).
        with_normals: put the true (noise-free) surface normals in ``n_S``; otherwise ``n_S`` is
            None like a real scanner's output.
        X_SH: optional (4, 4) homogeneous pose of H in the scan frame S (e.g. the hub turned
            and shifted on its fixture, for registration tests); points and normals are returned
            in S. Default: S = H.

    Returns:
        ScanCloud with ``p_S`` (N, 3) [m] in S (= H unless ``X_SH``); ``meta`` holds the
        parameters, the number of points and ``views_H`` (scanner positions in H).

    Raises:
        InputError: invalid arguments.
    """
    sigma, view_dir = scanner.sigma, scanner.view_dir
    if not (sigma >= 0 and math.isfinite(sigma)):
        raise InputError(f"simulate_scan: sigma must be >= 0, got {sigma}")
    if not (spacing > 0 and math.isfinite(spacing)) or spacing < 5e-5:
        raise InputError(f"simulate_scan: spacing must be >= 0.05 mm, got {spacing}")
    if partial is not None:
        th0, th1 = (float(x) for x in partial)
        if not th1 > th0:
            raise InputError(f"simulate_scan: partial sector needs theta_max > theta_min, "
                             f"got {partial}")
    views = scanner_origins_H(view_dir, distance=scanner.distance, tilt=scanner.tilt,
                              n_tilted=scanner.n_tilted)
    cos_max = math.cos(scanner.max_incidence)
    T, N = _facing_triangles(hub.vertices_H, hub.faces, views, cos_max)
    etree = None
    if max_edge_distance is not None:
        from scipy.spatial import cKDTree

        etree = cKDTree(np.concatenate([w.p_HE for w in hub.windows]))
        T, N = _split_near_edges(T, N, etree, max_edge_distance, spacing)
    rng = np.random.default_rng(seed)
    p, nrm, n = _sample(T, N, spacing, rng)
    keep = np.ones(len(p), bool)
    if etree is not None:
        d, _ = etree.query(p)
        keep &= d <= max_edge_distance
    if partial is not None:
        th = np.arctan2(p[:, 1], p[:, 0])
        th = th0 + np.mod(th - th0, 2 * math.pi)
        keep &= th <= th1
    p, nrm = p[keep], nrm[keep]
    seen = _visible(hub.vertices_H, hub.faces, p, nrm, views, cos_max)
    p, nrm = p[seen], nrm[seen]
    if sigma > 0:
        p = p + rng.normal(0.0, sigma, size=p.shape)
    frame = "H"
    if X_SH is not None:
        p, nrm = _to_scan_frame(p, nrm, X_SH)
        frame = "S"
    log.debug("simulate_scan %s: %d points (%d candidates)", hub.name, len(p), n)
    meta = {"sigma": sigma, "spacing": spacing, "seed": seed, "frame": frame,
            "X_SH": None if X_SH is None else np.asarray(X_SH, float).tolist(),
            "view_dir": [float(x) for x in _unit(view_dir)], "views_H": views.tolist(),
            "partial": None if partial is None else [float(x) for x in partial],
            "max_edge_distance": max_edge_distance, "count": int(len(p)), "hub": hub.name}
    return ScanCloud(p_S=p, n_S=nrm.copy() if with_normals else None,
                     source=f"simulated scan of hub {hub.name} (sigma {sigma * 1e3:.3f} mm, "
                            f"seed {seed})", meta=meta)


def _facing_triangles(V: np.ndarray, F: np.ndarray, views: np.ndarray, cos_max: float):
    """Triangles (K, 3, 3) facing at least one view, and their unit normals (K, 3)."""
    tri = V[F]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(area2, 1e-300)[:, None]
    centroid = tri.mean(axis=1)
    facing = np.zeros(len(F), bool)
    for o in views:
        to = o - centroid
        to /= np.linalg.norm(to, axis=1, keepdims=True)
        facing |= np.sum(normal * to, axis=1) > cos_max
    cand = facing & (area2 > 0)
    return tri[cand], normal[cand]


def _split_near_edges(T: np.ndarray, N: np.ndarray, etree, max_edge_distance: float,
                      spacing: float):
    """Keep triangles near the window edges, split large ones (longest-edge bisection) so the
    band test per triangle is tight."""
    lim = max(max_edge_distance, 2 * spacing)
    for _ in range(16):
        c = T.mean(axis=1)
        size = np.max(np.linalg.norm(T - c[:, None, :], axis=2), axis=1)
        d, _ = etree.query(c)
        near = d <= max_edge_distance + size
        T, N, size = T[near], N[near], size[near]
        big = size > lim
        if not big.any():
            break
        Tb = T[big]
        e = np.stack([np.linalg.norm(Tb[:, 1] - Tb[:, 0], axis=1),
                      np.linalg.norm(Tb[:, 2] - Tb[:, 1], axis=1),
                      np.linalg.norm(Tb[:, 0] - Tb[:, 2], axis=1)], axis=1)
        k = np.argmax(e, axis=1)  # longest edge k: vertices k, k+1
        rows = np.arange(len(Tb))
        a, b, o = Tb[rows, k], Tb[rows, (k + 1) % 3], Tb[rows, (k + 2) % 3]
        m = 0.5 * (a + b)
        T = np.concatenate([T[~big], np.stack([a, m, o], axis=1), np.stack([m, b, o], axis=1)])
        N = np.concatenate([N[~big], N[big], N[big]])
    return T, N


def _sample(T: np.ndarray, N: np.ndarray, spacing: float, rng):
    """Points drawn uniformly by area (area / spacing^2 of them), their normals, the count."""
    areas = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    total = float(areas.sum())
    n = int(round(total / spacing**2))
    if n > 5_000_000:
        raise InputError(f"simulate_scan: {n} points requested (area {total:.3f} m^2 at "
                         f"{spacing * 1e3:.2f} mm spacing); raise spacing or set "
                         "max_edge_distance")
    pick = rng.choice(len(T), size=n, p=areas / total)
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = T[pick]
    p = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    return p, N[pick], n


def _visible(V: np.ndarray, F: np.ndarray, p: np.ndarray, nrm: np.ndarray, views: np.ndarray,
             cos_max: float) -> np.ndarray:
    """(K,) bool: some view sees the point (facing it, and the first hit of the ray from the
    view toward the point is the point itself)."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)),
                        o3d.core.Tensor(F.astype(np.uint32)))
    seen = np.zeros(len(p), bool)
    for o in views:
        ray = p - o
        dist = np.linalg.norm(ray, axis=1)
        ray /= dist[:, None]
        facing_pt = -np.sum(ray * nrm, axis=1) > cos_max
        todo = facing_pt & ~seen
        if not todo.any():
            continue
        rays = np.concatenate([np.broadcast_to(o, (int(todo.sum()), 3)), ray[todo]], axis=1)
        hit = scene.cast_rays(o3d.core.Tensor(rays.astype(np.float32)))["t_hit"].numpy()
        seen[np.flatnonzero(todo)[hit >= dist[todo] - 2e-5]] = True
    return seen


def _to_scan_frame(p: np.ndarray, nrm: np.ndarray, X_SH) -> tuple[np.ndarray, np.ndarray]:
    X = np.asarray(X_SH, float)
    R = X[:3, :3] if X.shape == (4, 4) else None
    if R is None or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise InputError("simulate_scan: X_SH must be a (4, 4) rigid transform")
    return p @ R.T + X[:3, 3], nrm @ R.T
