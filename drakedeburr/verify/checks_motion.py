"""Checks of the joint motion: limits (certified on every polynomial piece), rest and home, the
configuration per window, the wrist singularity, manipulability."""

from __future__ import annotations

import numpy as np

from drakedeburr.verify.geometry import spline_extremes
from drakedeburr.verify.refs import LINEAR_KINDS
from drakedeburr.verify.report import CheckItem
from drakedeburr.verify.types import KIND_CODE

__all__ = ["joint_position", "joint_velocity", "joint_acceleration", "rest_at_ends",
           "start_end_home", "configuration", "wrist_singularity", "manipulability"]

_NAMES = [f"J{j + 1}" for j in range(6)]


def _extremes(sp) -> dict:
    return sp.memo("spline_extremes", lambda: spline_extremes(sp.plan.trajectory))


def _worst(sp, values: np.ndarray, xs: np.ndarray, ratio: np.ndarray):
    piece, cand, joint = np.unravel_index(np.argmax(ratio), ratio.shape)
    t_at = float(sp.plan.trajectory.t[piece] + xs[piece, cand, joint])
    return float(ratio[piece, cand, joint]), int(joint), t_at, float(values[piece, cand, joint])


def joint_position(sp, cfg) -> CheckItem:
    pos, pos_x, rem = _extremes(sp)["q"]
    lim = sp.limits
    margin = np.minimum(pos - rem[:, None] - lim.lower, lim.upper - pos - rem[:, None])
    piece, cand, joint = np.unravel_index(np.argmin(margin), margin.shape)
    t_at = float(sp.plan.trajectory.t[piece] + pos_x[piece, cand, joint])
    m = float(margin[piece, cand, joint])
    return CheckItem(
        "joint_position", m >= 0, m, 0.0, "rad", ">=", **sp.where_time(t_at),
        detail=f"smallest margin to a position limit: {_NAMES[joint]} at "
               f"{np.degrees(pos[piece, cand, joint]):.2f} deg (certified on every polynomial "
               "piece of the trajectory)")


def joint_velocity(sp, cfg) -> CheckItem:
    vel, x, rem = _extremes(sp)["qd"]
    vlim = sp.limits.velocity
    r, j, t_at, v = _worst(sp, vel, x, (np.abs(vel) + rem[:, None]) / vlim)
    return CheckItem("joint_velocity", r <= 1.0, r, 1.0, "ratio", "<=", **sp.where_time(t_at),
                     detail=f"worst |qd|/limit: {_NAMES[j]} {v:.4g} rad/s of {vlim[j]:.4g} "
                            "(certified on every piece)")


def joint_acceleration(sp, cfg) -> CheckItem:
    acc, x, rem = _extremes(sp)["qdd"]
    alim = sp.limits.acceleration
    r, j, t_at, v = _worst(sp, acc, x, (np.abs(acc) + rem[:, None]) / alim)
    return CheckItem("joint_acceleration", r <= 1.0, r, 1.0, "ratio", "<=",
                     **sp.where_time(t_at),
                     detail=f"worst |qdd|/limit: {_NAMES[j]} {v:.4g} rad/s^2 of {alim[j]:.4g} "
                            "(certified on every piece)")


def rest_at_ends(sp, cfg) -> CheckItem:
    qd = sp.plan.trajectory.qd
    rest = float(max(np.abs(qd[0]).max(), np.abs(qd[-1]).max()))
    return CheckItem("rest_at_ends", rest <= 1e-9, rest, 1e-9, "rad/s", "<=",
                     detail="joint velocity at the first and last knot")


def start_end_home(sp, cfg) -> CheckItem:
    q, home = sp.plan.trajectory.q, sp.limits.home
    d = float(max(np.abs(q[0] - home).max(), np.abs(q[-1] - home).max()))
    return CheckItem("start_end_home", d <= 1e-6, d, 1e-6, "rad", "<=",
                     detail="trajectory starts and ends at q_home")


def configuration(sp, cfg) -> CheckItem:
    s, opw = sp.samples, sp.kin.opw
    q_opw = opw.q_opw_from_robot(s.q)
    wrist = np.sign(s.q[:, 4])
    elbow = np.sign(q_opw[:, 2] + np.arctan2(opw.a2, opw.c3))
    c = s.X_WF[:, :3, 3] - opw.c4 * s.X_WF[:, :3, 2]
    shoulder = np.sign(c[:, 0] * np.cos(s.q[:, 0]) + c[:, 1] * np.sin(s.q[:, 0]) - opw.a1)
    contact_kinds = np.isin(s.kind, [KIND_CODE[k] for k in LINEAR_KINDS])
    flips = {}
    for w in sp.cut_windows:
        idx = np.flatnonzero((s.window == w) & contact_kinds)
        changed = [name for name, sgn in (("wrist", wrist), ("elbow", elbow),
                                          ("shoulder", shoulder))
                   if len(np.unique(sgn[idx][sgn[idx] != 0])) > 1]
        if changed:
            flips[w] = changed
    return CheckItem(
        "configuration", not flips, float(len(flips)), 0.0, "count", "<=",
        window=next(iter(flips), None),
        detail=("; ".join(f"window {w}: {', '.join(v)} flip" for w, v in flips.items())
                or "one shoulder/elbow/wrist configuration per window"))


def wrist_singularity(sp, cfg) -> CheckItem:
    """|J5| on every Cartesian (linear) segment: near J5 = 0 a linear move needs unbounded wrist
    speeds. Joint moves (home, transitions) may pass J5 = 0: the controller interpolates the
    joints there ("during joint interpolation there is never any problem when the robot passes
    singular points", ABB RAPID overview, "Singularities"); their speeds and accelerations are
    certified by the joint checks. The joint moves' least |J5| is given in the detail."""
    tol = cfg.tolerances
    j5 = np.abs(sp.samples.q[:, 4])
    linear = np.isin(sp.samples.kind, [KIND_CODE[k] for k in LINEAR_KINDS])
    joint_moves = f"; joint moves down to {np.degrees(j5[~linear].min()):.2f} deg" \
        if (~linear).any() else ""
    if not linear.any():
        return CheckItem("wrist_singularity", True, None, tol.wrist_margin, "rad", ">=",
                         detail="no linear segment" + joint_moves)
    i = int(np.flatnonzero(linear)[np.argmin(j5[linear])])
    return CheckItem(
        "wrist_singularity", bool(j5[i] >= tol.wrist_margin), float(j5[i]), tol.wrist_margin,
        "rad", ">=", **sp.where(i),
        detail="smallest |J5| on the linear segments (J5 = 0: axes 4 and 6 align)" + joint_moves)


def manipulability(sp, cfg) -> CheckItem:
    """Smallest |det J| on the linear segments (the joint moves' is no hazard: see
    :func:`wrist_singularity`)."""
    tol, m = cfg.tolerances, sp.distances.manipulability
    linear = np.isin(sp.samples.kind, [KIND_CODE[k] for k in LINEAR_KINDS]) & np.isfinite(m)
    if not linear.any():
        return CheckItem("manipulability", True, None, tol.min_manipulability, "-", ">=",
                         detail="no linear segment")
    i = int(np.flatnonzero(linear)[np.argmin(m[linear])])
    return CheckItem(
        "manipulability", bool(m[i] >= tol.min_manipulability), float(m[i]),
        tol.min_manipulability, "-", ">=", **sp.where(i),
        detail="smallest |det J| of the flange's spatial Jacobian on the linear segments "
               "(Yoshikawa measure)")
