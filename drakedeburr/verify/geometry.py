"""Geometry the verifier computes for itself: distances of points to segments and loops,
interpolated local frames, exact extremes of the cubic Hermite joint trajectory, and the slow
stretches of a cut. Pure numpy/scipy, no planner code (the verifier re-derives)."""

from __future__ import annotations

import numpy as np

__all__ = ["slow_stretches", "point_segment", "closed_polyline_distance",
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


#: below this many (point, segment) pairs the distances are read against every segment
_DENSE_PAIRS = 200_000
#: segments read per point first when pruning (the nearest by midpoint)
_NEAR = 16


def _to_segments(ap: np.ndarray, ab: np.ndarray, L2: np.ndarray):
    """Distances of points to segments from ``ap`` = p - a (..., 3), ``ab`` = b - a (..., 3)
    and ``L2`` = |ab|^2 (...), broadcast together: (d (...), fraction along the segment)."""
    f = np.clip(np.einsum("...k,...k->...", ap, ab) / L2, 0.0, 1.0)
    return np.linalg.norm(ap - f[..., None] * ab, axis=-1), f


def _point_segment_all(p, a, ab, L2, chunk):
    """:func:`point_segment` against every segment (chunks of ``chunk`` points)."""
    d_out, i_out, f_out = np.empty(len(p)), np.empty(len(p), int), np.empty(len(p))
    for s in range(0, len(p), chunk):
        pc = p[s:s + chunk]
        d, f = _to_segments(pc[:, None, :] - a[None], ab[None], L2[None])
        k = d.argmin(axis=1)
        r = np.arange(len(pc))
        d_out[s:s + chunk], i_out[s:s + chunk], f_out[s:s + chunk] = d[r, k], k, f[r, k]
    return d_out, i_out, f_out


def point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 256):
    """Distance of points to a set of segments, exact (the first segment on a tie).

    Many points against many segments (a sampled cut against its program or its edge) are read
    against the ``_NEAR`` segments of nearest midpoint first (scipy's KD-tree); a point is
    settled when its distance is below the midpoint distance of every other segment less the
    longest half-segment (no other segment can come closer), the rest against every segment.
    The numbers are those of the reading against every segment, bit for bit.

    Args:
        p: (N, 3) points. a, b: (S, 3) segment ends.

    Returns:
        (d (N,), index of the closest segment (N,), fraction along it (N,)).
    """
    p, a, b = (np.asarray(x, float) for x in (p, a, b))
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    if (len(p) * len(a) <= _DENSE_PAIRS or len(a) <= _NEAR
            or not (np.isfinite(p).all() and np.isfinite(a).all() and np.isfinite(b).all())):
        return _point_segment_all(p, a, ab, L2, chunk)  # (a non-finite input reads as NaN)
    from scipy.spatial import cKDTree

    dm, near = cKDTree(a + 0.5 * ab).query(p, k=_NEAR)
    near = np.sort(near, axis=1)  # ties to the first segment, as against every segment
    d, f = _to_segments(p[:, None, :] - a[near], ab[near], L2[near])
    k = d.argmin(axis=1)
    r = np.arange(len(p))
    d_out, i_out, f_out = d[r, k], near[r, k], f[r, k]
    half = 0.5 * float(np.sqrt(L2.max()))
    # (1e-12 relative: the tree's own rounding of the midpoint distances)
    open_ = np.flatnonzero(~(d_out < dm[:, -1] - half - 1e-12 * (1.0 + dm[:, -1])))
    if len(open_):
        d_out[open_], i_out[open_], f_out[open_] = _point_segment_all(p[open_], a, ab, L2, chunk)
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


def _polyval(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Horner: coefficients (D + 1, K, 6) highest first at times tau (K, n) -> (K, n, 6)."""
    out = np.zeros(tau.shape + c.shape[2:])
    for row in c:
        out = out * tau[..., None] + row[:, None, :]
    return out


def _derivative(c: np.ndarray) -> np.ndarray:
    """Coefficients of the derivative of the pieces (one row fewer)."""
    d = len(c) - 1
    if d == 0:
        return np.zeros((1,) + c.shape[1:])
    return c[:-1] * np.arange(d, 0, -1)[:, None, None]


def _abs_bound(c: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(K, 6) upper bound of |f(tau)| on [0, h] of each piece: sum |c_p| h^p."""
    d = len(c) - 1
    powers = np.arange(d, -1, -1)
    return np.einsum("pkj,pk->kj", np.abs(c), h[None] ** powers[:, None])


def _read_pieces(c: np.ndarray, h: np.ndarray, samples: int, rel: float):
    """Readings of the pieces ``c`` at evenly spaced times, more of them on a piece whose
    remainder would exceed ``rel`` times its scale, kept per piece and joint at the smallest
    and the largest reading (the first of equals): (values (K, 2, 6), times (K, 2, 6),
    remainder (K, 6)). Each group of pieces is read at its own count only (reading every
    piece at the largest count cost ~10 s for a hub's 15k pieces)."""
    M2 = _abs_bound(_derivative(_derivative(c)), h)  # (K, 6)
    scale = _abs_bound(c, h) + 1.0
    need = np.ceil(h * np.sqrt(np.max(M2 / (8.0 * rel * scale), axis=1))).astype(int) + 1
    counts = np.clip(np.maximum(need, samples), samples, 4097)
    groups = 2 ** np.ceil(np.log2(counts - 1)).astype(int) + 1  # a few distinct counts
    vals = np.empty((len(h), 2, c.shape[2]))
    tau = np.empty_like(vals)
    for n in np.unique(groups):
        rows = np.flatnonzero(groups == n)
        t_rows = h[rows, None] * np.linspace(0.0, 1.0, n)[None]  # (r, n)
        v = _polyval(c[:, rows], t_rows)  # (r, n, 6)
        for slot, pick in ((0, np.argmin), (1, np.argmax)):
            at = pick(v, axis=1)  # (r, 6)
            vals[rows, slot] = np.take_along_axis(v, at[:, None], axis=1)[:, 0]
            tau[rows, slot] = np.take_along_axis(t_rows, at, axis=1)
    rem = 0.125 * (h / (groups - 1))[:, None] ** 2 * M2
    return vals, tau, rem


def spline_extremes(traj, samples: int = 9, rel: float = 1e-7):
    """Certified extremes of q, qd and qdd over the trajectory, per piece and joint.

    Each piece is read at evenly spaced times (ends included; ``samples`` at least, more where
    needed); between two readings (spacing delta) a function can exceed the larger one by at
    most delta^2 / 8 times the bound of its second derivative on the piece, the *remainder*,
    kept under ``rel`` of the piece's scale. Exact for the cubic Hermite pieces' accelerations
    (linear).

    Returns:
        {"q" | "qd" | "qdd": (values (K-1, 2, 6): each piece's smallest and largest reading
        per joint, times from the piece start (K-1, 2, 6), remainder (K-1, 6))}.
    """
    c = np.asarray(traj.c, float)
    h = np.diff(np.asarray(traj.t, float))
    out = {}
    for key in ("q", "qd", "qdd"):
        out[key] = _read_pieces(c, h, samples, rel)
        c = _derivative(c)
    return out
