"""Fillet repair: the tool orientation re-planned where the timed cut slows below the feed band.

The cut's orientation program (smoothest axis in the cones, spin by dynamic programming) is
chosen before timing; at some fillets another orientation lets the robot hold the feed. For
each stretch where the timed cut falls below the band (:func:`slow_stretches`), with
``method="program"`` (the default) the feed program (:mod:`drakedeburr.plan.feed_program`:
sequential convex programs over the stretch's frames, the analytic IK, the timing's own spline)
asks whether any orientation in the cones lets the joints follow the stretch at a constant feed
inside the band, and if so, which; with ``method="kto"`` one Drake
KinematicTrajectoryOptimization over the joints does (tool point on the executed path
+-``position_tolerance`` every ``constraint_step``, axis in its cone, clearance, joint bounds at
a prescribed constant speed, the cut's joints and path velocity at both ends; 3-25 s a fillet).
The stretch takes the new orientation (the positions stay exactly on the executed path; the
analytic IK re-solves the joints) only if the whole cut then has more of its travel in the band
and is no slower, stays inside the cones, as clear of the hub as before and on one
configuration. Where the program cannot hold the feed (the joints cannot follow the fillet
at the feed with any orientation in the cones: on the default hub, J3 at the window fillets
inside the 7 degree cone), it is asked again for the timed cut's own speed profile there sped
up (``FilletOptions.slower``); that orientation is kept if the whole cut is then faster with
no less of it in the band. Each stretch is reported (:func:`repair_fillets`): where it was,
whether the feed can be held there, the speed held, whether the change was kept.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from drakedeburr.frames.vectors import angle_between
from drakedeburr.plan.feed_program import FeedProgramOptions, FeedStretch, hold_feed

log = logging.getLogger(__name__)

__all__ = ["FilletOptions", "FilletStretch", "CutSamples", "slow_stretches", "stretch_kto",
           "orientation_by_kto", "repair_fillets"]


@dataclass(frozen=True)
class FilletOptions:
    """Settings of the fillet repair.

    Attributes:
        speed_share: the prescribed constant speed as a share of the grinding speed.
        half_span: the optimised stretch reaches this far either side of the slowest point [m].
        control_points: B-spline control points of one stretch's KTO.
        constraint_step: tool travel between the KTO's path constraints [m].
        position_tolerance: half-width of the tool point's box at each constraint [m].
        acceleration_share: share of the joint acceleration limits the KTO may use (the
            re-solved positions add a little joint noise the timing must absorb).
        cone_margin: the KTO keeps the axis this far inside its cone [rad].
        iterations: SNOPT major iterations.
        minor_iterations: SNOPT's total minor iterations (an infeasible stretch spends them).
        method: "program" (the feed program) or "kto".
        margin: the program's stretch reaches this far either side of a slow run [m].
        program: the feed program's settings.
        slower: where the program cannot hold the feed, run it again at the timed cut's own
            speed profile there times each of ``slower_gains`` in turn (capped at the feed)
            until one holds: a fillet the joints cannot pass at the feed inside the cone is
            then passed faster if an orientation in the cones lets them (kept only if the
            whole cut is then faster with no less of it in the band).
        slower_gains: those factors on the timed speed profile, largest first.
    """

    speed_share: float = 0.96
    half_span: float = 0.05
    control_points: int = 24
    constraint_step: float = 1e-3
    position_tolerance: float = 0.02e-3
    acceleration_share: float = 0.75
    cone_margin: float = 5e-3
    iterations: int = 300
    minor_iterations: int = 200000
    clearance_in_kto: bool = True
    method: str = "program"
    margin: float = 0.02
    program: FeedProgramOptions = field(default_factory=FeedProgramOptions)
    slower: bool = True
    slower_gains: tuple[float, ...] = (1.25, 1.12)

    def __post_init__(self) -> None:
        if self.method not in ("program", "kto"):
            from drakedeburr.errors import InputError

            raise InputError(f"FilletOptions.method must be 'program' or 'kto', got "
                             f"{self.method!r}")


@dataclass(frozen=True)
class FilletStretch:
    """The fillet repair's report of one slow stretch of a timed cut.

    Attributes:
        from_m, to_m: where the stretch runs, as travel along the cut [m].
        slowest_mps: the timed cut's slowest TCP speed on it [m/s].
        held: the feed can be held there, by the repair method's own reading.
        kept: the new orientation was kept (the whole cut more in the band and no slower, or
            no less in the band and faster).
        held_mps: the least speed on the stretch the feed program held there [m/s] (below
            the feed when it cannot hold the feed: :attr:`FilletOptions.slower`; None: none
            held).
    """

    from_m: float
    to_m: float
    slowest_mps: float
    held: bool
    kept: bool = False
    held_mps: float | None = None

    def as_dict(self) -> dict:
        """JSON-ready record (the plan's ``meta["windows"][i]["fillets"]`` entries)."""
        return asdict(self)


@dataclass(frozen=True, eq=False)
class CutSamples:
    """Dense samples of a cut (or a stretch of it) with their cones.

    Attributes:
        s: (N,) tool travel [m]; q: (N, 6) joints [rad]; X_HT: (N, 4, 4) tool poses in H [m].
        cone: (N, 3) cone axes (tip -> spindle) in H; half_angle: the cones' half-angle [rad].
    """

    s: np.ndarray
    q: np.ndarray
    X_HT: np.ndarray
    cone: np.ndarray
    half_angle: float

    @property
    def p(self) -> np.ndarray:
        """(N, 3) tool points in H [m]."""
        return self.X_HT[:, :3, 3]

    def part(self, st: slice) -> CutSamples:
        """The samples ``st``."""
        return replace(self, s=self.s[st], q=self.q[st], X_HT=self.X_HT[st], cone=self.cone[st])


def slow_stretches(s: np.ndarray, v: np.ndarray, v_band: float, keep_off: float = 0.02,
                   merge: float = 0.02) -> list[tuple[int, int, int]]:
    """Stretches of a timed cut below ``v_band`` away from its rest-to-rest ends (``keep_off``
    of travel), runs closer than ``merge`` joined: (first sample, last sample, slowest)."""
    slow = (v < v_band) & (s > keep_off) & (s < s[-1] - keep_off)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], slow.astype(int), [0]])))
    runs: list[list[int]] = []
    for a, b in edges.reshape(-1, 2):
        if runs and s[a] - s[runs[-1][1]] < merge:
            runs[-1][1] = b - 1
        else:
            runs.append([a, b - 1])
    return [(a, b, a + int(np.argmin(v[a:b + 1]))) for a, b in runs]


def stretch_kto(cell, checker, cut: CutSamples, t: np.ndarray, a_max: np.ndarray,
                v_max: np.ndarray, options: FilletOptions):
    """One KTO over a stretch ``cut`` of the executed cut (its travel, joints, tool points and
    cones at the samples) with a prescribed timing ``t`` (N,) (times at the samples from 0; a
    constant speed v: (s - s[0]) / v) and joint limits ``a_max``, ``v_max`` (6,). Returns
    (SNOPT result, its trajectory). Not a library's because Drake's KTO is the library: this
    states the stretch's problem (path constraints at ``options.constraint_step``, bounds, the
    cut's joints and path velocity at both ends) and warm-starts it from the cut."""
    from pydrake.multibody.inverse_kinematics import (
        AngleBetweenVectorsConstraint,
        MinimumDistanceLowerBoundConstraint,
        PositionConstraint,
    )
    from pydrake.planning import KinematicTrajectoryOptimization
    from pydrake.solvers import SnoptSolver, SolverOptions

    from drakedeburr.plan.cut_path import axes_interp

    s, q, p, cone, half_angle = cut.s, cut.q, cut.p, cut.cone, cut.half_angle
    T = float(t[-1])
    r = np.asarray(t, float) / T
    dq_dr = np.gradient(q, r, axis=0)  # path velocity in the KTO's normalised time
    ctx = checker.plant_context
    n = options.control_points
    kto = KinematicTrajectoryOptimization(6, n, spline_order=4)
    prog = kto.get_mutable_prog()
    kto.AddDurationConstraint(T, T)
    kto.AddPositionBounds(cell.q_lower, cell.q_upper)
    kto.AddVelocityBounds(-0.95 * v_max, 0.95 * v_max)
    a = options.acceleration_share * a_max
    kto.AddAccelerationBounds(-a, a)
    kto.AddPathPositionConstraint(q[0], q[0], 0.0)
    kto.AddPathPositionConstraint(q[-1], q[-1], 1.0)
    kto.AddPathVelocityConstraint(dq_dr[0], dq_dr[0], 0.0)
    kto.AddPathVelocityConstraint(dq_dr[-1], dq_dr[-1], 1.0)
    # the clearance tolerance the checker certifies against (the run's min_clearance)
    dist = MinimumDistanceLowerBoundConstraint(cell.plant, checker.tolerances.min_clearance, ctx,
                                               None, 3e-3)
    keep = [dist]  # the program holds references only: keep the constraints alive
    L = float(s[-1] - s[0])
    s_c = np.linspace(s[0], s[-1], int(L / options.constraint_step) + 1)[1:-1]
    p_c = np.column_stack([np.interp(s_c, s, p[:, j]) for j in range(3)])
    c_c = axes_interp(s, cone, s_c)
    tol = options.position_tolerance
    for r_c, pt, c in zip(np.interp(s_c, s, r), p_c, c_c, strict=True):
        pc = PositionConstraint(cell.plant, cell.hub_frame, pt - tol, pt + tol, cell.tool_frame,
                                np.zeros(3), ctx)
        ac = AngleBetweenVectorsConstraint(cell.plant, cell.hub_frame, c, cell.tool_frame,
                                           np.array([0.0, 0.0, -1.0]), 0.0,
                                           half_angle - options.cone_margin, ctx)
        keep += [pc, ac]
        for con in (pc, ac, dist) if options.clearance_in_kto else (pc, ac):
            kto.AddPathPositionConstraint(con, float(r_c))
    basis = kto.basis()
    B = np.array([[basis.EvaluateBasisFunctionI(i, x) for i in range(n)]
                  for x in np.clip(r, 0.0, 1.0 - 1e-12)])
    prog.SetInitialGuess(kto.control_points(), np.linalg.lstsq(B, q, rcond=None)[0].T)
    prog.SetInitialGuess(kto.duration(), T)
    kto.AddPathLengthCost(1e-3)
    opts = SolverOptions()
    opts.SetOption(SnoptSolver().solver_id(), "Major iterations limit", options.iterations)
    opts.SetOption(SnoptSolver().solver_id(), "Iterations limit", options.minor_iterations)
    t0 = time.perf_counter()
    res = SnoptSolver().Solve(prog, None, opts)
    log.debug("fillet KTO over %.0f mm in %.3f s: %s (SNOPT info %d) in %.1f s", 1e3 * L, T,
             res.is_success(), res.get_solver_details().info, time.perf_counter() - t0)
    del keep
    return res, kto.ReconstructTrajectory(res)


def orientation_by_kto(cell, kin, checker, cut: CutSamples, speed: float, a_max: np.ndarray,
                       v_max: np.ndarray, options: FilletOptions) -> np.ndarray | None:
    """Tool orientations (N, 3, 3) at the samples of a stretch (see :func:`stretch_kto`) from
    its KTO at the constant ``speed``, or None if SNOPT found no solution."""
    s, p = cut.s, cut.p
    res, traj = stretch_kto(cell, checker, cut, (s - s[0]) / speed, a_max, v_max, options)
    if not res.is_success():
        return None
    rs = (s - s[0]) / (s[-1] - s[0])
    # the KTO's tool orientation where its tool point passes each sample: its tool path at a
    # fine time grid, each sample projected on it
    tt = np.linspace(traj.start_time(), traj.end_time(), 20 * len(s))
    Qk = traj.vector_values(tt).T
    Pk = kin.X_HT_from_q(Qk)[:, :3, 3]
    seg = Pk[1:] - Pk[:-1]
    near = np.clip(np.searchsorted(np.linspace(0, 1, len(tt)), rs), 1, len(tt) - 1)
    t_at = np.empty(len(s))
    for i, (pt, k) in enumerate(zip(p, near, strict=True)):
        lo, hi = max(k - 40, 0), min(k + 40, len(seg))
        d = seg[lo:hi]
        f = np.clip(np.einsum("ij,ij->i", pt - Pk[lo:hi], d) / np.maximum(
            np.einsum("ij,ij->i", d, d), 1e-30), 0, 1)
        e = np.linalg.norm(Pk[lo:hi] + f[:, None] * d - pt, axis=1)
        j = int(np.argmin(e))
        t_at[i] = tt[lo + j] + f[j] * (tt[lo + j + 1] - tt[lo + j])
    return kin.X_HT_from_q(traj.vector_values(t_at).T)[:, :3, :3]


def _repair_one(ctx, cur: CutSamples, d, st: slice, R, window: int, s_c: float):
    """The cut ``cur`` (distances ``d``) with the new orientation ``R`` on the samples ``st``,
    or None when it leaves the cone, the joints' reach or loses clearance: (poses, joints,
    distances)."""
    from drakedeburr.plan.kinematics import DISTANCE_SLACK

    X, q = cur.X_HT, cur.q
    ang = angle_between(cur.cone[st], -R[:, :, 2])
    if np.any(ang > cur.half_angle - 1e-3):
        log.debug("window %d: fillet at %.0f mm: the KTO's axis leaves its cone; kept as it "
                 "was", window, 1e3 * s_c)
        return None
    Xn = X.copy()
    Xn[st, :3, :3] = R
    qn, ok = ctx.kin.track(ctx.kin.X_WF_from_X_HT(Xn), q[0])
    jumps = np.max(np.abs(np.diff(qn, axis=0)), axis=1)
    if not (np.all(ok) and np.all(jumps <= ctx.options.max_joint_jump)):
        return None
    dn = d.copy()
    dn[st] = ctx.checker.min_distances_along(qn[st], ctx.min_clearance + 1e-3)
    if np.any(dn[st] < np.minimum(d[st] - DISTANCE_SLACK, ctx.cut_clearance)):
        log.debug("window %d: fillet at %.0f mm: the KTO's orientation costs clearance; kept "
                 "as it was", window, 1e3 * s_c)
        return None
    return Xn, qn, dn


def _in_band(v: np.ndarray, v_g: float, band: float) -> float:
    """Share of a timed cut's inner samples within ``band`` of the feed (as the stats read it)."""
    v_cut = v[1:-1]
    return float(np.mean(np.abs(v_cut - v_g) <= band * v_g)) if len(v_cut) else 0.0


def _stretch_frames(ctx, cur: CutSamples, run, lim, fo, v_now: np.ndarray):
    """New frames for one slow run ``(a, b, c)`` of the timed cut ``cur`` (``v_now`` (N,) its
    TCP speed [m/s]): (R (n, 3, 3) over the samples ``lo..hi`` or None, lo, hi, held, the
    least speed held on the run [m/s] or None)."""
    s = cur.s
    a, b, c = run
    v_g = ctx.process.grinding_speed
    if fo.method == "program":
        lo = int(np.searchsorted(s, max(s[a] - fo.margin, 0.01)))
        hi = int(np.searchsorted(s, min(s[b] + fo.margin, s[-1] - 0.01)))
        if hi - lo < 2 * fo.program.fixed + 8:
            return None, lo, hi, False, None
        fr = np.asarray(lim.acceleration_fraction) * np.asarray(lim.a_max)
        vr = np.asarray(lim.velocity_fraction) * np.asarray(lim.v_max)
        stretch = FeedStretch(s, cur.X_HT, cur.q, cur.cone, cur.half_angle, lo, hi)
        v = fo.speed_share * v_g
        res = hold_feed(ctx.kin, stretch, v, fr, vr, fo.program)
        if res.held:
            return res.R, lo, hi, True, v
        if not fo.slower:
            return None, lo, hi, False, None
        # the fillet cannot be passed at the feed: faster than now, if an orientation lets
        # the joints follow the timed profile sped up (the program's rows carry dv/ds); the
        # profile no slower than the run's least speed anywhere on the padded range (the
        # cut's rest at its ends demands less), and no try where the timed cut stops
        slowest = float(v_now[c])
        if slowest <= 0.01 * v_g:
            return None, lo, hi, False, None
        for gain in fo.slower_gains:
            v_up = np.minimum(gain * np.maximum(v_now, slowest), v)
            res = hold_feed(ctx.kin, stretch, v_up, fr, vr, fo.program)
            if res.held:
                return res.R, lo, hi, False, float(np.min(v_up[a:b + 1]))
        return None, lo, hi, False, None
    lo = int(np.searchsorted(s, max(s[c] - fo.half_span, 0.01)))
    hi = int(np.searchsorted(s, min(s[c] + fo.half_span, s[-1] - 0.01)))
    if hi - lo < 20:
        return None, lo, hi, False, None
    R = orientation_by_kto(ctx.cell, ctx.kin, ctx.checker, cur.part(slice(lo, hi + 1)),
                           fo.speed_share * v_g, np.asarray(lim.a_max), np.asarray(lim.v_max),
                           fo)
    return R, lo, hi, R is not None, (fo.speed_share * v_g if R is not None else None)


def _try_run(ctx, cur: CutSamples, d, run, v_now, best, window: int):
    """One try at the slow run ``run`` of the cut ``cur`` (distances ``d``; ``v_now`` its timed
    TCP speed; ``best`` its (time, share in band)): (its :class:`FilletStretch`, the new
    (poses, joints, distances) if better else None, the cut's (time, share) after)."""
    from drakedeburr.plan.timing import time_path

    fo = ctx.options.fillets
    v_g = ctx.process.grinding_speed
    tol_band = ctx.config.tolerances.speed_band
    lim = ctx.limits(v_g)
    s = cur.s
    slowest = float(v_now[run[2]])
    R, lo, hi, held, v_held = _stretch_frames(ctx, cur, run, lim, fo, v_now)
    rec = FilletStretch(from_m=float(s[run[0]]), to_m=float(s[run[1]]), slowest_mps=slowest,
                        held=bool(held), held_mps=None if v_held is None else float(v_held))
    new = None if R is None else _repair_one(ctx, cur, d, slice(lo, hi + 1), R, window,
                                             s[run[2]])
    if new is None:
        return rec, None, best
    timed = time_path(s, new[1], new[0][:, :3, 3], lim, fk=ctx.kin.p_HT)
    t_new, share = float(timed.t[-1]), _in_band(timed.v_tcp, v_g, tol_band)
    log.debug("window %d: fillet at %.0f mm (%.0f mm/s, held at %.0f mm/s): cut %.3f s -> "
              "%.3f s, in band %.3f -> %.3f", window, 1e3 * s[run[2]], 1e3 * slowest,
              1e3 * v_held, best[0], t_new, best[1], share)
    # held at the feed: more in the band and no slower; held below it: faster, no less in
    # the band
    better = (share > best[1] + 1e-9 and t_new <= best[0] + 1e-3) if held else (
        share >= best[1] - 1e-9 and t_new < best[0] - 1e-3)
    if not better:
        return rec, None, best
    return replace(rec, kept=True), new, (t_new, share)


def repair_fillets(ctx, cp, cut, dist, cone, half_angle, window):
    """The cut with a new orientation (:func:`_stretch_frames`) on each stretch around a fillet
    where the timed cut falls below the speed band, each kept only if the whole cut then has
    more travel in the band and is no slower (held at the feed) or no less in the band and
    faster (held below it: :attr:`FilletOptions.slower`), the axis stays 1 mrad inside its
    cone, the joints track on the same configuration without jumps and no sample loses
    clearance (below the bound). ``ctx`` is the planner's
    :class:`drakedeburr.plan.options.PlanContext`. Returns (CutPath, DensePath, distances,
    report): the report is a :class:`FilletStretch` for each slow stretch."""
    from drakedeburr.plan.timing import time_path

    v_g = ctx.process.grinding_speed
    tol_band = ctx.config.tolerances.speed_band
    s = cut.s
    base = time_path(s, cut.q, cut.X_HT[:, :3, 3], ctx.limits(v_g), fk=ctx.kin.p_HT)
    X, q, d = cut.X_HT, cut.q, dist
    best = (float(base.t[-1]), _in_band(base.v_tcp, v_g, tol_band))
    report: list[FilletStretch] = []
    for run in slow_stretches(s, base.v_tcp, (1 - tol_band) * v_g):
        rec, new, best = _try_run(ctx, CutSamples(s, q, X, cone, half_angle), d, run,
                                  base.v_tcp, best, window)
        report.append(rec)
        if new is not None:
            X, q, d = new
    if X is cut.X_HT:
        return cp, cut, dist, report
    X_tg = cp.X_target.copy()
    X_tg[:, :3, :3] = X[cp.target_index, :3, :3]
    return replace(cp, X_HT=X, X_target=X_tg), replace(cut, X_HT=X, q=q), d, report
