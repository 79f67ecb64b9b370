"""Two idioms on unit vectors, written once: the angle between directions, and a right-handed
basis around a direction."""

from __future__ import annotations

import numpy as np

__all__ = ["angle_between", "perpendicular_basis", "inverse_transform"]


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle [rad] between unit vectors ``a`` and ``b`` (..., 3), broadcast: (...,)."""
    c = np.sum(np.asarray(a, float) * np.asarray(b, float), axis=-1)
    return np.arccos(np.clip(c, -1.0, 1.0))


def perpendicular_basis(z: np.ndarray) -> np.ndarray:
    """(3, 3) right-handed basis with columns [e1, e2, z/|z|]: e1, e2 unit and orthogonal to
    ``z`` (3,); e1 = z x X (or z x Y when z is within ~26 deg of X), so the choice is the
    same for the same ``z``."""
    z = np.asarray(z, float) / np.linalg.norm(z)
    h = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(z, h)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(z, e1), z], axis=1)


def inverse_transform(X: np.ndarray) -> np.ndarray:
    """Inverse of (..., 4, 4) rigid transforms (transpose and back-rotated translation)."""
    X = np.asarray(X, float)
    out = np.zeros_like(X)
    Rt = np.swapaxes(X[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, X[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out
