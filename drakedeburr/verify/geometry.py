"""Geometry the verifier computes for itself: distances of points to segments and loops,
interpolated local frames, exact extremes of the cubic Hermite joint trajectory, and the slow
stretches of a cut. Pure numpy/scipy, no planner code (the verifier re-derives)."""

from __future__ import annotations

import numpy as np

__all__ = ["slow_stretches", "binding_limit", "point_segment", "closed_polyline_distance",
           "lerp_frames", "spline_extremes"]


def slow_stretches(inside: np.ndarray, ds: np.ndarray, v_mid: np.ndarray) -> list[dict]:
    """The stretches of one window's cut outside the speed band, in order: their intervals
    (``a``..``b``-1, between samples ``a`` and ``b``), where they lie (``from_m``/``to_m``: tool
    travel from the cut's start), the slowest speed (``min_mps``), and whether the stretch
    touches the cut's start or end (``at``: "start"/"end", where the tool starts or stops at
    rest) or lies inside it.

    ``inside`` (M,) marks the intervals between the M + 1 samples that are in the band; ``ds``
    and ``v_mid`` are their lengths and mid speeds.
    """
    run = np.concatenate([[0.0], np.cumsum(ds)])
    out = np.diff(np.concatenate([[0], (~inside).astype(int), [0]]))
    starts, ends = np.flatnonzero(out == 1), np.flatnonzero(out == -1)
    return [{"a": int(a), "b": int(b), "from_m": float(run[a]), "to_m": float(run[b]),
             "min_mps": float(v_mid[a:b].min()),
             "at": "start" if a == 0 else "end" if b == len(inside) else "inside"}
            for a, b in zip(starts, ends, strict=True)]


def binding_limit(ratios: np.ndarray, names: list[tuple[str, str]]) -> dict:
    """The limit nearest to binding over a set of samples: ``ratios`` (n, L) value/limit per
    sample and limit, ``names`` (L,) (what, kind) -> {"joint", "limit", "ratio"}."""
    peak = ratios.max(axis=0)
    k = int(np.argmax(peak))
    return {"joint": names[k][0], "limit": names[k][1], "ratio": float(peak[k])}


def point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 256):
    """Distance of points to a set of segments.

    Args:
        p: (N, 3) points. a, b: (S, 3) segment ends.

    Returns:
        (d (N,), index of the closest segment (N,), fraction along it (N,)).
    """
    d_out = np.empty(len(p))
    i_out = np.empty(len(p), int)
    f_out = np.empty(len(p))
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    for s in range(0, len(p), chunk):
        pc = p[s:s + chunk]
        ap = pc[:, None, :] - a[None]
        f = np.clip(np.einsum("nsk,sk->ns", ap, ab) / L2, 0.0, 1.0)
        d = np.linalg.norm(ap - f[..., None] * ab[None], axis=2)
        k = d.argmin(axis=1)
        r = np.arange(len(pc))
        d_out[s:s + chunk], i_out[s:s + chunk], f_out[s:s + chunk] = d[r, k], k, f[r, k]
    return d_out, i_out, f_out


def closed_polyline_distance(p: np.ndarray, loop: np.ndarray, tree=None):
    """Distance of points (N, 3) to a closed polyline (M, 3), exact, via its nearest vertices.

    Returns (d (N,), closest point (N, 3)).
    """
    from scipy.spatial import cKDTree

    tree = tree or cKDTree(loop)
    m = len(loop)
    _, idx = tree.query(p, k=min(4, m))
    idx = np.atleast_2d(idx)
    best = np.full(len(p), np.inf)
    best_pt = np.zeros_like(p)
    for col in range(idx.shape[1]):
        for off in (-1, 0):
            i0 = (idx[:, col] + off) % m
            a, b = loop[i0], loop[(i0 + 1) % m]
            ab = b - a
            f = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(
                np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
            c = a + f[:, None] * ab
            d = np.linalg.norm(p - c, axis=1)
            better = d < best
            best[better] = d[better]
            best_pt[better] = c[better]
    return best, best_pt


def lerp_frames(R0: np.ndarray, R1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Local frames [N, T, B] between CL points: T and N interpolated linearly and
    re-orthonormalised, B completed with the frames' own handedness ([N, T, B] with
    B = T x N is left-handed: slerp does not apply)."""
    T = (1 - f)[:, None] * R0[:, :, 1] + f[:, None] * R1[:, :, 1]
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    Nv = (1 - f)[:, None] * R0[:, :, 0] + f[:, None] * R1[:, :, 0]
    Nv -= np.einsum("ij,ij->i", Nv, T)[:, None] * T
    Nv /= np.linalg.norm(Nv, axis=1, keepdims=True)
    sign = np.sign(np.linalg.det(R0))
    B = sign[:, None] * np.cross(Nv, T)
    return np.stack([Nv, T, B], axis=2)


def _hermite_coefficients(traj) -> tuple[np.ndarray, np.ndarray]:
    """Piece coefficients c (4, K-1, 6) (c0 x^3 + c1 x^2 + c2 x + c3) and widths h (K-1,)."""
    from scipy.interpolate import CubicHermiteSpline

    spline = CubicHermiteSpline(traj.t, traj.q, traj.qd, axis=0)
    return spline.c, np.diff(traj.t)


def spline_extremes(traj):
    """Exact extremes of q, qd, qdd over the trajectory, per joint.

    Returns dict of (value (K-1, n, 6), x (K-1, n)) candidate arrays for "q", "qd", "qdd".
    """
    c, h = _hermite_coefficients(traj)
    c0, c1, c2, c3 = c
    H = np.broadcast_to(h[:, None], c0.shape)
    zeros = np.zeros_like(c0)
    # acceleration: linear per piece -> ends
    acc = np.stack([2 * c1, 6 * c0 * H + 2 * c1], axis=1)
    acc_x = np.stack([zeros, H], axis=1)
    # velocity: quadratic -> ends and vertex
    with np.errstate(divide="ignore", invalid="ignore"):
        xv = np.where(np.abs(c0) > 1e-300, -c1 / (3 * c0), 0.0)
    xv = np.where((xv > 0) & (xv < H), xv, 0.0)
    vel_x = np.stack([zeros, H, xv], axis=1)
    vel = 3 * c0[:, None] * vel_x**2 + 2 * c1[:, None] * vel_x + c2[:, None]
    # position: cubic -> ends and roots of the velocity
    A, B, C = 3 * c0, 2 * c1, c2
    disc = B * B - 4 * A * C
    sq = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(np.abs(A) > 1e-300, (-B + sq) / (2 * A), -C / np.where(B == 0, 1, B))
        r2 = np.where(np.abs(A) > 1e-300, (-B - sq) / (2 * A), 0.0)
    ok = disc >= 0
    r1 = np.where(ok & (r1 > 0) & (r1 < H), r1, 0.0)
    r2 = np.where(ok & (r2 > 0) & (r2 < H), r2, 0.0)
    pos_x = np.stack([zeros, H, r1, r2], axis=1)
    pos = (c0[:, None] * pos_x**3 + c1[:, None] * pos_x**2 + c2[:, None] * pos_x
           + c3[:, None])
    return {"q": (pos, pos_x), "qd": (vel, vel_x), "qdd": (acc, acc_x)}
