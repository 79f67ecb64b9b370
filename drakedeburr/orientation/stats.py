"""Per-window statistics like the source's Tab. 3-6, plus what the robot feels: the turning of
the tool axis in the hub/world frame per millimetre of path."""

from __future__ import annotations

import numpy as np

__all__ = ["angle_statistics", "axis_turning"]


def _describe(v: np.ndarray) -> dict[str, float]:
    mean = float(np.mean(v))
    var = float(np.var(v))
    return {
        "max": float(np.max(v)),
        "min": float(np.min(v)),
        "mean": mean,
        "variance": var,  # population variance [rad^2]
        "cv": float(np.sqrt(var) / abs(mean)) if mean != 0 else float("inf"),
    }


def axis_turning(p_HC: np.ndarray, zT_H: np.ndarray, closed: bool = True) -> np.ndarray:
    """Turning rate of the tool axis between consecutive CL points.

    Args:
        p_HC: (M, 3) CL points [m].
        zT_H: (M, 3) unit tool axes.
        closed: include the segment from the last point back to the first.

    Returns:
        (K,) angle between consecutive axes divided by the chord [rad/m].
    """
    i = np.arange(len(p_HC) if closed else len(p_HC) - 1)
    j = (i + 1) % len(p_HC)
    d = np.linalg.norm(p_HC[j] - p_HC[i], axis=1)
    cosang = np.clip(np.einsum("ij,ij->i", zT_H[i], zT_H[j]), -1.0, 1.0)
    cross = np.linalg.norm(np.cross(zT_H[i], zT_H[j]), axis=1)
    return np.arctan2(cross, cosang) / d


def angle_statistics(theta_A: np.ndarray, theta_B: np.ndarray, p_HC: np.ndarray,
                     zT_H: np.ndarray) -> dict:
    """Tab. 3-6 figures for theta_A and theta_B [rad] and the axis turning [rad/mm, deg/mm].

    Returns:
        {"theta_A": {max, min, mean, variance, cv}, "theta_B": {...},
         "axis_turn_rad_per_mm": {max, mean, rms}, "axis_turn_deg_per_mm": {max, mean, rms},
         "axis_turn_total_deg": total turning around the loop}
    """
    rate = axis_turning(p_HC, zT_H) * 1e-3  # rad/mm
    per_mm = {"max": float(rate.max()), "mean": float(rate.mean()),
              "rms": float(np.sqrt(np.mean(rate**2)))}
    i = np.arange(len(p_HC))
    d = np.linalg.norm(p_HC[(i + 1) % len(p_HC)] - p_HC[i], axis=1) * 1e3
    return {
        "theta_A": _describe(np.asarray(theta_A)),
        "theta_B": _describe(np.asarray(theta_B)),
        "axis_turn_rad_per_mm": per_mm,
        "axis_turn_deg_per_mm": {k: float(np.degrees(v)) for k, v in per_mm.items()},
        "axis_turn_total_deg": float(np.degrees((rate * d).sum())),
    }
