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

The timed path *is* the composition q(t) = Q(s(t)): Q the C2 cubic spline through the samples
and s(t) quadratic between samples (constant sddot, as the passes integrate it), so between two
samples each joint is a polynomial of degree 6 in time (:func:`compose`), stored exactly in the
plan. The joint accelerations the passes bounded at the samples are the trajectory's own; a
cubic Hermite spline through (t, q, qd) would instead read accelerations several times the
path's where q''(s) varies fast (measured 4.9x at the default hub's fillets), and slowing the
path until it complied cost 13 % of the cut time for no reason the robot imposes.
Why not Drake's ``Toppra``: it enforces its limits only at its grid points (a 30 mm/s limit was
overshot to 32.8 mm/s between them, DESIGN.md), and here the grid is the dense path itself, so
the passes are exact at every sample and need no LP per grid point. TOPP-RA
(``Toppra.AddFrameTranslationalSpeedLimit``) is used in the benchmark as the cross-check.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline

__all__ = ["TimingLimits", "TimedPath", "time_path", "joint_spline", "compose", "rest_path",
           "air_limits"]


@dataclass(frozen=True)
class TimingLimits:
    """Limits of one timed stretch.

    Attributes:
        v_cap: TCP speed cap [m/s] (relative speed of tool and hub).
        a_cap: TCP path acceleration cap [m/s^2]; ``inf``: none (:func:`air_limits`).
        v_max: (6,) joint speed limits [rad/s]; a_max: (6,) joint acceleration limits.
        velocity_fraction / acceleration_fraction: share of the joint limits used (margin).
    """

    v_cap: float
    a_cap: float
    v_max: tuple[float, ...]
    a_max: tuple[float, ...]
    velocity_fraction: float = 0.95
    acceleration_fraction: float = 0.9


def air_limits(limits: TimingLimits) -> TimingLimits:
    """The limits of a move off the cut (home, transition): the joint limits (at the same
    margins) and the move's programmed TCP speed, no TCP path acceleration cap.

    The recipe's TCP path acceleration (``ProcessParameters.tcp_acceleration``) shapes the
    cut's ramps, where the burr is in contact; off the cut the arm's joint limits are the
    limits (issue 46: air moves at the arm's limits). The programmed speed stays: it is what
    the program commands and ``tcp_speed_max`` checks (the default hub's moves off the cut
    are bound by it, docs/plan.md "Air moves")."""
    return replace(limits, a_cap=np.inf)


@dataclass(frozen=True, eq=False)
class TimedPath:
    """A timed stretch (rest to rest).

    Attributes:
        t: (N,) times from 0 [s]; q: (N, 6) [rad]; qd: (N, 6) [rad/s].
        sdot: (N,) parameter speed; v_tcp: (N,) TCP speed [m/s] at the samples.
        c: (7, N - 1, 6) the joints between the samples as polynomials in the time since the
            interval's start (power basis, highest power first: scipy's ``PPoly`` layout).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    sdot: np.ndarray
    v_tcp: np.ndarray
    c: np.ndarray


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


def _rows(x: np.ndarray, xx: np.ndarray, lim_a: np.ndarray):
    """The sddot bounds ``-alpha - beta w <= sddot <= alpha - beta w`` (w = sdot^2) of the
    constraints |x_j' sddot + x_j'' w| <= a_j, one row per constraint and column per sample:
    alpha = a/|x'|, beta = x''/x'; a constraint whose |x'| < 1e-12 bounds no sddot but caps
    w <= a/|x''| (above it nothing is admissible): alpha = inf, beta = 0, and the cap."""
    small = np.abs(x) < 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(small, np.inf, lim_a[:, None] / np.abs(x))
        beta = np.where(small, 0.0, xx / x)
        cap = np.where(small, lim_a[:, None] / np.abs(xx), np.inf)
    return alpha, beta, np.min(cap, axis=0)


def _passes(s, x, xx, lim_a, v_curve) -> np.ndarray:
    """The time-optimal sdot (N,) under ``v_curve`` (sdot^2 per sample), rest to rest.

    A step k -> k + 1 has a constant sddot, so w = sdot^2 is linear in s along it; the
    constraints are met at both of its ends with the w the step has there: at the far end
    w_{k+1} = w_k + 2 sddot ds, which keeps them linear in (w_k, sddot) with the coefficient
    ``x' + 2 ds x''``. A backward pass finds the controllable sets [0, W_k] (the w_k from which
    some admissible sddot reaches [0, W_{k+1}]: closed form, each constraint being linear); the
    forward pass then takes the largest admissible sddot that stays in them. (Clipping a
    forward pass at the maximum-velocity curve instead leaves sddot = 0 where the constraints
    demand an acceleration, and the joints then leave their limits.)
    """
    n = len(s)
    ds = np.diff(s)
    # constraints of step k in terms of w_k: at its start, and at its end (14 rows)
    a0, b0, c0 = _rows(x[:, :-1], xx[:, :-1], lim_a)
    a1, b1, c1 = _rows(x[:, 1:] + 2.0 * ds * xx[:, 1:], xx[:, 1:] * 1.0, lim_a)
    alpha, beta = np.vstack([a0, a1]).T, np.vstack([b0, b1]).T  # (n - 1, 14)
    # some sddot meets all 14 (the maximum-velocity curve of the step), under ``v_curve``
    x14 = np.vstack([x[:, :-1], x[:, 1:] + 2.0 * ds * xx[:, 1:]])
    xx14 = np.vstack([xx[:, :-1], xx[:, 1:]])
    mvc = _mvc(x14, xx14, np.concatenate([lim_a, lim_a]), np.sqrt(np.asarray(v_curve)[:-1]))
    cap = np.minimum(np.minimum(c0, c1), mvc)
    with np.errstate(divide="ignore", invalid="ignore"):
        # -w/(2 ds) <= alpha - beta w (some sddot >= -w / (2 ds) is admissible)
        k_neg = beta - 1.0 / (2.0 * ds[:, None])
        cap = np.minimum(cap, np.min(np.where(k_neg > 0, alpha / k_neg, np.inf), axis=1))
    W = np.zeros(n)
    for k in range(n - 2, -1, -1):
        # w + 2 ds lo(w) <= W_{k+1}: w (1 - 2 ds beta_j) <= W_{k+1} + 2 ds alpha_j for all j
        coef = 1.0 - 2.0 * ds[k] * beta[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            lim = np.where(coef > 0, (W[k + 1] + 2.0 * ds[k] * alpha[k]) / coef, np.inf)
        W[k] = max(0.0, min(cap[k], float(lim.min())))
    w = np.zeros(n)
    for k in range(n - 1):
        hi = float(np.min(alpha[k] - beta[k] * w[k]))
        w[k + 1] = max(0.0, min(W[k + 1], w[k] + 2.0 * hi * ds[k]))
    return np.sqrt(w)


def compose(A: np.ndarray, sdot: np.ndarray, sddot: np.ndarray) -> np.ndarray:
    """Coefficients of q(tau) = Q(sigma(tau)) per interval: Q cubic in sigma = s - s_k with
    coefficients ``A`` (4, n, 6) (highest first), sigma(tau) = sdot_k tau + sddot_k tau^2 / 2.
    Returns (7, n, 6), highest power of tau first."""
    a3, a2, a1, a0 = A  # Q = a3 sigma^3 + a2 sigma^2 + a1 sigma + a0
    b1 = sdot[:, None]
    b2 = 0.5 * sddot[:, None]
    return np.stack([
        a3 * b2 ** 3,                                   # tau^6
        3 * a3 * b1 * b2 ** 2,                          # tau^5
        a2 * b2 ** 2 + 3 * a3 * b1 ** 2 * b2,           # tau^4
        2 * a2 * b1 * b2 + a3 * b1 ** 3,                # tau^3
        a1 * b2 + a2 * b1 ** 2,                         # tau^2
        a1 * b1,                                        # tau
        a0,                                             # 1
    ])


#: the timing keeps each piece's certified acceleration bound under this share of the limit
#: (the verifier's certificate of the same maximum carries its own ~1e-7 remainder)
_ACCELERATION_BOUND = 1.0 - 1e-6


def _acceleration_ratio(c: np.ndarray, dt: np.ndarray, amax: np.ndarray,
                        points: int = 9) -> np.ndarray:
    """(n,) upper bound of |joint acceleration| / limit of the composed polynomials over each
    interval: the largest of ``points`` evenly spaced readings (ends included) plus what a
    quartic can rise between two readings, delta^2 / 8 times the bound sum |c_p| dt^p of its
    second derivative (the verifier certifies the same maximum on its own)."""
    powers = np.arange(6, -1, -1)
    c2 = c[:-2] * (powers[:-2] * (powers[:-2] - 1))[:, None, None]  # (5, n, 6), degree 4
    out = np.zeros(c.shape[1])
    for f in np.linspace(0.0, 1.0, points):
        tau = f * dt
        acc = np.zeros(c.shape[1:])
        for row in c2:  # Horner
            acc = acc * tau[:, None] + row
        out = np.maximum(out, np.max(np.abs(acc) / amax[None], axis=1))
    c4 = c2[:-2] * np.array([12.0, 6.0, 2.0])[:, None, None]  # second derivative, degree 2
    m2 = np.einsum("pkj,pk->kj", np.abs(c4), dt[None] ** np.array([2, 1, 0])[:, None])
    delta = dt / (points - 1)
    return out + np.max(0.125 * delta[:, None] ** 2 * m2 / amax[None], axis=1)


def rest_path(q0: np.ndarray) -> TimedPath:
    """A stretch that does not move (one sample at rest)."""
    q0 = np.asarray(q0, float).reshape(1, 6)
    return TimedPath(t=np.zeros(1), q=q0, qd=np.zeros((1, 6)), sdot=np.zeros(1),
                     v_tcp=np.zeros(1), c=np.zeros((7, 0, 6)))


def _mvc(x, xx, lim_a, v_lim) -> np.ndarray:
    """The maximum-velocity curve of the acceleration limits (sdot^2 per sample): the largest
    sdot^2 <= v_lim^2 for which some sddot satisfies |x_j' sddot + x_j'' sdot^2| <= a_j for
    every j (bisection per sample)."""
    n = len(v_lim)
    lo = np.zeros(n)
    hi = v_lim ** 2
    a_lo, a_hi = _sddot_interval(x, xx, lim_a, hi)
    feasible = a_lo <= a_hi
    lo[feasible] = hi[feasible]
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        a_lo, a_hi = _sddot_interval(x, xx, lim_a, mid)
        ok = a_lo <= a_hi
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    return lo


def time_path(s: np.ndarray, q: np.ndarray, p_HT: np.ndarray, limits: TimingLimits,
              fit_spacing: float | None = None,
              fk: Callable[[np.ndarray], np.ndarray] | None = None) -> TimedPath:
    """Time a sampled path rest to rest under a TCP speed cap and joint limits.

    Args:
        s: (N,) strictly increasing path parameter.
        q: (N, 6) joints at the samples [rad].
        p_HT: (N, 3) tool point relative to the hub at the samples [m] (for the TCP speed).
        limits: the caps.
        fit_spacing: knot spacing of a least-squares joint spline (None: interpolate); the
            returned ``q`` are then the fitted values at the samples.
        fk: joints (M, 6) -> tool point relative to the hub (M, 3) [m]. Given, the TCP path
            speed is that of the path the robot runs (the joint spline through forward
            kinematics, central differences); otherwise that of a spline through ``p_HT``,
            which differs from it by the IK's residuals over a sample spacing (a few % at
            0.5 mm samples: enough to program a move faster than it runs).

    Returns:
        TimedPath with knots at the samples (module docstring: the exact composition).
    """
    s = np.asarray(s, float)
    q = np.asarray(q, float)
    n = len(s)
    if n < 2:
        return rest_path(q[0])
    bc = "natural" if n < 4 else "not-a-knot"
    if fit_spacing is not None:
        q = joint_spline(s, q, fit_spacing)(s)
    spline = CubicSpline(s, q, axis=0, bc_type=bc)  # the path the robot runs
    dq = spline(s, 1)
    ddq = spline(s, 2)
    if fk is None:
        dp = CubicSpline(s, p_HT, axis=0, bc_type=bc)(s, 1)
    else:
        h = 1e-3 * float(np.min(np.diff(s)))
        dp = (fk(spline(s + h)) - fk(spline(s - h))) / (2 * h)
    dp_norm = np.linalg.norm(dp, axis=1)
    vmax = np.asarray(limits.v_max) * limits.velocity_fraction
    amax = np.asarray(limits.a_max) * limits.acceleration_fraction
    # (7, N): joints and the TCP path speed (6: joints alone without a TCP acceleration cap)
    tcp = [dp_norm[None]] if np.isfinite(limits.a_cap) else []
    x = np.vstack([dq.T, *tcp])
    xx = np.vstack([ddq.T, *[np.zeros((1, n))] * len(tcp)])  # their second derivatives
    lim_a = np.concatenate([amax, [limits.a_cap] * len(tcp)])  # acceleration limits
    with np.errstate(divide="ignore", invalid="ignore"):
        v_lim = np.minimum(
            limits.v_cap / np.maximum(dp_norm, 1e-12),
            np.min(vmax[None] / np.maximum(np.abs(dq), 1e-12), axis=1))
    v_curve = _mvc(x, xx, lim_a, v_lim)
    ds = np.diff(s)
    a_true = np.asarray(limits.a_max)
    for _ in range(12):
        sdot = _passes(s, x, xx, lim_a, v_curve)
        dt = 2.0 * ds / np.maximum(sdot[:-1] + sdot[1:], 1e-12)
        sddot = (sdot[1:] ** 2 - sdot[:-1] ** 2) / (2.0 * ds)
        c = compose(spline.c, sdot[:-1], sddot)
        # the passes bound the accelerations at the samples (within the margin of
        # ``acceleration_fraction``); between them each is a quartic in time: where one
        # leaves the robot's limit itself, slow down there and time again
        over = _acceleration_ratio(c, dt, a_true) / _ACCELERATION_BOUND
        if not np.any(over > 1.0):
            break
        bad = np.flatnonzero(over > 1.0)
        for k in (bad, bad + 1):
            v_curve[k] = np.minimum(v_curve[k], sdot[k] ** 2) / over[bad]
    else:  # not settled locally: slow the whole stretch (every acceleration scales as sdot^2)
        sdot = sdot / np.sqrt(over.max())
        dt = 2.0 * ds / np.maximum(sdot[:-1] + sdot[1:], 1e-12)
        sddot = (sdot[1:] ** 2 - sdot[:-1] ** 2) / (2.0 * ds)
        c = compose(spline.c, sdot[:-1], sddot)
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return TimedPath(t=t, q=q, qd=dq * sdot[:, None], sdot=sdot, v_tcp=dp_norm * sdot, c=c)
