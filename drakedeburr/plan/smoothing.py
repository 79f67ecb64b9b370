"""Smoothing of the tool orientations found by the per-target IK.

Each target's IK is its own small program, so neighbouring solutions carry solver noise in the
free directions (axis inside the cone, spin): tiny in angle (1e-4 rad) but, over targets 1.5 mm
apart sampled every 0.75 mm, enough to zig-zag the wrist joints (joint accelerations of 1e5
rad/m^2 along the path, which the timing turns into crawling). The positions are exact and
stay; the orientations are smoothed along the window with a Gaussian kernel on unit quaternions
(sign-aligned, renormalised), and any axis pushed outside its cone is rotated back onto the
cone's boundary (minimal rotation). The joints then follow from the analytic IK on the
window's branch, and the dense clearance check re-verifies every sample.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation

__all__ = ["smooth_orientations"]


def smooth_orientations(X_HT: np.ndarray, cone_axis_H: np.ndarray, cone_half_angle: float,
                        sigma: float = 2.0, s: np.ndarray | None = None) -> np.ndarray:
    """Gaussian-smoothed orientations of a sequence of tool poses, positions kept.

    Args:
        X_HT: (M, 4, 4) tool poses in H [m].
        cone_axis_H: (M, 3) cone axes (tip -> spindle); cone_half_angle: [rad].
        sigma: kernel width (0 = no smoothing): in targets, or, when ``s`` is given, in the
            units of ``s``.
        s: (M,) arc length of the targets [m] (optional). CL points from the path stage are
            spaced unevenly (0.1 mm on fillets to 10 mm on straight stretches): a kernel in
            targets then smooths 0.2 mm on one stretch and 20 mm on the next, while the wrist
            feels the turning per unit length.

    Returns:
        (M, 4, 4) poses with smoothed rotations; every axis (-Z_T) within the cone.
    """
    X = np.array(X_HT, float)
    if sigma <= 0 or len(X) < 3:
        return X
    quat = Rotation.from_matrix(X[:, :3, :3]).as_quat()
    for i in range(1, len(quat)):  # one hemisphere, continuous
        if quat[i] @ quat[i - 1] < 0:
            quat[i] = -quat[i]
    if s is None:
        quat = gaussian_filter1d(quat, sigma, axis=0, mode="nearest")
    else:
        s = np.asarray(s, float)
        w = np.exp(-0.5 * ((s[:, None] - s[None, :]) / sigma) ** 2)
        quat = (w @ quat) / np.sum(w, axis=1, keepdims=True)
    R = Rotation.from_quat(quat / np.linalg.norm(quat, axis=1, keepdims=True)).as_matrix()
    # back into the cone where smoothing pushed an axis out
    c = np.asarray(cone_axis_H, float)
    a = -R[:, :, 2]
    ang = np.arccos(np.clip(np.sum(a * c, axis=1), -1.0, 1.0))
    limit = cone_half_angle * (1 - 1e-6)
    for i in np.flatnonzero(ang > limit):
        k = np.cross(a[i], c[i])
        k /= np.linalg.norm(k)
        R[i] = Rotation.from_rotvec(k * (ang[i] - limit)).as_matrix() @ R[i]
    X[:, :3, :3] = R
    return X
