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

__all__ = ["segment_figures", "cl_metrics", "coefficient_of_variation", "point_chord_heights",
           "chord_edge_deviation"]

# samples per CL chord (ends included) read against the edge polyline
_CHORD_SAMPLES = 9


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


def _polyline_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) distance of each point ``q`` (n, 3) from the nearest of the segments a[j]-b[j]."""
    ab = b - a
    ll = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty(len(q))
    for i in range(0, len(q), 256):  # (256, m, 3) at a time
        d = q[i:i + 256, None, :] - a[None]
        t = np.clip(np.einsum("kij,ij->ki", d, ab) / ll, 0.0, 1.0)
        out[i:i + 256] = np.linalg.norm(d - t[..., None] * ab, axis=-1).min(axis=1)
    return out


def chord_edge_deviation(curve: EdgeCurve, u: np.ndarray) -> float:
    """How far the CL chords run from the real edge [m]: the larger of (a) the farthest edge
    point (the loop the fit came from, ``curve.p_data``) from the closed CL polyline and (b) the
    farthest point of a CL chord (ends and 7 inner samples each) from the closed edge polyline.

    Both sides: (a) is the chord height against the points (a tessellation corner the chords
    cut), (b) adds where the CL points themselves stand off the edge (the fit's own error, which
    the chord height against the fit does not see)."""
    u = np.asarray(u, float)
    c = curve.position(u)
    cn = np.roll(c, -1, axis=0)
    e = np.asarray(curve.p_data, float)
    en = np.roll(e, -1, axis=0)
    t = np.linspace(0.0, 1.0, _CHORD_SAMPLES)[:, None, None]
    samples = (c[None] + t * (cn - c)[None]).reshape(-1, 3)
    return float(max(_polyline_distance(e, c, cn).max(), _polyline_distance(samples, e, en).max()))


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
