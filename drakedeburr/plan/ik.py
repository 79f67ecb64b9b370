"""Cone-constrained inverse kinematics at the CL targets of one window (Drake).

For each CL target one small nonlinear program on the cell's plant (``InverseKinematics`` built
on the plant context of a :class:`ClearanceChecker`, whose scene-graph context filters the
burr-head/hub process contact):

* ``PositionConstraint``: the tool point (origin of T) on its target in H, tight box;
* ``AngleBetweenVectorsConstraint``: the tool axis (-Z_T) within ``cone_half_angle`` of the
  cone axis in H. This replaces the source's box bounds on (theta_A, theta_B): the cone is the
  largest one inside the box (``ToolPath.cone_half_angle``), so any axis it admits keeps both
  angles in their bounds. Keep it > 0: a zero-width cone has a vanishing gradient;
* ``AngleBetweenVectorsCost`` toward the preferred (optimised) axis of the ToolPath;
* a quadratic cost on ``q - q_prev``: fixes the free spin about the tool axis and keeps J6
  continuous (the burr is rotationally symmetric, so the spin is the planner's to choose);
* joint limits, and a trust region ``|q - q_prev| <= step`` that keeps the configuration
  (no shoulder/elbow/wrist flip, no 2*pi turn) along the window;
* ``MinimumDistanceLowerBoundConstraint`` (clearance to hub and cell), added *lazily*: a
  signed-distance query against the hub's hundreds of convex pieces costs a few ms, and nearly
  every target is far from contact, so the program is first solved without it and re-solved
  with it only when the solution's clearance is below the bound.

Warm start: the first target of a window is seeded by a sweep over the spin with the analytic
OPW IK (every branch, J5 kept away from its singularity, the configuration of ``q_ref``
preferred); later targets from the previous solution, re-posed analytically on the new target at
the preferred axis with the spin that minimises the program's joint cost. Where that warm start
already meets every constraint of the program (checked independently: FK position and cone,
limits, trust region, wrist, signed distance) it is taken as is (``IkOptions.analytic_first``):
the axis cost is then at its minimum and the solve would only move the spin, and most targets
are far from any contact. The Drake program runs where it does not: at the first target and
wherever the preferred axis lacks clearance, where the distance constraint tilts the axis inside
the cone. SNOPT with capped major iterations, IPOPT as fallback, then re-seeded retries; points
that still fail are reported per point, never raised.
"""

from __future__ import annotations

import logging
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.config import Tolerances
from drakedeburr.plan.ik_seeds import (
    ConeProbe,
    IkTarget,
    ProbeSettings,
    analytic_accept,
    analytic_seed,
    clearance_seed,
    cone_clearance_probe,
    reach_shortfall,
    recheck,
    seed_by_spin,
    unreachable,
)
from drakedeburr.plan.kinematics import (
    JOINT_WEIGHTS,
    WRIST_MARGIN,
    CellKinematics,
    ClearanceChecker,
)
from drakedeburr.plan.types import FailureRecord

if TYPE_CHECKING:
    from drakedeburr.cell.station import Cell
    from drakedeburr.plan.options import PlanContext

__all__ = ["IkOptions", "IkTargets", "IkAttempt", "WindowIk", "solve_window_ik", "seed_by_spin",
           "cone_clearance_probe", "CLEARANCE_MARGIN", "FLOOR_MARGIN"]

log = logging.getLogger(__name__)

#: [m] the IK's clearance bound (``IkOptions.min_distance``) above ``Tolerances.min_clearance``:
#: the straight moves between targets keep the tolerance
CLEARANCE_MARGIN = 0.1e-3
#: [m] the bound of the IK's last retry and of the cone probe (``IkOptions.min_distance_floor``)
#: above ``Tolerances.min_clearance``
FLOOR_MARGIN = 0.05e-3


@dataclass(frozen=True)
class IkOptions:
    """Settings of the per-target IK.

    The two clearance bounds are derived from the run's ``Tolerances.min_clearance``
    (:meth:`at_clearance`, applied by :class:`drakedeburr.plan.options.PlanContext`):
    ``min_distance`` = min_clearance + :data:`CLEARANCE_MARGIN`, ``min_distance_floor`` =
    min_clearance + :data:`FLOOR_MARGIN`; their defaults are those of the default tolerances,
    and a planning context replaces whatever is given with its tolerance's (to move the IK
    bound, change ``Tolerances.min_clearance``). They are fields so that the plan records the
    bounds its IK used.

    Attributes:
        position_tolerance: half-width of the position box [m].
        min_distance: clearance lower bound [m] (all pairs but burr head/hub). A margin
            above the acceptance bound would be safer for what happens between targets, but
            on the bundled tools the burr shank passes ~2.1 mm over the face at the preferred
            axis, and a distance-active solve against hundreds of convex hub pieces costs
            0.1-1 s: the planner instead re-checks every dense sample and keeps the IK
            orientation where smoothing would cost clearance.
        influence_distance: extra distance over ``min_distance`` the constraint looks at [m].
        axis_weight: weight of the preferred-axis cost (c * (1 - cos angle)).
        joint_weights: (6,) weights of the ``q - q_prev`` cost.
        trust_region: max joint change from the previous target [rad].
        snopt_major_iterations: SNOPT major iteration cap; ipopt_max_iterations: IPOPT's
            (40 % of it with the distance constraint).
        snopt_distance_iterations: SNOPT's cap with the distance constraint. Such a solve
            either converges in a few iterations or goes on trading axis for spin at 10-30 ms
            an iteration (measured: 0.2-0.85 s per solve at 40 iterations, its pose then
            accepted on the re-check): its result is taken on the independent re-check (FK,
            cone, limits, clearance) whatever SNOPT's status, so the cap only bounds the
            polishing of the costs.
        retries: re-seeded attempts after SNOPT and IPOPT both fail: from the axis of most
            clearance in the cone (distance-active at once), the same with the bare clearance
            bound (``min_distance_floor``), then the spin sweep with that bound.
        min_wrist: keep |J5| at least this far from the wrist singularity (seeds, and a bound
            in every solve on the side of the window's wrist branch) [rad].
        spin_samples: spins tried by the seed sweep.
        min_distance_floor: the clearance bound of the last retry [m] (the acceptance bound):
            ``min_distance`` carries a small margin so that the straight moves between targets
            keep the tolerance; where the cone leaves no room for the margin (a few fillet
            points) the target takes the bare bound and the dense check of the executed motion
            decides.
        analytic_first: accept the analytic warm start when it already meets every
            constraint of the program (see :func:`analytic_accept`) and run the Drake program
            only where it does not. The warm start puts the axis exactly on the preferred axis
            (the axis cost at its minimum, zero) with the smallest spin change, so the Drake
            solve would only trade a few mrad of axis for spin; it costs ~30 ms a point
            against ~1 ms for the check. False: the Drake program at every target.
        seed_spin: the warm start's spin about the preferred axis: ``"frame"`` the previous
            frame's own (least rotation of the tool frame), or ``"joint_cost"`` the one
            (within 0.5 rad of the previous frame's) minimising the program's joint cost. The
            planner tries the other rule on a window the first leaves failing or slow
            (:mod:`drakedeburr.plan.window`). ``"frame"`` first: on 4 bundled and 6 unseen hubs
            in both cells it leaves as many windows clean, their cuts 5-7 % shorter, and
            fewer windows need the retry (docs/plan.md "Slow windows re-planned").
    """

    position_tolerance: float = 1e-6
    min_distance: float = Tolerances.min_clearance + CLEARANCE_MARGIN
    influence_distance: float = 2e-3
    axis_weight: float = 10.0
    joint_weights: tuple[float, ...] = JOINT_WEIGHTS
    trust_region: float = 0.35
    snopt_major_iterations: int = 100
    snopt_distance_iterations: int = 15
    ipopt_max_iterations: int = 50
    retries: int = 3
    min_wrist: float = WRIST_MARGIN
    spin_samples: int = 36
    min_distance_floor: float = Tolerances.min_clearance + FLOOR_MARGIN
    analytic_first: bool = True
    seed_spin: str = "frame"

    def __post_init__(self) -> None:
        if self.seed_spin not in ("joint_cost", "frame"):
            from drakedeburr.errors import InputError

            raise InputError(f"IkOptions.seed_spin must be 'joint_cost' or 'frame', "
                             f"got {self.seed_spin!r}")

    def at_clearance(self, min_clearance: float) -> IkOptions:
        """These options with both clearance bounds derived from ``min_clearance`` [m] (the
        run's ``Tolerances.min_clearance``)."""
        return replace(self, min_distance=min_clearance + CLEARANCE_MARGIN,
                       min_distance_floor=min_clearance + FLOOR_MARGIN)

    def probe_settings(self, lift: float) -> ProbeSettings:
        """The cone probe's settings at this IK's bound (``min_distance_floor``) and wrist
        margin, the constrained point ``lift`` [m] from T toward the tip."""
        return ProbeSettings(bound=self.min_distance_floor, lift=lift, min_wrist=self.min_wrist)


@dataclass(frozen=True, eq=False)
class IkTargets:
    """The CL targets of one window's IK, in H and in solving order.

    Attributes:
        p_HT: (M, 3) targets of the constrained point [m]: on the burr axis, ``lift`` from T
            toward the tip (see :func:`solve_window_ik`).
        pref_retract_H: (M, 3) preferred tool axes (tip -> spindle).
        cone_retract_H: (M, 3) admissible cone axes; cone_half_angle: [rad] (> 0).
        t_H: (M, 3) feed tangents (spin reference of the seeds).
        lift: [m].
    """

    p_HT: np.ndarray
    pref_retract_H: np.ndarray
    cone_retract_H: np.ndarray
    t_H: np.ndarray
    cone_half_angle: float
    lift: float = 0.0

    def __len__(self) -> int:
        return len(self.p_HT)

    def at(self, i: int) -> IkTarget:
        """Target ``i``."""
        return IkTarget(self.p_HT[i], self.cone_retract_H[i], self.pref_retract_H[i],
                        self.t_H[i])

    def back_from(self, i: int) -> IkTargets:
        """Targets ``i, i-1, ..., 0``, their tangents reversed (the path walked backwards)."""
        rev = np.arange(i, -1, -1)
        return replace(self, p_HT=self.p_HT[rev], pref_retract_H=self.pref_retract_H[rev],
                       cone_retract_H=self.cone_retract_H[rev], t_H=-self.t_H[rev])


@dataclass(frozen=True, eq=False)
class IkAttempt:
    """One solve of a target, re-checked by the analytic FK: joints (6,) [rad], tool pose
    X_HT (4, 4) [m], clearance [m], position error of the constrained point [m] and angle of
    the tool axis to the cone axis [rad]."""

    q: np.ndarray
    X_HT: np.ndarray
    clearance: float
    position_error: float
    cone_angle: float


@dataclass(frozen=True, eq=False)
class WindowIk:
    """IK of one window's CL targets.

    Attributes:
        q: (M, 6) joints [rad]; rows of failed points hold the best attempt (or NaN).
        ok: (M,) bool, the point met every constraint on re-check.
        X_HT: (M, 4, 4) achieved tool poses in H (analytic FK) [m].
        clearance: (M,) minimum distance [m] (capped at ``influence + bound``).
        failures: per-point failure records.
        stats: timings and solver counts.
        probes: point -> the :class:`ConeProbe` of each failed point
            (:func:`cone_clearance_probe`; None where it did not run).
    """

    q: np.ndarray
    ok: np.ndarray
    X_HT: np.ndarray
    clearance: np.ndarray
    failures: tuple[FailureRecord, ...] = ()
    stats: dict = field(default_factory=dict)
    probes: dict = field(default_factory=dict)


def _solver_options(solver_id, options: IkOptions, with_distance: bool = False):
    from pydrake.solvers import SolverOptions

    # a distance-active iteration costs ~10-50 ms against a detailed hub: cap those harder
    scale = 0.4 if with_distance else 1.0
    so = SolverOptions()
    if solver_id.name() == "SNOPT":
        so.SetOption(solver_id, "Major iterations limit",
                     options.snopt_distance_iterations if with_distance
                     else options.snopt_major_iterations)
    else:
        so.SetOption(solver_id, "max_iter", max(10, int(scale * options.ipopt_max_iterations)))
        so.SetOption(solver_id, "print_level", 0)
    return so


#: the target programs solved in this process, per checker (its cell and collision filters):
#: the policy's passes (first pass, milder recipes, report-only pass) and the retries of a
#: window solve many programs again with the same data (audibot rim: 1 in 5), and a program's
#: solution is a function of that data (SNOPT / IPOPT are deterministic; re-solved, every
#: repeat gave the same bits)
_SOLVED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: programs kept per checker at most (the oldest dropped first)
SOLVED_MEMO_SIZE = 20000


def _program_key(run: _WindowRun, tg: IkTarget, q_prev: np.ndarray, q_seed: np.ndarray,
                 with_distance: bool, solver, options: IkOptions) -> bytes:
    """Everything :func:`_solve_program` reads, as bytes (the checker, hence the cell and its
    filters, keys the memo itself)."""
    arrays = (tg.p_HT, tg.cone_retract_H, tg.pref_retract_H, q_prev, q_seed,
              (run.lift, run.half, float(with_distance)))
    return (b"".join(np.asarray(a, float).tobytes() for a in arrays)
            + solver.solver_id().name().encode() + repr(options).encode())


def _solve_point(run: _WindowRun, tg: IkTarget, q_prev: np.ndarray, q_seed: np.ndarray,
                 with_distance: bool, solver, options: IkOptions) -> tuple[bool, np.ndarray]:
    """:func:`_solve_program`, answered from :data:`_SOLVED` when the same program was solved
    before in this process (a fresh copy of its solution)."""
    memo = _SOLVED.setdefault(run.checker, {})
    key = _program_key(run, tg, q_prev, q_seed, with_distance, solver, options)
    if key not in memo:
        if len(memo) >= SOLVED_MEMO_SIZE:
            del memo[next(iter(memo))]
        memo[key] = _solve_program(run, tg, q_prev, q_seed, with_distance, solver, options)
    ok, q = memo[key]
    return ok, q.copy()


def _solve_program(run: _WindowRun, tg: IkTarget, q_prev: np.ndarray, q_seed: np.ndarray,
                   with_distance: bool, solver, options: IkOptions) -> tuple[bool, np.ndarray]:
    from pydrake.multibody.inverse_kinematics import InverseKinematics

    cell = run.cell
    ik = InverseKinematics(cell.plant, run.checker.plant_context, with_joint_limits=True)
    tol = options.position_tolerance
    # the constrained point: on the burr axis, ``lift`` from T toward the tip (+Z_T)
    ik.AddPositionConstraint(cell.tool_frame, np.array([0.0, 0.0, run.lift]), cell.hub_frame,
                             tg.p_HT - tol, tg.p_HT + tol)
    down_T = np.array([0.0, 0.0, -1.0])  # the tool axis (tip -> spindle) is -Z_T
    ik.AddAngleBetweenVectorsConstraint(cell.hub_frame, tg.cone_retract_H, cell.tool_frame,
                                        down_T, 0.0, run.half)
    ik.AddAngleBetweenVectorsCost(cell.hub_frame, tg.pref_retract_H, cell.tool_frame, down_T,
                                  options.axis_weight)
    prog = ik.get_mutable_prog()
    q = ik.q()
    if with_distance:
        prog.AddConstraint(run.checker.distance_constraint(options.min_distance,
                                                           options.influence_distance), q)
    prog.AddQuadraticErrorCost(np.diag(options.joint_weights), q_prev, q)
    lo = np.maximum(cell.q_lower, q_prev - options.trust_region)
    hi = np.minimum(cell.q_upper, q_prev + options.trust_region)
    # stay on the wrist branch of the window, away from the J5 = 0 singularity: the free spin
    # about the burr axis moves J5 (45 deg spindle mount), so the IK can always use it
    if q_prev[4] >= 0:
        lo[4] = max(lo[4], min(options.min_wrist, q_prev[4]))
    else:
        hi[4] = min(hi[4], max(-options.min_wrist, q_prev[4]))
    prog.AddBoundingBoxConstraint(lo, hi, q)
    prog.SetInitialGuess(q, np.clip(q_seed, lo, hi))
    result = solver.Solve(prog, np.clip(q_seed, lo, hi),
                          _solver_options(solver.solver_id(), options, with_distance))
    return bool(result.is_success()), np.array(result.GetSolution(q), float)


def solve_window_ik(
    ctx: PlanContext,
    targets: IkTargets,
    q_ref: np.ndarray,
    *,
    window_index: int = 0,
    progress: Callable[[int, int, str], None] | None = None,
    q_first: np.ndarray | None = None,
    stop_at_failure: bool = False,
) -> WindowIk:
    """IK at every CL target of one window, warm-started along the path.

    Args:
        ctx: the planning context: its cell (:class:`drakedeburr.cell.Cell`), kinematics,
            clearance checker (``ctx.checker``) and IK options (``ctx.options.ik``).
        targets: the window's targets in solving order. Their constrained point is on the
            burr axis ``targets.lift`` [m] from T toward the tip (the centre of the cutting
            circle, :func:`targets.contact_geometry`), and ``targets.p_HT`` are its targets.
            Constraining that point rather than T keeps the implied edge point where it
            belongs when the IK tilts the axis inside the cone (T would carry the cutting
            circle off by ``lift * tilt``), and tilting about it swings the shank away from the
            face more per radian.
        q_ref: (6,) joints the robot comes from (configuration preference) [rad].
        window_index: for failure records.
        q_first: seed of the first target (default: the spin sweep's best).
        stop_at_failure: stop at the first failed target, the later ones left unsolved
            without records (``RunMode.FAIL_FAST``).

    Returns:
        WindowIk; failures are listed per point (:class:`FailureRecord`), never raised.
    """
    from pydrake.solvers import IpoptSolver, SnoptSolver

    options, kin, checker, lift = ctx.options.ik, ctx.kin, ctx.checker, targets.lift
    solvers = [s for s in (SnoptSolver(), IpoptSolver()) if s.available() and s.enabled()]
    m = len(targets)
    counts = dict.fromkeys(("distance", "fallback", "retry", "analytic", "probe"), 0)
    run = _WindowRun(cell=ctx.cell, kin=kin, checker=checker, solvers=solvers, options=options,
                     lift=lift, half=max(float(targets.cone_half_angle), 1e-3),
                     reach=options.min_distance + options.influence_distance, counts=counts)
    q_out, X_out = np.full((m, 6), np.nan), np.full((m, 4, 4), np.nan)
    ok, clearance = np.zeros(m, bool), np.zeros(m)
    failures: list[FailureRecord] = []
    probes: dict[int, ConeProbe | None] = {}  # per failed point: its cone probe (None: not run)
    t0 = time.perf_counter()
    pref = targets.pref_retract_H
    p_T_pref = targets.p_HT + lift * pref  # T itself at the preferred axis (seeds)
    q_prev, i_prev = None, -1
    for i in range(m):
        tg = targets.at(i)
        if q_prev is None:
            q_seed = (q_first if q_first is not None and i == 0 else
                      seed_by_spin(kin, checker, p_T_pref[i], pref[i], tg.t_H, q_ref, options))
            if q_seed is None:
                failures.append(_unreached(kin, window_index, i, p_T_pref[i], pref[i], tg.t_H))
                continue
            anchor = q_seed
        else:
            anchor = q_prev
            q_seed = analytic_seed(kin, X_out[i_prev], p_T_pref[i], pref[i], q_prev,
                                    options.joint_weights,
                                    spin_span=0.5 if options.seed_spin == "joint_cost" else 0.0,
                                    spin_samples=21 if options.seed_spin == "joint_cost" else 1)
        prev = None if q_prev is None else (q_prev, X_out[i_prev])
        done, best, probe = _solve_target(run, tg, q_seed, anchor, prev)
        if best is not None:
            q_out[i], X_out[i], clearance[i] = best.q, best.X_HT, best.clearance
        if done:
            ok[i] = True
            q_prev, i_prev = q_out[i], i
        else:
            failures.append(_failure(run, window_index, i, best, probe))
            probes[i] = probe
            if stop_at_failure:
                break
        if progress is not None:
            progress(i + 1, m, f"window {window_index} IK")
    dt = time.perf_counter() - t0
    c = run.counts
    stats = dict(points=m, seconds=dt, seconds_per_point=dt / max(m, 1),
                 distance_resolves=c["distance"], ipopt_fallbacks=c["fallback"],
                 retries=c["retry"], analytic_accepted=c["analytic"], cone_probes=c["probe"],
                 failed=int(m - ok.sum()))
    log.debug("window %d: IK %d/%d points in %.2f s (%.1f ms/point), %d analytic warm starts "
             "accepted, %d distance re-solves", window_index, int(ok.sum()), m, dt,
             1e3 * stats["seconds_per_point"], c["analytic"], c["distance"])
    return WindowIk(q=q_out, ok=ok, X_HT=X_out, clearance=clearance, failures=tuple(failures),
                    stats=stats, probes=probes)


def _unreached(kin, window: int, i: int, p_HT, retract_H, t_H) -> FailureRecord:
    """The record of a target no spin and no branch reaches: by how much, when out of reach."""
    short = reach_shortfall(kin, p_HT, retract_H, t_H)
    if short > 0:
        return FailureRecord(window=window, kind="ik", point=i, value=short, limit=0.0,
                             unit="m", reason=f"no IK branch reaches the first target: out of "
                                              f"the arm's reach by {short * 1e3:.0f} mm")
    return FailureRecord(window=window, kind="ik", point=i,
                         reason="no IK branch reaches the first target: within the arm's reach, "
                                "but every spin and branch leaves a joint limit, the wrist "
                                "margin or the clearance")


@dataclass(frozen=True, eq=False)
class _WindowRun:
    """What every target of one window's IK is solved with (``counts``: solver counters)."""

    cell: Cell
    kin: CellKinematics
    checker: ClearanceChecker
    solvers: list
    options: IkOptions
    lift: float
    half: float
    reach: float
    counts: dict


def _reseed(run: _WindowRun, tg: IkTarget, attempt: int, probe: ConeProbe | None, anchor, prev):
    """The seed of a retry: the cone probe's pose (attempt 1, when within the trust region),
    else the axis in the cone with the most clearance (attempts 1-2, distance-active at once),
    else the spin sweep. Returns (seed or None, start with the distance constraint)."""
    opt = run.options
    if attempt == 1 and probe.q is not None and np.max(
            np.abs(probe.q - anchor)) <= opt.trust_region:
        return probe.q, True  # the probe's pose: admissible and clear
    if attempt in (1, 2) and prev is not None:
        # where the preferred axis is too close to the hub (concave fillets), seed from the
        # axis in the cone with the most clearance, distance-active at once
        seed = clearance_seed(run.kin, run.checker, prev[1], tg, run.half, prev[0], run.reach,
                              lift=run.lift)
        if seed is not None:
            return seed, True
    p_T = tg.p_HT + run.lift * tg.pref_retract_H
    return seed_by_spin(run.kin, run.checker, p_T, tg.pref_retract_H, tg.t_H, anchor, opt), False


def _solve_with(run: _WindowRun, tg: IkTarget, solver, anchor, q_seed, with_distance, opts):
    """One solve (and a lazy re-solve with the distance constraint when the solution comes
    too close), re-checked by the analytic FK: (the :class:`IkAttempt`, accepted, whether the
    distance constraint is now on - it stays on for the next solver)."""
    _, q = _solve_point(run, tg, anchor, q_seed, with_distance, solver, opts)
    good, err, ang, X = recheck(run.kin, q, tg.p_HT, tg.cone_retract_H, run.half, opts, run.lift)
    dist = run.checker.distance(q, run.reach)
    if good and dist < opts.min_distance - 1e-5 and not with_distance:
        # lazy collision constraint: re-solve with it from this solution
        with_distance = True
        run.counts["distance"] += 1
        _, q = _solve_point(run, tg, anchor, q, True, solver, opts)
        good, err, ang, X = recheck(run.kin, q, tg.p_HT, tg.cone_retract_H, run.half, opts,
                                     run.lift)
        dist = run.checker.distance(q, run.reach)
    attempt = IkAttempt(q=q, X_HT=X, clearance=dist, position_error=err, cone_angle=ang)
    return attempt, good and dist >= opts.min_distance - 1e-5, with_distance


def _solve_target(run: _WindowRun, tg: IkTarget, q_seed, anchor, prev):
    """One target: the analytic warm start if it is admissible, else the NLP from the seed,
    with retries from other seeds (after a cone probe tells an unreachable target). Returns
    (done, the best :class:`IkAttempt` or None, the :class:`ConeProbe` or None)."""
    opt = run.options
    if opt.analytic_first and prev is not None:
        acc = analytic_accept(run.kin, run.checker, q_seed, anchor, tg, run.half, opt, run.lift)
        if acc is not None:
            run.counts["analytic"] += 1
            return True, IkAttempt(q=q_seed, X_HT=acc[0], clearance=acc[1], position_error=0.0,
                                   cone_angle=0.0), None
    best, probe = None, None
    for attempt in range(opt.retries + 1):
        with_distance = False
        # from the second retry on, ask only for the acceptance bound, not the margin
        opts = opt if attempt < 2 else replace(
            opt, min_distance=min(opt.min_distance, opt.min_distance_floor))
        if attempt == 1 and probe is None:
            # the program failed from the warm start: is there any admissible pose at all?
            probe = cone_clearance_probe(run.kin, run.checker, tg, run.half, anchor,
                                         opt.probe_settings(run.lift))
            run.counts["probe"] += 1
            if unreachable(probe, opt):
                break  # far from any admissible pose: no seed can help (reported)
        if attempt > 0:
            run.counts["retry"] += 1
            q_seed, with_distance = _reseed(run, tg, attempt, probe, anchor, prev)
            if q_seed is None:
                break
        for s_idx, solver in enumerate(run.solvers):
            if s_idx > 0:
                run.counts["fallback"] += 1
            best, accepted, with_distance = _solve_with(run, tg, solver, anchor, q_seed,
                                                        with_distance, opts)
            if accepted:
                return True, best, probe
    return False, best, probe


def _failure(run: _WindowRun, window: int, i: int, best: IkAttempt | None,
             probe: ConeProbe | None) -> FailureRecord:
    """The failure record of a target the IK could not meet."""
    reason, where, value, limit, unit = "IK failed", {}, None, None, ""
    floor = run.options.min_distance_floor
    if best is not None:
        where = dict(position_error=best.position_error, cone_angle=best.cone_angle,
                     clearance=best.clearance)
        met = best.position_error <= 1e-5 and best.cone_angle <= run.half + 1e-6
        reason = "clearance below bound" if met else "position/cone not met"
        if met:
            value, limit, unit = float(best.clearance), floor, "m"
    if probe is not None and unreachable(probe, run.options):
        where.update(cone_best_clearance=probe.best_clearance,
                     blocking_pair=list(probe.pair))
        value, limit, unit = float(probe.best_clearance), floor, "m"
        reason = (f"unreachable: no tool axis in the cone ({np.degrees(run.half):.1f} deg) and "
                  f"spin clears the cell; best {probe.best_clearance * 1e3:.2f} mm "
                  f"({probe.pair[0]} vs {probe.pair[1]})")
        bound = float(probe.axis_bound)
        if bound < floor:  # a near miss searched between the axes
            where.update(cone_axis_bound=bound)
            reason += (f"; on every axis in the cone the tool's round parts (shank, collet, "
                       f"spindle body) come within {bound * 1e3:.3f} mm of the hub side")
    return FailureRecord(window=window, kind="ik", point=i, reason=reason, value=value,
                         limit=limit, unit=unit, where=where,
                         tried=(f"{run.options.retries + 1} seeds", "SNOPT then IPOPT"))
