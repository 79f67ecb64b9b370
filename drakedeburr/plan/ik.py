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
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from drakedeburr.plan.kinematics import CellKinematics, ClearanceChecker
from drakedeburr.plan.targets import X_HT_from_axis

__all__ = ["IkOptions", "WindowIk", "solve_window_ik", "seed_by_spin", "cone_clearance_probe"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class IkOptions:
    """Settings of the per-target IK.

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
        snopt_major_iterations: SNOPT major iteration cap; ipopt_max_iterations: IPOPT's.
        retries: re-seeded attempts after SNOPT and IPOPT both fail: from the axis of most
            clearance in the cone (distance-active at once), the same with the bare clearance
            bound (``min_distance_floor``), then the spin sweep with that bound.
        min_wrist: keep |J5| at least this far from the wrist singularity (seeds, and a bound
            in every solve on the side of the window's wrist branch) [rad].
        spin_samples: spins tried by the seed sweep.
        min_distance_floor: the clearance bound of the last retry [m] (the acceptance bound):
            ``min_distance`` carries a small margin so that the straight moves between targets
            keep 2 mm; where the cone leaves no room for the margin (a few fillet points) the
            target takes the bare bound and the dense check of the executed motion decides.
        analytic_first: accept the analytic warm start when it already meets every
            constraint of the program (see :func:`_analytic_accept`) and run the Drake program
            only where it does not. The warm start puts the axis exactly on the preferred axis
            (the axis cost at its minimum, zero) with the smallest spin change, so the Drake
            solve would only trade a few mrad of axis for spin; it costs ~30 ms a point
            against ~1 ms for the check. False: the Drake program at every target.
        seed_spin: the warm start's spin about the preferred axis: ``"joint_cost"`` the one
            (within 0.5 rad of the previous frame's) minimising the program's joint cost, or
            ``"frame"`` the previous frame's own (least rotation of the tool frame). The
            planner tries the other rule on a window the first leaves failing.
    """

    position_tolerance: float = 1e-6
    min_distance: float = 2.1e-3
    influence_distance: float = 2e-3
    axis_weight: float = 10.0
    joint_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 0.3, 0.3, 0.3)
    trust_region: float = 0.35
    snopt_major_iterations: int = 100
    ipopt_max_iterations: int = 50
    retries: int = 3
    min_wrist: float = 0.25
    spin_samples: int = 36
    min_distance_floor: float = 2.05e-3
    analytic_first: bool = True
    seed_spin: str = "joint_cost"

    def __post_init__(self) -> None:
        if self.seed_spin not in ("joint_cost", "frame"):
            from drakedeburr.errors import InputError

            raise InputError(f"IkOptions.seed_spin must be 'joint_cost' or 'frame', "
                             f"got {self.seed_spin!r}")


@dataclass(frozen=True, eq=False)
class WindowIk:
    """IK of one window's CL targets.

    Attributes:
        q: (M, 6) joints [rad]; rows of failed points hold the best attempt (or NaN).
        ok: (M,) bool, the point met every constraint on re-check.
        X_HT: (M, 4, 4) achieved tool poses in H (analytic FK) [m].
        clearance: (M,) minimum distance [m] (capped at ``influence + bound``).
        failures: per-point failure records (dicts).
        stats: timings and solver counts.
    """

    q: np.ndarray
    ok: np.ndarray
    X_HT: np.ndarray
    clearance: np.ndarray
    failures: tuple[dict, ...] = ()
    stats: dict = field(default_factory=dict)


def seed_by_spin(kin: CellKinematics, checker: ClearanceChecker | None, p_HT: np.ndarray,
                 axis_H: np.ndarray, t_H: np.ndarray, q_ref: np.ndarray,
                 options: IkOptions = IkOptions(), count: int = 1) -> np.ndarray | None:
    """Best joint vector for one target over a sweep of spins and all IK branches.

    Score: same branch as ``q_ref`` first, then weighted distance to ``q_ref``; candidates with
    |J5| < ``min_wrist``, outside the limits or in collision are dropped.

    Args:
        p_HT: (3,) tool point [m]; axis_H: (3,) preferred axis; t_H: (3,) feed tangent.
        q_ref: (6,) reference joints (e.g. home or the previous window's end) [rad].

        count: > 1 returns a list of up to ``count`` distinct seeds (J4/J6 differing by more
            than 0.5 rad), best first, for window-level retries.

    Returns:
        (6,) joints [rad], or None when no spin/branch reaches (a list when count > 1).
    """
    spins = np.linspace(-np.pi, np.pi, options.spin_samples, endpoint=False)
    k = len(spins)
    X_HT = X_HT_from_axis(np.repeat(p_HT[None], k, 0), np.repeat(axis_H[None], k, 0),
                          np.repeat(t_H[None], len(spins), 0), spins)
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X_HT))
    b_ref = kin.branch_of(q_ref)
    cands, scores = [], []
    w = np.array([2.0, 2.0, 1.5, 0.5, 0.5, 0.5])
    centre = np.concatenate([q_ref[:3], 0.5 * (kin.q_lower + kin.q_upper)[3:]])
    for k in range(q_all.shape[0]):
        for b in range(8):
            q = q_all[k, b]
            if np.any(np.isnan(q)):
                continue
            # turns of J4/J6 nearest the middle of their range (a window winds the wrist by up
            # to ~100 deg: start it centred), the arm nearest q_ref
            q = centre + np.mod(q - centre + np.pi, 2 * np.pi) - np.pi
            if not kin.within_limits(q) or abs(q[4]) < options.min_wrist:
                continue
            score = (float(w[:3] @ np.abs(q - q_ref)[:3]) + float(w[3:] @ np.abs(q - centre)[3:])
                     + (0.0 if np.all(branches[b] == b_ref) else 100.0))
            cands.append(q)
            scores.append(score)
    if not cands:
        return None if count == 1 else []
    ranked = np.argsort(scores)
    if checker is None and count == 1:
        return cands[ranked[0]]
    # the IK's distance constraint can tilt the axis inside the cone: a seed needs clearance
    # from the arm and cell, not the full bound at the burr (that depends on the axis only)
    picked: list[np.ndarray] = []
    best, best_d = None, -np.inf
    for j in ranked[:max(12, 6 * count)]:
        if any(np.max(np.abs(cands[j][[3, 5]] - p[[3, 5]])) < 0.5 for p in picked):
            continue
        d = np.inf if checker is None else checker.min_distance(cands[j], options.min_distance)[0]
        if d >= options.min_distance:
            picked.append(cands[j])
            if len(picked) >= count:
                break
        elif d > best_d + 1e-4:
            best, best_d = cands[j], d
    if count > 1:
        return picked or ([best] if best is not None and best_d > 0.0 else [])
    if picked:
        return picked[0]
    return best if best_d > 0.0 else None


def _analytic_seed(kin: CellKinematics, X_prev: np.ndarray, p_HT: np.ndarray,
                   axis_H: np.ndarray, q_prev: np.ndarray,
                   weights: tuple[float, ...] = IkOptions.joint_weights,
                   spin_span: float = 0.5, spin_samples: int = 21) -> np.ndarray:
    """Seed that already meets position and preferred axis exactly, with the spin about the
    axis that minimises the program's own joint cost ``sum w_j (q_j - q_prev_j)^2``: spins
    within ``spin_span`` of the previous pose's X_T projected normal to the new axis, solved
    by the analytic IK on the previous configuration's branch. Falls back to ``q_prev``."""
    z = -axis_H / np.linalg.norm(axis_H)
    x = X_prev[:3, 0] - (X_prev[:3, 0] @ z) * z
    if np.linalg.norm(x) < 1e-6:
        return q_prev
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    psi = np.linspace(-spin_span, spin_span, spin_samples)
    X = np.repeat(np.eye(4)[None], spin_samples, axis=0)
    X[:, :3, 0] = np.cos(psi)[:, None] * x + np.sin(psi)[:, None] * y
    X[:, :3, 1] = -np.sin(psi)[:, None] * x + np.cos(psi)[:, None] * y
    X[:, :3, 2] = z
    X[:, :3, 3] = p_HT
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    match = np.flatnonzero(np.all(branches == kin.branch_of(q_prev)[None], axis=1))
    if match.size == 0:
        return q_prev
    cand = q_all[:, match[0]]
    cand = q_prev + np.mod(cand - q_prev + np.pi, 2 * np.pi) - np.pi  # no 2 pi turns
    good = ~np.any(np.isnan(cand), axis=1) & kin.within_limits(cand)
    good &= np.max(np.abs(cand - q_prev), axis=1) <= 0.6
    if not good.any():
        return q_prev
    cost = np.where(good, np.sum(np.asarray(weights) * (cand - q_prev) ** 2, axis=1), np.inf)
    return cand[int(np.argmin(cost))]


def _cone_ring(c: np.ndarray, angle: float, count: int) -> list[np.ndarray]:
    """``count`` unit axes at ``angle`` from the unit axis ``c``, evenly around it."""
    e1 = np.cross(c, [1.0, 0.0, 0.0] if abs(c[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    return [np.cos(angle) * c + np.sin(angle) * (np.cos(f) * e1 + np.sin(f) * e2)
            for f in np.linspace(0.0, 2 * np.pi, count, endpoint=False)]


def _clearance_seed(kin: CellKinematics, checker: ClearanceChecker, X_prev: np.ndarray,
                    p_HT: np.ndarray, cone_axis_H: np.ndarray, half_angle: float,
                    pref_axis_H: np.ndarray, q_prev: np.ndarray, reach: float,
                    samples: int = 12, lift: float = 0.0) -> np.ndarray | None:
    """Analytic seed at the axis of most clearance among the preferred axis, the cone axis and
    ``samples`` axes at 0.8 of the cone half-angle around it (None if none is reachable).
    ``p_HT`` is the constrained point (``lift`` below T on the axis, see solve_window_ik)."""
    c = cone_axis_H / np.linalg.norm(cone_axis_H)
    axes = [pref_axis_H, c] + _cone_ring(c, 0.8 * half_angle, samples)
    best, best_d = None, -np.inf
    for a in axes:
        q = _analytic_seed(kin, X_prev, p_HT + lift * a, a, q_prev)
        if q is q_prev:
            continue
        d = checker.min_distance(q, reach)[0]
        if d > best_d:
            best, best_d = q, d
    return best


def _analytic_accept(kin: CellKinematics, checker: ClearanceChecker, q: np.ndarray,
                     anchor: np.ndarray, p_HT: np.ndarray, cone_axis_H: np.ndarray, half: float,
                     options: IkOptions, lift: float, reach: float):
    """The analytic warm start as the target's solution when it meets every constraint of the
    Drake program: position and cone (re-checked by FK), joint limits, the trust region about
    the previous target, the wrist branch and margin, and the clearance bound. Returns
    ``(X_HT, clearance)`` or None (then the Drake program runs)."""
    if q is anchor or np.max(np.abs(q - anchor)) > options.trust_region:
        return None
    if abs(q[4]) < options.min_wrist or np.sign(q[4]) != np.sign(anchor[4]):
        return None
    good, _, _, X = _recheck(kin, q, p_HT, cone_axis_H, half, options, lift)
    if not good:
        return None
    dist = checker.min_distance(q, reach)[0]
    if dist < options.min_distance:
        return None
    return X, dist


def cone_clearance_probe(kin: CellKinematics, checker: ClearanceChecker, p_HQ: np.ndarray,
                         cone_axis_H: np.ndarray, half_angle: float, pref_axis_H: np.ndarray,
                         t_H: np.ndarray, q_ref: np.ndarray, *, lift: float = 0.0,
                         bound: float = 2.05e-3, min_wrist: float = 0.25,
                         rings: tuple[float, ...] = (0.0, 0.33, 0.66, 0.98), ring_axes: int = 16,
                         spins: int = 24, per_axis: int = 24) -> dict:
    """Is there any admissible pose at a target? A sampled search of the whole cone.

    Axes: the preferred and the cone axis, then ``ring_axes`` axes on each ring of ``rings``
    x half-angle; for each, ``spins`` spins about it and every analytic IK branch (J4/J6 turned
    into the limits where a turn fits, |J5| >= ``min_wrist``), up to ``per_axis`` of them
    queried for signed distance. Stops at the first pose with ``bound`` clearance.

    Used when the IK fails at a target, to tell an unreachable target (no axis in the cone
    clears the cell: the tool or the theta box has to change) from a solver failure (a pose
    exists; the returned one seeds the retry). The search is sampled, so only a best pose more
    than 0.2 mm short of the bound ends the target's retries and labels it unreachable; nearer
    misses go on to the distance-constrained retries, which can still find the bound.

    Returns:
        ``{"feasible", "best_clearance", "pair", "q", "queries"}`` (q: the best pose found).
    """
    c = cone_axis_H / np.linalg.norm(cone_axis_H)
    axes = [pref_axis_H / np.linalg.norm(pref_axis_H), c]
    for ring in rings:
        if ring > 0:
            axes += _cone_ring(c, ring * half_angle, ring_axes)
    psi = np.linspace(-np.pi, np.pi, spins, endpoint=False)
    best = dict(feasible=False, best_clearance=-np.inf, pair=("", ""), q=None, queries=0)
    b_ref = kin.branch_of(q_ref)
    for a in axes:
        X = X_HT_from_axis(np.repeat((p_HQ + lift * a)[None], spins, 0),
                           np.repeat(a[None], spins, 0), np.repeat(t_H[None], spins, 0), psi)
        q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
        # the reference configuration's branch first, then the others
        order = np.argsort([0 if np.all(b == b_ref) else 1 for b in branches], kind="stable")
        q = q_all[:, order].transpose(1, 0, 2).reshape(-1, 6)
        q = q[~np.any(np.isnan(q), axis=1)]
        for j in (3, 5):
            q[q[:, j] < kin.q_lower[j], j] += 2 * np.pi
            q[q[:, j] > kin.q_upper[j], j] -= 2 * np.pi
        q = q[kin.within_limits(q) & (np.abs(q[:, 4]) >= min_wrist)]
        for qq in q[:: max(1, len(q) // per_axis)]:
            d, pair = checker.min_distance(qq, bound + 1e-3)
            best["queries"] += 1
            if d > best["best_clearance"]:
                best.update(best_clearance=float(d), pair=pair, q=qq.copy())
            if d >= bound:
                best["feasible"] = True
                return best
    return best


def _unreachable(probe: dict, options: IkOptions) -> bool:
    """The probe's best pose is more than 0.2 mm short of the bound (the sampled search may
    miss a pose within that; the retries may still find it)."""
    return not probe["feasible"] and probe["best_clearance"] < options.min_distance_floor - 0.2e-3


def _solver_options(solver_id, options: IkOptions, with_distance: bool = False):
    from pydrake.solvers import SolverOptions

    # a distance-active iteration costs ~10-50 ms against a detailed hub: cap those harder
    scale = 0.4 if with_distance else 1.0
    so = SolverOptions()
    if solver_id.name() == "SNOPT":
        so.SetOption(solver_id, "Major iterations limit",
                     max(10, int(scale * options.snopt_major_iterations)))
    else:
        so.SetOption(solver_id, "max_iter", max(10, int(scale * options.ipopt_max_iterations)))
        so.SetOption(solver_id, "print_level", 0)
    return so


def _solve_point(cell, checker: ClearanceChecker, p_HT: np.ndarray, cone_axis_H: np.ndarray,
                 half_angle: float, pref_axis_H: np.ndarray, q_prev: np.ndarray, q_seed: np.ndarray,
                 with_distance: bool, solver, options: IkOptions,
                 lift: float = 0.0) -> tuple[bool, np.ndarray]:
    from pydrake.multibody.inverse_kinematics import InverseKinematics

    ik = InverseKinematics(cell.plant, checker.plant_context, with_joint_limits=True)
    tol = options.position_tolerance
    # the constrained point: on the burr axis, ``lift`` from T toward the tip (+Z_T)
    ik.AddPositionConstraint(cell.tool_frame, np.array([0.0, 0.0, lift]), cell.hub_frame,
                             p_HT - tol, p_HT + tol)
    down_T = np.array([0.0, 0.0, -1.0])  # the tool axis (tip -> spindle) is -Z_T
    ik.AddAngleBetweenVectorsConstraint(cell.hub_frame, cone_axis_H, cell.tool_frame, down_T,
                                        0.0, half_angle)
    ik.AddAngleBetweenVectorsCost(cell.hub_frame, pref_axis_H, cell.tool_frame, down_T,
                                  options.axis_weight)
    prog = ik.get_mutable_prog()
    q = ik.q()
    if with_distance:
        prog.AddConstraint(checker.distance_constraint(options.min_distance,
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
    return bool(result.is_success()), result.GetSolution(q)


def _recheck(kin: CellKinematics, q: np.ndarray, p_HT: np.ndarray, cone_axis_H: np.ndarray,
             half_angle: float, options: IkOptions,
             lift: float = 0.0) -> tuple[bool, float, float, np.ndarray]:
    """Independent check of a solution with the analytic FK: (ok, position error, cone angle)."""
    X = kin.X_HT_from_q(q)
    err = float(np.linalg.norm(X[:3, 3] + lift * X[:3, 2] - p_HT))
    ang = float(np.arccos(np.clip(-X[:3, 2] @ cone_axis_H, -1.0, 1.0)))
    ok = (err <= 10 * options.position_tolerance and ang <= half_angle + 1e-6
          and bool(kin.within_limits(q)))
    return ok, err, ang, X


def solve_window_ik(
    cell,
    kin: CellKinematics,
    checker: ClearanceChecker,
    p_HT: np.ndarray,
    pref_axis_H: np.ndarray,
    cone_axis_H: np.ndarray,
    cone_half_angle: float,
    t_H: np.ndarray,
    q_ref: np.ndarray,
    *,
    window_index: int = 0,
    options: IkOptions = IkOptions(),
    progress: Callable[[int, int, str], None] | None = None,
    q_first: np.ndarray | None = None,
    lift: float = 0.0,
) -> WindowIk:
    """IK at every CL target of one window, warm-started along the path.

    Args:
        cell: the loaded :class:`drakedeburr.cell.Cell`.
        kin: its :class:`CellKinematics`; checker: its :class:`ClearanceChecker`.
        p_HT: (M, 3) tool-point targets in H [m] (see :mod:`drakedeburr.plan.targets`).
        pref_axis_H: (M, 3) preferred tool axes (tip -> spindle) in H.
        cone_axis_H: (M, 3) admissible cone axes in H; cone_half_angle: [rad] (> 0).
        t_H: (M, 3) feed tangents (spin reference of the seeds).
        q_ref: (6,) joints the robot comes from (configuration preference) [rad].
        window_index: for failure records.
        q_first: seed of the first target (default: the spin sweep's best).
        lift: the constrained point is on the burr axis ``lift`` [m] from T toward the tip
            (the centre of the cutting circle, :func:`targets.contact_geometry`), and ``p_HT``
            are its targets. Constraining that point rather than T keeps the implied edge point
            where it belongs when the IK tilts the axis inside the cone (T would carry the
            cutting circle off by ``lift * tilt``), and tilting about it swings the shank away
            from the face more per radian.

    Returns:
        WindowIk; failures are listed per point (``{"window", "cl_index", "stage", "reason",
        ...}``), never raised.
    """
    from pydrake.solvers import IpoptSolver, SnoptSolver

    snopt, ipopt = SnoptSolver(), IpoptSolver()
    solvers = [s for s in (snopt, ipopt) if s.available() and s.enabled()]
    half = max(float(cone_half_angle), 1e-3)
    m = len(p_HT)
    q_out = np.full((m, 6), np.nan)
    X_out = np.full((m, 4, 4), np.nan)
    ok = np.zeros(m, bool)
    clearance = np.zeros(m)
    failures: list[dict] = []
    n_dist = n_fallback = n_retry = n_analytic = n_probe = 0
    reach = options.min_distance + options.influence_distance
    t0 = time.perf_counter()
    p_T_pref = p_HT + lift * pref_axis_H  # T itself at the preferred axis (seeds)
    q_prev = None
    i_prev = -1
    for i in range(m):
        if q_prev is None:
            q_seed = (q_first if q_first is not None and i == 0 else
                      seed_by_spin(kin, checker, p_T_pref[i], pref_axis_H[i], t_H[i], q_ref,
                                   options))
            if q_seed is None:
                failures.append(dict(window=window_index, cl_index=i, stage="ik",
                                     reason="no IK branch reaches the first target"))
                continue
            anchor = q_seed
        else:
            anchor = q_prev
            q_seed = _analytic_seed(kin, X_out[i_prev], p_T_pref[i], pref_axis_H[i], q_prev,
                                    options.joint_weights,
                                    spin_span=0.5 if options.seed_spin == "joint_cost" else 0.0,
                                    spin_samples=21 if options.seed_spin == "joint_cost" else 1)
        done = False
        best = None
        probe = None
        if options.analytic_first and q_prev is not None:
            acc = _analytic_accept(kin, checker, q_seed, anchor, p_HT[i], cone_axis_H[i], half,
                                   options, lift, reach)
            if acc is not None:
                n_analytic += 1
                best = (q_seed, acc[0], acc[1], 0.0, 0.0)
                done = True
        for attempt in range(0 if done else options.retries + 1):
            start_with_distance = False
            # from the second retry on, ask only for the acceptance bound, not the margin
            opts = options if attempt < 2 else replace(
                options, min_distance=min(options.min_distance, options.min_distance_floor))
            if attempt == 1 and probe is None:
                # the program failed from the warm start: is there any admissible pose at all?
                probe = cone_clearance_probe(kin, checker, p_HT[i], cone_axis_H[i], half,
                                             pref_axis_H[i], t_H[i], anchor, lift=lift,
                                             bound=options.min_distance_floor,
                                             min_wrist=options.min_wrist)
                n_probe += 1
                if _unreachable(probe, options):
                    break  # far from any admissible pose: no seed can help (reported below)
            if attempt > 0:
                n_retry += 1
                reseed = None
                if attempt == 1 and probe["q"] is not None and np.max(
                        np.abs(probe["q"] - anchor)) <= options.trust_region:
                    reseed = probe["q"]  # the probe's pose: admissible and clear
                    start_with_distance = True
                elif attempt in (1, 2) and i_prev >= 0:
                    # where the preferred axis is too close to the hub (concave fillets), seed
                    # from the axis in the cone with the most clearance, distance-active at once
                    reseed = _clearance_seed(kin, checker, X_out[i_prev], p_HT[i],
                                             cone_axis_H[i], half, pref_axis_H[i], q_prev,
                                             reach, lift=lift)
                    start_with_distance = reseed is not None
                if reseed is None:
                    reseed = seed_by_spin(kin, checker, p_T_pref[i], pref_axis_H[i], t_H[i],
                                          anchor, options)
                if reseed is None:
                    break
                q_seed = reseed
            with_distance = start_with_distance
            for s_idx, solver in enumerate(solvers):
                if s_idx > 0:
                    n_fallback += 1
                success, q = _solve_point(cell, checker, p_HT[i], cone_axis_H[i], half,
                                          pref_axis_H[i], anchor, q_seed, with_distance, solver,
                                          opts, lift)
                good, err, ang, X = _recheck(kin, q, p_HT[i], cone_axis_H[i], half, opts, lift)
                dist = checker.min_distance(q, reach)[0]
                if good and dist < opts.min_distance - 1e-5 and not with_distance:
                    # lazy collision constraint: re-solve with it from this solution
                    with_distance = True
                    n_dist += 1
                    success, q = _solve_point(cell, checker, p_HT[i], cone_axis_H[i], half,
                                              pref_axis_H[i], anchor, q, True, solver, opts,
                                              lift)
                    good, err, ang, X = _recheck(kin, q, p_HT[i], cone_axis_H[i], half, opts,
                                                 lift)
                    dist = checker.min_distance(q, reach)[0]
                best = (q, X, dist, err, ang)
                if good and dist >= opts.min_distance - 1e-5:
                    done = True
                    break
            if done:
                break
        if best is not None:
            q_out[i], X_out[i], clearance[i] = best[0], best[1], best[2]
        if done:
            ok[i] = True
            q_prev = q_out[i]
            i_prev = i
        else:
            rec = dict(window=window_index, cl_index=i, stage="ik", reason="IK failed")
            if best is not None:
                rec.update(position_error=best[3], cone_angle=best[4], clearance=best[2])
                met = best[3] <= 1e-5 and best[4] <= half + 1e-6
                rec["reason"] = "clearance below bound" if met else "position/cone not met"
            if probe is not None and _unreachable(probe, options):
                rec.update(cone_best_clearance=probe["best_clearance"],
                           blocking_pair=list(probe["pair"]))
                rec["reason"] = (
                    f"unreachable: no tool axis in the cone ({np.degrees(half):.1f} deg) and "
                    f"spin clears the cell; best {probe['best_clearance'] * 1e3:.2f} mm "
                    f"({probe['pair'][0]} vs {probe['pair'][1]})")
            failures.append(rec)
        if progress is not None:
            progress(i + 1, m, f"window {window_index} IK")
    dt = time.perf_counter() - t0
    stats = dict(points=m, seconds=dt, seconds_per_point=dt / max(m, 1),
                 distance_resolves=n_dist, ipopt_fallbacks=n_fallback, retries=n_retry,
                 analytic_accepted=n_analytic, cone_probes=n_probe,
                 failed=int(m - ok.sum()))
    log.info("window %d: IK %d/%d points in %.2f s (%.1f ms/point), %d analytic warm starts "
             "accepted, %d distance re-solves", window_index, int(ok.sum()), m, dt,
             1e3 * stats["seconds_per_point"], n_analytic, n_dist)
    return WindowIk(q=q_out, ok=ok, X_HT=X_out, clearance=clearance, failures=tuple(failures),
                    stats=stats)
