"""Cell calibration from touched points (SPEC.md S2, seed 002).

A calibration tip on the flange touches known points of the worktable (or of the tool
holder); the robot reports the touched positions in its base frame W. The rigid transform
X_WT with p_W = X_WT p_T is the least-squares (Kabsch) fit, done by scipy's
``Rotation.align_vectors`` on the centred point sets. A systematic error that grows with the
distance (robot zero offset + geometry error, ~2 mm in the paper) is absorbed by a scale:
p_W = s R p_T + t (Umeyama). Residuals are reported before (rigid) and after (scaled) fitting.

Scale compensation (the paper's fix for its ~2 mm systematic error) is a
:class:`ScaleCompensation`: a model of how the cell distorts what it makes, with a single
operation, :meth:`ScaleCompensation.compensate_path`, that gives the model to generate the
path from. Its direction is fixed by how it was measured, never by the caller:

- from a **machined part** (:func:`fit_machined_contour`): the measured contour m of a part
  cut along a path generated from the nominal contour n fits m = c + s R (n - c); the part
  comes out ``scale`` times too large about the centre c, so the path is generated from
  c + R^T (n - c) / s (scaling the model by s instead doubles the error);
- from **touch points** (:meth:`CalibrationFit.scale_compensation`): the robot reports a
  point of the table s times too far from T's origin, so a point commanded at b is reached at
  b / s and the path is generated from s n (the model scaled by s, about T's origin).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from drakedeburr.errors import InputError

__all__ = ["CalibrationFit", "PivotFit", "ScaleCompensation", "fit_touch_points",
           "fit_machined_contour", "fit_pivot_tcp", "extrapolation_error", "calibrated_pose",
           "COMPENSATION_MODELS"]


@dataclass(frozen=True)
class CalibrationFit:
    """Result of :func:`fit_touch_points`.

    Attributes:
        X_WT: (4, 4) rigid transform of the target frame T (worktable / tool holder) in the
            robot base W [m] (from the rigid fit, or the rotation/translation of the scaled
            fit when ``scale`` was estimated).
        scale: estimated scale s (1.0 when not estimated).
        residuals_rigid: (N,) distances [m] between touched points and X_WT p_T, rigid fit.
        residuals_scaled: (N,) distances [m] after the scaled fit (= rigid when not estimated).
        n_points: number of touched points.
        p_T, p_W: the points fitted (for :func:`extrapolation_error`).
    """

    X_WT: np.ndarray
    scale: float
    residuals_rigid: np.ndarray
    residuals_scaled: np.ndarray
    n_points: int
    p_T: np.ndarray | None = None  # (N, 3) the nominal points fitted [m]
    p_W: np.ndarray | None = None  # (N, 3) the touched points [m]

    @property
    def rms_rigid(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_rigid ** 2)))

    @property
    def rms_scaled(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_scaled ** 2)))

    def scale_compensation(self) -> ScaleCompensation:
        """The scale as a compensation of paths in T (module docstring): the robot reaches
        a point commanded at b at b / s about T's origin; needs ``estimate_scale``."""
        if self.scale == 1.0:
            raise InputError("touch-point fit without a scale: fit with estimate_scale=True")
        return ScaleCompensation(linear=np.eye(3) / self.scale, offset=np.zeros(3),
                                 plane_normal=None, model="scale",
                                 deviations=self.residuals_rigid,
                                 residuals=self.residuals_scaled)


#: the maps :func:`fit_machined_contour` fits, in the contour's plane
COMPENSATION_MODELS = ("scale", "similarity", "affine")


@dataclass(frozen=True)
class ScaleCompensation:
    """How the cell distorts the part, and the one way to undo it (module docstring).

    A path generated from points p is made as m = L p + offset in the part frame; for a
    planar contour L acts in the contour's plane only (``plane_normal``), the height along
    the normal is left as it is. L is s I for the paper's "scale" model, s R (R about the
    normal) for "similarity", any 2 x 2 in-plane map for "affine" (a scale per direction).

    Attributes:
        linear: (3, 3) L (identity along ``plane_normal``).
        offset: (3,) [m] the shift of the map (``center`` is its fixed point).
        plane_normal: (3,) unit normal of the contour plane, or None (a 3-D map).
        model: "scale", "similarity" or "affine".
        deviations: (N,) [m] the measured error before compensation (signed distances of the
            measured points from the nominal contour, outside positive; for touch points the
            rigid-fit residuals).
        residuals: (N,) [m] what the fitted map leaves: the predicted error after
            compensation.
    """

    linear: np.ndarray
    offset: np.ndarray
    plane_normal: np.ndarray | None
    model: str
    deviations: np.ndarray
    residuals: np.ndarray

    def _plane(self) -> np.ndarray:
        from drakedeburr.frames.vectors import perpendicular_basis

        if self.plane_normal is None:
            return np.eye(3)
        return perpendicular_basis(self.plane_normal)[:, :2]

    @property
    def scale(self) -> float:
        """s: the made part's size over the path's (> 1: parts come out too large); for
        "affine" the mean scale sqrt(det) in the plane."""
        E = self._plane()
        return float(abs(np.linalg.det(E.T @ self.linear @ E)) ** (1.0 / E.shape[1]))

    @property
    def error_before(self) -> float:
        """Largest measured error [m] before compensation."""
        return float(np.max(np.abs(self.deviations)))

    @property
    def predicted_residual(self) -> float:
        """Largest error [m] predicted after compensation (what the map does not explain)."""
        return float(np.max(np.abs(self.residuals)))

    @property
    def center(self) -> np.ndarray:
        """(3,) the fixed point c of the map, m - c = L (p - c) [m], in the plane."""
        E = self._plane()
        A = np.eye(E.shape[1]) - E.T @ self.linear @ E
        if np.linalg.cond(A) > 1e9:
            raise InputError("scale compensation: the map has no fixed point (scale 1, no "
                             "rotation: the error is a pure shift)")
        return E @ np.linalg.solve(A, E.T @ self.offset)

    def compensate_path(self, nominal: np.ndarray) -> np.ndarray:
        """The points to generate the path from so that the cell makes ``nominal``.

        Args:
            nominal: (N, 3) the nominal part points (contour, model vertices) [m], in the
                frame the compensation was measured in.

        Returns:
            (N, 3) the compensated points L^-1 (nominal - offset) [m] (in the plane: the
            height along the normal stays).
        """
        p = np.asarray(nominal, float)
        if p.ndim != 2 or p.shape[1] != 3 or not np.all(np.isfinite(p)):
            raise InputError(f"compensate_path: expected finite (N, 3) points, got {p.shape}")
        inv = np.linalg.solve(self.linear, (p - self.offset).T).T
        if self.plane_normal is None:
            return inv
        n = self.plane_normal
        return inv - np.outer(inv @ n, n) + np.outer(p @ n, n)


def _check(p_T: np.ndarray, p_W: np.ndarray, min_separation: float, min_spread: float
           ) -> tuple[np.ndarray, np.ndarray]:
    p_T = np.asarray(p_T, float)
    p_W = np.asarray(p_W, float)
    if p_T.ndim != 2 or p_T.shape[1] != 3 or p_T.shape != p_W.shape:
        raise InputError(f"touch points: p_T {p_T.shape} and p_W {p_W.shape} must both be "
                         "(N, 3)")
    if p_T.shape[0] < 3:
        raise InputError(f"touch points: at least 3 are needed, got {p_T.shape[0]}")
    for name, p in (("p_T", p_T), ("p_W", p_W)):
        bad = np.flatnonzero(~np.all(np.isfinite(p), axis=1))
        if bad.size:
            raise InputError(f"touch points: {name} point {bad[0] + 1} is not finite")
        d = np.linalg.norm(p[:, None] - p[None], axis=-1) + np.eye(len(p)) * 1e9
        i, j = np.unravel_index(np.argmin(d), d.shape)
        if d[i, j] < min_separation:
            raise InputError(f"touch points: {name} points {min(i, j) + 1} and {max(i, j) + 1} "
                             f"are duplicates ({d[i, j] * 1e3:.3f} mm apart)")
    sv = np.linalg.svd(p_T - p_T.mean(0), compute_uv=False)
    if sv[1] < min_spread * np.sqrt(p_T.shape[0]):
        raise InputError("touch points: the nominal points are (nearly) collinear: the "
                         "rotation about their line is undetermined; touch a point off the line")
    return p_T, p_W


def fit_touch_points(p_T: np.ndarray, p_W: np.ndarray, estimate_scale: bool = False,
                     min_separation: float = 1e-3, min_spread: float = 1e-3) -> CalibrationFit:
    """Fit X_WT (and optionally a scale) to touched points.

    Args:
        p_T: (N, 3) nominal points in the target frame T (worktable / tool holder) [m].
        p_W: (N, 3) the same points as touched by the robot, in the robot base W [m].
        estimate_scale: also estimate s in p_W = s R p_T + t.
        min_separation: points closer than this are duplicates [m].
        min_spread: the points must spread at least this much off a line [m] (RMS).

    Returns:
        CalibrationFit with residuals before/after the scale.

    Raises:
        InputError: fewer than 3 points, duplicates, collinear or non-finite input.
    """
    p_T, p_W = _check(p_T, p_W, min_separation, min_spread)
    cT, cW = p_T.mean(0), p_W.mean(0)
    a, b = p_T - cT, p_W - cW
    rot, _ = Rotation.align_vectors(b, a)  # b ~ R a
    R = rot.as_matrix()
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = cW - R @ cT
    res_rigid = np.linalg.norm(p_W - (p_T @ R.T + X[:3, 3]), axis=1)
    s = 1.0
    res_scaled = res_rigid
    if estimate_scale:
        s = float(np.sum(b * (a @ R.T)) / np.sum(a * a))
        X[:3, 3] = cW - s * R @ cT
        res_scaled = np.linalg.norm(p_W - (s * p_T @ R.T + X[:3, 3]), axis=1)
    return CalibrationFit(X_WT=X, scale=s, residuals_rigid=res_rigid,
                          residuals_scaled=res_scaled, n_points=p_T.shape[0], p_T=p_T.copy(),
                          p_W=p_W.copy())


def calibrated_pose(fit: CalibrationFit, X_TH: np.ndarray) -> np.ndarray:
    """Pose in the robot base of something placed at X_TH on the calibrated target.

    E.g. the hub H clamped on the worktable T at its design pose X_TH: returns the X_WH a
    scenario should use (``X_WT @ X_TH``). The scale, if any, applies to the paths
    (:meth:`CalibrationFit.scale_compensation`), not to the rigid pose.

    Args:
        fit: calibration of T.
        X_TH: (4, 4) pose of H in T [m].

    Returns:
        (4, 4) X_WH [m].
    """
    X_TH = np.asarray(X_TH, float)
    if X_TH.shape != (4, 4):
        raise InputError(f"X_TH must be (4, 4), got {X_TH.shape}")
    return fit.X_WT @ X_TH


def _closest_on_polygon(x: np.ndarray, poly: np.ndarray):
    """For 2-D points x (M, 2) and a closed polygon (N, 2): (segment index, parameter in
    [0, 1], signed distance: + outside) of each point's closest point on the polygon."""
    import shapely

    a, b = poly, np.roll(poly, -1, 0)
    ab = b - a
    seg, par, dist = (np.empty(len(x), int), np.empty(len(x)), np.empty(len(x)))
    for k in range(0, len(x), 256):  # bounded memory: 256 x N segments at a time
        xk = x[k:k + 256]
        t = np.clip(np.einsum("mnk,nk->mn", xk[:, None] - a[None], ab)
                    / np.maximum(np.sum(ab * ab, 1), 1e-300), 0.0, 1.0)
        d = np.linalg.norm(xk[:, None] - (a[None] + t[..., None] * ab[None]), axis=-1)
        j = np.argmin(d, 1)
        seg[k:k + 256], par[k:k + 256] = j, t[np.arange(len(xk)), j]
        dist[k:k + 256] = d[np.arange(len(xk)), j]
    inside = shapely.contains_xy(shapely.Polygon(poly), x[:, 0], x[:, 1])
    return seg, par, np.where(inside, -dist, dist)


def _map_2d(a: np.ndarray, nu: np.ndarray, m: np.ndarray, model: str):
    """Least squares of nu . (A a + t - m) = 0 over t and A = s I ("scale"),
    [[p, -q], [q, p]] ("similarity") or any 2 x 2 ("affine"): returns (A, t)."""
    if model == "affine":
        cols = [nu[:, i] * a[:, j] for i in range(2) for j in range(2)]
    else:
        cols = [np.sum(nu * a, 1)]
        if model == "similarity":
            cols.append(np.sum(nu * np.column_stack([-a[:, 1], a[:, 0]]), 1))
    cols += [nu[:, 0], nu[:, 1]]
    M = np.column_stack(cols)
    sv = np.linalg.svd(M, compute_uv=False)
    if sv[-1] < 1e-9 * max(sv[0], 1e-12):
        raise InputError("machined contour: the contour's normals do not determine a scale "
                         "and a centre (all points on a line?)")
    x, *_ = np.linalg.lstsq(M, np.sum(nu * m, 1), rcond=None)
    if model == "affine":
        return x[:4].reshape(2, 2), x[-2:]
    q = x[1] if model == "similarity" else 0.0
    return np.array([[x[0], -q], [q, x[0]]]), x[-2:]


def fit_machined_contour(nominal: np.ndarray, measured: np.ndarray,
                         normal: np.ndarray = (0.0, 0.0, 1.0), model: str = "affine",
                         iterations: int = 20) -> ScaleCompensation:
    """Fit the cell's systematic error from a machined part (the paper's scale compensation).

    A part was cut along a path generated from the planar closed contour ``nominal`` (the
    part model, a polygon); ``measured`` are points measured on the machined edge (a scan or
    probe points, any number and spacing, same frame). Fitted: the map m = s R n + offset in
    the contour's plane (``model``: "scale" L = s I, the paper's; "similarity" L = s R with
    R about the normal; "affine" any in-plane L, a scale per direction) that puts the
    measured points on the mapped contour, by least squares on their distances to
    it (point-to-line ICP: the closest points and normals are updated each iteration, so a
    shift of several mm at a tight corner is not linearised away).

    Args:
        nominal: (N, 3) nominal closed contour in the part frame [m] (N >= 3, not a line).
        measured: (M, 3) points on the machined edge, same frame [m] (at least one more
            than the model's unknowns: 3, 4, 6).
        normal: (3,) normal of the contour plane.
        model: "scale", "similarity" or "affine" (:data:`COMPENSATION_MODELS`).
        iterations: at most this many closest-point updates.

    Returns:
        :class:`ScaleCompensation` with ``deviations`` = the measured points' signed
        distances from the nominal contour (outside positive) and ``residuals`` = those from
        the fitted contour (the predicted error after compensation); apply it with
        :meth:`ScaleCompensation.compensate_path`.

    Raises:
        InputError: shapes, non-finite values, too few points, or a contour whose normals do
            not determine the fit (e.g. a straight line).
    """
    from drakedeburr.frames.vectors import perpendicular_basis

    n_pts = np.asarray(nominal, float)
    m_pts = np.asarray(measured, float)
    for name, q in (("nominal", n_pts), ("measured", m_pts)):
        if q.ndim != 2 or q.shape[1] != 3:
            raise InputError(f"machined contour: {name} must be (N, 3), got {q.shape}")
        bad = np.flatnonzero(~np.all(np.isfinite(q), 1))
        if bad.size:
            raise InputError(f"machined contour: {name} point {bad[0] + 1} is not finite")
    if model not in COMPENSATION_MODELS:
        raise InputError(f"compensation model {model!r}: use one of "
                         + ", ".join(COMPENSATION_MODELS))
    need = {"scale": 4, "similarity": 5, "affine": 7}[model]
    if n_pts.shape[0] < 3 or m_pts.shape[0] < need:
        raise InputError(f"machined contour: at least 3 nominal and {need} measured points are "
                         f"needed, got {n_pts.shape[0]} and {m_pts.shape[0]}")
    B = perpendicular_basis(normal)
    a, m = n_pts @ B[:, :2], m_pts @ B[:, :2]
    ab = np.roll(a, -1, 0) - a
    sign = 1.0 if np.sum(a[:, 0] * np.roll(a[:, 1], -1) - np.roll(a[:, 0], -1) * a[:, 1]) > 0 \
        else -1.0
    A, t = np.eye(2), np.zeros(2)
    deviations = _closest_on_polygon(m, a)[2]
    for _ in range(max(1, iterations)):
        mapped = a @ A.T + t
        seg, par, _ = _closest_on_polygon(m, mapped)
        d = (np.roll(mapped, -1, 0) - mapped)[seg]
        nu = sign * np.column_stack([d[:, 1], -d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
        foot = a[seg] + par[:, None] * ab[seg]  # the same place on the nominal contour
        A_new, t_new = _map_2d(foot, nu, m, model)
        step = np.abs(A_new - A).max() + np.abs(t_new - t).max()
        A, t = A_new, t_new
        if step < 1e-12:
            break
    residuals = _closest_on_polygon(m, a @ A.T + t)[2]
    E = B[:, :2]
    L = E @ A @ E.T + np.outer(B[:, 2], B[:, 2])
    return ScaleCompensation(linear=L, offset=E @ t, plane_normal=B[:, 2].copy(), model=model,
                             deviations=deviations, residuals=residuals)


@dataclass(frozen=True)
class PivotFit:
    """The calibration tool's own TCP from the pivot (4-point) method.

    Attributes:
        p_FT: (3,) the tip in the flange frame [m].
        p_W: (3,) the fixed point the tip was held on, in the robot base [m].
        residuals: (N,) distances [m] of each pose's tip from that point.
    """

    p_FT: np.ndarray
    p_W: np.ndarray
    residuals: np.ndarray

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals ** 2)))


def fit_pivot_tcp(X_WF: np.ndarray, min_tilt: float = np.radians(15.0)) -> PivotFit:
    """TCP by the pivot (4-point) method: the tip held on one fixed point in N >= 4 flange
    orientations, R_i p_FT + p_i = p_W solved by linear least squares for p_FT and p_W.

    Args:
        X_WF: (N, 4, 4) flange poses in the robot base at the touches [m].
        min_tilt: the orientations must differ by at least this much [rad] (largest angle
            between any two), else the tip position along the flange axis is undetermined.

    Raises:
        InputError: fewer than 4 poses, non-finite, or orientations too alike.
    """
    X = np.asarray(X_WF, float)
    if X.ndim != 3 or X.shape[1:] != (4, 4) or X.shape[0] < 4:
        raise InputError(f"TCP pivot: at least 4 flange poses (N, 4, 4) are needed, got "
                         f"{X.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(X.reshape(len(X), -1)), 1))
    if bad.size:
        raise InputError(f"TCP pivot: pose {bad[0] + 1} is not finite")
    rots = Rotation.from_matrix(X[:, :3, :3])
    spread = max(float((rots[i].inv() * rots).magnitude().max()) for i in range(len(X)))
    if spread < min_tilt:
        raise InputError(f"TCP pivot: the tool orientations differ by at most "
                         f"{np.degrees(spread):.1f} deg; tilt the tool by at least "
                         f"{np.degrees(min_tilt):.0f} deg between touches of the point")
    A = np.concatenate([X[:, :3, :3], -np.broadcast_to(np.eye(3), (len(X), 3, 3))], axis=2)
    x, *_ = np.linalg.lstsq(A.reshape(-1, 6), -X[:, :3, 3].reshape(-1), rcond=None)
    tips = X[:, :3, :3] @ x[:3] + X[:, :3, 3]
    return PivotFit(p_FT=x[:3], p_W=x[3:], residuals=np.linalg.norm(tips - x[3:], axis=1))


def extrapolation_error(fit: CalibrationFit, p_T: np.ndarray) -> np.ndarray:
    """Predicted position error [m] of points placed through a touch-point calibration.

    Two parts, added: the fit's statistical error at each point (the touches' noise sigma,
    estimated from the residuals of a scaled fit with 3N - 7 degrees of freedom, through the
    linearised
    covariance of the rigid fit: sigma^2 (1/N + r^T-weighted rotation variance), growing with
    the distance r from the touches' centroid), and the systematic error that grows with that
    distance, |s - 1| |r|, with the scale s of a scaled fit of the same touches (robot zero and
    geometry error: the paper's ~2 mm). A point far outside the touched region is off by
    about |s - 1| times its distance.

    Args:
        fit: a :func:`fit_touch_points` result.
        p_T: (M, 3) points in T [m] (e.g. the corners of the part's bounding box).

    Returns:
        (M,) predicted errors [m].
    """
    if fit.p_T is None:
        raise InputError("extrapolation_error: the fit carries no touch points")
    q = np.asarray(p_T, float).reshape(-1, 3)
    a = fit.p_T - fit.p_T.mean(0)
    b = fit.p_W - fit.p_W.mean(0)
    R = fit.X_WT[:3, :3]
    s = float(np.sum(b * (a @ R.T)) / np.sum(a * a))  # the touches' scale
    n = len(a)
    sigma2 = float(np.sum((b - s * a @ R.T) ** 2)) / max(3 * n - 7, 1)  # noise, scale removed
    Minv = np.linalg.pinv(np.sum(a * a) * np.eye(3) - a.T @ a)
    r = q - fit.p_T.mean(0)
    var = np.empty(len(r))
    for i, ri in enumerate(r):
        K = np.array([[0, -ri[2], ri[1]], [ri[2], 0, -ri[0]], [-ri[1], ri[0], 0]])
        var[i] = sigma2 * (3.0 / n + np.trace(K @ Minv @ K.T))
    return np.sqrt(var) + abs(s - 1.0) * np.linalg.norm(r, axis=1)
