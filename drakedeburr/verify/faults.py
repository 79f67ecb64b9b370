"""Fault injection: take a good plan and break it in one known way.

Used by the tests and the tutorial to show that the verifier names the right check. Each
function returns a new Plan (plans are frozen); the original is untouched.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from drakedeburr.plan.types import JointTrajectory, Plan

__all__ = ["shift_knot_into_hub", "speed_up_segment", "slow_down_stretch", "drop_window",
           "cut_knot_index", "graze_between_samples"]


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


def _bump(traj: JointTrajectory, ta: float, tb: float, bump: np.ndarray) -> JointTrajectory:
    """The same trajectory with knots added at ``ta``/``tb`` and ``bump`` (6,) [rad] added on
    [ta, tb] as 16 s^2 (1 - s)^2 (zero value and slope at both ends, ``bump`` at the
    middle): a C1 change confined to one new piece."""
    t = np.unique(np.concatenate([traj.t, [ta, tb]]))
    deg = max(np.asarray(traj.c).shape[0] - 1, 4)
    c = np.zeros((deg + 1, len(t) - 1, 6))
    for n in range(deg + 1):  # Taylor coefficients of the old pieces at the new starts
        c[deg - n] = (traj.derivative(t[:-1], n) if n else traj.value(t[:-1])) / \
            math.factorial(n)
    k = int(np.flatnonzero(np.isclose(t, ta))[0])
    w = tb - ta
    # 16 s^2 (1 - s)^2 with s = tau / w: coefficients of tau^4, tau^3, tau^2
    c[deg - 4, k] += 16.0 / w ** 4 * bump
    c[deg - 3, k] += -32.0 / w ** 3 * bump
    c[deg - 2, k] += 16.0 / w ** 2 * bump
    return JointTrajectory(t=t, c=c)


def graze_between_samples(plan: Plan, cell, tolerances, t_near: float, depth: float
                          ) -> tuple[Plan, tuple[float, float]]:
    """Push the tool toward the hub and back between two of the verifier's samples, until the
    closest pair counted by the clearance comes ``depth`` [m] nearer than
    ``tolerances.min_clearance``: a graze that sampling with ``tolerances`` does not see.

    The bump sits on a new piece [ta, tb] a tenth of the way into the gap after the last
    sample at or before ``t_near`` [s] (pick the plan's closest approach) and an eighth of the
    gap long; its direction is the tool-point step (of 26, orientation kept, through the
    Jacobian's pseudo-inverse at the piece's middle) that brings the clearance down fastest,
    its size found by bisection on the cell's own distance query. Returns the plan and
    (ta, tb). The sampler places its samples by tool travel read on a time grid, so a bump
    this short gets none inside (measured on the reference plan at 2 mm and at 0.5 mm
    sampling; ``tests/test_verify_certificate.py`` checks it of the case it uses).

    Raises:
        ValueError: no step of up to 2 mm of tool travel comes that near.
    """
    from pydrake.multibody.tree import JacobianWrtVariable

    from drakedeburr.verify.distances import DistanceProbe
    from drakedeburr.verify.sampling import sample_times

    t_s = np.unique(sample_times(plan, cell, tolerances))  # segments share their end times
    k = min(max(int(np.searchsorted(t_s, t_near, side="right")) - 1, 0), len(t_s) - 2)
    gap = float(t_s[k + 1] - t_s[k])
    ta = float(t_s[k]) + 0.1 * gap
    tb = ta + 0.125 * gap
    q_c = plan.trajectory.value(0.5 * (ta + tb))
    probe = DistanceProbe(cell, 0.02)

    def clearance(q) -> float:
        return probe.measure(q).clearance

    ctx = cell.plant.CreateDefaultContext()
    cell.plant.SetPositions(ctx, q_c)
    J = cell.plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kQDot, cell.tool_frame,
                                               np.zeros(3), cell.hub_frame, cell.hub_frame)
    J_inv = np.linalg.pinv(J)
    grid = np.array([u for u in np.ndindex(3, 3, 3) if u != (1, 1, 1)], float) - 1.0
    grid /= np.linalg.norm(grid, axis=1, keepdims=True)
    steps = [J_inv @ np.concatenate([np.zeros(3), u]) for u in grid]  # [rad per m of travel]
    dq = steps[int(np.argmin([clearance(q_c + 0.3e-3 * d) for d in steps]))]
    target = float(tolerances.min_clearance) - float(depth)
    lo, hi = 0.0, 2e-3
    if clearance(q_c + hi * dq) > target:
        raise ValueError(f"no tool step of up to 2 mm at t = {0.5 * (ta + tb):.4f} s comes "
                         f"within {target * 1e3:.3f} mm of the hub")
    for _ in range(40):  # how far along it [m of tool travel]
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clearance(q_c + mid * dq) > target else (lo, mid)
    return replace(plan, trajectory=_bump(plan.trajectory, ta, tb, hi * dq)), (ta, tb)
