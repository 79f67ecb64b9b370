"""Analytic window-like loops: rounded convex polygons on a gently curved hub face.

Used by tests, the benchmark and the tutorial as inputs whose geometry is known exactly
(straight edges, circular fillets of known radius), independent of any mesh.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rounded_polygon", "hub_like_window"]


def rounded_polygon(vertices_xy: np.ndarray, radii, n_points: int) -> np.ndarray:
    """A convex polygon with circular fillets, sampled at equal arc length.

    Args:
        vertices_xy: (K, 2) convex polygon corners, counter-clockwise [m].
        radii: scalar or (K,) fillet radius at each corner [m].
        n_points: number of samples (equal arc length, first one on edge 0's straight part).

    Returns:
        (n_points, 2) points, counter-clockwise, first point not repeated.
    """
    v = np.asarray(vertices_xy, float)
    k = len(v)
    r = np.broadcast_to(np.asarray(radii, float), (k,))
    pieces = []  # ("line", a, b) or ("arc", center, radius, phi0, dphi)
    tan_in = []
    tan_out = []
    centers = []
    for i in range(k):
        a, b, c = v[i - 1], v[i], v[(i + 1) % k]
        e1 = (b - a) / np.linalg.norm(b - a)
        e2 = (c - b) / np.linalg.norm(c - b)
        turn = np.arccos(np.clip(e1 @ e2, -1, 1))  # exterior angle
        d = r[i] * np.tan(turn / 2)
        tan_in.append(b - d * e1)
        tan_out.append(b + d * e2)
        nrm = np.array([-e1[1], e1[0]])  # left normal (interior for CCW)
        centers.append(tan_in[-1] + r[i] * nrm)
    for i in range(k):
        j = (i + 1) % k
        pieces.append(("line", tan_out[i], tan_in[j]))
        cj = centers[j]
        phi0 = np.arctan2(*(tan_in[j] - cj)[::-1])
        phi1 = np.arctan2(*(tan_out[j] - cj)[::-1])
        pieces.append(("arc", cj, r[j], phi0, (phi1 - phi0) % (2 * np.pi)))
    lengths = np.array([np.linalg.norm(p[2] - p[1]) if p[0] == "line" else p[2] * p[4]
                        for p in pieces])
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    s = np.linspace(0.0, cum[-1], n_points, endpoint=False)
    out = np.empty((n_points, 2))
    idx = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(pieces) - 1)
    for m, (si, pi) in enumerate(zip(s, idx, strict=True)):
        p = pieces[pi]
        t = si - cum[pi]
        if p[0] == "line":
            out[m] = p[1] + (p[2] - p[1]) * (t / max(lengths[pi], 1e-300))
        else:
            phi = p[3] + t / p[2]
            out[m] = p[1] + p[2] * np.array([np.cos(phi), np.sin(phi)])
    return out


def hub_like_window(
    kind: str = "large", n_points: int = 180, *, angle: float = 0.0, dome: float = 0.25
) -> np.ndarray:
    """A window-edge-like closed 3-D loop in a hub frame H [m].

    A rounded trapezoid between two spokes (large: r = 95..195 mm, fillets 6-14 mm; small:
    r = 120..185 mm, narrow, fillets 4-8 mm) on a conical front face z = -dome * (r - 0.1).

    Args:
        kind: "large" or "small".
        n_points: samples at (plan-view) equal arc length.
        angle: polar angle of the window centre [rad].
        dome: slope of the conical face (0 = flat).

    Returns:
        (n_points, 3) loop, counter-clockwise seen from +Z_H.
    """
    if kind == "large":
        r1, r2, a1, a2, radii = 0.095, 0.195, 0.30, 0.40, [0.006, 0.014, 0.014, 0.006]
    else:
        r1, r2, a1, a2, radii = 0.120, 0.185, 0.09, 0.13, [0.004, 0.008, 0.008, 0.004]
    pol = [(r1, -a1), (r2, -a2), (r2, a2), (r1, a1)]
    v = np.array([[r * np.cos(t + angle), r * np.sin(t + angle)] for r, t in pol])
    xy = rounded_polygon(v, radii, n_points)
    r = np.linalg.norm(xy, axis=1)
    return np.c_[xy, -dome * (r - 0.1)]
