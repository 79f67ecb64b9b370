"""Timed stretches of a plan and the program targets they end at: Cartesian stretches (tool
poses tracked by the analytic IK, timed at a TCP speed cap), joint moves between windows and
home."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.plan.kinematics import DISTANCE_SLACK
from drakedeburr.plan.options import PlanContext
from drakedeburr.plan.results import Stretch
from drakedeburr.plan.timing import TimedPath, air_limits, rest_path, time_path
from drakedeburr.plan.transitions import faster_move, joint_move
from drakedeburr.plan.types import CartesianTarget, FailureRecord

__all__ = ["TargetPoint", "make_target", "time_cartesian", "time_joint", "joint_stretch"]


@dataclass(frozen=True, eq=False)
class TargetPoint:
    """What a program target machines: the CL point ``p_HC`` (3,) [m] and its inner normal
    ``n_H`` (3,) in H (None: a target off the edge), and its corner ``zone`` [m]."""

    p_HC: np.ndarray | None = None
    n_H: np.ndarray | None = None
    zone: float = 0.0


def make_target(kin, q, window, seg, cl, speed, motion,
                point: TargetPoint = TargetPoint()) -> CartesianTarget:
    """A program target at joints ``q`` (its poses by the analytic FK) machining ``point``."""
    q = np.asarray(q, float)
    p_HC, n_H, zone = point.p_HC, point.n_H, point.zone
    return CartesianTarget(window_index=window, segment=seg, cl_index=cl,
                           X_HT=kin.X_HT_from_q(q), X_WF=kin.fk_flange(q), q=q.copy(),
                           speed=float(speed), zone=float(zone), motion=motion,
                           p_HC=None if p_HC is None else np.asarray(p_HC, float),
                           n_H=None if n_H is None else np.asarray(n_H, float))


def time_cartesian(ctx: PlanContext, q, s, X, v_cap, interpolate: bool = False
                   ) -> tuple[TimedPath, float]:
    """Timed Cartesian stretch with the widest joint-spline fit whose tool deviation from the
    commanded samples stays within ``options.fit_tolerance`` (``interpolate``: no fit); returns
    it and that deviation."""
    limits = ctx.limits(v_cap)
    opt = ctx.options
    for spacing in ((None,) if interpolate else (*opt.fit_spacings, None)):
        timed = time_path(s, q, X[:, :3, 3], limits, fit_spacing=spacing, fk=ctx.kin.p_HT)
        dev = float(np.max(np.linalg.norm(ctx.kin.X_HT_from_q(timed.q)[:, :3, 3] - X[:, :3, 3],
                                          axis=1)))
        if dev <= opt.fit_tolerance or spacing is None:
            return timed, dev
    raise AssertionError("unreachable")


def time_joint(ctx: PlanContext, q, s, v_cap) -> TimedPath:
    """Timed joint move (``s``: joint-space arc length) under a TCP speed cap and the joint
    limits (:func:`drakedeburr.plan.timing.air_limits`)."""
    p = ctx.kin.X_HT_from_q(q)[:, :3, 3]
    return time_path(s, q, p, air_limits(ctx.limits(v_cap)), fk=ctx.kin.p_HT)


def joint_stretch(ctx: PlanContext, q0, q1, v_cap, kind, label, window: int = -1
                  ) -> tuple[Stretch, object, list[FailureRecord]]:
    """A collision-free joint move ``q0 -> q1`` checked as executed (every ``joint_step``
    rad) against the acceptance bound with the burr head not filtered; returns the stretch,
    the move and its failure records. ``window``: the window whose stretches the move joins
    (a partial window's runs, :mod:`drakedeburr.plan.partial`), its records' window; -1 (the
    default) a move between windows or home."""
    kin = ctx.kin
    bound = ctx.min_clearance + DISTANCE_SLACK
    mv = joint_move(ctx.cell, kin, ctx.free_checker, q0, q1, min_distance=bound,
                    step=ctx.options.joint_step)
    mv = faster_move(kin, ctx.free_checker, mv, lambda q, s: time_joint(ctx, q, s, v_cap).t[-1],
                     bound, ctx.options.joint_step)
    failures = []
    if not mv.ok:
        failures.append(FailureRecord(
            window=window, kind=kind, value=float(mv.clearance), limit=ctx.min_clearance, unit="m",
            tried=(mv.method,),
            reason=f"{label}: no collision-free joint move found (clearance "
                   f"{mv.clearance * 1e3:.2f} mm, {mv.method})"))
    s = mv.s if mv.s[-1] > 0 else np.linspace(0.0, 1e-9, len(mv.s))
    if len(mv.q) < 2 or mv.s[-1] <= 0:
        timed = rest_path(mv.q[0])
    else:
        timed = time_joint(ctx, mv.q, s, v_cap)
    return Stretch(kind, -1, timed, [make_target(kin, q1, -1, kind, -1, v_cap, "joint")]), mv, \
        failures
