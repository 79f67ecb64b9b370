"""How far geometry can move between two times: the bounds behind the clearance certificate.

A *track* is the motion of one collision geometry G (bounded by a ball: centre ``c`` in the
frame of the link L it moves with, radius ``rho``) relative to a reference link R (the world
for fixed geometry). Any signed distance between G and a geometry fixed to R changes by at
most how far a point of G moves relative to R, so for times ``t_a < t_b`` (one polynomial
piece of the trajectory, length ``h``) and any ``t`` between them at share ``s``:

* endpoint displacement (first order, exact from FK at both ends): every point of the ball
  moves by at most ``delta = |c_R(t_b) - c_R(t_a)| + 2 rho sin(Theta / 2)``, Theta the angle
  of L's rotation relative to R;
* path deviation (second order, from the trajectory's own pieces): a point ``p(t)`` leaves
  the chord between ``p(t_a)`` and ``p(t_b)`` by at most ``h^2 / 8 * max |p''|``, and for a
  point on a chain of revolute joints (axes ``a_j`` through ``o_j``, rates ``qd_j``)
  ``|p''| <= sum_j qdd_j r_j + sum_j qd_j (2 W_j r_j + sum_{i >= j} qd_i r_i)`` with ``r_j``
  the point's distance from axis j and ``W_j`` the sum of the rates of the joints between R
  and axis j (differentiate ``v = sum_j qd_j a_j x (p - o_j)``; ``|a_j'| <= W_j``). The
  rates are bounded exactly by the Taylor expansion of each polynomial piece at ``t_a``;
  ``r_j`` by the link reach (:meth:`drakedeburr.cell.chain.KinematicTree.reach`).

Hence ``|p(t) - p(t_a)| <= s delta + e`` and ``|p(t) - p(t_b)| <= (1 - s) delta + e`` with
``e = h^2 / 8 * A``, and from distances ``d_a``, ``d_b`` at the ends the distance over the
interval is at least ``min_s max(d_a - s delta, d_b - (1 - s) delta) - e``
(:func:`interval_lower_bound`: ``(d_a + d_b - delta) / 2 - e`` where the two lines cross).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import factorial

import numpy as np

from drakedeburr.cell.chain import rotation_angle

__all__ = ["Tracks", "relative_pose", "chord_bound", "rate_bounds", "accel_weights",
           "accel_bound",
           "interval_lower_bound", "track_interval_bounds"]

#: relative slack on every bound (floating-point rounding of the chains of products)
_SLACK = 1e-9
#: absolute slack [m]
_SLACK_ABS = 1e-12


@dataclass(frozen=True, eq=False)
class Tracks:
    """T motion tracks (module docstring), as arrays.

    Attributes:
        ref: (T,) reference link R (body index, 0: world); link: (T,) link L of the geometry.
        c: (T, 3) ball centre in L [m]; rho: (T,) its radius [m].
        seq: (T, nq) position indices of the joints from R to L, -1 padded.
        reach: (T, nq) bound of the ball's distance from each of those axes [m] (0 padded).
        cls: (T,) distance class of the track's pairs (0 clearance, 1 self, 2 burr).
    """

    ref: np.ndarray
    link: np.ndarray
    c: np.ndarray
    rho: np.ndarray
    seq: np.ndarray
    reach: np.ndarray
    cls: np.ndarray

    def __len__(self) -> int:
        return len(self.ref)


def relative_pose(X: np.ndarray, ref, link) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (K, 3, 3) and position (K, 3) of ``link`` in ``ref`` from body poses ``X``
    (K, n_bodies, 4, 4); ``ref``/``link`` scalars or (K,) body indices."""
    k = np.arange(len(X))
    X_R, X_L = X[k, ref], X[k, link]
    R_RW = np.swapaxes(X_R[:, :3, :3], 1, 2)
    return R_RW @ X_L[:, :3, :3], np.einsum("kij,kj->ki", R_RW, X_L[:, :3, 3] - X_R[:, :3, 3])


def chord_bound(R_a, p_a, R_b, p_b, c: np.ndarray, rho) -> np.ndarray:
    """Largest displacement of a ball (centre ``c`` (K, 3) or (3,) in L, radius ``rho``)
    between two relative poses (R, p) of L [m] -> (K,)."""
    c_a = np.einsum("kij,kj->ki", R_a, np.broadcast_to(c, p_a.shape)) + p_a
    c_b = np.einsum("kij,kj->ki", R_b, np.broadcast_to(c, p_b.shape)) + p_b
    theta = rotation_angle(R_a, R_b)
    d = np.linalg.norm(c_b - c_a, axis=1) + 2.0 * np.asarray(rho) * np.sin(0.5 * theta)
    return d * (1.0 + _SLACK) + _SLACK_ABS


def rate_bounds(traj, t_a: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of |qd| and |qdd| on [t_a, t_a + h] (inside one piece) -> two (K, nq) arrays
    [rad/s, rad/s^2]: the Taylor expansion of the piece at ``t_a``, term by term."""
    degree = np.asarray(traj.c).shape[0] - 1
    t_a, h = np.asarray(t_a, float), np.asarray(h, float)[:, None]
    derivs = [np.abs(traj.derivative(t_a, n)) for n in range(1, degree + 1)]
    zero = np.zeros((len(t_a), np.asarray(traj.c).shape[2]))
    qd = sum((d * h ** n / factorial(n) for n, d in enumerate(derivs)), zero)
    qdd = sum((d * h ** n / factorial(n) for n, d in enumerate(derivs[1:])), zero)
    return qd * (1.0 + _SLACK), qdd * (1.0 + _SLACK)


def accel_weights(qd: np.ndarray, qdd: np.ndarray, seq: np.ndarray) -> np.ndarray:
    """(K, nq) weights F with ``|p''| <= F @ reach`` for a track's joint sequence ``seq``
    ((K, nq) or (nq,), -1 padded): the module docstring's bound regrouped per axis,
    ``sum_j r_j (qdd_j + qd_j (3 W_j + qd_j))`` (``sum_j qd_j sum_{i >= j} qd_i r_i =
    sum_i qd_i r_i (W_i + qd_i)``)."""
    seq = np.broadcast_to(seq, qd.shape)
    valid = seq >= 0
    idx = np.where(valid, seq, 0)
    w = np.where(valid, np.take_along_axis(qd, idx, axis=1), 0.0)
    a = np.where(valid, np.take_along_axis(qdd, idx, axis=1), 0.0)
    before = np.cumsum(w, axis=1) - w  # rates of the joints between R and axis j
    return a + w * (3.0 * before + w)


def accel_bound(qd: np.ndarray, qdd: np.ndarray, seq: np.ndarray, reach: np.ndarray
                ) -> np.ndarray:
    """Bound of |p''| for the points of a track's ball (module docstring) -> (K,) [m/s^2].

    Args:
        qd, qdd: (K, nq) rate bounds; seq, reach: (K, nq) or (nq,) the track's joints from the
            reference outward (-1 padded) and reach bounds [m].
    """
    return np.sum(accel_weights(qd, qdd, seq) * np.broadcast_to(reach, qd.shape), axis=1)


def interval_lower_bound(d_a, d_b, delta, e) -> np.ndarray:
    """Smallest distance possible on an interval from the distances at its ends, the ends'
    displacement bound ``delta`` and the path-deviation bound ``e`` (module docstring)."""
    d_a, d_b, delta = np.asarray(d_a, float), np.asarray(d_b, float), np.asarray(delta, float)
    with np.errstate(invalid="ignore"):
        s = np.clip(np.where(delta > 0, (d_a - d_b + delta) / (2.0 * np.maximum(delta, 1e-300)),
                             0.5), 0.0, 1.0)
    return np.maximum(d_a - s * delta, d_b - (1.0 - s) * delta) - e


def track_interval_bounds(tracks: Tracks, which: np.ndarray, X_a: np.ndarray,
                          X_b: np.ndarray, qd: np.ndarray, qdd: np.ndarray, h: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
    """``delta`` and ``e`` (K,) [m] of tracks ``which`` (K,) over K intervals, from body poses
    at both ends ``X_a``/``X_b`` (K, n_bodies, 4, 4), rate bounds (K, nq) and lengths h (K,)."""
    ref, link = tracks.ref[which], tracks.link[which]
    R_a, p_a = relative_pose(X_a, ref, link)
    R_b, p_b = relative_pose(X_b, ref, link)
    delta = chord_bound(R_a, p_a, R_b, p_b, tracks.c[which], tracks.rho[which])
    A = accel_bound(qd, qdd, tracks.seq[which], tracks.reach[which])
    return delta, 0.125 * np.asarray(h) ** 2 * A * (1.0 + _SLACK)
