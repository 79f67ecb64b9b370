"""The planner: window targets -> cone-constrained IK -> executed motion -> timed Plan.

Per window (in order):

1. tool-point targets from the CL points (:mod:`drakedeburr.plan.targets`);
2. Drake IK at every CL target (:mod:`drakedeburr.plan.ik`): the freedom (axis inside the
   cone, spin about it) exists only there;
3. the loop closed back to the first target; the executed linear/slerp motion sampled every
   ``dense_step`` of tool travel and solved by the analytic IK on the window's configuration
   (:mod:`drakedeburr.plan.interpolate`), each sample checked for clearance and joint jumps;
4. approach and retract along the tool axis, a joint move from the previous window (or home)
   (:mod:`drakedeburr.plan.transitions`);
5. timing: 150 mm/s along the window, 450 mm/s between windows, 600 mm/s home, within the
   joint limits (:mod:`drakedeburr.plan.timing`).

Both cells are the same code: only :class:`CellKinematics` knows which of T and H rides on
the flange.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from drakedeburr.config import ProcessParameters, Tolerances
from drakedeburr.plan.cut_path import axes_interp, least_axis_curvature
from drakedeburr.plan.fillets import FilletOptions, orientation_by_kto, slow_stretches
from drakedeburr.plan.ik import IkOptions, seed_by_spin, solve_window_ik
from drakedeburr.plan.interpolate import track_poses
from drakedeburr.plan.io import _jsonable
from drakedeburr.plan.kinematics import CellKinematics, ClearanceChecker, cell_kinematics
from drakedeburr.plan.program_reading import (
    program_orientation_error,
    program_orientations,
    rot_angle,
    slerp_pairs,
)
from drakedeburr.plan.smoothing import smooth_orientations
from drakedeburr.plan.targets import contact_geometry, tool_point_H
from drakedeburr.plan.timing import TimedPath, TimingLimits, joint_spline, time_path
from drakedeburr.plan.transitions import approach_pose, joint_move
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment
from drakedeburr.plan.window_targets import WindowTargets

__all__ = ["PlanOptions", "plan_windows", "plan_hub", "window_targets_for_hub"]

log = logging.getLogger(__name__)

Progress = Callable[[int, int, str], None] | None

# numerical slack of the clearance acceptance [m]: the IK's own bound ends exactly on 2 mm at a
# few fillet targets, and the signed-distance query of the mesh pieces is good to ~1e-7 m
_DISTANCE_SLACK = 1e-6
# CL targets of the real chain: the path stage's ``adaptive`` segmentation at 0.03 mm chord
# height (the executed linear moves stay within it of the edge curve), with the FEWEST points
# that meet it and L_max (count budget 1): long chords on straight edges, short ones in fillets.
# The default budget (the proposed method's count) spreads ~2.3x as many points evenly; the
# robot gains nothing from them (every move is linear and blended), and each costs an IK solve.
CL_DELTA = 0.03e-3
CL_COUNT_BUDGET = 1


@dataclass(frozen=True)
class PlanOptions:
    """Planner settings (process speeds come from ``params``).

    Attributes:
        params: process parameters (speeds, depth of cut, bounds); None: the hub's own
            (:func:`drakedeburr.config.process_parameters`: ``process.yaml`` in the hub folder
            over the defaults) in :func:`plan_hub`, the defaults in :func:`plan_windows`.
        ik: per-target IK settings.
        dense_step: tool travel between dense samples of the executed motion [m].
        approach_distance: approach/retract length along the tool axis [m].
        approach_speed: TCP speed of approach/retract [m/s].
        tcp_acceleration: TCP path acceleration cap [m/s^2] (ramps at start/end of moves).
        joint_step: joint-space sample spacing of joint moves [rad].
        max_joint_jump: largest joint change allowed between dense samples [rad] (a flip or a
            2*pi turn shows as ~1-6 rad; fast wrist motion at corners reaches ~0.05).
        windows: indices of the windows to plan (None = all), in this order.
        orientation_sigma: Gaussian width (in targets) of the orientation smoothing.
        fit_spacings: knot spacings [m] of the least-squares joint spline, widest first.
        fit_tolerance: largest tool deviation [m] the joint-spline fit may cause.
        min_clearance: acceptance bound on every dense sample [m] (burr head/hub excepted).
        wrist_margin: smallest |J5| on a cut [rad] (the verifier's singularity margin); a cut
            that comes closer to the wrist singularity is a failure record.
        contact_radius: radius of the flank circle that cuts [m] (None: the burr's nominal
            3 mm); smaller lifts the shank off the face (:func:`targets.contact_geometry`).
        window_attempts: distinct start configurations tried when a window's IK fails.
        orientation_sigma_length: Gaussian width [m] of the orientation smoothing in tool
            travel (None: ``orientation_sigma`` in targets). The path stage spaces CL points
            unevenly, so a width in targets would not mean a width the wrist feels.
        cut_motion: "blended" (default: corners blended within ``blend_deviation``, the
            smoothest axis in the cones, spin search; :mod:`drakedeburr.plan.cut_path`) or
            "linear" (linear/slerp moves between the targets, the first version).
        blend_deviation: largest distance of a corner blend from its target [m].
        spin_sigma: Gaussian width of the IK orientations' smoothing before the axis program [m].
        axis_margin: the smoothed axis keeps this far inside its cone [rad] (so the program's
            own slerp between targets stays inside too).
        spin_search: choose the spin about the tool axis by dynamic programming
            (:mod:`drakedeburr.plan.spin`); False: the IK's spin, smoothed.
        spin_band: the search stays within this of the IK's spin [rad].
        program_orientation: largest angle [rad] between the executed tool orientation and the
            program's (slerp between consecutive targets, as a controller interpolates); where
            the smooth cut turns faster than that allows, via targets (``cl_index`` -1) are
            added on the executed path (60 % of the verifier's ``Tolerances.orientation_match``).
        via_rounds: rounds of via insertion.
        conform_program: where the program still strays after the vias (moves too short for
            one), pull the executed orientation onto the program's there
            (:func:`_conform_to_program`).
        retry_in_band: a window planned without failure records but with less than this share
            of its cut within +-5 % of the grinding speed is planned again with the other
            warm-start spin rule, and the faster of the two kept.
        acceleration_scale: what-if factor on the robot model's joint acceleration limits and
            on ``tcp_acceleration`` (1: plan to the model). The model's accelerations are
            assumed values (``models/robots/irb1600_10_120.sdf``); this factor measures how the
            speed band and cycle time depend on them (``benchmarks/bench_plan.py --accel-sweep``).
            The verifier checks the model's own limits, so a plan made with a factor above 1
            fails its acceleration check: to plan for a robot whose real accelerations are
            known, put them in the model instead.
        fillets: fillet repair (:mod:`drakedeburr.plan.fillets`): where the timed cut falls
            below the speed band, a KTO over the joints may find a tool orientation that holds
            the feed; None: off.
    """

    params: ProcessParameters | None = None
    ik: IkOptions = field(default_factory=IkOptions)
    dense_step: float = 0.25e-3
    approach_distance: float = 15e-3
    approach_speed: float = 0.05
    tcp_acceleration: float = 3.0
    joint_step: float = 0.004
    max_joint_jump: float = 0.2
    windows: tuple[int, ...] | None = None
    orientation_sigma: float = 2.0
    fit_spacings: tuple[float, ...] = (6e-3, 4e-3, 2e-3, 1e-3)
    fit_tolerance: float = 0.03e-3
    min_clearance: float = field(default_factory=lambda: Tolerances().min_clearance)
    wrist_margin: float = field(default_factory=lambda: Tolerances().wrist_margin)
    contact_radius: float | None = 1.6e-3
    window_attempts: int = 4
    orientation_sigma_length: float | None = 2e-3
    cut_motion: str = "blended"
    blend_deviation: float = 0.03e-3
    spin_sigma: float = 3e-3
    axis_margin: float = 10e-3
    spin_search: bool = True
    spin_band: float = 1.2
    program_orientation: float = field(
        default_factory=lambda: 0.6 * Tolerances().orientation_match)
    via_rounds: int = 8
    conform_program: bool = True
    retry_in_band: float = 0.5
    acceleration_scale: float = 1.0
    fillets: FilletOptions | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.acceleration_scale) and self.acceleration_scale > 0):
            raise ValueError("PlanOptions.acceleration_scale must be a positive number, got "
                             f"{self.acceleration_scale!r}")


@dataclass
class _Stretch:
    kind: str
    window_index: int
    timed: TimedPath
    targets: list


def _limits(kin: CellKinematics, v_cap: float, options: PlanOptions) -> TimingLimits:
    f = options.acceleration_scale
    return TimingLimits(v_cap=v_cap, a_cap=options.tcp_acceleration * f,
                        v_max=tuple(kin.v_max), a_max=tuple(np.asarray(kin.a_max) * f))


def _time_cartesian(kin, q, s, X, v_cap, options, interpolate: bool = False
                    ) -> tuple[TimedPath, float]:
    """Timed Cartesian stretch with the widest joint-spline fit whose tool deviation from the
    commanded samples stays within ``options.fit_tolerance`` (``interpolate``: no fit); returns
    it and that deviation."""
    limits = _limits(kin, v_cap, options)
    for spacing in ((None,) if interpolate else (*options.fit_spacings, None)):
        timed = time_path(s, q, X[:, :3, 3], limits, fit_spacing=spacing)
        dev = float(np.max(np.linalg.norm(kin.X_HT_from_q(timed.q)[:, :3, 3] - X[:, :3, 3],
                                          axis=1)))
        if dev <= options.fit_tolerance or spacing is None:
            return timed, dev
    raise AssertionError("unreachable")


def _time_joint(kin, q, s, v_cap, options) -> TimedPath:
    p = kin.X_HT_from_q(q)[:, :3, 3]
    return time_path(s, q, p, _limits(kin, v_cap, options))


def _target(kin, q, window, seg, cl, speed, motion, p_HC=None, n_H=None,
            zone: float = 0.0) -> CartesianTarget:
    q = np.asarray(q, float)
    return CartesianTarget(window_index=window, segment=seg, cl_index=cl,
                           X_HT=kin.X_HT_from_q(q), X_WF=kin.fk_flange(q), q=q.copy(),
                           speed=float(speed), zone=float(zone), motion=motion,
                           p_HC=None if p_HC is None else np.asarray(p_HC, float),
                           n_H=None if n_H is None else np.asarray(n_H, float))


def _clearance_records(window: int, checker, cut, dist: np.ndarray, bound: float) -> list[dict]:
    """One failure record per stretch of the executed cut under the clearance bound: where it
    starts and ends (sample index and tool travel), its least clearance and the closest pair."""
    low = dist < bound
    out = []
    k = 0
    while k < len(low):
        if not low[k]:
            k += 1
            continue
        end = k
        while end + 1 < len(low) and low[end + 1]:
            end += 1
        j = k + int(np.argmin(dist[k:end + 1]))
        d, pair = checker.min_distance(cut.q[j], bound + 1e-3)
        out.append(dict(window=window, cl_index=-1, stage="dense", sample=int(j),
                        samples=[int(k), int(end)],
                        s_range_mm=[float(cut.s[k] * 1e3), float(cut.s[end] * 1e3)],
                        clearance=float(d), pair=list(pair),
                        reason=f"clearance {d * 1e3:.3f} mm on the executed motion over "
                               f"{cut.s[k] * 1e3:.1f}-{cut.s[end] * 1e3:.1f} mm of the cut "
                               f"({end - k + 1} samples; {pair[0]} vs {pair[1]})"))
        k = end + 1
    return out


def _plan_window(cell, kin, checker, wt: WindowTargets, q_from: np.ndarray, options: PlanOptions,
                 failures: list, progress: Progress
                 ) -> tuple[list[_Stretch], dict, np.ndarray] | None:
    """Approach, cut and retract of one window; None when the window cannot be planned.

    Planned with the IK's warm-start spin rule, and again with the other rule when that leaves
    failure records (the better result is kept) or holds less than ``options.retry_in_band`` of
    the cut in the speed band (the faster clean one is kept): the spin picked target by target
    decides how far the wrist winds around the loop, and each rule winds some window into its
    J4/J6 limits, or slowly around, where the other does not.
    """
    first: list = []
    res = _plan_window_once(cell, kin, checker, wt, q_from, options, first, progress)
    other = "frame" if options.ik.seed_spin == "joint_cost" else "joint_cost"
    if res is not None and not first:
        band = res[1]["speed_in_band_fraction"]
        if band >= options.retry_in_band:
            return res
        # clean but slow: the other rule may wind the wrist less (workpiece cell)
        log.info("window %d: %.0f %% of the cut in the speed band; planning it again with the "
                 "%r warm-start spin", wt.window_index, 100 * band, other)
        second: list = []
        res2 = _plan_window_once(cell, kin, checker, wt, q_from,
                                 replace(options, ik=replace(options.ik, seed_spin=other)),
                                 second, progress)
        if res2 is not None and not second and res2[1]["cut_seconds"] < res[1]["cut_seconds"]:
            return res2
        return res
    log.info("window %d: %d failure records; planning it again with the %r warm-start spin",
             wt.window_index, len(first), other)
    second: list = []
    res2 = _plan_window_once(cell, kin, checker, wt, q_from,
                             replace(options, ik=replace(options.ik, seed_spin=other)), second,
                             progress)
    if res2 is not None and (res is None or len(second) < len(first)):
        res, first = res2, second
    failures += first
    return res


def _rewound_start(kin: CellKinematics, trial, q_first: np.ndarray | None,
                   near: float = 0.2) -> np.ndarray | None:
    """``q_first`` with J4/J6 turned by 2 pi away from the limit the window's IK ran into.

    A closed loop winds the wrist (in the workpiece cell J6 turns almost a full circle per
    window, the hub spinning under the fixed burr): started mid-range it runs into +-400 deg.
    The same start a turn the other way leaves room for the whole loop. None when the reached
    joints came within ``near`` [rad] of neither limit (or of both), or the turn leaves the
    limits.
    """
    reached = np.flatnonzero(trial.ok)
    if q_first is None or len(reached) == 0:
        return None
    q = trial.q[reached]
    out = np.array(q_first, float)
    for j in (3, 5):
        lo, hi = kin.q_lower[j], kin.q_upper[j]
        at_lo, at_hi = q[:, j].min() < lo + near, q[:, j].max() > hi - near
        if at_lo != at_hi:
            turned = out[j] + (2 * np.pi if at_lo else -2 * np.pi)
            if lo <= turned <= hi:
                out[j] = turned
    return None if np.array_equal(out, q_first) else out


def _plan_window_once(cell, kin, checker, wt: WindowTargets, q_from: np.ndarray,
                      options: PlanOptions, failures: list, progress: Progress
                      ) -> tuple[list[_Stretch], dict, np.ndarray] | None:
    """One planning pass of a window (see :func:`_plan_window`)."""
    r_c, lift = contact_geometry(options.contact_radius)
    m = len(wt)
    # the loop closes on a second copy of CL 0 solved last (warm-started from CL M-1): the burr
    # is rotationally symmetric, so the spin there need not equal the first one (no J6 unwind)
    loop = np.concatenate([np.arange(m), [0]]) if wt.closed else np.arange(m)
    # the IK ties the centre of the cutting circle (``lift`` below T on the axis) to its target
    p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.axis_H, wt.depth_of_cut, r_c, 0.0)[loop]
    p_HT = p_HQ + lift * wt.axis_H[loop]
    t0 = time.perf_counter()
    # window-level retries: the start configuration (J4/J6 turns, spin) decides whether the
    # wrist can follow the whole loop inside its limits; try the best few distinct seeds
    seeds = seed_by_spin(kin, checker, p_HT[0], wt.axis_H[0], wt.t_H[0], q_from, options.ik,
                         count=options.window_attempts) or [None]
    # then the seeds ranked from home: the previous window's end may hold the arm in a
    # configuration from which this loop cannot be closed (the joint move goes anywhere)
    more = seed_by_spin(kin, checker, p_HT[0], wt.axis_H[0], wt.t_H[0], kin.q_home, options.ik,
                        count=options.window_attempts) or []
    seeds = list(seeds) + [q for q in more if q is not None and not any(
        s is not None and np.max(np.abs(q - s)) < 1e-6 for s in seeds)]
    wik, best_score = None, 0
    for attempt, q_first in enumerate(seeds):
        trial = solve_window_ik(cell, kin, checker, p_HQ, wt.axis_H[loop], wt.cone_axis_H[loop],
                                wt.cone_half_angle, wt.t_H[loop], q_from,
                                window_index=wt.window_index, options=options.ik,
                                progress=progress, q_first=q_first, lift=lift)
        # the executed motion between the targets must stay on the branch and inside the
        # joint limits too (J4 winds around a loop): a cheap analytic pre-check
        reached = np.flatnonzero(trial.ok)
        dense_ok = bool(len(reached) > 1 and np.all(track_poses(
            kin, trial.X_HT[reached], trial.q[reached[0]], options.dense_step).ok))
        score = len(trial.failures) + (0 if dense_ok else 10 * (m + 1))
        if wik is None or score < best_score:
            wik, best_score = trial, score
        if score == 0:
            break
        # targets no pose in the cone can reach (the IK's probe): no other start fixes those
        unreachable = sum(1 for f in trial.failures if "cone_best_clearance" in f)
        if score == unreachable and trial is wik:
            log.warning("window %d: %d targets unreachable with %.1f mm clearance by any tool "
                        "axis in the cone; reported", wt.window_index, unreachable,
                        1e3 * options.ik.min_distance_floor)
            break
        log.info("window %d: start seed %d left %d IK failures (executed motion %s); trying "
                 "another", wt.window_index, attempt, len(trial.failures),
                 "ok" if dense_ok else "leaves the limits")
        # a wrist that wound into a J4/J6 limit: the same start a full turn the other way next
        wound = _rewound_start(kin, trial, q_first)
        if wound is not None and not any(s is not None and np.max(np.abs(wound - s)) < 1e-6
                                         for s in seeds):
            seeds.insert(attempt + 1, wound)
    t_ik = time.perf_counter() - t0
    for rec in wik.failures:
        failures.append({**rec, "cl_index": int(loop[rec["cl_index"]])})
    # only the targets that met every constraint (a failed point's row holds its best attempt)
    good = np.flatnonzero(wik.ok)
    if len(good) < (m + 1) // 2 or 0 not in good:
        failures.append(dict(window=wt.window_index, cl_index=-1, stage="window",
                             reason=f"IK reached only {len(good)} of {m + 1} targets; "
                                    "window skipped"))
        return None
    order = loop[good]
    X_ik = wik.X_HT[good]
    if options.cut_motion == "blended":
        return _finish_window_blended(cell, kin, checker, wt, options, failures, wik, good,
                                      order, X_ik, t_ik)
    if options.orientation_sigma_length:
        s_ik = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(X_ik[:, :3, 3], axis=0),
                                                               axis=1))])
        X_cut = smooth_orientations(X_ik, wt.cone_axis_H[order], wt.cone_half_angle,
                                    options.orientation_sigma_length, s=s_ik)
    else:
        X_cut = smooth_orientations(X_ik, wt.cone_axis_H[order], wt.cone_half_angle,
                                    options.orientation_sigma)
    t1 = time.perf_counter()
    # track the executed motion; where smoothing cost clearance, keep the IK orientation of the
    # targets around the offending samples and track again
    reverted = np.zeros(len(order), bool)
    for _ in range(4):
        cut = track_poses(kin, X_cut, wik.q[good[0]], options.dense_step)
        dist = np.full(len(cut.s), np.inf)
        for k in range(len(cut.s)):
            if cut.ok[k]:
                dist[k] = checker.min_distance(cut.q[k], options.min_clearance + 1e-3)[0]
        low = np.flatnonzero(dist < options.min_clearance - _DISTANCE_SLACK)
        if low.size == 0 or options.orientation_sigma <= 0:
            break
        seg = np.searchsorted(cut.target_index, low)
        near = np.concatenate([seg - 2, seg - 1, seg, seg + 1])
        fix = np.unique(np.clip(near, 0, len(order) - 1))
        fix = fix[~reverted[fix]]
        if fix.size == 0:
            break
        X_cut[fix] = X_ik[fix]
        reverted[fix] = True
    jumps = np.max(np.abs(np.diff(cut.q, axis=0)), axis=1)
    for k in np.flatnonzero(~(jumps <= options.max_joint_jump)):
        failures.append(dict(window=wt.window_index, cl_index=-1, stage="dense", sample=int(k),
                             reason=f"joint jump {float(jumps[k]):.3g} rad between dense samples"))
    for k in np.flatnonzero(~cut.ok):
        failures.append(dict(window=wt.window_index, cl_index=-1, stage="dense", sample=int(k),
                             reason="dense sample unreachable on the window's configuration"))
    if not np.all(cut.ok):
        return None
    failures += _clearance_records(wt.window_index, checker, cut, dist,
                                   options.min_clearance - _DISTANCE_SLACK)
    t_dense = time.perf_counter() - t1
    return _approach_time_stats(kin, checker, wt, options, failures, wik, good, order, X_ik,
                                X_cut, cut, cut.q[cut.target_index], dist, reverted, t_ik,
                                t_dense)


def _finish_window_blended(cell, kin, checker, wt, options, failures, wik, good, order, X_ik,
                           t_ik):
    """The executed cut as a smooth path (:mod:`drakedeburr.plan.cut_path`): blended corners
    within ``blend_deviation`` of the linear program, the smoothest axis inside the cones.

    Sampled every ``options.dense_step`` of travel, and again at half that where the program
    has moves the sampling cannot resolve (:func:`_between_samples_error`)."""
    step = options.dense_step
    while True:
        records: list[dict] = []
        out = _blended_cut(cell, kin, checker, wt, options, records, wik, good, order, X_ik,
                           t_ik, step, refine=step == options.dense_step)
        if isinstance(out, str):
            step *= 0.5
            log.info("window %d: between its samples the cut would stray from the program's "
                     "orientation; sampling it every %.3f mm", wt.window_index, step * 1e3)
            continue
        failures += records
        return out


def _between_samples_error(kin, cut, cp) -> float:
    """Largest angle [rad] between the program's orientation and the executed one *between*
    the dense samples, where the timed trajectory runs on the joint spline through them
    (:func:`drakedeburr.plan.timing.joint_spline`): read at the quarter points of every
    interval together with the samples, as the verifier reads the trajectory. Where the
    program's moves are shorter than the sampling and turn the tool, the spline cannot follow
    its orientation kinks (measured on h5_split's tight corners: 0.1-0.37 mm moves turning
    25-50 mrad read 11 mrad off the program at 0.25 mm sampling, 6.6 mrad at 0.125 mm)."""
    sp = joint_spline(cut.s, cut.q)
    ds = np.diff(cut.s)
    s_all = np.sort(np.concatenate([cut.s] + [cut.s[:-1] + f * ds for f in (0.25, 0.5, 0.75)]))
    X = kin.X_HT_from_q(sp(s_all))
    return float(program_orientation_error(X, cp.X_target)[0].max())


def _blended_cut(cell, kin, checker, wt, options, failures, wik, good, order, X_ik, t_ik,
                 step: float, refine: bool):
    """One try of :func:`_finish_window_blended` at sampling ``step``: the window's stretches,
    None, or "finer" (``refine`` and the trajectory would stray from the program between the
    samples, :func:`_between_samples_error`)."""
    from drakedeburr.plan.cut_path import cut_path
    from drakedeburr.plan.interpolate import DensePath
    from drakedeburr.plan.spin import optimize_spin, spin_frames

    t1 = time.perf_counter()
    w = wt.window_index
    pin = None
    spin_mode = "search"
    dev = np.full(len(order), options.blend_deviation)
    for attempt in range(6):
        cp = cut_path(X_ik, wt.cone_axis_H[order], wt.cone_half_angle, step=step,
                      spin_sigma=options.spin_sigma, axis_margin=options.axis_margin, pin=pin,
                      deviation=dev)
        if spin_mode == "search" and options.spin_search:
            # the spin program keeps its travel resolution (every 2nd sample at the base step)
            # when the cut is sampled more finely
            X_spin, spin_stats = optimize_spin(kin, cp.X_HT, cp.s, wik.q[good[0]],
                                               wrist_margin=options.ik.min_wrist,
                                               psi_ref=cp.psi_ik, band=options.spin_band,
                                               stride=max(1, round(2 * options.dense_step / step)))
            if spin_stats["ok"]:
                X_tg = cp.X_target.copy()
                X_tg[:, :3, :3] = X_spin[cp.target_index, :3, :3]
                cp = replace(cp, X_HT=X_spin, X_target=X_tg)
            else:
                log.info("window %d: spin search failed (%s); using the IK's spin", w,
                         spin_stats["reason"])
                spin_mode = "ik"
        if spin_mode == "ik" or not options.spin_search:
            # the IK's own spin (clearance-checked at the targets), smoothed
            X_sp = cp.X_HT.copy()
            X_sp[:, :3, :3] = spin_frames(cp.X_HT[:, :3, :3], cp.psi_ik)
            X_tg = cp.X_target.copy()
            X_tg[:, :3, :3] = X_sp[cp.target_index, :3, :3]
            cp = replace(cp, X_HT=X_sp, X_target=X_tg)
        q_d, ok_d = kin.track(kin.X_WF_from_X_HT(cp.X_HT), wik.q[good[0]])
        cut = DensePath(X_HT=cp.X_HT, s=cp.s, target_index=cp.target_index, q=q_d, ok=ok_d)
        jumps = np.max(np.abs(np.diff(cut.q, axis=0)), axis=1)
        if not (np.all(cut.ok) and np.all(jumps <= options.max_joint_jump)):
            if spin_mode != "ik":
                log.info("window %d: searched spin leaves the limits or jumps; using the IK's "
                         "spin", w)
                spin_mode = "ik"
                continue
            break
        dist = np.array([checker.min_distance(q, options.min_clearance + 1e-3)[0]
                         for q in cut.q])
        low = dist < options.min_clearance - _DISTANCE_SLACK
        if not low.any():
            break
        if dist.min() < options.min_clearance - 0.5e-3 and spin_mode != "ik":
            # far below the bound: the spin put the spindle body into the hub (pinning the
            # axis cannot fix that); fall back to the IK's spin
            log.info("window %d: %.2f mm clearance with the searched spin; using the IK's spin",
                     w, dist.min() * 1e3)
            spin_mode = "ik"
            continue
        # keep the IK's (clearance-checked) axis around the samples that came too close
        near = np.convolve(low.astype(float), np.ones(2 * int(3e-3 / step) + 1),
                           mode="same") > 0
        margin = 3e-3
        new_iv = np.column_stack([cp.s[low] - margin, cp.s[low] + margin])
        pin = new_iv if pin is None else np.vstack([pin, new_iv])
        # and round the corners there less (a blend cuts the corner by up to its deviation)
        tight = np.unique(np.searchsorted(cp.s[cp.target_index], cp.s[near]))
        tight = np.clip(np.concatenate([tight - 1, tight]), 0, len(order) - 1)
        dev[tight] *= 0.25
        log.info("window %d: %d samples under the clearance; pinning the axis and tightening "
                 "the blends around them (attempt %d)", w, int(low.sum()), attempt + 1)
    jumps = np.max(np.abs(np.diff(cut.q, axis=0)), axis=1)
    for k in np.flatnonzero(~(jumps <= options.max_joint_jump)):
        failures.append(dict(window=w, cl_index=-1, stage="dense", sample=int(k),
                             reason=f"joint jump {float(jumps[k]):.3g} rad between dense samples"))
    for k in np.flatnonzero(~cut.ok):
        failures.append(dict(window=w, cl_index=-1, stage="dense", sample=int(k),
                             reason="dense sample unreachable on the window's configuration"))
    if not np.all(cut.ok):
        return None
    failures += _clearance_records(w, checker, cut, dist, options.min_clearance - _DISTANCE_SLACK)
    if options.fillets is not None:
        cone_now = axes_interp(cp.s[cp.target_index], wt.cone_axis_H[order], cp.s)
        cp, cut, dist = _repair_fillets(cell, kin, checker, cp, cut, dist, cone_now,
                                        wt.cone_half_angle, options, w)
    # the program's targets: the CL targets' tool points with the smooth orientation there,
    # and via targets on the executed cut where the program would stray from it
    cp, via_cp = _add_vias(cp, options.program_orientation, options.via_rounds, w)
    cut = replace(cut, target_index=cp.target_index)
    if options.conform_program:
        cone_dense = axes_interp(cp.s[cp.target_index[~via_cp]], wt.cone_axis_H[order], cp.s)
        cp, cut, dist = _conform_to_program(kin, checker, cp, cut, dist, options, w,
                                            cone_dense, wt.cone_half_angle)
    q_targets = np.array([kin.track(kin.X_WF_from_X_HT(cp.X_target[j][None]),
                                    cut.q[cp.target_index[j]])[0][0]
                          for j in range(len(cp.X_target))])
    bad = np.flatnonzero(np.any(~np.isfinite(q_targets), axis=1))
    cl_of = np.full(len(via_cp), -1)
    cl_of[~via_cp] = order
    for j in bad:
        failures.append(dict(window=w, cl_index=int(cl_of[j]), stage="dense",
                             reason="program target unreachable with the smoothed orientation"))
    if bad.size:
        return None
    if refine and _between_samples_error(kin, cut, cp) > 0.8 * Tolerances().orientation_match:
        return "finer"
    stray = program_orientation_error(cp.X_HT, cp.X_target)[0]
    if stray.max() > Tolerances().orientation_match:
        k = int(np.argmax(stray))
        failures.append(dict(window=w, cl_index=-1, stage="dense", sample=k,
                             reason=f"program orientation strays {1e3 * stray[k]:.1f} mrad from "
                                    f"the executed cut (via targets: {int(via_cp.sum())})"))
    t_dense = time.perf_counter() - t1
    return _approach_time_stats(kin, checker, wt, options, failures, wik, good, order, X_ik,
                                cp.X_target, cut, q_targets, dist,
                                np.zeros(len(order), bool), t_ik, t_dense, zones=cp.zone,
                                via=via_cp)


def _repair_fillets(cell, kin, checker, cp, cut, dist, cone, half_angle, options, window):
    """The cut with the KTO's orientation (:func:`drakedeburr.plan.fillets.orientation_by_kto`)
    on each stretch around a fillet where the timed cut falls below the speed band, each kept
    only if the whole cut then times faster, the axis stays 1 mrad inside its cone, the joints
    track on the same configuration without jumps and no sample loses clearance (below the
    bound). Returns (CutPath, DensePath, distances), changed or not."""
    fo = options.fillets
    v_g = options.params.grinding_speed
    lim = _limits(kin, v_g, options)
    s = cut.s

    def duration(q, X):
        return float(time_path(s, q, X[:, :3, 3], lim).t[-1])

    base = time_path(s, cut.q, cut.X_HT[:, :3, 3], lim)
    X, q, d, best = cut.X_HT, cut.q, dist, float(base.t[-1])
    for _a, _b, c in slow_stretches(s, base.v_tcp, (1 - Tolerances().speed_band) * v_g):
        lo = int(np.searchsorted(s, max(s[c] - fo.half_span, 0.01)))
        hi = int(np.searchsorted(s, min(s[c] + fo.half_span, s[-1] - 0.01)))
        if hi - lo < 20:
            continue
        st = slice(lo, hi + 1)
        R = orientation_by_kto(cell, kin, checker, s[st], q[st], X[st, :3, 3], cone[st],
                               half_angle, fo.speed_share * v_g, np.asarray(lim.a_max),
                               np.asarray(lim.v_max), fo)
        if R is None:
            continue
        ang = np.arccos(np.clip(np.sum(cone[st] * -R[:, :, 2], axis=1), -1.0, 1.0))
        if np.any(ang > half_angle - 1e-3):
            log.info("window %d: fillet at %.0f mm: the KTO's axis leaves its cone; kept as it "
                     "was", window, 1e3 * s[c])
            continue
        Xn = X.copy()
        Xn[st, :3, :3] = R
        qn, ok = kin.track(kin.X_WF_from_X_HT(Xn), q[0])
        jumps = np.max(np.abs(np.diff(qn, axis=0)), axis=1)
        if not (np.all(ok) and np.all(jumps <= options.max_joint_jump)):
            continue
        dn = d.copy()
        dn[st] = [checker.min_distance(qi, options.min_clearance + 1e-3)[0] for qi in qn[st]]
        if np.any(dn[st] < np.minimum(d[st], options.min_clearance) - _DISTANCE_SLACK):
            log.info("window %d: fillet at %.0f mm: the KTO's orientation costs clearance; kept "
                     "as it was", window, 1e3 * s[c])
            continue
        t_new = duration(qn, Xn)
        log.info("window %d: fillet at %.0f mm (%.0f mm/s): cut %.3f s -> %.3f s", window,
                 1e3 * s[c], 1e3 * base.v_tcp[c], best, t_new)
        if t_new < best - 1e-3:
            X, q, d, best = Xn, qn, dn, t_new
    if X is cut.X_HT:
        return cp, cut, dist
    X_tg = cp.X_target.copy()
    X_tg[:, :3, :3] = X[cp.target_index, :3, :3]
    return replace(cp, X_HT=X, X_target=X_tg), replace(cut, X_HT=X, q=q), d


def _via_samples(X: np.ndarray, X_targets: np.ndarray, target_index: np.ndarray,
                 tol: float) -> np.ndarray:
    """Dense samples to make via targets: on each move of the program whose orientation strays
    more than ``tol`` from the executed poses ``X`` (read as the verifier reads it,
    :func:`drakedeburr.plan.program_reading.program_orientation_error`), the sample where it
    strays most (sorted; never a target's own sample)."""
    err, move = program_orientation_error(X, X_targets)
    err[np.asarray(target_index)] = 0.0
    out = []
    for k in np.unique(move[err > tol]):
        on = np.flatnonzero(move == k)
        # in the middle half of a move of >= 3 samples: a via next to a target (or on a move
        # shorter than the sampling) only shortens moves below what the reading resolves
        mid = on[len(on) // 4:len(on) - len(on) // 4]
        if len(on) >= 3 and len(mid):
            out.append(int(mid[np.argmax(err[mid])]))
    return np.asarray(sorted(set(out)), int)


def _add_vias(cp, tol: float, rounds: int, window: int, zone_quantum: float = 0.05e-3):
    """The cut program with via targets: executed poses (position and orientation of a dense
    sample of the cut) made targets where the program's orientation strays more than ``tol``
    (:func:`_via_samples`), for up to ``rounds`` rounds. The executed cut is not changed: a via
    lies on it, so the program only gains a vertex on the path it already runs. Its zone: 45 %
    of the shorter of its two moves, rounded down to ``zone_quantum`` (at least that; a zone
    of 0 would be a stop). Returns (CutPath with the vias, via mask per target)."""
    via = np.zeros(len(cp.target_index), bool)
    for k in range(rounds):
        add = _via_samples(cp.X_HT, cp.X_target, cp.target_index, tol)
        if add.size == 0:
            break
        at = np.searchsorted(cp.target_index, add)
        ti = np.insert(cp.target_index, at, add)
        Xt = np.insert(cp.X_target, at, cp.X_HT[add], axis=0)
        via = np.insert(via, at, True)
        zone = np.insert(cp.zone, at, 0.0)
        P = Xt[:, :3, 3]
        for j in np.flatnonzero(via & (zone == 0.0)):
            leg = 0.45 * min(np.linalg.norm(P[j] - P[j - 1]), np.linalg.norm(P[j + 1] - P[j]))
            zone[j] = max(zone_quantum, np.floor(leg / zone_quantum) * zone_quantum)
        cp = replace(cp, target_index=ti, X_target=Xt, zone=zone)
        log.info("window %d: %d via targets where the program's orientation strays more than "
                 "%.1f mrad (round %d)", window, len(add), 1e3 * tol, k + 1)
    return cp, via


def _conform_to_program(kin, checker, cp, cut, dist, options, window: int,
                        cone_axis: np.ndarray, half_angle: float, ramp: float = 1.5e-3,
                        cone_margin: float = 1e-3):
    """Where the program's orientation still strays more than ``options.program_orientation``
    after the vias (moves too short for a via: a tight corner of a small window, 0.25-0.5 mm
    moves over which the smooth executed orientation turns unevenly), the executed orientation
    is pulled onto the program's (each move's slerp, as a controller runs it) there, fading
    back to the smooth one over ``ramp`` of travel either side. The targets keep their poses
    (the program is unchanged); the joints are re-tracked and the change is kept only if they
    stay reachable, without jumps and at least as clear of the hub as the smooth cut was (or
    the clearance bound), and only if the tool axis stays ``cone_margin`` inside its cone
    (``cone_axis`` per dense sample, tip -> spindle) or no farther out than the smooth cut's:
    near a tight corner the chord of a slerp can cut across the turning cone. Returns
    (CutPath, DensePath, distances), changed or not."""
    tol = options.program_orientation
    R_prog, move = program_orientations(cp.X_HT, cp.X_target)
    err = rot_angle(R_prog, cp.X_HT[:, :3, :3])
    err[cp.target_index] = 0.0
    if err.max() <= tol:
        return cp, cut, dist
    on = np.isin(move, np.unique(move[err > tol]))
    s_on = cp.s[on]
    gap = np.abs(cp.s[:, None] - s_on[None]).min(axis=1)
    wgt = np.clip(1.0 - gap / ramp, 0.0, 1.0)
    ch = np.flatnonzero(wgt > 0)
    X = cp.X_HT.copy()
    X[ch, :3, :3] = slerp_pairs(cp.X_HT[ch, :3, :3], R_prog[ch], wgt[ch])
    c = np.asarray(cone_axis, float)[ch]
    before = np.arccos(np.clip(np.sum(c * -cp.X_HT[ch, :3, 2], axis=1), -1.0, 1.0))
    after = np.arccos(np.clip(np.sum(c * -X[ch, :3, 2], axis=1), -1.0, 1.0))
    if np.any(after > np.maximum(half_angle - cone_margin, before)):
        log.info("window %d: the program's orientation leaves the tool axis' cone (by %.2f mrad); "
                 "keeping the smooth cut", window, 1e3 * float(np.max(after - half_angle)))
        return cp, cut, dist
    q, ok = kin.track(kin.X_WF_from_X_HT(X), cut.q[0])
    jumps = np.max(np.abs(np.diff(q, axis=0)), axis=1) if len(q) > 1 else np.zeros(0)
    if not (np.all(ok) and np.all(jumps <= options.max_joint_jump)):
        log.info("window %d: the program's orientation at %d samples leaves the joints' reach; "
                 "keeping the smooth cut", window, int(on.sum()))
        return cp, cut, dist
    d_new = dist.copy()
    d_new[ch] = [checker.min_distance(qi, options.min_clearance + 1e-3)[0] for qi in q[ch]]
    floor = np.minimum(dist[ch], options.min_clearance) - _DISTANCE_SLACK
    if np.any(d_new[ch] < floor):
        log.info("window %d: the program's orientation at %d samples costs clearance (%.2f mm); "
                 "keeping the smooth cut", window, int(on.sum()), 1e3 * d_new[ch].min())
        return cp, cut, dist
    log.info("window %d: executed orientation pulled onto the program's on %d samples "
             "(strayed up to %.1f mrad)", window, int(on.sum()), 1e3 * err.max())
    return replace(cp, X_HT=X), replace(cut, X_HT=X, q=q, ok=ok), d_new


def _approach_time_stats(kin, checker, wt, options, failures, wik, good, order, X_ik, X_cut,
                         cut, q_targets, dist, reverted, t_ik, t_dense, zones=None, via=None):
    """Approach/retract, timing and statistics of a window whose cut is tracked.

    ``X_cut``/``q_targets``: the program's cut targets, the CL targets in ``order`` with via
    targets between them where ``via`` (bool per target) is True.
    """
    params = options.params
    via = np.zeros(len(q_targets), bool) if via is None else np.asarray(via, bool)
    dmin = float(np.min(dist))
    # approach and retract along the tool axis
    X0, Xe = X_cut[0], X_cut[-1]
    app = track_poses(kin, np.stack([X0, approach_pose(X0, options.approach_distance)]),
                      cut.q[0], options.dense_step)
    ret = track_poses(kin, np.stack([Xe, approach_pose(Xe, options.approach_distance)]),
                      cut.q[-1], options.dense_step)
    for name, d in (("approach", app), ("retract", ret)):
        if not np.all(d.ok):
            failures.append(dict(window=wt.window_index, cl_index=-1, stage=name,
                                 reason=f"{name} unreachable on the window's configuration"))
            return None
        dd = min(checker.min_distance(q, options.min_clearance + 1e-3)[0] for q in d.q[1:])
        if dd < options.min_clearance - _DISTANCE_SLACK:
            failures.append(dict(window=wt.window_index, cl_index=-1, stage=name,
                                 reason=f"{name} clearance {dd * 1e3:.2f} mm"))
    j5 = float(np.min(np.abs(cut.q[:, 4])))
    if j5 < options.wrist_margin:
        failures.append(dict(window=wt.window_index, cl_index=-1, stage="dense",
                             sample=int(np.argmin(np.abs(cut.q[:, 4]))),
                             reason=f"wrist singularity: |J5| down to {np.degrees(j5):.1f} deg "
                                    f"on the cut (margin {np.degrees(options.wrist_margin):.1f})"))
    q_app = app.q[::-1]
    X_app = app.X_HT[::-1]
    s_app = app.s[-1] - app.s[::-1]
    t2 = time.perf_counter()
    timed_app, _ = _time_cartesian(kin, q_app, s_app, X_app, options.approach_speed, options)
    # a blended cut is smooth already: interpolate its dense joints, no least-squares fit
    timed_cut, fit_dev = _time_cartesian(kin, cut.q, cut.s, cut.X_HT, params.grinding_speed,
                                         options, interpolate=options.cut_motion == "blended")
    timed_ret, _ = _time_cartesian(kin, ret.q, ret.s, ret.X_HT, options.approach_speed, options)
    t_time = time.perf_counter() - t2
    w = wt.window_index
    zones = np.zeros(len(order)) if zones is None else zones
    cut_targets = []
    cl_rows = np.flatnonzero(~via)
    for j in range(len(q_targets)):
        if not via[j]:
            i = int(order[np.searchsorted(cl_rows, j)])
            p_HC, n_H = wt.p_HC[i], wt.n_H[i]
        else:
            # a via cuts the edge between its CL neighbours: their chord point and normal at
            # its share of the travel between them
            a, b = cl_rows[cl_rows < j][-1], cl_rows[cl_rows > j][0]
            s_a, s_j, s_b = cut.s[cut.target_index[[a, j, b]]]
            f = (s_j - s_a) / max(s_b - s_a, 1e-12)
            ia, ib = (int(order[np.searchsorted(cl_rows, r)]) for r in (a, b))
            p_HC = (1 - f) * wt.p_HC[ia] + f * wt.p_HC[ib]
            n_H = (1 - f) * wt.n_H[ia] + f * wt.n_H[ib]
            n_H = n_H / np.linalg.norm(n_H)
            i = -1
        cut_targets.append(_target(kin, q_targets[j], w, "cut", i, params.grinding_speed,
                                   "linear", p_HC, n_H, zone=float(zones[j])))
    stretches = [
        _Stretch("approach", w, timed_app, [_target(kin, q_app[-1], w, "approach", int(good[0]),
                                                    options.approach_speed, "linear",
                                                    wt.p_HC[good[0]], wt.n_H[good[0]])]),
        _Stretch("cut", w, timed_cut, cut_targets[1:]),
        _Stretch("retract", w, timed_ret, [_target(kin, ret.q[-1], w, "retract", -1,
                                                   options.approach_speed, "linear")]),
    ]
    q_deg = np.degrees(cut.q)
    box_share = _box_share(wt, order, q_targets[cl_rows], kin)
    v_cut = timed_cut.v_tcp[1:-1]
    band = params.grinding_speed * 0.05
    stats = dict(
        window=w, kind=wt.kind, cl_points=len(wt), reached=int(len(good)),
        edge_length_m=float(np.sum(np.linalg.norm(np.diff(np.vstack([wt.p_HC, wt.p_HC[:1]]),
                                                          axis=0), axis=1))),
        tool_travel_m=float(cut.s[-1]), dense_samples=int(len(cut.s)),
        cut_seconds=float(timed_cut.t[-1]),
        j4_range_deg=float(np.ptp(q_deg[:, 3])), j5_range_deg=float(np.ptp(q_deg[:, 4])),
        j6_range_deg=float(np.ptp(q_deg[:, 5])),
        min_abs_j5_deg=float(np.min(np.abs(q_deg[:, 4]))),
        min_clearance_m=float(dmin), axis_in_theta_box_fraction=box_share,
        cone_half_angle_rad=float(wt.cone_half_angle),
        smoothing_reverted_targets=int(reverted.sum()),
        speed_in_band_fraction=float(np.mean(np.abs(v_cut - params.grinding_speed) <= band))
        if len(v_cut) else 0.0,
        ik_seconds=t_ik, dense_seconds=t_dense, timing_seconds=t_time, ik=wik.stats,
        joint_fit_deviation_m=fit_dev,
        orientation_smoothing_rad=float(np.max(_angle(X_ik, X_cut[cl_rows]))),
        via_targets=int(via.sum()),
        least_axis_acceleration_radps2=params.grinding_speed ** 2 * least_axis_curvature(
            wt.p_HC, wt.cone_axis_H, wt.cone_half_angle, closed=wt.closed),
        q_ik_rad=wik.q[good].tolist(), q_smoothed_rad=q_targets[cl_rows].tolist(),
        cl_order=[int(i) for i in order])
    return stretches, stats, q_app[0]


def _box_share(wt: WindowTargets, order: np.ndarray, q: np.ndarray,
               kin: CellKinematics) -> float | None:
    """Share of the cut targets whose planned tool axis keeps both angles inside the
    orientation stage's (theta_A, theta_B) box (the exact test, ``ToolPath.admissible``); the
    IK cone is the smallest cone containing the box, so its rim admits a little more."""
    tp = wt.tool_path
    if tp is None or len(tp) != len(wt) or not hasattr(tp, "bounds"):
        return None  # no ToolPath, or a stretch of one
    from drakedeburr.frames.local_frames import angles_from_axis_H

    z_H = kin.X_HT_from_q(q)[:, :3, 2]  # +Z_T (spindle -> tip), the ToolPath convention
    a, b = angles_from_axis_H(np.asarray(tp.R_HL)[order], z_H)
    lo, hi = tp.bounds.theta_min - 1e-9, tp.bounds.theta_max + 1e-9
    return float(np.mean((a >= lo) & (a <= hi) & (b >= lo) & (b <= hi)))


def _angle(Xa: np.ndarray, Xb: np.ndarray) -> np.ndarray:
    """(M,) rotation angle between paired poses [rad]."""
    c = (np.einsum("mij,mij->m", Xa[:, :3, :3], Xb[:, :3, :3]) - 1.0) / 2.0
    return np.arccos(np.clip(c, -1.0, 1.0))


def _joint_stretch(cell, kin, checker, q0, q1, v_cap, kind, options, failures, label) -> _Stretch:
    # the move is checked as executed (every ``joint_step`` rad), so it needs the acceptance
    # bound, not the IK's 0.1 mm margin (that is for the smoothing between cut targets)
    mv = joint_move(cell, kin, checker, q0, q1,
                    min_distance=options.min_clearance + _DISTANCE_SLACK, step=options.joint_step)
    if not mv.ok:
        failures.append(dict(window=-1, cl_index=-1, stage=kind,
                             reason=f"{label}: no collision-free joint move found "
                                    f"(clearance {mv.clearance * 1e3:.2f} mm, {mv.method})"))
    s = mv.s if mv.s[-1] > 0 else np.linspace(0.0, 1e-9, len(mv.s))
    if len(mv.q) < 2 or mv.s[-1] <= 0:
        timed = TimedPath(t=np.zeros(1), q=mv.q[:1], qd=np.zeros((1, 6)), sdot=np.zeros(1),
                          v_tcp=np.zeros(1))
    else:
        timed = _time_joint(kin, mv.q, s, v_cap, options)
    return _Stretch(kind, -1, timed, [_target(kin, q1, -1, kind, -1, v_cap, "joint")]), mv


def plan_windows(
    cell,
    windows: Sequence[WindowTargets],
    *,
    scenario: str = "",
    hub: str = "",
    options: PlanOptions = PlanOptions(),
    progress: Progress = None,
) -> Plan:
    """Plan the given windows of a loaded cell, from home and back.

    Args:
        cell: :class:`drakedeburr.cell.Cell` (tool- or workpiece-in-hand).
        windows: the windows' targets, in execution order.
        scenario, hub: names recorded in the plan.
        options: planner settings.
        progress: optional callback (done, total, label) per window.

    Returns:
        Plan; ``failures`` lists every point/move that failed (empty when all planned).
    """
    t_start = time.perf_counter()
    if options.params is None:
        options = replace(options, params=ProcessParameters())
    kin = cell_kinematics(cell)
    checker = ClearanceChecker(cell)
    # moves that do not cut keep the burr head clear of the hub too
    free_checker = ClearanceChecker(cell, filter_burr_contact=False)
    params = options.params
    failures: list[dict] = []
    stretches: list[_Stretch] = []
    window_stats = []
    q_cur = kin.q_home.copy()
    home = _target(kin, q_cur, -1, "home", -1, params.home_speed, "joint")
    n = len(windows)
    transition_seconds = 0.0
    for k, wt in enumerate(windows):
        if progress is not None:
            progress(k, n, f"window {wt.window_index}")
        res = _plan_window(cell, kin, checker, wt, q_cur, options, failures, None)
        if res is None:
            continue
        win_stretches, stats, q_app0 = res
        speed = params.home_speed if not stretches else params.window_switch_speed
        kind = "home" if not stretches else "transition"
        t0 = time.perf_counter()
        js, mv = _joint_stretch(cell, kin, free_checker, q_cur, q_app0, speed, kind, options,
                                failures, f"to window {wt.window_index}")
        transition_seconds += time.perf_counter() - t0
        stats["transition_method"] = mv.method
        stretches.append(js)
        stretches.extend(win_stretches)
        window_stats.append(stats)
        q_cur = win_stretches[-1].timed.q[-1]
    t0 = time.perf_counter()
    js, mv = _joint_stretch(cell, kin, free_checker, q_cur, kin.q_home, params.home_speed,
                            "home", options, failures, "return home")
    transition_seconds += time.perf_counter() - t0
    stretches.append(js)
    if progress is not None:
        progress(n, n, "done")
    planned = {s["window"] for s in window_stats}
    for wt in windows:
        if wt.window_index not in planned:
            log.warning("window %d not planned", wt.window_index)
    return _assemble(cell, kin, stretches, home, window_stats, failures, scenario, hub, windows,
                     options, dict(total_seconds=time.perf_counter() - t_start,
                                   transition_seconds=transition_seconds))


def _assemble(cell, kin, stretches, home, window_stats, failures, scenario, hub, windows, options,
              timings) -> Plan:
    t_all, q_all, qd_all = [np.zeros(1)], [kin.q_home[None]], [np.zeros((1, 6))]
    targets = [home]
    segments = []
    t_off = 0.0
    for st in stretches:
        tp = st.timed
        first = len(targets)
        targets.extend(st.targets)
        if len(tp.t) > 1:
            t_all.append(t_off + tp.t[1:])
            q_all.append(tp.q[1:])
            qd_all.append(tp.qd[1:])
        t_end = t_off + float(tp.t[-1])
        segments.append(PlanSegment(window_index=st.window_index, kind=st.kind,
                                    target_range=(first, len(targets)), t_range=(t_off, t_end)))
        t_off = t_end
    t = np.concatenate(t_all)
    q = np.concatenate(q_all)
    qd = np.concatenate(qd_all)
    keep = np.concatenate([[True], np.diff(t) > 1e-9])  # zero-length stretches
    traj = JointTrajectory(t=t[keep], q=q[keep], qd=qd[keep])
    params = options.params
    edge_total = sum(s["tool_travel_m"] for s in window_stats)
    cut_time = sum(s["cut_seconds"] for s in window_stats)
    seg_time = {}
    for sgm in segments:
        seg_time[sgm.kind] = seg_time.get(sgm.kind, 0.0) + sgm.t_range[1] - sgm.t_range[0]
    meta = dict(
        version=1,
        planner="drakedeburr.plan",
        contact_radius_m=contact_geometry(options.contact_radius)[0],
        contact_lift_m=contact_geometry(options.contact_radius)[1],
        X_FT=kin.X_FT.tolist(), X_FH=kin.X_FH.tolist(), X_WT=kin.X_WT.tolist(),
        robot=cell.arm.name, X_WB=kin.X_WB.tolist(),
        windows=window_stats,
        window_sources=[w.source for w in windows],
        depth_of_cut={str(w.window_index): w.depth_of_cut for w in windows},
        cycle_seconds=traj.duration,
        segment_seconds=seg_time,
        cutting_seconds=cut_time,
        physical_cut_seconds=edge_total / params.grinding_speed,
        cut_time_ratio=cut_time / (edge_total / params.grinding_speed) if edge_total else None,
        timings=timings,
        options=_jsonable(asdict(options)),
    )
    tool_paths = tuple(w.tool_path for w in windows) if any(w.tool_path is not None
                                                           for w in windows) else None
    return Plan(scenario=str(scenario), hub=str(hub), mode=cell.mode, X_WH=kin.X_WH.copy(),
                targets=tuple(targets), segments=tuple(segments), trajectory=traj,
                tool_path=tool_paths, failures=tuple(failures), meta=meta)


def window_targets_for_hub(hub_model, *, source: str = "auto",
                           params: ProcessParameters | None = None,
                           windows: Sequence[int] | None = None,
                           progress: Progress = None) -> list[WindowTargets]:
    """Targets of a hub's windows: hub edges -> CL points -> orientation (-> WindowTargets).

    Args:
        hub_model: ``drakedeburr.hub.HubModel``.
        source: "toolpath" (path + orientation stages), "edges" (ground-truth edges with a fixed
            tilt, no upstream stages), or "auto" (the toolpath chain; the edges stand-in only
            when the upstream stages cannot be imported, with a logged warning - a ToolPath
            that is wrong raises, as with "toolpath").
        params: process parameters (default: the hub's, ``hub_model.process``).
        windows: window indices (default all).
    """
    params = params or hub_model.process
    chosen = [w for w in hub_model.windows if windows is None or w.index in set(windows)]
    out = []
    for k, edge in enumerate(chosen):
        if progress is not None:
            progress(k, len(chosen), f"targets window {edge.index}")
        wt = None
        if source in ("toolpath", "auto"):
            try:
                wt = WindowTargets.from_tool_path(_tool_path(edge, params))
            except ImportError as exc:
                if source == "toolpath":
                    raise
                log.warning("window %d: path/orientation stage unavailable (%s); using the "
                            "ground-truth edge with a fixed tilt instead", edge.index, exc)
        if wt is None:
            wt = WindowTargets.from_window_edge(edge, params=params)
        out.append(wt)
    if progress is not None:
        progress(len(chosen), len(chosen), "targets")
    return out


def _tool_path(edge, params: ProcessParameters):
    """CL points and tool axes of one window by the path and orientation stages."""
    from scipy.spatial import cKDTree

    from drakedeburr.orientation.orient import orient_window
    from drakedeburr.path import fit_edge_curve, plan_cl
    from drakedeburr.path.cl_planning import PlannerParams

    curve = fit_edge_curve(edge.p_HE, name=f"window {edge.index}")
    cl = plan_cl(curve, method="adaptive", params=PlannerParams(delta_max=CL_DELTA,
                                                            count_budget=CL_COUNT_BUDGET),
                 window_index=edge.index, kind=edge.kind)
    nearest = cKDTree(edge.p_HE).query(cl.p_HC)[1]
    return orient_window(cl, edge.n_wall_H[nearest], params=params)


def plan_hub(
    scenario: str = "tool_in_hand",
    hub: str | None = None,
    mode: str | None = None,
    *,
    source: str = "auto",
    options: PlanOptions = PlanOptions(),
    progress: Progress = None,
    robot: str | None = None,
) -> Plan:
    """Plan a whole hub end to end: hub -> CL -> orientation -> IK -> timed Plan.

    Args:
        scenario: bundled scenario name or path; ``mode`` "tool"/"workpiece" picks the bundled
            ``tool_in_hand``/``workpiece_in_hand`` scenario instead.
        hub: bundled hub name or folder (default: the first bundled hub).
        source: where the tool axes come from (see :func:`window_targets_for_hub`).
        options: planner settings (``options.windows`` limits the windows).
        progress: callback (done, total, label).
        robot: registered arm (``drakedeburr robots``); None: the scenario's own arm.

    Returns:
        The Plan (check ``plan.failures``); ``meta["robot"]`` names the arm.
    """
    from drakedeburr.cell.station import load_cell
    from drakedeburr.errors import InputError
    from drakedeburr.hub import load_hub

    if mode is not None:
        if mode not in ("tool", "workpiece"):
            raise InputError(f"mode must be 'tool' or 'workpiece', got {mode!r}")
        scenario = "tool_in_hand" if mode == "tool" else "workpiece_in_hand"
    cell = load_cell(scenario, hub, robot=robot)
    hub_name = hub if hub is not None else cell.hub_sdf.parent.name
    hub_model = load_hub(cell.hub_sdf.parent)
    if options.params is None:
        options = replace(options, params=hub_model.process)
    t0 = time.perf_counter()
    wts = window_targets_for_hub(hub_model, source=source, params=options.params,
                                 windows=options.windows)
    t_targets = time.perf_counter() - t0
    plan = plan_windows(cell, wts, scenario=str(scenario), hub=str(hub_name), options=options,
                        progress=progress)
    plan.meta["timings"]["targets_seconds"] = t_targets
    return plan
