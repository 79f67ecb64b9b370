"""Inner-side normals at CL points (source §2.1), from a hub point cloud or from a mesh.

The inner-side normal is the normal of the window's side wall at the edge point, pointing out
of the material into the opening (WindowEdge.n_wall_H). Point-cloud procedure, as the source:

1. voxel filter (open3d ``voxel_down_sample``); per-point normals from a KNN query (open3d
   ``estimate_normals`` with ``KDTreeSearchParamKNN``) - the "KNN feature query";
2. radius search (r = ``ProcessParameters.normal_search_radius``, 6 mm) around each CL point
   with open3d ``KDTreeFlann``; k-means (scikit-learn, k = 2) on the sign-free normal feature
   n n^T splits the neighbourhood into the two faces meeting at the edge;
3. key points (curvature > ``key_point_curvature``, 0.12 1/mm) get a local curved-surface fit
   (a Gaussian-weighted quadric height field, refitted once in its own tangent frame), the
   others a RANSAC plane (seeded, 0.1 mm threshold) refined by least squares
   on its inliers. A plane that does not describe the surface *at* the CL point (the point off
   the plane, or the points next to it not inliers - RANSAC found a flat stretch beside a
   fillet whose curvature is just under the threshold) is rejected for the curved fit;
4. consistent grouping along the curve with the source's angle test | |angle| - pi/2 |;
5. inner-side group = the one whose normals make the larger (sign-free) angle with the loop
   axis Z (the Z axis of the frame at the CL-point centroid), i.e. the wall, not the face;
6. both normals are made exactly perpendicular to the edge tangent (the edge lies on both
   faces; this is eq. 5's correction applied to the estimate, and it removes the fits' bias
   along the edge at fillet/flat junctions);
7. sign: each wall normal must point away from the material, i.e. away from the centroid of its
   neighbourhood's *front-face* cluster (a local test that also holds on non-convex windows).
   The source's test (dot product with the vector to the CL-point centroid) is evaluated too
   and its disagreements are reported, not used.

Mesh procedure: a mesh's outward face normals already point out of the material, so the wall
normal is a Gaussian-weighted (sigma = ``mesh_sigma``) mean of the outward normals of surface
samples of the wall-class triangles near the CL point (k-means on normals as above).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.frames.vectors import perpendicular_basis
from drakedeburr.hub.types import ScanCloud
from drakedeburr.path.types import ClPath

__all__ = ["NormalEstimate", "CloudNormalOptions", "inner_normals_from_cloud",
           "inner_normals_from_mesh", "loop_axis"]

log = logging.getLogger(__name__)

Progress = Callable[[int, int, str], None]


@dataclass(frozen=True, eq=False)
class NormalEstimate:
    """Normals at the CL points of one window (hub frame H).

    Attributes:
        window_index: the window.
        n_wall_H: (M, 3) unit inner-side normals (out of the material into the opening).
        n_face_H: (M, 3) unit front-face normals (out of the material).
        method: (M,) "quadric" (key point), "plane" (RANSAC), "quadric (plane rejected)"
            (a non-key point whose RANSAC plane did not describe the surface at the point) or
            "mesh".
        neighbours: (M,) points found within the search radius.
        source_sign_disagreements: (K,) indices where the source's centroid sign test would
            have chosen the other sign (informative; empty on convex windows).
    """

    window_index: int
    n_wall_H: np.ndarray
    n_face_H: np.ndarray
    method: tuple[str, ...]
    neighbours: np.ndarray
    source_sign_disagreements: np.ndarray


def loop_axis(p_HC: np.ndarray) -> np.ndarray:
    """Unit normal of the best-fit plane of a closed loop, oriented so that the loop runs
    counter-clockwise about it (i.e. +Z_H for a window loop). (3,)"""
    c = p_HC.mean(axis=0)
    _, _, vt = np.linalg.svd(p_HC - c, full_matrices=False)
    z = vt[2]
    area = np.cross(p_HC - c, np.roll(p_HC, -1, axis=0) - c).sum(axis=0)
    return z if area @ z >= 0 else -z


def _perpendicular_to_edge(n: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Remove the tangent component: the edge lies on both faces, so both normals are exactly
    perpendicular to its tangent (eq. 5's correction, applied to the estimate). This removes
    the fits' bias along the edge where a fillet meets a flat stretch."""
    t = t / np.linalg.norm(t, axis=1, keepdims=True)
    v = n - np.einsum("ij,ij->i", n, t)[:, None] * t
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _sym_features(n: np.ndarray) -> np.ndarray:
    s = np.sqrt(2.0)
    return np.column_stack([n[:, 0] ** 2, n[:, 1] ** 2, n[:, 2] ** 2, s * n[:, 0] * n[:, 1],
                            s * n[:, 0] * n[:, 2], s * n[:, 1] * n[:, 2]])


def _principal(n: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(n.T @ n)
    return v[:, -1]


def _fold(cos: np.ndarray) -> np.ndarray:
    """Source's angle transform | |angle| - pi/2 | from cosines."""
    return np.abs(np.arccos(np.clip(cos, -1.0, 1.0)) - np.pi / 2)


def _ransac_plane(pts: np.ndarray, threshold: float, seed: int,
                  iterations: int = 200) -> np.ndarray:
    """Inlier indices of the RANSAC plane with the most points within ``threshold``.

    Written here, vectorised over the candidate planes with a seeded numpy generator, because
    open3d's ``segment_plane`` (0.20) returns different planes for the same points and seed
    from call to call (measured: 2-3 distinct planes in 30 calls, also with one OpenMP thread),
    and a plan must not depend on the run.
    """
    rng = np.random.default_rng(seed)
    n = len(pts)
    tri = np.array([rng.choice(n, 3, replace=False) for _ in range(iterations)])
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    nrm = np.cross(b - a, c - a)
    size = np.linalg.norm(nrm, axis=1)
    ok = size > 1e-15
    nrm = nrm[ok] / size[ok, None]
    d = np.abs((pts[None] - a[ok][:, None]) @ nrm[..., None])[..., 0]  # (K, N)
    inliers = d <= threshold
    if not len(inliers):
        return np.arange(n)
    return np.flatnonzero(inliers[int(np.argmax(inliers.sum(axis=1)))])


def _plane_normal(pts: np.ndarray, p0: np.ndarray, threshold: float, seed: int,
                  local_radius: float) -> np.ndarray | None:
    """RANSAC plane (:func:`_ransac_plane`) refined by least squares on its inliers; None
    when the plane is not the local surface at p0 (p0 farther than 2 thresholds from it, or
    fewer than 80 % of the points within ``local_radius`` of p0 are inliers) - e.g. a
    fillet next to a flat stretch, where RANSAC finds the flat stretch."""
    inliers = _ransac_plane(pts, threshold, seed)
    q = pts[inliers] if len(inliers) >= 3 else pts
    c = q.mean(axis=0)
    _, _, vt = np.linalg.svd(q - c, full_matrices=False)
    n = vt[2]
    near = np.linalg.norm(pts - p0, axis=1) <= local_radius
    dist = np.abs((pts[near] - c) @ n)
    if abs((p0 - c) @ n) > 2 * threshold or (near.any() and np.mean(dist <= threshold) < 0.8):
        return None
    return n


def _quadric_normal(pts: np.ndarray, p0: np.ndarray, n0: np.ndarray, t0: np.ndarray,
                    sigma_t: float, sigma_d: float) -> np.ndarray:
    """Normal at (the projection of) p0 of a Gaussian-weighted quadric height field
    h(x, y) = a x^2 + b x y + c y^2 + d x + e y + f over the tangent plane of n0, with x along
    the edge tangent t0 (weight radius sigma_t) and y across it (sigma_d, larger: the surface
    changes along the edge, so the fit is kept short in that direction only)."""
    n = n0 / np.linalg.norm(n0)
    for _ in range(2):
        u = t0 - (t0 @ n) * n
        if np.linalg.norm(u) < 0.1:
            u = perpendicular_basis(n)[:, 0]
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        q = pts - p0
        x, y, h = q @ u, q @ v, q @ n
        w = np.exp(-0.5 * (x**2 / sigma_t**2 + y**2 / sigma_d**2))
        A = np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)])
        sw = np.sqrt(w)
        coef = np.linalg.lstsq(A * sw[:, None], h * sw, rcond=None)[0]
        res = np.abs(A @ coef - h)
        mad = np.median(res) + 1e-12
        keep = res < 6.0 * mad  # drop the other face's stragglers, then refit
        if keep.sum() >= 12:
            coef = np.linalg.lstsq(A[keep] * sw[keep, None], h[keep] * sw[keep], rcond=None)[0]
        # normal at the point of the fitted surface above the origin (x = y = 0)
        g = np.array([-coef[3], -coef[4], 1.0])
        n_new = g[0] * u + g[1] * v + g[2] * n
        n_new /= np.linalg.norm(n_new)
        n = n_new if n_new @ n > 0 else -n_new
    return n


def _kmeans_split(n: np.ndarray, seed: int) -> np.ndarray:
    from sklearn.cluster import KMeans

    km = KMeans(n_clusters=2, n_init=1, random_state=seed).fit(_sym_features(n))
    return km.labels_


@dataclass(frozen=True)
class CloudNormalOptions:
    """Settings of :func:`inner_normals_from_cloud` beyond the process parameters.

    Attributes:
        voxel_size: voxel filter size [m].
        knn: neighbours of the per-point normal estimate.
        min_neighbours: fewer points than this within the search radius is an InputError.
        quadric_sigma: Gaussian weight radius of the key-point quadric fit along the edge [m]
            (across the edge it is half the search radius): short, so that a fit across a
            plane/fillet junction stays local.
        seed: k-means / RANSAC seed.
    """

    voxel_size: float = 0.3e-3
    knn: int = 20
    min_neighbours: int = 40
    quadric_sigma: float = 1.0e-3
    seed: int = 0


def inner_normals_from_cloud(
    cloud: ScanCloud,
    cl: ClPath,
    *,
    params: ProcessParameters | None = None,
    options: CloudNormalOptions = CloudNormalOptions(),
    progress: Progress | None = None,
) -> NormalEstimate:
    """Inner-side normals at the CL points from a point cloud given in H.

    Args:
        cloud: scan with ``p_S`` already in the hub frame H [m] (register it first, see
            :func:`drakedeburr.hub.registration.register_hub`).
        cl: the window's CL points (H).
        params: search radius, key-point curvature, RANSAC threshold.
        options: voxel filter, neighbours, quadric weight radius, seed
            (:class:`CloudNormalOptions`).
        progress: optional callback (done, total, label).

    Raises:
        InputError: a CL point has too few neighbours (names the window and the point).
    """
    params = params or ProcessParameters()
    min_neighbours = options.min_neighbours
    p = np.asarray(cloud.p_S, float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < min_neighbours:
        raise InputError(f"{cloud.source or 'scan'}: need an (N, 3) cloud, got {p.shape}")
    from threadpoolctl import threadpool_limits

    r = params.normal_search_radius
    pts, nrm, tree = _window_cloud(p, cl, r, options.voxel_size, options.knn)
    m = len(cl.p_HC)
    w = cl.window_index
    z_loop = loop_axis(cl.p_HC)
    fitted = np.zeros((m, 2, 3))  # two surface normals per point, arbitrary order and sign
    side_pts = np.zeros((m, 2, 3))  # centroid of each cluster's points
    method: list[str] = []
    counts = np.zeros(m, int)
    # one thread for k-means: the neighbourhoods are small and OpenMP start-up/spinning would
    # dominate (x100 on a loaded machine). sklearn must be imported before the limit is set.
    import sklearn.cluster  # noqa: F401

    with threadpool_limits(1):
        for i, p_C in enumerate(cl.p_HC):
            k, idx, _ = tree.search_radius_vector_3d(p_C, r)
            counts[i] = k
            if k < min_neighbours:
                raise InputError(
                    f"{cloud.source or 'scan'}: window {w}, CL point {i} at "
                    f"{np.round(p_C * 1e3, 2).tolist()} mm: only {k} scan points within "
                    f"{r * 1e3:.1f} mm (need {min_neighbours}); is the scan registered to H and "
                    "does it cover this edge?")
            key = cl.kappa[i] > params.key_point_curvature
            label, fitted[i], side_pts[i] = _fit_point(
                (pts, nrm), np.asarray(idx), p_C, cl.t_H[i], key, params, options, z_loop)
            method.append(label)
            if progress is not None:
                progress(i + 1, m, f"window {w}")
    n_wall, n_face, disagree = _group_and_sign(fitted, side_pts, cl, z_loop)
    return NormalEstimate(w, n_wall, n_face, tuple(method), counts, disagree)


def _window_cloud(p: np.ndarray, cl: ClPath, r: float, voxel_size: float, knn: int):
    """The scan near one window's CL points (voxel-filtered, with per-point normals):
    (points (N, 3), normals (N, 3), open3d KD-tree)."""
    import open3d as o3d

    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
    # keep only the scan near this window's edge (per-point normals need a margin of KNN)
    lo = cl.p_HC.min(axis=0) - 2 * r
    hi = cl.p_HC.max(axis=0) + 2 * r
    pcd = pcd.crop(o3d.geometry.AxisAlignedBoundingBox(lo, hi))
    if voxel_size > 0:
        pcd = pcd.voxel_down_sample(voxel_size)
    full_tree = o3d.geometry.KDTreeFlann(pcd)
    near: set[int] = set()
    for p_C in cl.p_HC:
        near.update(full_tree.search_radius_vector_3d(p_C, r + 2e-3)[1])
    pcd = pcd.select_by_index(sorted(near))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn))
    return np.asarray(pcd.points), np.asarray(pcd.normals), o3d.geometry.KDTreeFlann(pcd)


def _fit_point(cloud: tuple[np.ndarray, np.ndarray], idx, p_C, t_C, key: bool, params,
               options: CloudNormalOptions, z_loop) -> tuple[str, np.ndarray, np.ndarray]:
    """The two faces meeting at one CL point: k-means splits its neighbourhood ``idx`` of the
    window cloud ``(points, normals)`` into two clusters, each fitted by a RANSAC plane (or,
    at a key point or where the plane is rejected, a local quadric). Returns the fit's label,
    the normals (2, 3) and the cluster centroids (2, 3)."""
    pts, nrm = cloud
    seed, quadric_sigma = options.seed, options.quadric_sigma
    fitted_out, side_out = np.zeros((2, 3)), np.zeros((2, 3))
    labels = _kmeans_split(nrm[idx], seed)
    label = "quadric" if key else "plane"
    r = params.normal_search_radius
    for c in range(2):
        q = pts[idx[labels == c]]
        side_out[c] = q.mean(axis=0) if len(q) else p_C
        if len(q) < 6:
            fitted_out[c] = _principal(nrm[idx[labels == c]]) if len(q) else z_loop
            continue
        n_fit = None
        if not key:
            n_fit = _plane_normal(q, p_C, params.ransac_threshold, seed, 2 * quadric_sigma)
            if n_fit is None:  # not planar at this point after all: curved fit
                label = "quadric (plane rejected)"
        if n_fit is None:
            n0 = _principal(nrm[idx[labels == c]])
            n_fit = _quadric_normal(q, p_C, n0, t_C, quadric_sigma, 0.5 * r)
        fitted_out[c] = n_fit
    return label, fitted_out, side_out


def _group_and_sign(fitted: np.ndarray, side_pts: np.ndarray, cl: ClPath, z_loop: np.ndarray):
    """The two normals per point grouped consistently along the curve (the source's angle
    test), the inner side chosen (the group farther from the loop axis) and both signed out of
    the material: (n_wall (M, 3), n_face (M, 3), points where the source's centroid sign test
    disagrees)."""
    m = len(fitted)
    order = np.zeros(m, int)  # which of the two fitted normals is in group A
    ref = fitted[0, 0]
    for i in range(1, m):
        score = _fold(fitted[i] @ ref)
        order[i] = 0 if score[0] >= score[1] else 1
        ref = fitted[i, order[i]]
    rows = np.arange(m)
    group_a, group_b = fitted[rows, order], fitted[rows, 1 - order]
    side_a, side_b = side_pts[rows, order], side_pts[rows, 1 - order]
    if _fold(group_a @ z_loop).mean() <= _fold(group_b @ z_loop).mean():
        n_wall, n_face, wall_side, face_side = group_a, group_b, side_a, side_b
    else:
        n_wall, n_face, wall_side, face_side = group_b, group_a, side_b, side_a
    # sign: out of the material (away from the other face's points)
    flip = np.einsum("ij,ij->i", n_wall, face_side - cl.p_HC) > 0
    n_wall = np.where(flip[:, None], -n_wall, n_wall)
    flip_f = np.einsum("ij,ij->i", n_face, wall_side - cl.p_HC) > 0
    n_face = np.where(flip_f[:, None], -n_face, n_face)
    n_wall, n_face = _perpendicular_to_edge(n_wall, cl.t_H), _perpendicular_to_edge(n_face, cl.t_H)
    to_centroid = cl.p_HC.mean(axis=0) - cl.p_HC
    disagree = np.flatnonzero(~(np.einsum("ij,ij->i", n_wall, to_centroid) > 0))
    if disagree.size:
        log.info("window %d: the source's centroid sign test disagrees at %d point(s)",
                 cl.window_index, disagree.size)
    return n_wall, n_face, disagree


def inner_normals_from_mesh(
    mesh,
    cl: ClPath,
    *,
    params: ProcessParameters | None = None,
    sample_spacing: float = 0.3e-3,
    mesh_sigma: float = 0.5e-3,
    seed: int = 0,
) -> NormalEstimate:
    """Inner-side normals from a hub mesh in H (no scan needed).

    Args:
        mesh: ``trimesh.Trimesh`` in H [m] with outward face normals (watertight or at least
            consistently wound).
        cl: the window's CL points (H).
        sample_spacing: surface sampling spacing near the edge [m].
        mesh_sigma: Gaussian weight radius around the CL point [m].

    Raises:
        InputError: no mesh surface near a CL point (names window and point).
    """
    import trimesh

    params = params or ProcessParameters()
    r = params.normal_search_radius
    lo = cl.p_HC.min(axis=0) - r
    hi = cl.p_HC.max(axis=0) + r
    tri = mesh.triangles
    near = np.all((tri.max(axis=1) >= lo) & (tri.min(axis=1) <= hi), axis=1)
    faces = np.flatnonzero(near)
    if faces.size == 0:
        raise InputError(f"window {cl.window_index}: the mesh has no surface near the CL points")
    sub = mesh.submesh([faces], append=True)
    count = int(np.ceil(sub.area / sample_spacing**2))
    pts, fid = trimesh.sample.sample_surface(sub, count, seed=seed)
    nrm = sub.face_normals[fid]
    from scipy.spatial import cKDTree

    tree = cKDTree(pts)
    z_loop = loop_axis(cl.p_HC)
    m = len(cl.p_HC)
    n_wall = np.zeros((m, 3))
    n_face = np.zeros((m, 3))
    counts = np.zeros(m, int)
    import sklearn.cluster  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):  # see inner_normals_from_cloud
        for i, p_C in enumerate(cl.p_HC):
            idx = np.asarray(tree.query_ball_point(p_C, r))
            counts[i] = idx.size
            if idx.size < 10:
                raise InputError(f"window {cl.window_index}, CL point {i}: no mesh surface within "
                                 f"{r * 1e3:.1f} mm of {np.round(p_C * 1e3, 2).tolist()} mm")
            labels = _kmeans_split(nrm[idx], seed)
            w = np.exp(-0.5 * np.sum((pts[idx] - p_C) ** 2, axis=1) / mesh_sigma**2)
            means = []
            for c in range(2):
                sel = labels == c
                v = (nrm[idx[sel]] * w[sel, None]).sum(axis=0) if sel.any() else z_loop
                means.append(v / max(np.linalg.norm(v), 1e-300))
            wall = int(np.argmin([_fold(v @ z_loop) for v in means]))  # wall: ~perpendicular to Z
            n_wall[i], n_face[i] = means[wall], means[1 - wall]
    n_wall, n_face = _perpendicular_to_edge(n_wall, cl.t_H), _perpendicular_to_edge(n_face, cl.t_H)
    return NormalEstimate(cl.window_index, n_wall, n_face, ("mesh",) * m, counts,
                          np.zeros(0, int))
