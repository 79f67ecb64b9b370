"""Cell calibration from touched points (SPEC.md S2, seed 002).

A calibration tip on the flange touches known points of the worktable (or of the tool
holder); the robot reports the touched positions in its base frame W. The rigid transform
X_WT with p_W = X_WT p_T is the least-squares (Kabsch) fit, done by scipy's
``Rotation.align_vectors`` on the centred point sets. A systematic error that grows with the
distance (robot zero offset + geometry error, ~2 mm in the paper) is absorbed by a scale:
p_W = s R p_T + t (Umeyama); the paper removes it by scaling the part model before path
generation. Residuals are reported before (rigid) and after (scaled) fitting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from drakedeburr.errors import InputError

__all__ = ["CalibrationFit", "fit_touch_points", "calibrated_pose", "scale_about"]


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
    """

    X_WT: np.ndarray
    scale: float
    residuals_rigid: np.ndarray
    residuals_scaled: np.ndarray
    n_points: int

    @property
    def rms_rigid(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_rigid ** 2)))

    @property
    def rms_scaled(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_scaled ** 2)))


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
                          residuals_scaled=res_scaled, n_points=p_T.shape[0])


def scale_about(p: np.ndarray, scale: float, center: np.ndarray = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Scale points (e.g. a part model) about a centre: the paper's systematic-error fix.

    Args:
        p: (N, 3) points [m].
        scale: factor (from :attr:`CalibrationFit.scale`).
        center: (3,) fixed point [m].
    """
    c = np.asarray(center, float)
    return (np.asarray(p, float) - c) * scale + c


def calibrated_pose(fit: CalibrationFit, X_TH: np.ndarray) -> np.ndarray:
    """Pose in the robot base of something placed at X_TH on the calibrated target.

    E.g. the hub H clamped on the worktable T at its design pose X_TH: returns the X_WH a
    scenario should use (``X_WT @ X_TH``). The scale, if any, applies to the model points
    (:func:`scale_about`), not to the rigid pose.

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
