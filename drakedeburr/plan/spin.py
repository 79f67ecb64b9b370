"""The spin about the tool axis along a cut: the robot's one free rotation, chosen globally.

The burr is rotationally symmetric, so the rotation of the tool about its own axis is free at
every point of a cut. It decides the whole arm pose: a poor choice drives the wrist toward its
singularity (J5 -> 0), where J4 and J6 counter-rotate at many rad/s for a small change of the
tool axis, and the timing has to crawl. So the spin is chosen for the whole cut at once by
dynamic programming over a grid of spins at every dense sample: the path that minimises the
joint motion (each joint's step divided by its speed limit, squared, summed) while staying on
the window's configuration branch, inside the joint limits and away from the wrist singularity.
The grid path is then unwrapped and Gaussian-smoothed along the travel, so the spin is smooth.

Why hand-written: redundancy resolution of a 6-axis robot for a 5-axis task is a small dynamic
program over the analytic IK; no maintained library offers it for our kinematics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from drakedeburr.plan.kinematics import CellKinematics

__all__ = ["spin_frames", "SpinSearch", "optimize_spin"]


def spin_frames(R: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Frames ``R`` turned by ``psi`` about their own Z axis: (N, 3, 3) x (N,) -> (N, 3, 3)."""
    c, s = np.cos(psi), np.sin(psi)
    out = np.array(R, float, copy=True)
    out[:, :, 0] = c[:, None] * R[:, :, 0] + s[:, None] * R[:, :, 1]
    out[:, :, 1] = -s[:, None] * R[:, :, 0] + c[:, None] * R[:, :, 1]
    return out


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.mod(a + np.pi, 2.0 * np.pi) - np.pi


@dataclass(frozen=True)
class SpinSearch:
    """Settings of :func:`optimize_spin`.

    Attributes:
        n_spin: spin grid size over a full turn; max_step: largest grid step between samples.
        wrist_margin: smallest |J5| allowed [rad].
        sigma: Gaussian width of the final smoothing [m].
        stride: the program runs on every ``stride``-th sample (the result is interpolated).
        band: spins farther than this from the reference spin are not considered [rad].
    """

    n_spin: int = 72
    max_step: int = 4
    wrist_margin: float = 0.15
    sigma: float = 4e-3
    stride: int = 2
    band: float = float(np.pi)


def optimize_spin(kin: CellKinematics, X_HT: np.ndarray, s: np.ndarray, q_branch: np.ndarray,
                  options: SpinSearch = SpinSearch(), psi_ref: np.ndarray | None = None
                  ) -> tuple[np.ndarray, dict]:
    """Smooth spin along a dense cut that minimises the joint motion.

    Args:
        kin: cell kinematics.
        X_HT: (N, 4, 4) dense tool poses in H [m]; their Z axes (and positions) are kept.
        s: (N,) travel [m].
        q_branch: (6,) joints whose (shoulder, elbow, wrist) branch the cut keeps [rad].
        options: grid, steps, wrist margin, smoothing, stride and band (:class:`SpinSearch`).
        psi_ref: (N,) reference spin [rad] (the IK's, chosen with the clearance constraint);
            spins farther than ``options.band`` from it are not considered. The search does
            not query distances (too slow for 72 spins x every sample): staying near the IK's
            spin keeps the spindle body where the IK found room, and the caller re-checks.

    Returns:
        (N, 4, 4) poses with the chosen spin, and stats (cost, feasible share, spin range).
        When no spin path is feasible the input poses are returned and stats["ok"] is False.
    """
    n_spin, max_step, wrist_margin = options.n_spin, options.max_step, options.wrist_margin
    sigma, stride, band = options.sigma, options.stride, options.band
    X_HT = np.asarray(X_HT, float)
    N = len(X_HT)
    sel = np.unique(np.concatenate([np.arange(0, N, stride), [N - 1]]))
    n = len(sel)
    psi = np.arange(n_spin) * (2.0 * np.pi / n_spin)
    # the states to solve: every spin, or those within ``band`` of the reference (the others
    # are excluded anyway; the analytic IK is elementwise, so this only saves work)
    live = np.ones((n, n_spin), bool)
    if psi_ref is not None and band < np.pi:
        ref = np.asarray(psi_ref, float)[sel]
        live = np.abs(_wrap(psi[None, :] - ref[:, None])) <= band
    k_of, m_of = np.nonzero(live)
    X = X_HT[sel][k_of]
    X[:, :3, :3] = spin_frames(X[:, :3, :3], psi[m_of])
    q_live, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    b0 = kin.branch_of(np.asarray(q_branch, float))
    match = np.flatnonzero(np.all(branches == b0[None], axis=1))
    if match.size == 0:
        return X_HT, {"ok": False, "reason": "branch not found"}
    q = np.full((n, n_spin, 6), np.nan)
    q[k_of, m_of] = q_live[:, match[0]]
    bad = np.any(~np.isfinite(q), axis=2)
    qq = np.where(np.isfinite(q), q, 0.0)
    # the turning joints J4/J6 taken within half a turn of the start (a cut turns the wrist by
    # well under that), then every joint inside its limits
    qb = np.asarray(q_branch, float)
    for j in (3, 5):
        qq[..., j] = qb[j] + _wrap(qq[..., j] - qb[j])
    bad |= np.any((qq < kin.q_lower) | (qq > kin.q_upper), axis=2)
    bad |= np.abs(qq[..., 4]) < wrist_margin
    w = 1.0 / np.asarray(kin.v_max, float)
    if np.all(_j6_alone(q, live)):
        return _hold_j6(kin, X_HT, s, q, sel, psi, qb, w)
    # state m at sample k comes from state P[m, i] = m - shift_i (mod n_spin) at k - 1; the
    # step costs of every transition at once: (n - 1, n_spin, shifts) weighted squared motion
    shifts = np.arange(-max_step, max_step + 1)
    P = (np.arange(n_spin)[:, None] - shifts[None, :]) % n_spin
    step = np.empty((n - 1, n_spin, len(shifts)))
    for i in range(len(shifts)):  # J4/J6 may not jump a turn
        dq = (qq[1:] - qq[:-1, P[:, i]]) * w
        step[:, :, i] = np.sum(dq * dq, axis=2)
    cost = np.where(bad[0], np.inf, 0.0)
    back = np.zeros((n, n_spin), int)
    rows = np.arange(n_spin)
    for k in range(1, n):
        c = cost[P] + step[k - 1]
        arg = np.argmin(c, axis=1)  # the first of equal costs, as a scan in shift order
        best = c[rows, arg]
        best[bad[k]] = np.inf
        cost, back[k] = best, P[rows, arg]
    if not np.isfinite(cost).any():
        return X_HT, {"ok": False, "reason": "no feasible spin path"}
    m = int(np.argmin(cost))
    path = np.zeros(n, int)
    path[-1] = m
    for k in range(n - 1, 0, -1):
        path[k - 1] = back[k, path[k]]
    ang = np.unwrap(psi[path])
    ang_grid = np.interp(s, s[sel], ang)
    step = max(float(np.median(np.diff(s))), 1e-9)
    # the smoothing moves the spin off the grid path the program checked: re-check the joints
    # it gives (branch, limits, wrist margin, J4/J6 in the start's turn window) on every sample
    # and smooth less where it breaks them (a path hugging a J4 limit); unsmoothed, only the
    # interpolation between the program's samples remains
    for sig in ((sigma, 0.5 * sigma, 0.25 * sigma, 0.0) if sigma > 0 else (0.0,)):
        ang_full = gaussian_filter1d(ang_grid, sig / step, mode="nearest") if sig > 0 else ang_grid
        out = X_HT.copy()
        out[:, :3, :3] = spin_frames(X_HT[:, :3, :3], ang_full)
        q_out, ok = kin.track(kin.X_WF_from_X_HT(out), qb)
        if _joints_ok(kin, q_out, ok, qb, wrist_margin):
            break
    else:
        return X_HT, {"ok": False, "reason": "the spin path leaves the limits between samples"}
    return out, {"ok": True, "cost": float(cost[m]), "spin_range_rad": float(np.ptp(ang_full)),
                 "feasible_share": float(np.mean(~bad)), "sigma_m": sig}


def _hold_j6(kin: CellKinematics, X_HT: np.ndarray, s: np.ndarray, q: np.ndarray,
             sel: np.ndarray, psi: np.ndarray, qb: np.ndarray,
             w: np.ndarray) -> tuple[np.ndarray, dict]:
    """The spin of a cut on which it moves J6 alone (the burr on the J6 axis: every sample's
    J1-J5 the same at every spin, :func:`_j6_alone`): J6 held at the start's ``qb[5]``, the
    least joint motion, in closed form. The grid program cannot find it: its
    ``2 pi / n_spin`` spin steps cost more than J6's own drift, and where J5 is under the wrist
    margin no spin can lift it (it is the tool axis's; the tracking and the verifier judge it),
    so the program's margin would exclude every spin. J6 = J6(spin m) + (spin - psi[m]): the
    spin turns the flange about its own axis."""
    solved = np.all(np.isfinite(q), axis=2)
    m = np.argmax(solved, axis=1)
    j6 = q[np.arange(len(q)), m, 5]
    ang = np.unwrap(psi[m] + _wrap(qb[5] - j6))
    out = X_HT.copy()
    out[:, :3, :3] = spin_frames(X_HT[:, :3, :3], np.interp(s, s[sel], ang))
    q_out, ok = kin.track(kin.X_WF_from_X_HT(out), qb)
    if not (np.all(ok) and bool(np.all(np.abs(q_out[:, 5] - qb[5]) <= np.pi))):
        return X_HT, {"ok": False, "reason": "the J6-holding spin leaves the limits"}
    cost = float(np.sum((np.diff(q_out[sel], axis=0) * w) ** 2))
    return out, {"ok": True, "cost": cost, "spin_range_rad": float(np.ptp(ang)),
                 "feasible_share": 1.0, "sigma_m": 0.0, "rule": "hold J6"}


def _j6_alone(q: np.ndarray, live: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n,) per sample: at least two spins solved and every solved spin gives the same J1-J5
    (to ``tol`` rad, whole turns apart): the spin moves J6 alone."""
    solved = live & np.all(np.isfinite(q), axis=2)
    first = q[np.arange(len(q)), np.argmax(solved, axis=1), :5]
    d = np.abs(np.angle(np.exp(1j * (np.where(solved[..., None], q[..., :5], 0.0)
                                      - first[:, None]))))
    return np.all(~solved[..., None] | (d <= tol), axis=(1, 2)) & (solved.sum(axis=1) > 1)


def _joints_ok(kin: CellKinematics, q: np.ndarray, ok: np.ndarray, qb: np.ndarray,
               wrist_margin: float) -> bool:
    """The joints of a spin path meet what the program demanded of its grid states (the wrist
    margin to 80 %: between the program's samples the path is interpolated)."""
    if not np.all(ok) or np.any(np.abs(q[:, 4]) < 0.8 * wrist_margin):
        return False
    return bool(np.all(np.abs(q[:, [3, 5]] - qb[[3, 5]]) <= np.pi))
