"""Hub-pose registration: where is the hub, exactly? (source §3.5 "vision re-targeting").

The cell's vision gives the hub only roughly (centre, model, angular position of the windows).
A scan of the clamped hub (partial, noisy, in the world frame W) is registered to the hub
model (a mesh in H) with open3d:

1. global, feature based: FPFH features on voxel-filtered clouds, RANSAC on feature
   correspondences (``registration_ransac_based_on_feature_matching``). A hub is n-fold
   symmetric about its axis, so the global result is snapped to the symmetric equivalent
   closest to the prior pose (the vision's angular position is good to better than pi/n);
2. candidates around the prior as well (turns about the hub axis across +-pi/n every
   ``start_step``), because RANSAC is random and a symmetric part gives it several equally good
   answers;
3. each candidate refined by coarse point-to-plane ICP (scan onto the model, whose normals are
   exact), the best plausible one (turn within the window, hub axis not tilted) refined by fine
   point-to-plane ICP;
4. acceptance: share of scan points within ``registration_inlier_distance`` of the posed mesh
   (fitness) and the RMS point-to-mesh distance of those inliers, both measured exactly on the
   mesh with open3d's RaycastingScene. A poor fit (e.g. the wrong hub model) is refused:
   ``RegistrationResult.accepted`` is False with a message, and :meth:`RegistrationResult.require`
   raises :class:`RegistrationRefused`.

The CL points and tool paths live in H; they follow the registered pose through ``X_WH``
(:func:`points_in_world`, ``ToolPath.with_hub_pose``).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from drakedeburr.config import Tolerances, default_tolerances
from drakedeburr.errors import DrakeDeburrError, InputError
from drakedeburr.hub.types import ScanCloud

__all__ = ["RegistrationOptions", "RegistrationResult", "RegistrationRefused", "register_hub",
           "points_in_world", "turn_about_hub_axis"]

log = logging.getLogger(__name__)


class RegistrationRefused(DrakeDeburrError):
    """The scan does not fit the hub model well enough to machine on it."""


@dataclass(frozen=True)
class RegistrationOptions:
    """Registration settings (lengths in m).

    Attributes:
        symmetry_order: n of the hub's n-fold symmetry about +Z_H (number of identical window
            groups); 1 = no symmetry assumed.
        prior_turn_range: [rad] the vision's angular uncertainty; default pi / symmetry_order.
        feature_voxel: voxel size of the FPFH / RANSAC stage.
        global_voxel: voxel size of the coarse ICP stage.
        fine_voxel: voxel size of the fine ICP stage.
        model_spacing: sampling spacing of the model mesh (only the part near the scan).
        start_step: [rad] spacing of the ICP starts over the prior turn range (in addition to
            the global result); smaller than the turn an ICP recovers from (about half a
            window's angular width).
        roi_radii: optional (r_min, r_max) [m]: use only scan and model points at these
            distances from the hub axis (e.g. the window annulus: the axisymmetric rim says
            nothing about the turn and only costs time).
        ransac_iterations: RANSAC iteration cap of the global stage.
        max_tilt: [rad] largest angle between the hub axis of a candidate and of the prior (a
            clamped hub is never upside down; a flat, mirror-symmetric part could fit so).
        seed: RANSAC / sampling seed.
    """

    symmetry_order: int = 1
    prior_turn_range: float | None = None
    feature_voxel: float = 6.0e-3
    global_voxel: float = 3.0e-3
    fine_voxel: float = 1.0e-3
    model_spacing: float = 0.7e-3
    start_step: float = np.radians(4.0)
    roi_radii: tuple[float, float] | None = None
    ransac_iterations: int = 5000
    max_tilt: float = np.radians(5.0)
    seed: int = 0


@dataclass(frozen=True, eq=False)
class RegistrationResult:
    """Registered hub pose.

    Attributes:
        X_WH: hub pose in the scan's frame W.
        accepted: fit passed the thresholds.
        fitness: share of scan points within the inlier distance of the posed mesh [-].
        rmse: RMS distance of those inliers to the mesh [m].
        message: verdict, with the figures and thresholds.
        turn_from_prior: [rad] rotation about Z_H between the prior and the result.
        seconds: wall time [s].
        candidates: (fitness, rmse, label) of every refined candidate.
    """

    X_WH: RigidTransform
    accepted: bool
    fitness: float
    rmse: float
    message: str
    turn_from_prior: float
    seconds: float
    candidates: list = field(default_factory=list)

    def require(self) -> RegistrationResult:
        """Return self if accepted, else raise RegistrationRefused with the message."""
        if not self.accepted:
            raise RegistrationRefused(self.message)
        return self


def turn_about_hub_axis(X_WH: RigidTransform, angle: float) -> RigidTransform:
    """X_WH composed with a rotation by ``angle`` [rad] about +Z_H."""
    return X_WH.multiply(RigidTransform(RotationMatrix.MakeZRotation(angle), np.zeros(3)))


def points_in_world(X_WH: RigidTransform, p_H: np.ndarray) -> np.ndarray:
    """(N, 3) points in H -> (N, 3) in W."""
    return X_WH.multiply(np.asarray(p_H, float).T).T


def _cloud(p, normals=None):
    import open3d as o3d

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(p, float)))
    if normals is not None:
        pc.normals = o3d.utility.Vector3dVector(np.asarray(normals, float))
    return pc


def _fpfh(pc, voxel):
    import open3d as o3d

    pc.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    return o3d.pipelines.registration.compute_fpfh_feature(
        pc, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))


def _z_turn(R_a: np.ndarray, R_b: np.ndarray) -> float:
    """Angle [rad] of R_a^T R_b about its z axis (the hub axis), in (-pi, pi]."""
    R = R_a.T @ R_b
    return float(np.arctan2(R[1, 0], R[0, 0]))


def register_hub(
    scan: ScanCloud,
    mesh,
    X_WH_prior: RigidTransform | None = None,
    *,
    options: RegistrationOptions = RegistrationOptions(),
    tolerances: Tolerances | None = None,
) -> RegistrationResult:
    """Register a scan (in W) to the hub mesh (in H).

    Args:
        scan: points ``p_S`` in the cell frame W [m] (partial, noisy).
        mesh: ``trimesh.Trimesh`` hub model in H [m].
        X_WH_prior: the vision's rough hub pose (default identity).
        options: see RegistrationOptions.
        tolerances: acceptance thresholds (registration_* fields); default tolerances.

    Returns:
        RegistrationResult (check ``accepted`` or call ``require()``).
    """
    t0 = time.perf_counter()
    tolerances = tolerances or default_tolerances()
    p_W = np.asarray(scan.p_S, float)
    if p_W.ndim != 2 or p_W.shape[1] != 3 or len(p_W) < 100:
        raise InputError(f"{scan.source or 'scan'}: need an (N>=100, 3) cloud, got {p_W.shape}")
    X0 = RigidTransform() if X_WH_prior is None else RigidTransform(X_WH_prior)
    n_sym = max(int(options.symmetry_order), 1)
    turn_range = options.prior_turn_range if options.prior_turn_range is not None else np.pi / n_sym
    scan_pc, model = _clouds(scan, p_W, mesh, X0, options)
    starts = _starts(scan_pc, model, X0, n_sym, turn_range, options)
    scan_c = scan_pc.voxel_down_sample(options.global_voxel)
    model_c = model.voxel_down_sample(options.global_voxel)
    # coarse: point-to-plane ICP of the scan onto the model (exact normals) from every start
    cands = []
    for label, X in starts:
        r = _icp(scan_c, model_c, X.inverse().GetAsMatrix4(), 2.0 * options.global_voxel, 30)
        cands.append((float(r.fitness), float(r.inlier_rmse), label,
                      RigidTransform(np.linalg.inv(r.transformation))))
    X0_R = X0.rotation().matrix()

    def plausible(X: RigidTransform) -> bool:
        """Within the vision's turn window and hub axis within max_tilt of the prior's."""
        R = X.rotation().matrix()
        tilt = np.arccos(np.clip(R[:, 2] @ X0_R[:, 2], -1.0, 1.0))
        return tilt <= options.max_tilt and abs(_z_turn(X0_R, R)) <= turn_range + 1e-3

    pool = [c for c in cands if plausible(c[3])]
    if not pool:
        return RegistrationResult(
            X0, False, 0.0, float("inf"),
            f"{scan.source or 'scan'}: registration REFUSED: no candidate pose within "
            f"{np.degrees(turn_range):.1f} deg turn and {np.degrees(options.max_tilt):.1f} deg "
            "axis tilt of the prior", 0.0, time.perf_counter() - t0,
            [(c[0], c[1], c[2]) for c in cands])
    _, _, label, X = max(pool, key=lambda c: (round(c[0], 3), -c[1]))
    # fine: point-to-plane ICP at the fine voxel size, shrinking the correspondence distance
    scan_f = scan_pc.voxel_down_sample(options.fine_voxel)
    model_f = model.voxel_down_sample(options.fine_voxel)
    T = X.inverse().GetAsMatrix4()
    for dist in (4 * options.fine_voxel, 2 * options.fine_voxel, options.fine_voxel):
        T = _icp(scan_f, model_f, T, dist, 60).transformation
    X = RigidTransform(np.linalg.inv(T))
    fit, rmse = _score(mesh, np.asarray(scan_pc.points), X,
                       tolerances.registration_inlier_distance)
    turn = _z_turn(X0.rotation().matrix(), X.rotation().matrix())
    ok = fit >= tolerances.registration_fitness_min and rmse <= tolerances.registration_rmse_max
    verdict = "accepted" if ok else "REFUSED (wrong hub model, or a poor scan?)"
    message = (f"{scan.source or 'scan'}: registration {verdict}: fitness {fit:.3f} (min "
               f"{tolerances.registration_fitness_min}), inlier RMS {rmse * 1e3:.3f} mm (max "
               f"{tolerances.registration_rmse_max * 1e3:.3f} mm), turn from prior "
               f"{np.degrees(turn):+.3f} deg, best start {label}")
    rpy = RollPitchYaw(X.rotation()).vector()
    log.info("%s; X_WH xyz %s mm rpy %s deg", message, np.round(X.translation() * 1e3, 3),
             np.round(np.degrees(rpy), 3))
    return RegistrationResult(X, ok, fit, rmse, message, turn, time.perf_counter() - t0,
                              [(c[0], c[1], c[2]) for c in cands])


def _clouds(scan: ScanCloud, p_W: np.ndarray, mesh, X0: RigidTransform,
            options: RegistrationOptions):
    """(scan cloud in W, optionally cut to the region of interest; model cloud in H: samples
    with exact face normals near the scanned region)."""
    import trimesh

    p_Hprior = X0.inverse().multiply(p_W.T).T
    keep = np.ones(len(p_W), bool)
    if options.roi_radii is not None:
        rad = np.hypot(p_Hprior[:, 0], p_Hprior[:, 1])
        keep = (rad >= options.roi_radii[0]) & (rad <= options.roi_radii[1])
        if keep.sum() < 100:
            raise InputError(f"{scan.source or 'scan'}: fewer than 100 points inside the region "
                             f"of interest r = {options.roi_radii} m")
    scan_pc = _cloud(p_W[keep])
    margin = 0.02
    lo = p_Hprior[keep].min(axis=0) - margin
    hi = p_Hprior[keep].max(axis=0) + margin
    tri = np.asarray(mesh.triangles)
    faces = np.flatnonzero(np.all((tri.max(axis=1) >= lo) & (tri.min(axis=1) <= hi), axis=1))
    sub = mesh.submesh([faces], append=True)
    count = int(np.ceil(sub.area / options.model_spacing**2))
    p_H, fid = trimesh.sample.sample_surface(sub, count, seed=options.seed)
    n_H = sub.face_normals[fid]
    if options.roi_radii is not None:
        rad = np.hypot(p_H[:, 0], p_H[:, 1])
        sel = (rad >= options.roi_radii[0] - margin) & (rad <= options.roi_radii[1] + margin)
        p_H, n_H = p_H[sel], n_H[sel]
    return scan_pc, _cloud(p_H, n_H)


def _starts(scan_pc, model, X0: RigidTransform, n_sym: int, turn_range: float,
            options: RegistrationOptions) -> list[tuple[str, RigidTransform]]:
    """Candidate starts (as X_WH): the global feature-based result snapped to the symmetric
    equivalent nearest the prior, and turns about the hub axis around the prior."""
    import open3d as o3d

    reg = o3d.pipelines.registration
    starts: list[tuple[str, RigidTransform]] = []
    try:  # global, feature based
        fv = options.feature_voxel
        src_g, tgt_g = model.voxel_down_sample(fv), scan_pc.voxel_down_sample(fv)
        f_src, f_tgt = _fpfh(src_g, fv), _fpfh(tgt_g, fv)
        o3d.utility.random.seed(options.seed)
        glob = reg.registration_ransac_based_on_feature_matching(
            src_g, tgt_g, f_src, f_tgt, True, 1.5 * fv,
            reg.TransformationEstimationPointToPoint(False), 3,
            [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9),
             reg.CorrespondenceCheckerBasedOnDistance(1.5 * fv)],
            reg.RANSACConvergenceCriteria(options.ransac_iterations, 0.999))
        X_g = RigidTransform(glob.transformation)
        best = min(range(n_sym), key=lambda k: abs(_z_turn(
            X0.rotation().matrix(), turn_about_hub_axis(X_g, 2 * np.pi * k / n_sym)
            .rotation().matrix())))
        starts.append(("global", turn_about_hub_axis(X_g, 2 * np.pi * best / n_sym)))
    except RuntimeError as exc:  # pragma: no cover - open3d failure is reported, not fatal
        log.warning("global registration failed: %s", exc)
    n_starts = max(int(np.ceil(2 * turn_range / options.start_step)) + 1, 1)
    for phi in np.linspace(-turn_range, turn_range, n_starts):
        starts.append((f"prior{np.degrees(phi):+.1f}deg", turn_about_hub_axis(X0, float(phi))))
    return starts


def _icp(source, target, X_HW: np.ndarray, dist: float, iters: int):
    import open3d as o3d

    reg = o3d.pipelines.registration
    return reg.registration_icp(source, target, dist, X_HW,
                                reg.TransformationEstimationPointToPlane(),
                                reg.ICPConvergenceCriteria(1e-9, 1e-9, iters))


def _score(mesh, scan_all: np.ndarray, X_WH: RigidTransform, thr: float) -> tuple[float, float]:
    """(fitness, inlier RMS [m]) of the scan against the posed mesh (exact distances)."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)),
                        o3d.core.Tensor(np.asarray(mesh.faces, np.uint32)))
    q_H = X_WH.inverse().multiply(scan_all.T).T.astype(np.float32)
    d = scene.compute_distance(o3d.core.Tensor(q_H)).numpy().astype(float)
    inl = d <= thr
    fit = float(inl.mean())
    rmse = float(np.sqrt(np.mean(d[inl] ** 2))) if inl.any() else float("inf")
    return fit, rmse
