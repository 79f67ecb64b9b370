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
"""

from __future__ import annotations

import numpy as np

__all__ = ["carried_normal", "normal_reversals", "side_consistent_normals"]


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
    """Inner normals with a mispaired corner normal replaced (see the module docstring).

    Args:
        t_H: (M, 3) tangents (feed direction); n_H: (M, 3) inner normals (not necessarily
            orthogonal to ``t_H``); closed: the loop wraps (M-1 -> 0).

    Returns:
        (normals (M, 3), repaired point indices (list)); without a reversal ``n_H`` itself.
    """
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
