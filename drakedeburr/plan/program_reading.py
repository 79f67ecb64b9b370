"""How a program of linear moves is read against an executed path.

A controller runs each linear move from its start target to its end target with the tool
orientation slerped between theirs in step with the tool's progress along the move. Reading a
dense executed path against such a program: each sample is put on the move it is executed on
(in execution order); its position is compared with the move's segment (projection), its
orientation with the slerp of the move's targets at the share of the travel the path has made
between passing the move's start and end targets (where it comes nearest to each). The
projection alone would misread the progress where the path rounds a corner (in a zone the
projection stands still while the tool moves on), and counting samples would misread moves
shorter than the sampling; near tight corners moves are 0.25-0.5 mm long and the tool turns
by 0.1-0.3 rad per move.

Shared by the verifier (``path_deviation``, ``orientation_agreement``) and the planner, which
adds via targets where this reading strays from its executed cut - so that both judge the
program by the same definition.
"""

from __future__ import annotations

import numpy as np

__all__ = ["moves_in_order", "passing_fractions", "rot_angle", "slerp_pairs",
           "program_orientations", "program_orientation_error", "cone_axes_on_moves"]


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


def cone_axes_on_moves(p: np.ndarray, P: np.ndarray, C: np.ndarray) -> np.ndarray:
    """The cone axis where each executed sample is, read as the verifier reads it
    (``drakedeburr.verify.cut_geometry``): the sample on its move (:func:`moves_in_order`), at
    the share of its projection on the move, the targets' cone axes interpolated linearly
    there and renormalised. Through a corner zone the projection stands still, so the cone
    stays the corner target's; a reading by travel turns on through the zone and differs by up
    to the share of the zone times the cone's turn between the targets (mrad where the cone
    turns 0.17 rad between two CL points of a small window).

    Args:
        p: (N, 3) executed samples in travel order; P: (K, 3) the targets in order, K >= 2;
            C: (K, 3) unit cone axes at the targets.

    Returns:
        (N, 3) unit cone axes.
    """
    P, C = np.asarray(P, float), np.asarray(C, float)
    _, m, f = moves_in_order(np.asarray(p, float), P[:-1], P[1:])
    c = (1.0 - f)[:, None] * C[m] + f[:, None] * C[m + 1]
    return c / np.linalg.norm(c, axis=1, keepdims=True)


def passing_fractions(p: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where along the program each executed sample is: the move it is on and the share of
    that move travelled.

    A target is *passed* where the executed path comes nearest to it (a corner zone's middle;
    the target itself where the path runs through it), found to a fraction of a chord on the
    polyline of the samples, in order (:func:`moves_in_order` with the roles swapped: targets
    on the path's chords). A sample between the passing points of targets k and k + 1 is on
    move k, at the share of the executed travel between them. Unlike the projection on the
    move's segment this keeps growing through a corner zone (where the projection stands
    still while the tool turns on), and unlike a count of samples it does not depend on how
    densely the path was sampled (moves of 0.25 mm at a tight corner are shorter than the
    0.5 mm sampling).

    Args:
        p: (N, 3) executed samples in travel order, N >= 2; P: (K, 3) the program's targets
            of that stretch in order, K >= 2, the first where it starts.

    Returns:
        (move index (N,) in [0, K - 2], share of it travelled (N,) in [0, 1]).
    """
    p = np.asarray(p, float)
    P = np.asarray(P, float)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    _, j, f = moves_in_order(P, p[:-1], p[1:])
    s_pass = s[j] + f * (s[j + 1] - s[j])
    m = np.clip(np.searchsorted(s_pass, s, side="right") - 1, 0, len(P) - 2)
    span = np.maximum(s_pass[m + 1] - s_pass[m], 1e-15)
    return m, np.clip((s - s_pass[m]) / span, 0.0, 1.0)


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


def program_orientations(X: np.ndarray, X_targets: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """The program's orientation where each executed pose is: the slerp of the move the sample
    is on, at the share of the move travelled (:func:`passing_fractions`).

    Args:
        X: (N, 4, 4) executed poses in travel order; X_targets: (K, 4, 4) the program's
            targets of that stretch, the first where it starts.

    Returns:
        (rotations (N, 3, 3), move index (N,): the sample lies on the move from target m to
        m + 1).
    """
    X = np.asarray(X, float)
    Xt = np.asarray(X_targets, float)
    m, f = passing_fractions(X[:, :3, 3], Xt[:, :3, 3])
    return slerp_pairs(Xt[m, :3, :3], Xt[m + 1, :3, :3], f), m


def program_orientation_error(X: np.ndarray, X_targets: np.ndarray
                              ) -> tuple[np.ndarray, np.ndarray]:
    """Angle [rad] between each executed pose's orientation and the program's there.

    Args:
        X: (N, 4, 4) executed poses in travel order; X_targets: (K, 4, 4) the program's
            targets of that stretch, the first where it starts.

    Returns:
        (error (N,), move index (N,): the sample lies on the move from target m to m + 1).
    """
    R_prog, m = program_orientations(X, X_targets)
    return rot_angle(R_prog, np.asarray(X, float)[:, :3, :3]), m
