"""How a program of linear moves is read against an executed path.

A controller runs each linear move from its start target to its end target with the tool
orientation slerped between theirs in step with the tool's progress along the move. Reading a
dense executed path against such a program: each sample is put on the move it is executed on
(in execution order); its position is compared with the move's segment (projection), its
orientation with the slerp of the move's targets at the share of the travel the path has made
between the move's start and end (the midpoints between the last sample of one move and the
first of the next). The projection alone would misread the progress where the path rounds a
corner (in a zone the projection stands still while the tool moves on), and near tight corners
the tool turns by 0.1-0.3 rad per move.

Shared by the verifier (``path_deviation``, ``orientation_agreement``) and the planner, which
adds via targets where this reading strays from its executed cut - so that both judge the
program by the same definition.
"""

from __future__ import annotations

import numpy as np

__all__ = ["moves_in_order", "travel_fractions", "rot_angle", "slerp_pairs",
           "program_orientation_error"]


def moves_in_order(p: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Like the nearest-segment reading for trajectory samples in time order against a program's
    moves run in order: each sample is put on a move such that the move index never decreases
    along the samples and the summed distance is least (dynamic programming over samples x
    moves). The nearest move alone is ambiguous where the path comes back: a closed window
    loop ends on its first CL point, where its last samples are as near the start of the first
    move as the end of the last (and the spin there may differ by a turn of the wrist).

    Written by hand: a monotone assignment of points to polyline segments is a few lines of
    dynamic programming; no library offers it.

    Returns:
        (d (N,), move index (N,), fraction along it (N,)).
    """
    n, S = len(p), len(a)
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    ap = p[:, None, :] - a[None]
    F = np.clip(np.einsum("nsk,sk->ns", ap, ab) / L2, 0.0, 1.0)
    D = np.linalg.norm(ap - F[..., None] * ab[None], axis=2)
    idx = np.arange(S)
    back = np.empty((n, S), np.int32)
    cost = D[0].copy()
    for i in range(1, n):
        best = np.minimum.accumulate(cost)
        # the latest position of the running minimum: the best earlier-or-same move
        back[i] = np.maximum.accumulate(np.where(cost <= best, idx, 0))
        cost = D[i] + best
    m = np.empty(n, int)
    m[-1] = int(np.argmin(cost))
    for i in range(n - 1, 0, -1):
        m[i - 1] = back[i, m[i]]
    r = np.arange(n)
    return D[r, m], m, F[r, m]


def travel_fractions(p: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(N,) share of each sample's move travelled when the path reaches it: samples ``p``
    (N, 3) in order on moves ``m`` (non-decreasing, :func:`moves_in_order`); a move runs from
    the midpoint between its first sample and the previous move's last to the same point at
    its end (the path's ends: its first and last sample)."""
    p = np.asarray(p, float)
    m = np.asarray(m)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    change = np.flatnonzero(np.diff(m) != 0)  # last sample of each run but the final one
    cut = 0.5 * (s[change] + s[change + 1])
    start = np.concatenate([[s[0]], cut])
    end = np.concatenate([cut, [s[-1]]])
    run = np.concatenate([[0], np.cumsum(np.diff(m) != 0)])  # run index of each sample
    span = np.maximum(end[run] - start[run], 1e-15)
    return np.clip((s - start[run]) / span, 0.0, 1.0)


def rot_angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Angles [rad] of the relative rotations of (N, 3, 3) stacks."""
    tr = np.einsum("nij,nij->n", Ra, Rb)
    return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))


def slerp_pairs(R0: np.ndarray, R1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations a fraction f (N,) of the way from R0[i] to R1[i]."""
    from scipy.spatial.transform import Rotation

    r0 = Rotation.from_matrix(R0)
    rel = (r0.inv() * Rotation.from_matrix(R1)).as_rotvec()
    return (r0 * Rotation.from_rotvec(rel * f[:, None])).as_matrix()


def program_orientation_error(X: np.ndarray, X_targets: np.ndarray
                              ) -> tuple[np.ndarray, np.ndarray]:
    """Angle [rad] between each executed pose's orientation and the program's there.

    Args:
        X: (N, 4, 4) executed poses in travel order; X_targets: (K, 4, 4) the program's
            targets of that stretch, the first where it starts.

    Returns:
        (error (N,), move index (N,): the sample lies on the move from target m to m + 1).
    """
    X = np.asarray(X, float)
    Xt = np.asarray(X_targets, float)
    _, m, _ = moves_in_order(X[:, :3, 3], Xt[:-1, :3, 3], Xt[1:, :3, 3])
    f = travel_fractions(X[:, :3, 3], m)
    R_prog = slerp_pairs(Xt[m, :3, :3], Xt[m + 1, :3, :3], f)
    return rot_angle(R_prog, X[:, :3, :3]), m
