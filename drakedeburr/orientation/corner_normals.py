"""Inner normals on one side of the edge at a tessellated corner (issue 42).

The orientation stage pairs each CL point's tangent (the fitted edge curve's, which rounds a
corner over a fraction of a millimetre) with the inner normal of the nearest edge sample (the
mesh's, which jumps at the corner vertex). At a CL point just before (or after) a sharp corner
of a real wheel's 3-D loop that pairs the tangent of one side with the wall normal of the other
side: carried along the edge by the rotation that turns its tangent (the wall of a continuous
edge turns with it), the normal REVERSES (> 90 deg) across a step where the edge runs on
(nearly) straight, while the edge turns sharply at the next step. The local frame
``[n, t, n x t]`` is then upside down and the tool axis points into the hub (audibot rim:
window 1 CL 151 - the tangent turns 1 deg, the normal 146 deg - and window 9 CL 56).

Rule (:func:`side_consistent_normals`): across a step where the carried normal reverses, the
point on the side where the tangent turns more (the corner) took its normal from across the
corner; it gets its neighbour's normal carried to its own tangent. A reversal at the step where
the edge turns most (a real hairpin) is kept. Loops without a reversal (every smooth loop,
every bundled hub) get their normals back bit for bit.

Rule (:func:`corner_bounded_normals`, applied after it): at a sharp corner of a faceted loop
(the tangent turns more than ``CORNER_TURN`` between the two neighbouring points) the inner
normal read at the corner vertex (the probe between two facets, the outline's plan normal made
perpendicular to the bisecting chord) may swing far from both sides' normals (audibot rim:
window 1 CL 110 -50 deg to the face plane between -29 and -3 deg). At a corner the material's
inner side is bounded by the two adjacent sides' inner normals: a corner normal outside the
arc between its neighbours' (each made perpendicular to its own tangent) by more than
``SPAN_EXCESS`` is replaced by their bisector made perpendicular to its own tangent, turned
about that tangent until its angle to the face plane (X_H Y_H) lies between the neighbours'
(the face-plane side kept). A smooth loop's normal lies on that arc (it turns continuously):
untouched, bit for bit (the bundled hubs' CL points turn at most 28.6 deg across their
neighbours and no normal of theirs is bounded). On the audibot rim 4-10 CL points a window are
bounded (window 1 CL 110: -50 -> -20 deg; window 3 CL 177: +53 -> +22 deg; window 8 CL 53:
+65 -> +21 deg), and every window gives targets under every theta box.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CORNER_TURN", "SPAN_EXCESS", "carried_normal", "corner_bounded_normals",
           "normal_reversals", "side_consistent_normals"]

#: [rad] a tangent turn between a point's two neighbours above this makes the point a corner
CORNER_TURN = np.radians(30.0)
#: [rad] how far a corner's normal may lie outside the arc between its neighbours' normals
SPAN_EXCESS = np.radians(10.0)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def carried_normal(t_from: np.ndarray, t_to: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(M, 3) ``n`` turned by the smallest rotation taking unit ``t_from`` to unit ``t_to``
    (rows; Rodrigues' formula; for antiparallel tangents the rotation is undefined and ``n`` is
    returned reflected through the tangent's normal plane, the limit of that formula)."""
    c = np.sum(t_from * t_to, axis=1, keepdims=True)
    k = np.cross(t_from, t_to)
    return (n * c + np.cross(k, n)
            + k * np.sum(k * n, axis=1, keepdims=True) / np.maximum(1.0 + c, 1e-9))


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(_unit(a) * _unit(b), axis=1), -1.0, 1.0))


def normal_reversals(t_H: np.ndarray, n_H: np.ndarray, closed: bool = True):
    """Steps ``i -> i+1`` where the normal carried from ``i`` to ``i+1`` is more than 90 deg
    from ``n[i+1]``. Returns (steps (K,), carried mismatch (M,) [rad] of step i -> i+1, tangent
    turn (M,) [rad] of step i -> i+1); the last step wraps on a closed loop (else it is 0)."""
    t, n = _unit(np.asarray(t_H, float)), np.asarray(n_H, float)
    t1, n1 = np.roll(t, -1, axis=0), np.roll(n, -1, axis=0)
    mismatch = _angle(carried_normal(t, t1, n), n1)
    turn = _angle(t, t1)
    if not closed:
        mismatch[-1] = turn[-1] = 0.0
    return np.flatnonzero(mismatch > 0.5 * np.pi), mismatch, turn


def side_consistent_normals(t_H: np.ndarray, n_H: np.ndarray, closed: bool = True):
    """Inner normals with a mispaired corner normal replaced and a corner normal outside its
    neighbours' span bounded by them (both rules of the module docstring).

    Args:
        t_H: (M, 3) tangents (feed direction); n_H: (M, 3) inner normals (not necessarily
            orthogonal to ``t_H``); closed: the loop wraps (M-1 -> 0).

    Returns:
        (normals (M, 3), repaired point indices (list)); without a reversal or an outlying
        corner normal ``n_H`` itself.
    """
    n, fixed = _reversal_repaired(t_H, n_H, closed)
    n, bounded = corner_bounded_normals(t_H, n, closed)
    return n, sorted(set(fixed) | set(bounded))


def _reversal_repaired(t_H: np.ndarray, n_H: np.ndarray, closed: bool):
    """The reversal rule of the module docstring alone: (normals, repaired indices)."""
    steps, _, turn = normal_reversals(t_H, n_H, closed)
    if steps.size == 0:
        return np.asarray(n_H, float), []
    t, n = _unit(np.asarray(t_H, float)), np.array(n_H, float)
    m = len(t)
    fixed = []
    for i in steps.tolist():
        j = (i + 1) % m
        before = turn[(i - 1) % m] if closed or i > 0 else 0.0  # turn on i's far side
        after = turn[j] if closed or j < m - 1 else 0.0  # turn on j's far side
        if turn[i] >= max(before, after):
            continue  # the edge turns most at the reversal itself: a real hairpin, kept
        # the point next to the sharper turn is the one at the corner: it gets the other's
        k, src = (j, i) if after > before else (i, j)
        n[k] = carried_normal(t[src][None], t[k][None], n[src][None])[0]
        fixed.append(int(k))
    return n, sorted(set(fixed))


def _elevation(v: np.ndarray) -> np.ndarray:
    """Angle [rad] of unit rows ``v`` to the face plane X_H Y_H (positive toward +Z_H)."""
    return np.arcsin(np.clip(v[..., 2], -1.0, 1.0))


def _perpendicular(n: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Rows of ``n`` made perpendicular to the unit rows ``t`` (the local frames' X_L)."""
    return _unit(n - np.sum(n * t, axis=1, keepdims=True) * t)


def _turned_to_elevation(g: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """Unit rows ``g`` (perpendicular to the unit rows ``t``) turned about ``t`` by the smallest
    angle that brings their elevation into [lo, hi] [rad] (as near as the circle of normals
    perpendicular to ``t`` reaches)."""
    w = np.cross(t, g)
    amp = np.hypot(g[:, 2], w[:, 2])  # z(phi) = amp cos(phi - phi0) on that circle
    phi0 = np.arctan2(w[:, 2], g[:, 2])
    z = np.clip(np.clip(g[:, 2], np.sin(lo), np.sin(hi)), -amp, amp)
    d = np.arccos(np.clip(z / np.maximum(amp, 1e-12), -1.0, 1.0))
    cand = np.stack([phi0 + d, phi0 - d], axis=1)
    cand = (cand + np.pi) % (2 * np.pi) - np.pi
    phi = np.where(np.abs(cand[:, 0]) <= np.abs(cand[:, 1]), cand[:, 0], cand[:, 1])
    keep = (g[:, 2] >= np.sin(lo)) & (g[:, 2] <= np.sin(hi))
    phi = np.where(keep, 0.0, phi)[:, None]
    return _unit(np.cos(phi) * g + np.sin(phi) * w)


def corner_bounded_normals(t_H: np.ndarray, n_H: np.ndarray, closed: bool = True):
    """Inner normals with a sharp corner's normal bounded by its neighbours' (module docstring).

    The normals compared are those the local frames are built on (each made perpendicular to
    its own tangent), of a point and of its two neighbours. A bounded normal is perpendicular
    to its tangent: the neighbours' bisector made so, then turned about the tangent until its
    angle to the face plane lies between theirs. Not bounded: a point where the tangent turns
    by more than 90 deg at a step (a hairpin), or whose bound would reverse against a
    neighbour's normal carried to it (:func:`carried_normal`; a reversal is the first rule's).

    Args:
        t_H: (M, 3) tangents (feed direction); n_H: (M, 3) inner normals (not necessarily
            orthogonal to ``t_H``); closed: the loop wraps (M-1 -> 0); else the end points
            keep theirs.

    Returns:
        (normals (M, 3), bounded point indices (list)); without such a corner ``n_H`` itself.
    """
    t = _unit(np.asarray(t_H, float))
    n = np.asarray(n_H, float)
    m = len(t)
    if m < 3:
        return n, []
    a, b = np.roll(np.arange(m), 1), np.roll(np.arange(m), -1)
    f = _perpendicular(n, t)
    mid = f[a] + f[b]
    hit = _angle(t[a], t[b]) > CORNER_TURN
    hit &= (np.sum(t[a] * t, axis=1) > 0.0) & (np.sum(t[b] * t, axis=1) > 0.0)
    hit &= _angle(f, f[a]) + _angle(f, f[b]) - _angle(f[a], f[b]) > SPAN_EXCESS
    hit &= np.linalg.norm(np.cross(t, mid), axis=1) > 1e-6  # a span off the tangent line
    if not closed:
        hit[[0, -1]] = False
    idx = np.flatnonzero(hit)
    if idx.size == 0:
        return n, []
    ia, ib = a[idx], b[idx]
    g = _perpendicular(mid[idx], t[idx])
    # the face-plane side kept: no further below (or above) the face plane than both sides
    el_a, el_b = _elevation(f[ia]), _elevation(f[ib])
    g = _turned_to_elevation(g, t[idx], np.minimum(el_a, el_b), np.maximum(el_a, el_b))
    keep = np.ones(len(idx), bool)
    for j in (ia, ib):  # no reversal against either neighbour carried to the point
        keep &= np.sum(carried_normal(t[j], t[idx], f[j]) * g, axis=1) > 0.0
    if not keep.any():
        return n, []
    out = n.copy()
    out[idx[keep]] = g[keep]
    return out, idx[keep].tolist()
