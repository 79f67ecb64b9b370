"""A window's approach and retract along the tool axis, the timing of its three stretches, its
program targets and its figures (:class:`drakedeburr.plan.results.WindowStats`)."""

from __future__ import annotations

import time

import numpy as np

from drakedeburr.plan.cut_path import least_axis_curvature
from drakedeburr.plan.options import PlanContext
from drakedeburr.plan.program_reading import rot_angle
from drakedeburr.plan.results import (
    CutStep,
    ExecutedCut,
    IkStep,
    Stretch,
    WindowPlan,
    WindowStats,
    WindowStatus,
)
from drakedeburr.plan.stretch import TargetPoint, make_target, time_cartesian
from drakedeburr.plan.transitions import clear_retract
from drakedeburr.plan.types import FailureRecord

__all__ = ["finish_window", "box_share", "move_speeds"]


def box_share(wt, order: np.ndarray, q: np.ndarray, kin) -> float | None:
    """Share of the cut targets whose planned tool axis keeps both angles inside the
    orientation stage's (theta_A, theta_B) box (the exact test, ``ToolPath.admissible``); the
    IK cone is the smallest cone containing the box, so its rim admits a little more."""
    tp = wt.tool_path
    if tp is None or len(tp) != len(wt) or not hasattr(tp, "bounds"):
        return None  # no ToolPath, or a stretch of one
    from drakedeburr.frames.local_frames import angles_from_zT_H

    z_H = kin.X_HT_from_q(q)[:, :3, 2]  # +Z_T (spindle -> tip), the ToolPath convention
    a, b = angles_from_zT_H(np.asarray(tp.R_HL)[order], z_H)
    lo, hi = tp.bounds.theta_min - 1e-9, tp.bounds.theta_max + 1e-9
    return float(np.mean((a >= lo) & (a <= hi) & (b >= lo) & (b <= hi)))


def _approach_and_retract(ctx: PlanContext, wt, ex: ExecutedCut, failures: list):
    """The tracked approach and retract (None if one is unreachable; recorded): each along
    the tool axis, or tilted toward +Z_H where that passes the cell under the clearance
    (:func:`drakedeburr.plan.transitions.clear_retract`)."""
    X0, Xe = ex.cp.X_target[0], ex.cp.X_target[-1]
    d = ctx.options.approach_distance
    out = []
    for name, X, q0 in (("approach", X0, ex.cut.q[0]), ("retract", Xe, ex.cut.q[-1])):
        mv = clear_retract(ctx.kin, ctx.checker, X, q0, d, ctx.cut_clearance,
                           ctx.options.dense_step)
        if mv is None:
            failures.append(FailureRecord(window=wt.window_index, kind=name,
                                          reason=f"{name} unreachable on the window's "
                                                 "configuration"))
            return None
        dd = mv.clearance
        if dd < ctx.cut_clearance:
            failures.append(FailureRecord(window=wt.window_index, kind=name, value=float(dd),
                                          limit=ctx.cut_clearance, unit="m", tried=mv.tried,
                                          reason=f"{name} clearance {dd * 1e3:.2f} mm"))
        out.append(mv.path)
    return out


def _wrist_record(ctx: PlanContext, wt, cut) -> list[FailureRecord]:
    j5 = float(np.min(np.abs(cut.q[:, 4])))
    margin = ctx.config.tolerances.wrist_margin
    if j5 >= margin:
        return []
    return [FailureRecord(window=wt.window_index, kind="dense", value=j5, limit=margin,
                          unit="rad", where=dict(sample=int(np.argmin(np.abs(cut.q[:, 4])))),
                          reason=f"wrist singularity: |J5| down to {np.degrees(j5):.1f} deg on "
                                 f"the cut (margin {np.degrees(margin):.1f})")]


def move_speeds(v_tcp: np.ndarray, target_index: np.ndarray, quantum: float) -> np.ndarray:
    """The programmed speed of each move of a timed cut [m/s]: the largest planned TCP speed
    over the move (the dense samples from its start target to its end target), rounded up to
    ``quantum``; (T,) for the T targets, the first (the cut's start) 0."""
    out = np.zeros(len(target_index))
    for j in range(1, len(target_index)):
        v = float(np.max(v_tcp[target_index[j - 1]:target_index[j] + 1]))
        out[j] = max(quantum, quantum * np.ceil(v / quantum - 1e-9))
    return out


def _cut_targets(ctx: PlanContext, wt, ex: ExecutedCut, order: np.ndarray,
                 speeds: np.ndarray) -> list:
    """The program's cut targets, each with the speed of the move that ends at it: CL targets
    with their edge point and normal; a via cuts the edge between its CL neighbours: their
    chord point and normal at its share of the travel between them."""
    cut, cp, via = ex.cut, ex.cp, ex.via
    cl_rows = np.flatnonzero(~via)
    out = []
    for j in range(len(ex.q_targets)):
        if not via[j]:
            i = int(order[np.searchsorted(cl_rows, j)])
            p_HC, n_H = wt.p_HC[i], wt.n_H[i]
        else:
            a, b = cl_rows[cl_rows < j][-1], cl_rows[cl_rows > j][0]
            s_a, s_j, s_b = cut.s[cut.target_index[[a, j, b]]]
            f = (s_j - s_a) / max(s_b - s_a, 1e-12)
            ia, ib = (int(order[np.searchsorted(cl_rows, r)]) for r in (a, b))
            p_HC = (1 - f) * wt.p_HC[ia] + f * wt.p_HC[ib]
            n_H = (1 - f) * wt.n_H[ia] + f * wt.n_H[ib]
            n_H = n_H / np.linalg.norm(n_H)
            i = -1
        out.append(make_target(ctx.kin, ex.q_targets[j], wt.window_index, "cut", i,
                               float(speeds[j]), "linear",
                               TargetPoint(p_HC, n_H, zone=float(cp.zone[j]))))
    return out


def _stats(ctx: PlanContext, wt, ik: IkStep, ex: ExecutedCut, timed_cut,
           fit_dev) -> WindowStats:
    wik, good, order, X_ik = ik.wik, ik.good, ik.order, ik.X_ik
    q_deg = np.degrees(ex.cut.q)
    v_g = ctx.process.grinding_speed
    v_cut = timed_cut.v_tcp[1:-1]
    band = v_g * ctx.config.tolerances.speed_band
    cl_rows = np.flatnonzero(~ex.via)
    return WindowStats(
        window=wt.window_index, kind=wt.kind, cl_points=len(wt), reached=int(len(good)),
        edge_length_m=float(np.sum(np.linalg.norm(np.diff(np.vstack([wt.p_HC, wt.p_HC[:1]]),
                                                          axis=0), axis=1))),
        tool_travel_m=float(ex.cut.s[-1]), dense_samples=int(len(ex.cut.s)),
        cut_seconds=float(timed_cut.t[-1]),
        j4_range_deg=float(np.ptp(q_deg[:, 3])), j5_range_deg=float(np.ptp(q_deg[:, 4])),
        j6_range_deg=float(np.ptp(q_deg[:, 5])),
        min_abs_j5_deg=float(np.min(np.abs(q_deg[:, 4]))),
        min_clearance_m=float(np.min(ex.dist)),
        axis_in_theta_box_fraction=box_share(wt, order, ex.q_targets[cl_rows], ctx.kin),
        cone_half_angle_rad=float(wt.cone_half_angle),
        speed_in_band_fraction=float(np.mean(np.abs(v_cut - v_g) <= band)) if len(v_cut)
        else 0.0,
        ik={k: v for k, v in wik.stats.items() if "seconds" not in k},
        joint_fit_deviation_m=fit_dev,
        orientation_smoothing_rad=float(np.max(rot_angle(X_ik[:, :3, :3],
                                                           ex.cp.X_target[cl_rows, :3, :3]))),
        via_targets=int(ex.via.sum()),
        least_axis_acceleration_radps2=v_g ** 2 * least_axis_curvature(
            wt.p_HC, wt.cone_retract_H, wt.cone_half_angle, closed=wt.closed),
        q_ik_rad=wik.q[good].tolist(), q_smoothed_rad=ex.q_targets[cl_rows].tolist(),
        cl_order=[int(i) for i in order], spin_rule=ctx.options.ik.seed_spin,
        speed_in_band_bound=_band_bound(ctx, ex, timed_cut),
        fillets=[f.as_dict() for f in ex.fillets])


def _band_bound(ctx: PlanContext, ex: ExecutedCut, timed_cut) -> float | None:
    """The planner's figure of the share of the cut that could be in the feed band: the share
    in band, plus the samples below it that lie on a stretch where the fillet repair found the
    feed can be held (cut at the feed there). None without the repair."""
    if ctx.options.fillets is None:
        return None
    v_g = ctx.process.grinding_speed
    v = timed_cut.v_tcp[1:-1]
    s = ex.cut.s[1:-1]
    ok = np.abs(v - v_g) <= ctx.config.tolerances.speed_band * v_g
    for f in ex.fillets:
        if f.held:
            ok |= (s >= f.from_m) & (s <= f.to_m)
    return float(np.mean(ok)) if len(v) else 0.0


def finish_window(ctx: PlanContext, wt, ik: IkStep, cut: CutStep) -> WindowPlan:
    """Step 5 of a window pass (:func:`drakedeburr.plan.window.plan_window_pass`):
    approach/retract, timing and statistics of a window whose cut ``cut`` and program are
    made from its IK ``ik``. Its failure records: the IK's, the cut's, then its own."""
    w, ex, wik, order = wt.window_index, cut.executed, ik.wik, ik.order
    failures = [*ik.failures, *cut.failures]
    paths = _approach_and_retract(ctx, wt, ex, failures)
    if paths is None:
        return WindowPlan.skipped(w, WindowStatus.APPROACH_FAILED, failures)
    app, ret = paths
    failures += _wrist_record(ctx, wt, ex.cut)
    v_app = ctx.process.approach_speed
    t2 = time.perf_counter()
    q_app = app.q[::-1]
    timed_app, _ = time_cartesian(ctx, q_app, app.s[-1] - app.s[::-1], app.X_HT[::-1], v_app)
    # a blended cut is smooth already: interpolate its dense joints, no least-squares fit
    timed_cut, fit_dev = time_cartesian(ctx, ex.cut.q, ex.cut.s, ex.cut.X_HT,
                                        ctx.process.grinding_speed, interpolate=True)
    timed_ret, _ = time_cartesian(ctx, ret.q, ret.s, ret.X_HT, v_app)
    seconds = {"window": w, "ik_seconds": ik.seconds, "dense_seconds": cut.seconds,
               "timing_seconds": time.perf_counter() - t2,
               "ik_seconds_per_point": wik.stats.get("seconds_per_point")}
    i0 = int(order[0])
    stretches = [
        Stretch("approach", w, timed_app, [make_target(ctx.kin, q_app[-1], w, "approach", i0,
                                                       v_app, "linear",
                                                       TargetPoint(wt.p_HC[i0], wt.n_H[i0]))]),
        Stretch("cut", w, timed_cut, _cut_targets(
            ctx, wt, ex, order, move_speeds(timed_cut.v_tcp, ex.cut.target_index,
                                            ctx.config.tolerances.speed_quantum))[1:]),
        Stretch("retract", w, timed_ret, [make_target(ctx.kin, ret.q[-1], w, "retract", -1,
                                                      v_app, "linear")]),
    ]
    stats = _stats(ctx, wt, ik, ex, timed_cut, fit_dev)
    status = WindowStatus.DEGRADED if failures else WindowStatus.OK
    return WindowPlan(window=w, status=status, stretches=stretches, stats=stats,
                      q_start=q_app[0], failures=failures, seconds=seconds)
