"""Quality figures of a set of CL points on a closed edge curve (source §3.1, eq. 12).

All segments are taken on the *closed* loop: point M-1 connects back to point 0.

Two uniformity figures are given:
    ``cv``: coefficient of variation sigma/mu of the neighbour distances (chord lengths between
        consecutive CL points), the reading of eq. (12) in SPEC.md.
    ``cv_pairwise``: sigma/mu of the distances between *all* pairs of CL points. The source
        says "点对之间距离" (distances between point pairs) and its isoparametric points score
        c_v = 0.54-0.55, which equally spaced points can only score on the all-pairs reading
        (on the neighbour reading they score ~0). We report both.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist

from drakedeburr.path.edge_curve import EdgeCurve

__all__ = ["segment_figures", "cl_metrics", "coefficient_of_variation", "point_chord_heights"]


def coefficient_of_variation(d: np.ndarray) -> float:
    """sigma / mu of a sample (population standard deviation), eq. (12)."""
    d = np.asarray(d, float)
    mu = d.mean()
    return float(d.std() / mu) if mu > 0 else 0.0


def segment_figures(curve: EdgeCurve, u: np.ndarray) -> dict[str, np.ndarray]:
    """Per-segment chord length, true and circle-approximated chord height, arc length.

    Args:
        curve: the fitted edge.
        u: (M,) increasing parameters in [0, 1) of the CL points.

    Returns:
        dict of (M,) arrays [m]: ``chord``, ``chord_height``, ``chord_height_circle``, ``arc``;
        entry i is the segment from point i to point i+1 (the last one wraps to point 0).
    """
    u = np.asarray(u, float)
    u_next = np.roll(u, -1)
    u_next[-1] += 1.0
    return {
        "chord": np.atleast_1d(curve.chord_length(u, u_next)),
        "chord_height": curve.chord_height(u, u_next),
        "chord_height_circle": curve.chord_height_circle(u, u_next),
        "arc": np.atleast_1d(curve.arc_length(u, u_next)),
    }


def point_chord_heights(curve: EdgeCurve, u: np.ndarray) -> np.ndarray:
    """(M,) chord height of each CL segment against the fitted points themselves (the edge
    samples the loop came from, not the fit): the largest distance of a point whose parameter
    lies between the segment's ends from the line through its chord [m] (0 without one)."""
    u = np.asarray(u, float)
    a = curve.position(u)
    b = np.roll(a, -1, axis=0)
    k = (np.searchsorted(u, curve.u_data, side="right") - 1) % len(u)
    ab = b[k] - a[k]
    ab /= np.maximum(np.linalg.norm(ab, axis=1, keepdims=True), 1e-300)
    dv = curve.p_data - a[k]
    d = np.linalg.norm(dv - np.einsum("ij,ij->i", dv, ab)[:, None] * ab, axis=1)
    out = np.zeros(len(u))
    np.maximum.at(out, k, d)
    return out


def cl_metrics(curve: EdgeCurve, u: np.ndarray) -> dict[str, float]:
    """The figures of the source's Tab. 1-2 plus the thresholds' checks.

    Returns:
        count, cv, cv_pairwise, max_chord_height_m (true, on the fitted curve),
        max_chord_height_circle_m (eq. 2), max_chord_length_m, min_chord_length_m,
        mean_chord_length_m, max_chord_height_points_m (against the fitted points themselves,
        :func:`point_chord_heights`: what verify's ``cl_chord_error`` reads).
    """
    seg = segment_figures(curve, u)
    p = curve.position(np.asarray(u, float))
    return {
        "count": int(len(u)),
        "cv": coefficient_of_variation(seg["chord"]),
        "cv_pairwise": coefficient_of_variation(pdist(p)),
        "max_chord_height_m": float(seg["chord_height"].max()),
        "max_chord_height_circle_m": float(seg["chord_height_circle"].max()),
        "max_chord_length_m": float(seg["chord"].max()),
        "min_chord_length_m": float(seg["chord"].min()),
        "mean_chord_length_m": float(seg["chord"].mean()),
        "max_chord_height_points_m": float(point_chord_heights(curve, u).max()),
    }
