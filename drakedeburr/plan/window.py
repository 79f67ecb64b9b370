"""One window: its CL targets solved by the cone-constrained IK from the best start, then the
executed cut, approach, retract and timing (:mod:`drakedeburr.plan.cut`,
:mod:`drakedeburr.plan.finish`).

A window is planned with the IK's warm-start spin rule, and again with the other rule when
that leaves failure records (the better result is kept) or holds less than
``options.retry_in_band`` of the cut in the speed band (the faster clean one is kept): the spin
picked target by target decides how far the wrist winds around the loop, and each rule winds
some window into its J4/J6 limits, or slowly around, where the other does not.
"""

from __future__ import annotations

import hashlib
import logging
import time
import weakref
from dataclasses import dataclass, replace

import numpy as np

from drakedeburr.plan.cut import track_cut
from drakedeburr.plan.finish import finish_window
from drakedeburr.plan.ik import IkTargets, seed_by_spin, solve_window_ik
from drakedeburr.plan.interpolate import track_poses
from drakedeburr.plan.options import PlanContext, RunMode
from drakedeburr.plan.program_fit import fit_program
from drakedeburr.plan.results import CutStep, CutTargets, IkStep, WindowPlan, WindowStatus
from drakedeburr.plan.targets import contact_geometry, tool_point_H
from drakedeburr.plan.types import FailureRecord
from drakedeburr.plan.window_targets import WindowTargets

__all__ = ["plan_window", "plan_whole", "precheck", "blocked_anywhere", "tool_refusal",
           "REFUSAL_MARGIN",
           "plan_window_pass", "cut_targets", "ik_step", "execute_cut", "needs_other_rule",
           "better_of", "rewound_start"]

log = logging.getLogger(__name__)


def _other_rule(ctx: PlanContext) -> tuple[str, PlanContext]:
    other = "frame" if ctx.options.ik.seed_spin == "joint_cost" else "joint_cost"
    options = replace(ctx.options, ik=replace(ctx.options.ik, seed_spin=other))
    return other, replace(ctx, options=options)


def window_reference(ctx: PlanContext, wt: WindowTargets) -> np.ndarray:
    """(6,) the configuration a window's start configurations are ranked from: the branch the
    placement search chose for it (:mod:`drakedeburr.plan.placement`), else home. Not the
    previous window's end: each window is planned on its own (in any order, in parallel, the
    same plan), and the joint moves between windows go anywhere."""
    q_ref = ctx.q_refs.get(wt.window_index)
    return ctx.kin.q_home.copy() if q_ref is None else np.asarray(q_ref, float)


def plan_window(ctx: PlanContext, wt: WindowTargets,
                mode: RunMode = RunMode.FULL) -> WindowPlan:
    """Approach, cut and retract of one window (module docstring), run as ``mode`` says."""
    refusal = precheck(ctx, wt)
    if refusal is not None:
        if ctx.options.partial_windows and wt.closed:
            from drakedeburr.plan.partial import plan_partial

            return plan_partial(ctx, wt, refusal, mode, plan_whole)
        log.info("window %d refused before its IK: %s", wt.window_index, refusal.reason)
        return WindowPlan.skipped(wt.window_index, WindowStatus.IK_FAILED, [refusal])
    return plan_whole(ctx, wt, mode)


def precheck(ctx: PlanContext, wt: WindowTargets) -> FailureRecord | None:
    """:func:`tool_refusal` of ``wt`` when ``ctx`` runs the tool pre-check
    (``options.tool_precheck``), else None (so is a stand-in context without a checker: it has
    nothing to search). A window it refuses is never planned clean: cut in part
    (:mod:`drakedeburr.plan.partial`), its refusal is a failure record of the plan, else the
    window is refused with it."""
    if getattr(ctx, "checker", None) is None or not ctx.options.tool_precheck:
        return None
    return tool_refusal(ctx, wt)


def plan_whole(ctx: PlanContext, wt: WindowTargets, mode: RunMode = RunMode.FULL) -> WindowPlan:
    """:func:`plan_window` after the pre-check: the IK's warm-start spin rule, and the other
    one where that leaves failures or a slow cut (module docstring)."""
    q_from = window_reference(ctx, wt)
    first = _plan_window_once(ctx, wt, q_from, mode)
    if mode is RunMode.REPORT_ONLY or not needs_other_rule(first, ctx.options.retry_in_band):
        return first
    other, ctx2 = _other_rule(ctx)
    if first.status.planned and not first.failures:  # clean but slow: the other rule may wind
        log.debug("window %d: %.0f %% of the cut in the speed band; planning it again with "
                  "the %r warm-start spin", wt.window_index,
                  100 * first.stats.speed_in_band_fraction, other)
    elif first.status is not WindowStatus.ABANDONED:
        log.debug("window %d: %d failure records; planning it again with the %r warm-start "
                  "spin", wt.window_index, len(first.failures), other)
    return better_of(first, _plan_window_once(ctx2, wt, q_from, mode))


#: a target is refused only when every axis of its cone is proven this far under the
#: clearance bound [m] (the distance readings' own spread)
REFUSAL_MARGIN = 0.2e-3
#: how often :func:`execute_cut` may halve the dense step where the trajectory would stray
#: from the program between the samples (:attr:`ProgramFit.finer`): 3, down to 1/8 of
#: ``options.dense_step``. Where the tool turns fast about its tool point near the wrist
#: singularity the joint spline swings the tool point off the program's line between samples
#: and the verifier reads the orientation at the wrong share of the move (audibot rim window 6:
#: an open stretch starting on a flank-to-face corner, 33 deg/mm at J5 = 0.41 rad: 15 mrad
#: against the slerp at 0.125 mm; sampled at 0.0625 mm there, the window's worst is 5.7 mrad;
#: one halving only had been allowed)
FINER_HALVINGS = 3


#: the pre-check's cone searches made in this process, per tool scene (its cell and tool):
#: a window's targets are searched again in each pass of the policy (first pass, the milder
#: recipes, the report-only pass) with the same inputs, and the search is a function of them
_SEARCHES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _search_key(wt: WindowTargets, p_HQ: np.ndarray, lift: float, bound: float) -> str:
    """Digest of everything :func:`~drakedeburr.plan.clearance.tool_axis_clearance` reads of
    a window (its constrained points, lift, cone, tool axes and tangents, the bound)."""
    h = hashlib.sha256()
    for a in (p_HQ, wt.cone_retract_H, wt.retract_H, wt.t_H,
              [lift, bound, REFUSAL_MARGIN, wt.cone_half_angle]):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def tool_refusal(ctx: PlanContext, wt: WindowTargets) -> FailureRecord | None:
    """The window refused before its IK, or None: the round tool parts (shank, collet, spindle
    body, clamp; the same at every spin and arm pose) searched over the window's cone at
    every CL target, the cutting circle held where the IK holds it
    (:func:`drakedeburr.plan.clearance.tool_axis_clearance`). A target where that search
    proves every axis of the cone :data:`REFUSAL_MARGIN` or more under the clearance bound has
    no admissible pose whatever the robot does; the record names how many, the tool part, how
    deep the least bad axis puts it into the part, and the worst target with its edge slope."""
    from drakedeburr.plan.clearance import tool_axis_clearance, tool_scene

    bound = ctx.min_clearance
    targets = cut_targets(ctx, wt, np.zeros((len(wt), 3)))
    m = len(wt)
    scene = tool_scene(ctx.checker)
    key = _search_key(wt, targets.p_HQ[:m], targets.lift, bound)
    known = _SEARCHES.setdefault(scene, {})
    if key not in known:
        known[key] = tool_axis_clearance(scene, wt, targets.p_HQ[:m], targets.lift,
                                         bound=bound, margin=REFUSAL_MARGIN)
    else:
        log.debug("window %d: the pre-check's search of these targets reused", wt.window_index)
    search = known[key]
    blocked = np.flatnonzero(search.proven)
    if not blocked.size:
        return None
    worst = int(blocked[np.argmin(search.best[blocked])])
    t_edge = getattr(getattr(wt.tool_path, "cl_path", None), "t_H", wt.t_H)
    slope = np.degrees(np.arcsin(np.clip(np.abs(np.asarray(t_edge)[:, 2]), 0.0, 1.0)))
    inside = blocked[search.best[blocked] < 0.0]
    parts = sorted({search.part[i] for i in blocked})
    depth = -search.best[inside] if inside.size else np.zeros(0)
    how = (f"puts the {'/'.join(sorted({search.part[i] for i in inside}))} up to "
           f"{1e3 * depth.max():.1f} mm (median {1e3 * np.median(depth):.1f} mm) inside the "
           f"part at {inside.size} of them" if inside.size else
           f"leaves the {'/'.join(parts)} at most {1e3 * search.best[blocked].max():.2f} mm "
           "from the part")
    reason = (f"at {blocked.size} of {m} CL points every tool axis within the "
              f"{np.degrees(search.half_angle):.1f} deg cone {how} ({1e3 * bound:.1f} mm "
              f"clearance needed; the worst at CL {worst}, "
              f"{tuple(np.round(wt.p_HC[worst] * 1e3, 1).tolist())} mm, where the edge runs "
              f"at {slope[worst]:.0f} deg to the face plane: "
              f"{1e3 * search.best[worst]:.1f} mm); no arm pose changes that (the parts are "
              f"round about the burr axis; the whole cone searched at each of them, "
              f"{int(search.reads[blocked].sum())} axes read)")
    return FailureRecord(
        window=wt.window_index, kind="window", point=worst, value=float(search.best[worst]),
        limit=float(bound), unit="m", reason=reason,
        where={"pair": (f"tool::{search.part[worst]}", "hub::hub"),
               "blocked_points": blocked.tolist(),
               "best_clearance_mm": np.round(1e3 * search.best, 3).tolist(),
               "edge_slope_deg": float(slope[worst])},
        tried=(f"{int(search.reads.sum())} tool axes read over the cone "
               f"({np.degrees(search.half_angle):.1f} deg) at the {m} CL points",))


@dataclass(frozen=True, eq=False)
class _Points:
    """CL targets of a window, as :func:`~drakedeburr.plan.clearance.tool_axis_clearance`
    reads them (a few rows of a WindowTargets, which needs three at least)."""

    retract_H: np.ndarray
    cone_retract_H: np.ndarray
    t_H: np.ndarray
    cone_half_angle: float

    def __len__(self) -> int:
        return len(self.retract_H)


def blocked_anywhere(ctx: PlanContext, wt: WindowTargets, first=()) -> FailureRecord | None:
    """Does the tool pre-check refuse ``wt`` (:func:`tool_refusal`: some CL target where
    every axis of the cone is proven :data:`REFUSAL_MARGIN` under the clearance bound)? The
    targets are searched one at a time, those in ``first`` first (e.g. the points another tilt
    box proved), then in loop order, up to the first one proven: a record naming that target
    (how deep the least bad axis puts the tool part), or None when none is, and then the
    search of every target is kept for :func:`tool_refusal` (one target's search reads that
    target alone, so the targets searched one by one are the whole window's search, bit for
    bit). None as well when ``ctx`` runs no pre-check (:func:`precheck`)."""
    from drakedeburr.plan.clearance import AxisSearch, tool_axis_clearance, tool_scene

    if getattr(ctx, "checker", None) is None or not ctx.options.tool_precheck:
        return None
    bound, m = ctx.min_clearance, len(wt)
    targets = cut_targets(ctx, wt, np.zeros((m, 3)))
    scene = tool_scene(ctx.checker)
    key = _search_key(wt, targets.p_HQ[:m], targets.lift, bound)
    known = _SEARCHES.setdefault(scene, {})
    if key in known:
        return tool_refusal(ctx, wt)
    order = list(dict.fromkeys([int(i) for i in first if 0 <= int(i) < m] + list(range(m))))
    found: dict = {}
    for i in order:
        one = tool_axis_clearance(
            scene, _Points(wt.retract_H[i:i + 1], wt.cone_retract_H[i:i + 1], wt.t_H[i:i + 1],
                           wt.cone_half_angle), targets.p_HQ[i:i + 1], targets.lift,
            bound=bound, margin=REFUSAL_MARGIN)
        if one.proven[0]:
            d, part = float(one.best[0]), one.part[0]
            how = (f"puts the {part} {-1e3 * d:.1f} mm inside the part" if d < 0.0 else
                   f"leaves the {part} at most {1e3 * d:.2f} mm from the part")
            return FailureRecord(
                window=wt.window_index, kind="window", point=i, value=d, limit=float(bound),
                unit="m", where={"pair": (f"tool::{part}", "hub::hub"), "blocked_points": [i]},
                reason=f"the tool pre-check proves CL {i} at "
                       f"{tuple(np.round(wt.p_HC[i] * 1e3, 1).tolist())} mm blocked: every "
                       f"tool axis within the {np.degrees(one.half_angle):.1f} deg cone {how} "
                       f"({1e3 * bound:.1f} mm clearance needed; no arm pose changes that), so "
                       f"the window cannot be cut whole in this box (searched up to the first "
                       f"such CL point: {len(found) + 1} of {m})",
                tried=(f"{int(one.reads[0])} tool axes read over the cone at CL {i}",))
        found[i] = one
    rows = [found[i] for i in range(m)]
    known[key] = AxisSearch(
        best=np.concatenate([r.best for r in rows]), part=tuple(r.part[0] for r in rows),
        best_axis_H=np.concatenate([r.best_axis_H for r in rows]),
        proven=np.concatenate([r.proven for r in rows]),
        reads=np.concatenate([r.reads for r in rows]), half_angle=rows[0].half_angle)
    return None


def needs_other_rule(first: WindowPlan, retry_in_band: float) -> bool:
    """Whether a window planned with one warm-start spin rule is planned again with the other:
    when it failed (a fail-fast pass: is the other rule clean?) or is clean but holds less than
    ``retry_in_band`` of its cut in the speed band."""
    if first.status.planned and not first.failures:
        return first.stats.speed_in_band_fraction < retry_in_band
    return True


def better_of(first: WindowPlan, second: WindowPlan) -> WindowPlan:
    """The window plan kept of a window's two (first rule, other rule): the faster clean one
    (the first on a tie), else the one with fewer failure records."""
    if first.status is WindowStatus.ABANDONED:
        return second if second.status.planned and not second.failures else first
    if first.status.planned and not first.failures:
        if (second.status.planned and not second.failures
                and second.stats.cut_seconds < first.stats.cut_seconds):
            return second
        return first
    if second.status is WindowStatus.ABANDONED:
        # fail-fast: the window fails either way; which rule fails less is decided by
        # planning it in full, if no relaxation is kept (planner._relax)
        return WindowPlan.skipped(first.window, WindowStatus.ABANDONED, first.failures)
    if second.status.planned and (not first.status.planned
                                  or len(second.failures) < len(first.failures)):
        return second
    return first


def rewound_start(kin, trial, q_first: np.ndarray | None,
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


def _seeds(ctx: PlanContext, wt: WindowTargets, p_HT0: np.ndarray, q_from: np.ndarray) -> list:
    """Start configurations to try: the best few distinct ones ranked from the window's
    reference ``q_from`` (:func:`window_reference`), then from home."""
    kin, opt = ctx.kin, ctx.options
    refs = [q_from] + ([] if np.array_equal(q_from, kin.q_home) else [kin.q_home])
    seeds: list = []
    for q_ref in refs:
        more = seed_by_spin(kin, ctx.checker, p_HT0, wt.retract_H[0], wt.t_H[0], q_ref, opt.ik,
                            count=opt.window_attempts) or []
        seeds += [q for q in more if q is not None and not _known(q, seeds)]
    return seeds or [None]


def _known(q: np.ndarray, seeds: list) -> bool:
    return any(s is not None and np.max(np.abs(q - s)) < 1e-6 for s in seeds)


def _solve_ik(ctx: PlanContext, wt: WindowTargets, q_from: np.ndarray, targets: CutTargets,
              mode: RunMode):
    """The window's IK from the best of its start configurations (each start is judged by its
    failures and by whether the executed motion between the targets stays on the branch and
    inside the joint limits: a cheap analytic pre-check)."""
    kin, opt = ctx.kin, ctx.options
    loop, p_HQ, lift = targets.loop, targets.p_HQ, targets.lift
    fail_fast, report_only = mode is RunMode.FAIL_FAST, mode is RunMode.REPORT_ONLY
    m = len(wt)
    seeds = _seeds(ctx, wt, p_HQ[0] + lift * wt.retract_H[0], q_from)
    if report_only:
        seeds = seeds[:1]
    wik, best_score = None, 0
    tracked_back: set[int] = set()
    ik_targets = IkTargets(p_HQ, wt.retract_H[loop], wt.cone_retract_H[loop], wt.t_H[loop],
                           wt.cone_half_angle, lift)
    for attempt, q_first in enumerate(seeds):
        trial = solve_window_ik(ctx, ik_targets, q_from, window_index=wt.window_index,
                                q_first=q_first, stop_at_failure=fail_fast)
        reached = np.flatnonzero(trial.ok)
        dense_ok = bool(len(reached) > 1 and np.all(track_poses(
            kin, trial.X_HT[reached], trial.q[reached[0]], opt.dense_step).ok))
        score = len(trial.failures) + (0 if dense_ok else 10 * (m + 1))
        if wik is None or score < best_score:
            wik, best_score = trial, score
        if score == 0:
            break
        # targets no pose in the cone can reach (the IK's probe): no other start fixes those
        unreachable = sum(1 for f in trial.failures if "cone_best_clearance" in f.where)
        if score == unreachable and trial is wik:
            say = log.debug if fail_fast else log.warning  # fail-fast: relaxation next
            say("window %d: %d targets unreachable with %.1f mm clearance by any tool axis in "
                "the cone; reported", wt.window_index, unreachable,
                1e3 * opt.ik.min_distance_floor)
            break
        log.debug("window %d: start seed %d left %d IK failures (executed motion %s); trying "
                 "another", wt.window_index, attempt, len(trial.failures),
                 "ok" if dense_ok else "leaves the limits")
        # one start tracked back from each failed target (of the first two) where the probe
        # found a clear pose the tracks did not arrive in: tried after the ranked starts (it
        # may lie far from the reference, and the moves to and from the window with it)
        first_fail = int(trial.failures[0].point) if trial.failures else None
        if (first_fail is not None and first_fail not in tracked_back and len(tracked_back) < 2
                and not report_only):
            tracked_back.add(first_fail)
            back = _backward_seed(ctx, wt, loop, p_HQ, lift, trial, first_fail)
            if back is not None and not _known(back, seeds):
                seeds.append(back)
        # a wrist that wound into a J4/J6 limit: the same start a full turn the other way next
        wound = rewound_start(kin, trial, q_first)
        if wound is not None and not _known(wound, seeds) and not report_only:
            seeds.insert(attempt + 1, wound)
    return wik, len(seeds)


def _backward_seed(ctx: PlanContext, wt: WindowTargets, loop: np.ndarray, p_HQ: np.ndarray,
                   lift: float, trial, i: int) -> np.ndarray | None:
    """A start configuration that arrives at target ``i`` (a position in ``loop``), where the
    trial failed, in the pose the cone probe found clear there: the IK tracked backwards from
    that pose to the window's first target. None when the probe did not run there, its pose
    clears the bound by less than ``NEAR_MISS`` (a pose at the bound's edge is what the failed
    tracks came within micrometres of: on an unseen hub, tracking back from such poses made
    the plan ~30 s longer and planned nothing more) or the backward pass fails."""
    from drakedeburr.plan.ik_seeds import NEAR_MISS

    probe, opt = trial.probes.get(i), ctx.options.ik
    if (i == 0 or probe is None or not probe.feasible
            or probe.best_clearance < opt.min_distance_floor + NEAR_MISS):
        return None
    ik_targets = IkTargets(p_HQ, wt.retract_H[loop], wt.cone_retract_H[loop], wt.t_H[loop],
                           wt.cone_half_angle, lift).back_from(i)
    back = solve_window_ik(ctx, ik_targets, probe.q, window_index=wt.window_index,
                           q_first=probe.q, stop_at_failure=True)
    log.debug("window %d: tracked back from an admissible pose at CL %d: %d of %d targets",
              wt.window_index, int(loop[i]), int(back.ok.sum()), len(ik_targets))
    return back.q[-1].copy() if back.ok.all() else None


def _plan_window_once(ctx: PlanContext, wt: WindowTargets, q_from: np.ndarray,
                      mode: RunMode) -> WindowPlan:
    """One planning pass of a window (see :func:`plan_window`), its chamfer leg relieved where
    the burr would reach deeper into the hub than the verifier allows
    (:mod:`drakedeburr.plan.burr_depth`). A report-only pass is relieved too: its plan is the
    one a window that fails in every recipe keeps and runs (audibot rim window 0 gouged
    1.9 mm on its approach when it was not)."""
    from drakedeburr.plan import burr_depth

    offset = np.zeros((len(wt), 3))
    result = plan_window_pass(ctx, wt, q_from, offset, mode)
    if not result.status.planned:
        return result
    hub = burr_depth.hub_model_of(str(ctx.cell.hub_sdf.parent))
    r_c, _lift = contact_geometry(ctx.options.contact_radius)
    p_HQ0 = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    bound = wt.depth_of_cut + ctx.config.tolerances.edge_deviation
    first = worst = None
    for attempt in range(burr_depth.ROUNDS + 1):
        X = ctx.kin.X_HT_from_q(np.concatenate(
            [st.timed.q for st in result.stretches if st.kind in ("approach", "cut", "retract")]))
        new, worst = burr_depth.relieved_offsets(hub, X, p_HQ0 + offset, offset, bound,
                                                 wt.closed)
        first = worst if first is None else first
        # a tool point never moves by more than the depth of cut (the line stays engaged)
        size = np.linalg.norm(new, axis=1, keepdims=True)
        new *= np.minimum(1.0, wt.depth_of_cut / np.maximum(size, 1e-12))
        if worst <= 0.0 or attempt == burr_depth.ROUNDS or np.allclose(new, offset):
            break
        log.info("window %d: the burr reaches %.3f mm into the hub (bound %.3f mm, kept "
                 "%.3f mm inside); moving %d tool points out by up to %.3f mm", wt.window_index,
                 1e3 * (worst + bound - burr_depth.MARGIN), 1e3 * bound,
                 1e3 * burr_depth.MARGIN, int(np.sum(np.any(new != offset, axis=1))),
                 1e3 * float(np.linalg.norm(new, axis=1).max()))
        retry = plan_window_pass(ctx, wt, q_from, new, mode)
        if not retry.status.planned or len(retry.failures) > len(result.failures):
            log.info("window %d: the moved tool points did not plan; kept the last plan",
                     wt.window_index)
            break
        result, offset = retry, new
    moved = np.linalg.norm(offset, axis=1)
    if moved.max() > 0.0:
        result.stats = replace(result.stats, chamfer_relief={
            "max_mm": float(1e3 * moved.max()), "cl_points": int(np.sum(moved > 0.0)),
            "depth_read_mm": float(1e3 * (first + bound - burr_depth.MARGIN)),
            "bound_mm": float(1e3 * bound),
            "excess_left_mm": float(1e3 * max(worst - burr_depth.MARGIN, 0.0))})
    if worst > burr_depth.MARGIN:  # still deeper than the verifier's bound: said, relaxed
        deepest = worst + bound - burr_depth.MARGIN
        result.failures = [*result.failures, FailureRecord(
            window=wt.window_index, kind="burr_depth", value=float(deepest), limit=float(bound),
            unit="m", reason=f"the burr reaches {1e3 * deepest:.3f} mm into the hub, "
                             f"{1e3 * bound:.3f} mm allowed (depth of cut + edge tolerance)",
            tried=(f"tool points moved out by up to {1e3 * moved.max():.3f} mm",))]
        result.status = WindowStatus.DEGRADED
    return result


def plan_window_pass(ctx: PlanContext, wt: WindowTargets, q_from: np.ndarray,
                     offset: np.ndarray, mode: RunMode = RunMode.FULL) -> WindowPlan:
    """THE window pipeline: one planning pass of a window, its CL targets' tool points moved by
    ``offset`` (M, 3) [m] (:mod:`drakedeburr.plan.burr_depth`; zero: the recipe's). Each step
    returns a typed result with its status; the pass stops at the first that does not plan.

    1. targets: the IK's targets, the tool points of the CL points (:func:`cut_targets`);
    2. IK from the best start configuration ranked from ``q_from`` (:func:`ik_step`);
    3.-4. the tracked cut and its program, sampled finer where needed
       (:func:`execute_cut`);
    5. approach, retract, timing and figures (:func:`drakedeburr.plan.finish.finish_window`).
    """
    targets = cut_targets(ctx, wt, offset)
    ik = ik_step(ctx, wt, q_from, targets, mode)
    if not ik.status.planned:
        return WindowPlan.skipped(wt.window_index, ik.status, list(ik.failures))
    cut = execute_cut(ctx, wt, ik, mode)
    if not cut.status.planned:
        return WindowPlan.skipped(wt.window_index, cut.status, [*ik.failures, *cut.failures])
    return finish_window(ctx, wt, ik, cut)


def execute_cut(ctx: PlanContext, wt, ik: IkStep, mode: RunMode = RunMode.FULL) -> CutStep:
    """Steps 3-4 of a window pass (:func:`plan_window_pass`): the
    window's executed cut and its program (:mod:`drakedeburr.plan.cut`), sampled every
    ``options.dense_step`` of travel and again at half that, up to ``FINER_HALVINGS`` times,
    where the program has moves the sampling cannot resolve (:attr:`ProgramFit.finer`)."""
    step = ctx.options.dense_step
    halvings = 0
    t1 = time.perf_counter()
    while True:
        tr = track_cut(ctx, wt, ik, step)
        records = list(tr.records)
        if not np.all(tr.cut.ok):
            return _cut_step(WindowStatus.MOTION_FAILED, None, records, t1)
        if mode is RunMode.FAIL_FAST and np.any(tr.dist < ctx.cut_clearance):
            # the window fails this recipe (the pinned axis and tightened blends did not
            # clear the hub): relaxed next (RunMode.FAIL_FAST), its program and timing
            # not made (on an unseen hub they were ~40 s a window and spin rule)
            log.debug("window %d: the executed cut stays under the clearance; abandoned for "
                      "a milder recipe", wt.window_index)
            return _cut_step(WindowStatus.ABANDONED, None, records, t1)
        fit = fit_program(ctx, wt, tr, ik.order, refine=halvings < FINER_HALVINGS)
        if fit.finer:
            step *= 0.5
            halvings += 1
            log.debug("window %d: between its samples the cut would stray from the program or "
                      "its cone; sampling it every %.3f mm", wt.window_index,
                     step * 1e3)
            continue
        records += fit.failures
        if not fit.status.planned:
            return _cut_step(fit.status, None, records, t1)
        status = WindowStatus.DEGRADED if records else WindowStatus.OK
        return _cut_step(status, fit.executed, records, t1)


def _cut_step(status: WindowStatus, executed, records: list, t1: float) -> CutStep:
    return CutStep(status=status, executed=executed, failures=tuple(records),
                   seconds=time.perf_counter() - t1)


def cut_targets(ctx: PlanContext, wt: WindowTargets, offset: np.ndarray) -> CutTargets:
    """Step 1 of :func:`plan_window_pass`: the IK's targets of a window."""
    r_c, lift = contact_geometry(ctx.options.contact_radius)
    m = len(wt)
    # the loop closes on a second copy of CL 0 solved last (warm-started from CL M-1): the burr
    # is rotationally symmetric, so the spin there need not equal the first one (no J6 unwind)
    loop = np.concatenate([np.arange(m), [0]]) if wt.closed else np.arange(m)
    # the IK ties the centre of the cutting circle (``lift`` below T on the axis) to its target
    p_HQ = (tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
            + offset)[loop]
    return CutTargets(loop=loop, p_HQ=p_HQ, lift=lift)


def ik_step(ctx: PlanContext, wt: WindowTargets, q_from: np.ndarray, targets: CutTargets,
            mode: RunMode = RunMode.FULL) -> IkStep:
    """Step 2 of :func:`plan_window_pass`: the window's IK from its best start; it stops the
    window (IK_FAILED) when fewer than half the targets or not the first are reached, and
    (ABANDONED) at any failed target in a fail-fast pass."""
    m, loop = len(wt), targets.loop
    t0 = time.perf_counter()
    wik, n_starts = _solve_ik(ctx, wt, q_from, targets, mode)
    t_ik = time.perf_counter() - t0
    failures = [replace(rec, point=int(loop[rec.point])) for rec in wik.failures]
    # only the targets that met every constraint (a failed point's row holds its best attempt)
    good = np.flatnonzero(wik.ok)
    status = WindowStatus.DEGRADED if failures else WindowStatus.OK
    if mode is RunMode.FAIL_FAST and failures:
        status = WindowStatus.ABANDONED
    elif len(good) < (m + 1) // 2 or 0 not in good:
        failures.append(FailureRecord(
            window=wt.window_index, kind="window", value=float(len(good)), limit=float(m + 1),
            unit="count", reason=f"IK reached only {len(good)} of {m + 1} targets; window "
                                 "skipped",
            tried=(f"{n_starts} start configurations", f"spin rule {ctx.options.ik.seed_spin}")))
        status = WindowStatus.IK_FAILED
    return IkStep(status=status, wik=wik, good=good, order=loop[good], failures=tuple(failures),
                  seconds=t_ik, starts=n_starts)
