"""Time-parameterisation of a dense joint path: a TCP speed cap plus joint limits.

A path is given by samples ``q_k`` at a monotone parameter ``s_k`` (tool travel relative to the
hub for Cartesian moves, joint-space arc length for joint moves). A C2 cubic spline q(s) gives
q'(s) and q''(s); the speed profile sdot(s) is then the largest one that respects

* the TCP speed cap: |dp_HT/ds| sdot <= v_cap (150 mm/s cutting, 450 mm/s between windows...),
* joint velocities: |q_j'| sdot <= f_v v_max_j,
* joint accelerations: |q_j' sddot + q_j'' sdot^2| <= f_a a_max_j, exactly (no split between
  the curvature and the tangential term), and a TCP acceleration cap on sddot,

found by the classic time-optimal construction (Bobrow; Pham's TOPP): the maximum-velocity
curve where the admissible sddot interval closes, then forward (largest sddot) and backward
(most negative sddot) integration passes under it, rest to rest.
Why not Drake's ``Toppra``: it enforces its limits only at its grid points (a 30 mm/s limit was
overshot to 32.8 mm/s between them, DESIGN.md), and here the grid is the dense path itself, so
the passes are exact at every sample and need no LP per grid point. TOPP-RA
(``Toppra.AddFrameTranslationalSpeedLimit``) is used in the benchmark as the cross-check.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

__all__ = ["TimingLimits", "TimedPath", "time_path", "joint_spline"]


@dataclass(frozen=True)
class TimingLimits:
    """Limits of one timed stretch.

    Attributes:
        v_cap: TCP speed cap [m/s] (relative speed of tool and hub).
        a_cap: TCP path acceleration cap [m/s^2].
        v_max: (6,) joint speed limits [rad/s]; a_max: (6,) joint acceleration limits.
        velocity_fraction / acceleration_fraction: share of the joint limits used (margin).
    """

    v_cap: float
    a_cap: float
    v_max: tuple[float, ...]
    a_max: tuple[float, ...]
    velocity_fraction: float = 0.95
    acceleration_fraction: float = 0.9


@dataclass(frozen=True, eq=False)
class TimedPath:
    """A timed stretch (rest to rest).

    Attributes:
        t: (N,) times from 0 [s]; q: (N, 6) [rad]; qd: (N, 6) [rad/s].
        sdot: (N,) parameter speed; v_tcp: (N,) TCP speed [m/s] at the samples.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    sdot: np.ndarray
    v_tcp: np.ndarray


def joint_spline(s: np.ndarray, q: np.ndarray, fit_spacing: float | None = None):
    """C2 cubic spline q(s) through (``fit_spacing`` None) or fitted to the samples.

    The executed motion is piecewise linear in Cartesian space, so the joints have slope kinks
    at every target; interpolating dense samples turns each kink into a curvature spike (and the
    timing into a crawl). A least-squares cubic B-spline with knots every ``fit_spacing`` of
    ``s`` rounds the kinks like a controller's small zone does; the caller checks the tool
    deviation it causes.

    Returns:
        A callable ``f(s, nu=0)`` (scipy spline) with values (len(s), 6).
    """
    from scipy.interpolate import make_lsq_spline

    s = np.asarray(s, float)
    n = len(s)
    if fit_spacing is None or n < 8 or s[-1] - s[0] < 3 * fit_spacing:
        return CubicSpline(s, q, axis=0, bc_type="natural" if n < 4 else "not-a-knot")
    m = int(np.ceil((s[-1] - s[0]) / fit_spacing))
    interior = np.linspace(s[0], s[-1], m + 1)[1:-1]
    knots = np.concatenate([[s[0]] * 4, interior, [s[-1]] * 4])
    return make_lsq_spline(s, q, knots, k=3, axis=0)


def _sddot_interval(x: np.ndarray, xx: np.ndarray, a: np.ndarray, v2: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Admissible path acceleration interval [lo, hi] at given sdot^2 (per sample).

    Args:
        x: (J, N) first derivatives dx_j/ds; xx: (J, N) second derivatives; a: (J,) limits;
        v2: (N,) sdot^2.
    """
    acc_c = xx * v2[None]                      # curvature term x_j'' sdot^2
    with np.errstate(divide="ignore", invalid="ignore"):
        b1 = (-a[:, None] - acc_c) / x
        b2 = (a[:, None] - acc_c) / x
    small = np.abs(x) < 1e-12
    lo_j = np.where(small, -np.inf, np.minimum(b1, b2))
    hi_j = np.where(small, np.inf, np.maximum(b1, b2))
    # a joint that barely moves along the path still needs |x_j''| sdot^2 <= a_j
    bad = small & (np.abs(acc_c) > a[:, None])
    lo = np.max(lo_j, axis=0)
    hi = np.min(hi_j, axis=0)
    hi = np.where(np.any(bad, axis=0), -np.inf, hi)
    return lo, hi


def _passes(s, x, xx, lim_a, v_curve) -> np.ndarray:
    """Forward (largest sddot) and backward (most negative sddot) passes under the curve
    ``v_curve`` (sdot^2 per sample), rest to rest; the accelerations are evaluated at both ends
    of each step (the tighter counts). Returns sdot (N,).

    The passes are sequential, so they run as a plain loop; it is kept cheap by the bounds of
    :func:`_sddot_interval` being linear in sdot^2 for a moving joint: the upper bound is
    ``min_j (a_j/|x_j'| - (x_j''/x_j') sdot^2)`` and the lower ``max_j (-a_j/|x_j'| - ...)``;
    a joint that does not move (|x_j'| < 1e-12) bounds nothing but caps
    ``sdot^2 <= a_j/|x_j''|`` (above it no sddot is admissible).
    """
    v2 = np.array(v_curve, float)
    n = len(v2)
    v2[0] = v2[-1] = 0.0
    ds = np.diff(s).tolist()
    small = np.abs(x) < 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(small, np.inf, lim_a[:, None] / np.abs(x))
        beta = np.where(small, 0.0, xx / x)
        cap = np.where(small, lim_a[:, None] / np.abs(xx), np.inf)
    alpha_t, beta_t = alpha.T.tolist(), beta.T.tolist()
    cap_t = np.min(cap, axis=0).tolist()
    inf = float("inf")

    def hi(k: int, v: float) -> float:
        if v > cap_t[k]:
            return -inf
        return min(a - b * v for a, b in zip(alpha_t[k], beta_t[k], strict=True))

    def lo(k: int, v: float) -> float:
        return max(-a - b * v for a, b in zip(alpha_t[k], beta_t[k], strict=True))

    w = v2.tolist()
    for k in range(n - 1):
        acc = min(hi(k, w[k]), hi(k + 1, w[k]))
        w[k + 1] = min(w[k + 1], max(w[k] + 2.0 * max(acc, 0.0) * ds[k], 0.0))
    for k in range(n - 2, -1, -1):
        dec = max(lo(k + 1, w[k + 1]), lo(k, w[k + 1]))
        w[k] = min(w[k], max(w[k + 1] - 2.0 * min(dec, 0.0) * ds[k], 0.0))
    return np.sqrt(np.maximum(np.array(w), 0.0))


def _hermite_accel_ratio(t, q, qd, amax) -> np.ndarray:
    """(N,) largest |acceleration| / limit of the cubic Hermite spline at each knot (over the
    intervals that touch it)."""
    h = np.diff(t)[:, None]
    dq = np.diff(q, axis=0)
    a0 = (6.0 * dq - h * (4.0 * qd[:-1] + 2.0 * qd[1:])) / h ** 2
    a1 = (-6.0 * dq + h * (2.0 * qd[:-1] + 4.0 * qd[1:])) / h ** 2
    r = np.max(np.maximum(np.abs(a0), np.abs(a1)) / amax[None], axis=1)  # per interval
    out = np.zeros(len(t))
    out[:-1] = r
    out[1:] = np.maximum(out[1:], r)
    return out


def time_path(s: np.ndarray, q: np.ndarray, p_HT: np.ndarray, limits: TimingLimits,
              fit_spacing: float | None = None) -> TimedPath:
    """Time a sampled path rest to rest under a TCP speed cap and joint limits.

    Args:
        s: (N,) strictly increasing path parameter.
        q: (N, 6) joints at the samples [rad].
        p_HT: (N, 3) tool point relative to the hub at the samples [m] (for the TCP speed).
        limits: the caps.
        fit_spacing: knot spacing of a least-squares joint spline (None: interpolate); the
            returned ``q`` are then the fitted values at the samples.

    Returns:
        TimedPath with knots at the samples.
    """
    s = np.asarray(s, float)
    q = np.asarray(q, float)
    n = len(s)
    if n < 2:
        return TimedPath(t=np.zeros(1), q=q[:1], qd=np.zeros((1, 6)), sdot=np.zeros(1),
                         v_tcp=np.zeros(1))
    bc = "natural" if n < 4 else "not-a-knot"
    spline = joint_spline(s, q, fit_spacing)
    q = spline(s)
    dq = spline(s, 1)
    ddq = spline(s, 2)
    dp = CubicSpline(s, p_HT, axis=0, bc_type=bc)(s, 1)
    dp_norm = np.linalg.norm(dp, axis=1)
    vmax = np.asarray(limits.v_max) * limits.velocity_fraction
    amax = np.asarray(limits.a_max) * limits.acceleration_fraction
    x = np.vstack([dq.T, dp_norm[None]])            # (7, N): joints and the TCP path speed
    xx = np.vstack([ddq.T, np.zeros((1, n))])      # their second derivatives
    lim_a = np.concatenate([amax, [limits.a_cap]])  # (7,) acceleration limits
    with np.errstate(divide="ignore", invalid="ignore"):
        v_lim = np.minimum(
            limits.v_cap / np.maximum(dp_norm, 1e-12),
            np.min(vmax[None] / np.maximum(np.abs(dq), 1e-12), axis=1))
    # the maximum-velocity curve of the acceleration limits: the largest sdot^2 for which some
    # sddot satisfies |x_j' sddot + x_j'' sdot^2| <= a_j for every j (bisection per sample)
    lo = np.zeros(n)
    hi = v_lim ** 2
    feasible = _sddot_interval(x, xx, lim_a, hi)[0] <= _sddot_interval(x, xx, lim_a, hi)[1]
    lo[feasible] = hi[feasible]
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        a_lo, a_hi = _sddot_interval(x, xx, lim_a, mid)
        ok = a_lo <= a_hi
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    v_curve = lo
    # the trajectory is stored as a cubic Hermite spline through (t, q, qd) at the samples; its
    # accelerations between samples differ from the path's where q'' varies fast, so check them
    # exactly (linear within an interval: the ends are the extremes) and slow down locally
    for _ in range(12):
        sdot = _passes(s, x, xx, lim_a, v_curve)
        dt = 2.0 * np.diff(s) / np.maximum(sdot[:-1] + sdot[1:], 1e-12)
        t = np.concatenate([[0.0], np.cumsum(dt)])
        qd = dq * sdot[:, None]
        ratio = _hermite_accel_ratio(t, q, qd, amax)
        over = ratio > 1.0 + 1e-6
        if not over.any():
            break
        v_curve = np.where(over, np.minimum(v_curve, sdot ** 2) / ratio ** 1.2, v_curve)
    return TimedPath(t=t, q=q, qd=qd, sdot=sdot, v_tcp=dp_norm * sdot)
