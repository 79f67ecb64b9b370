"""The motion a controller executes between targets, sampled densely and solved analytically.

Between consecutive targets the controller moves linearly: the tool point on a straight line,
the orientation by slerp (MoveL / LIN / L). This module samples that motion every
``step`` of tool travel (relative to the hub), turns each sample into a flange pose and solves
it with the analytic OPW IK on the window's configuration branch, unwrapping every joint toward
its neighbour (no configuration flips, no 2*pi jumps: :meth:`CellKinematics.track`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from drakedeburr.plan.kinematics import CellKinematics

__all__ = ["DensePath", "dense_poses", "track_poses"]


@dataclass(frozen=True, eq=False)
class DensePath:
    """Dense samples of a piecewise-linear Cartesian motion.

    Attributes:
        X_HT: (N, 4, 4) tool poses in H [m].
        s: (N,) tool travel relative to the hub from the first sample [m].
        target_index: (K,) sample index of each target (first 0, last N-1).
        q: (N, 6) joints [rad] (NaN where unreachable).
        ok: (N,) bool reached inside the joint limits on the branch.
    """

    X_HT: np.ndarray
    s: np.ndarray
    target_index: np.ndarray
    q: np.ndarray
    ok: np.ndarray


def dense_poses(X_HT: np.ndarray, step: float = 1e-3, min_samples: int = 1
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Samples of the linear/slerp motion through target poses.

    Args:
        X_HT: (K, 4, 4) target tool poses [m], K >= 2.
        step: max tool travel between samples [m].
        min_samples: minimum number of sub-steps per segment (>= 1).

    Returns:
        X (N, 4, 4) dense poses, s (N,) travel [m], target_index (K,).
    """
    X_HT = np.asarray(X_HT, float)
    out_X, out_s, idx = [X_HT[0][None]], [np.zeros(1)], [0]
    s0 = 0.0
    for k in range(len(X_HT) - 1):
        p0, p1 = X_HT[k, :3, 3], X_HT[k + 1, :3, 3]
        length = float(np.linalg.norm(p1 - p0))
        rot = Rotation.from_matrix(X_HT[k:k + 2, :3, :3])
        angle = float((rot[0].inv() * rot[1]).magnitude())
        # orientation-only stretches still get samples (every ~0.01 rad)
        n = max(min_samples, int(np.ceil(length / step)), int(np.ceil(angle / 0.01)))
        f = np.linspace(0.0, 1.0, n + 1)[1:]
        X = np.zeros((n, 4, 4))
        X[:, :3, :3] = Slerp([0.0, 1.0], rot)(f).as_matrix()
        X[:, :3, 3] = (1 - f)[:, None] * p0 + f[:, None] * p1
        X[:, 3, 3] = 1.0
        out_X.append(X)
        out_s.append(s0 + f * length)
        s0 += length
        idx.append(idx[-1] + n)
    return np.concatenate(out_X), np.concatenate(out_s), np.asarray(idx)


def track_poses(kin: CellKinematics, X_HT_targets: np.ndarray, q_start: np.ndarray,
                step: float = 1e-3) -> DensePath:
    """Dense joints of the linear motion through targets on ``q_start``'s branch.

    Args:
        kin: cell kinematics.
        X_HT_targets: (K, 4, 4) target poses [m].
        q_start: (6,) joints at the first target [rad] (fixes branch and turns).
        step: tool travel between samples [m].
    """
    X, s, idx = dense_poses(X_HT_targets, step)
    q, ok = kin.track(kin.X_WF_from_X_HT(X), q_start)
    return DensePath(X_HT=X, s=s, target_index=idx, q=q, ok=ok)
