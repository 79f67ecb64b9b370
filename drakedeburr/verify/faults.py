"""Fault injection: take a good plan and break it in one known way.

Used by the tests and the tutorial to show that the verifier names the right check. Each
function returns a new Plan (plans are frozen); the original is untouched.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from drakedeburr.plan.types import JointTrajectory, Plan

__all__ = ["shift_knot_into_hub", "speed_up_segment", "slow_down_stretch", "drop_window",
           "cut_knot_index"]


def cut_knot_index(plan: Plan, window: int, fraction: float = 0.5) -> int:
    """Index of the trajectory knot nearest ``fraction`` of the way through a window's cut."""
    seg = next(s for s in plan.segments if s.kind == "cut" and s.window_index == window)
    t = seg.t_range[0] + fraction * (seg.t_range[1] - seg.t_range[0])
    return int(np.argmin(np.abs(plan.trajectory.t - t)))


def shift_knot_into_hub(plan: Plan, knot: int, depth: float, cell) -> Plan:
    """Move one knot so the tool point goes ``depth`` [m] further along +Z_T (into the hub).

    The knot's joints are moved by one Gauss-Newton step on the tool Jacobian (relative to
    the hub); its velocity is kept.
    """
    from pydrake.multibody.tree import JacobianWrtVariable

    traj = plan.trajectory
    q = np.array(traj.q, float)
    context = cell.plant.CreateDefaultContext()
    cell.plant.SetPositions(context, q[knot])
    X_HT = cell.tool_frame.CalcPose(context, cell.hub_frame)
    J = cell.plant.CalcJacobianSpatialVelocity(context, JacobianWrtVariable.kQDot,
                                               cell.tool_frame, np.zeros(3), cell.hub_frame,
                                               cell.hub_frame)
    dx = np.concatenate([np.zeros(3), depth * X_HT.rotation().matrix()[:, 2]])
    q[knot] = q[knot] + np.linalg.lstsq(J, dx, rcond=None)[0]
    return replace(plan, trajectory=JointTrajectory.from_hermite(t=traj.t.copy(), q=q,
                                                                 qd=traj.qd.copy()))


def speed_up_segment(plan: Plan, segment: int, factor: float) -> Plan:
    """Run one segment ``factor`` times faster (its knots squeezed in time, velocities scaled);
    later times shift so the trajectory stays continuous."""
    traj = plan.trajectory
    seg = plan.segments[segment]
    t0, t1 = seg.t_range
    t = np.array(traj.t, float)
    qd = np.array(traj.qd, float)
    inside = (t > t0) & (t <= t1)
    after = t > t1
    new_t = t.copy()
    new_t[inside] = t0 + (t[inside] - t0) / factor
    new_t[after] = t[after] - (t1 - t0) * (1 - 1 / factor)
    qd[(t >= t0) & (t <= t1)] *= factor
    shift = (t1 - t0) * (1 - 1 / factor)

    def retime(a, b):
        a2 = t0 + (a - t0) / factor if t0 <= a <= t1 else (a - shift if a > t1 else a)
        b2 = t0 + (b - t0) / factor if t0 <= b <= t1 else (b - shift if b > t1 else b)
        return (a2, b2)

    segments = tuple(replace(s, t_range=retime(*s.t_range)) for s in plan.segments)
    return replace(plan, segments=segments,
                   trajectory=JointTrajectory.from_hermite(t=new_t, q=traj.q.copy(), qd=qd))


def slow_down_stretch(plan: Plan, window: int, start: float, end: float, factor: float) -> Plan:
    """Slow a stretch of a window's cut down for no reason (a plan with needless slack): time
    runs ``k(t)`` times slower, ``k`` rising from 1 to ``factor`` and back as a raised cosine
    over the fractions ``start``..``end`` of the cut's duration. The knots keep their joints;
    their times are warped exactly (the integral of ``k``) and their velocities divided by
    ``k``; later times shift. The path is unchanged, the joint accelerations only fall."""
    seg = next(s for s in plan.segments if s.kind == "cut" and s.window_index == window)
    c0, c1 = seg.t_range
    ta, tb = c0 + start * (c1 - c0), c0 + end * (c1 - c0)
    width = tb - ta

    def warp(t):
        t = np.asarray(t, float)
        x = np.clip(t - ta, 0.0, width)
        return t + 0.5 * (factor - 1.0) * (x - width / (2 * np.pi) * np.sin(2 * np.pi * x / width))

    def k(t):
        x = np.clip(np.asarray(t, float) - ta, 0.0, width)
        return 1.0 + 0.5 * (factor - 1.0) * (1.0 - np.cos(2 * np.pi * x / width))

    traj = plan.trajectory
    segments = tuple(replace(s, t_range=(float(warp(s.t_range[0])), float(warp(s.t_range[1]))))
                     for s in plan.segments)
    return replace(plan, segments=segments, trajectory=JointTrajectory.from_hermite(
        t=warp(traj.t), q=traj.q.copy(), qd=np.asarray(traj.qd, float) / k(traj.t)[:, None]))


def drop_window(plan: Plan, window: int) -> Plan:
    """Remove a window's approach/cut/retract from the program and the trajectory; the
    transition into it then leads straight to the next move (a plan that forgot a window)."""
    keep_targets = [k for k, t in enumerate(plan.targets) if t.window_index != window]
    segs = [s for s in plan.segments if s.window_index != window]
    removed = [s for s in plan.segments if s.window_index == window]
    t_lo = min(s.t_range[0] for s in removed)
    t_hi = max(s.t_range[1] for s in removed)
    traj = plan.trajectory
    t = np.array(traj.t, float)
    # drop the knots of the window (and the one ending its retract): the move after it then
    # starts where the transition into the window ended, at rest
    keep = (t <= t_lo + 1e-12) | (t > t_hi + 1e-12)
    gap = t_hi - t_lo
    new_t = np.where(t > t_hi + 1e-12, t - gap, t)[keep]
    old_to_new = {k: i for i, k in enumerate(keep_targets)}
    new_segs = []
    for s in segs:
        a, b = s.target_range
        ks = [old_to_new[k] for k in range(a, b) if k in old_to_new]
        t_a, t_b = (v - gap if v >= t_hi - 1e-12 else v for v in s.t_range)
        new_segs.append(replace(s, target_range=(min(ks), max(ks) + 1), t_range=(t_a, t_b)))
    return replace(plan, targets=tuple(plan.targets[k] for k in keep_targets),
                   segments=tuple(new_segs),
                   trajectory=JointTrajectory.from_hermite(t=new_t, q=traj.q[keep].copy(),
                                              qd=traj.qd[keep].copy()),
                   tool_path={w: tp for w, tp in (plan.tool_path or {}).items() if w != window})
