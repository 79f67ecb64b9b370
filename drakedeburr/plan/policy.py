"""The hub-level policy: which passes plan a hub's windows, in which run mode, and which plan is
kept. Each pass works on typed results (:class:`~drakedeburr.plan.results.WindowPlan` per
window, :class:`~drakedeburr.plan.results.PlanDraft` per assembled plan) and returns new ones;
nothing is edited after it is made, and the Plan itself is made once, from the kept draft, by
:mod:`drakedeburr.plan.planner`.

The passes, in order (:func:`hub_pass` calls them):

1. :func:`first_pass`: every window once, in :attr:`RunMode.FAIL_FAST` when relaxation is on
   (a window that fails under the recipe is abandoned at its first failure: it is relaxed
   next), else :attr:`RunMode.FULL`;
2. :func:`relax_pass`: the failing windows' milder recipes (:mod:`drakedeburr.plan.relax`), the
   relaxed plan kept when it leaves fewer failure records; the abandoned windows no relaxation
   replaces are planned in full once for their report (:func:`report_only_pass`,
   :attr:`RunMode.REPORT_ONLY`);
3. :func:`long_reach_pass`: where the standard burr's body blocked a window, the hub in the
   long-reach cell (its failing windows first), kept when it cuts the hub better
   (:func:`drakedeburr.plan.relax.choose_tool`: what is cut, not the count of failure
   entries; a program with a move under the clearance loses).

How windows are planned and assembled in one cell is given to the policy as a
:class:`CellPasses` (the planner's: :func:`drakedeburr.plan.planner.cell_passes`), so the
policy runs the same on stand-ins.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from drakedeburr.config import ProcessParameters
from drakedeburr.plan import relax
from drakedeburr.plan.burr_depth import MARGIN
from drakedeburr.plan.options import RunMode
from drakedeburr.plan.results import Deviation, PlanDraft, WindowPlan, WindowStatus
from drakedeburr.plan.types import FailureRecord

__all__ = ["CellPasses", "first_pass", "report_only_pass", "relax_pass", "cell_pass",
           "long_reach_pass", "hub_pass", "long_reach_allowed", "relief_deviation",
           "first_failures", "in_vain_records"]

log = logging.getLogger(__name__)

Progress = Callable[[int, int, str], None] | None


@dataclass(frozen=True)
class CellPasses:
    """How the policy plans and assembles windows in one cell.

    Attributes:
        plan: ``plan(windows' targets, mode, progress)`` -> one WindowPlan per window, in
            their order (:func:`drakedeburr.plan.window.plan_window` in run mode ``mode``).
        ladders: ``ladders(WindowEdges, mode)`` -> per edge its ladder of milder recipes
            (:func:`drakedeburr.plan.relax.plan_ladder`: [(box, targets, WindowPlan)]).
        assemble: ``assemble(windows' targets, their WindowPlans)`` -> the PlanDraft of those
            windows from home and back.
        params: the recipe's process parameters (the deviations name its defaults).
        progress: callback (done, total, label) of the first pass, or None.
    """

    plan: Callable[[Sequence, RunMode, Progress], list]
    ladders: Callable[[list, RunMode], list]
    assemble: Callable[[Sequence, Sequence], PlanDraft]
    params: ProcessParameters
    progress: Progress = None


def first_pass(passes: CellPasses, wts: Sequence, relaxing: bool) -> list[WindowPlan]:
    """Every window planned once: in :attr:`RunMode.FAIL_FAST` when the recipe is relaxed
    where it fails (a window is abandoned at its first failure, an IK target or its cut under
    the clearance: it fails under this recipe whatever the rest does), else in
    :attr:`RunMode.FULL`."""
    return passes.plan(wts, RunMode.FAIL_FAST if relaxing else RunMode.FULL, passes.progress)


def report_only_pass(passes: CellPasses, wts: Sequence, results: Sequence[WindowPlan],
                     which: Sequence[int]) -> list[WindowPlan]:
    """``results`` with each abandoned one among positions ``which`` planned in full, once, for
    its report (:attr:`RunMode.REPORT_ONLY`: the first start, the IK's own spin rule; its
    failure records say where the window fails and by how much)."""
    out = list(results)
    ks = [k for k in which if out[k].status is WindowStatus.ABANDONED]
    if ks:
        done = passes.plan([wts[k] for k in ks], RunMode.REPORT_ONLY, None)
        for k, r in zip(ks, done, strict=True):
            out[k] = r
    return out


def first_failures(results: Sequence[WindowPlan]) -> dict[int, str]:
    """Window -> its first failure record, as text (why the recipe failed there)."""
    first: dict[int, str] = {}
    for r in results:
        for f in r.failures:
            first.setdefault(f.window, str(f))
    return first


def in_vain_records(failing: Sequence[int], accepted: dict, tried: dict,
                    abandoned: set[int]) -> list[FailureRecord]:
    """A ``relaxation`` record per failing window no milder recipe cut (``accepted`` and
    ``tried`` as :func:`drakedeburr.plan.relax.relax_windows` returns them): what was tried and
    the first failure each left; for an abandoned window also that its records are the first
    start's."""
    return [FailureRecord(window=w, kind="relaxation", tried=tuple(t for t, _ in tried[w]),
                          reason="milder recipes failed too: " + "; ".join(
                              f"{t}: {r}" for t, r in tried[w]) + (
                              "; with the recipe both spin rules stopped at a first failure"
                              " (an IK target no start configuration reached, or the executed"
                              " cut under the clearance), the records are the first start's"
                              if w in abandoned else ""))
            for w in failing if w not in accepted and tried[w]]


def relax_pass(passes: CellPasses, edges: dict, wts: Sequence,
               results: Sequence[WindowPlan]) -> PlanDraft:
    """The plan with a milder recipe for each window the recipe could not cut
    (:func:`drakedeburr.plan.relax.relax_windows`: each window's variants in turn, the windows
    at once, in :attr:`RunMode.FAIL_FAST`), kept when it leaves fewer failure records than the
    recipe's; each milder tilt kept is a recorded deviation. The other windows keep their
    first-pass plans (windows are planned independently); the plan is assembled from them.

    Args:
        passes: how windows are planned and assembled in this cell.
        edges: window index -> WindowEdge (the hub's windows; a window without one is not
            relaxed).
        wts: the windows' targets, in execution order; results: their first pass (may hold
            ``WindowStatus.ABANDONED`` windows: those not replaced by a kept relaxation are
            planned in full here, once, by :func:`report_only_pass`).

    Returns:
        The kept PlanDraft, with a ``relaxation`` failure record per window relaxed in vain.
    """
    first = first_failures(results)
    failing = [wt.window_index for wt in wts if wt.window_index in first
               and wt.window_index in edges]
    accepted, tried = ({}, {}) if not failing else relax.relax_windows(
        [edges[w] for w in failing], passes.params, first,
        lambda es: passes.ladders(es, RunMode.FAIL_FAST))
    abandoned = {wt.window_index for wt, r in zip(wts, results, strict=True)
                 if r.status is WindowStatus.ABANDONED}
    in_vain = in_vain_records(failing, accepted, tried, abandoned)
    results = report_only_pass(passes, wts, results, [k for k, wt in enumerate(wts)
                                                      if wt.window_index not in accepted])
    plan = None
    if accepted:
        wts2 = [accepted[wt.window_index][0] if wt.window_index in accepted else wt
                for wt in wts]
        res2 = [accepted[wt.window_index][1] if wt.window_index in accepted else r
                for wt, r in zip(wts, results, strict=True)]
        relaxed = passes.assemble(wts2, res2)
        # the default's windows' records (an abandoned window's: its first ones) bound its
        # count from below: fewer than that is fewer than the default; else assemble it
        kept = len(relaxed.failures) < sum(len(r.failures) for r in results)
        if not kept:
            results = report_only_pass(passes, wts, results, range(len(wts)))
            plan = passes.assemble(wts, results)
            kept = len(relaxed.failures) < len(plan.failures)  # both without in-vain records
        if kept:
            deviations = tuple(accepted[w][2] for w in failing if w in accepted)
            log.warning("recipe relaxed for window(s) %s: %s", [d.window for d in deviations],
                        "; ".join(f"{d.item} {d.default} -> {d.used}" for d in deviations))
            plan = relaxed.with_deviations(back=deviations)
    if plan is None:
        plan = passes.assemble(wts, results)
    if in_vain:  # said with the failures of whichever plan is kept
        plan = replace(plan, failures=(*plan.failures,
                                       *relax.on_uncut_edge(plan.failures, in_vain)))
    return plan


def cell_pass(passes: CellPasses, edges: dict, wts: Sequence, relaxing: bool) -> PlanDraft:
    """The windows' plan in one cell: :func:`first_pass`, then :func:`relax_pass` when
    ``relaxing`` and a window left failure records, else the first pass assembled."""
    results = first_pass(passes, wts, relaxing)
    if relaxing and any(r.failures for r in results):
        return relax_pass(passes, edges, wts, results)
    return passes.assemble(wts, results)


def long_reach_pass(standard: PlanDraft, windows: Sequence[int],
                    plan_long_reach: Callable[[set[int] | None], PlanDraft],
                    refused: Callable[[list[int]], dict] | None = None) -> PlanDraft:
    """The hub planned again with the long-reach burr, the standard burr's plan or that one
    kept (:func:`drakedeburr.plan.relax.choose_tool`).

    The windows the standard burr left failing are planned first (``plan_long_reach(only)``:
    in the long-reach cell placed for the whole hub, as the full pass places it). A window's
    plan depends only on the cell, the placement and its own targets, so one that fails there
    (its milder recipes included, and no move between windows failing) is cut the same in the
    full pass too; the other windows the standard burr cuts whole, so when the long-reach plan
    of the failing windows does not cut them better (:func:`drakedeburr.plan.relax.better_cut`
    against the standard plan's tally of those windows), its plan of the hub cannot cut it
    better, and the other windows are not planned again
    (:func:`drakedeburr.plan.relax.keep_standard`).

    Before either, when no move between windows failed, the long-reach burr's tool pre-check
    is asked of the failing windows (``refused``): when it refuses each of them in the
    recipe's tilt box and in every milder one, each fails with that burr too (cut in part at
    best, whatever is planned), so the long-reach plan (of those windows or of the hub) cannot
    leave fewer windows failing and is not made: the standard burr's plan is kept, as either
    pass would keep it (:func:`drakedeburr.plan.relax.keep_refused`).

    Args:
        standard: the standard burr's plan. windows: the hub's planned windows' indices.
        plan_long_reach: ``only`` (window indices, or None: all) -> their plan in the
            long-reach cell.
        refused: failing window indices -> {window: its refusal} of those the long-reach
            pre-check refuses in every box
            (:func:`drakedeburr.plan.relax.refused_in_every_box`), or None (not asked).
    """
    failing = relax.failing_windows(standard)
    log.warning("the standard burr leaves window(s) %s failing where the spindle meets the "
                "cell: planning %s again with the %s", failing,
                "them" if -1 not in failing else "the hub", relax.long_reach().title)
    if refused is not None and -1 not in failing:
        proven = refused(failing)
        if set(failing) <= set(proven):
            log.warning("the %s's tool pre-check refuses window(s) %s in every tilt box: the "
                        "standard burr's plan kept", relax.long_reach().title, failing)
            return relax.keep_refused(standard, {w: proven[w] for w in failing})
    if -1 not in failing and len(failing) < len(windows):
        first = plan_long_reach(set(failing))
        still = relax.failing_windows(first)
        # the other windows the standard burr cuts whole: the long-reach plan of the hub
        # cuts better only where it cuts these better
        if -1 not in still and not relax.better_cut(relax.cut_tally(first),
                                                    relax.cut_tally(standard, failing)):
            return relax.keep_standard(standard, first)
        log.warning("the %s cuts window(s) %s: planning the hub with it",
                    relax.long_reach().title, sorted(set(failing) - set(still)))
    return relax.choose_tool(standard, plan_long_reach(None))


def long_reach_allowed(options, config) -> bool:
    """May :func:`hub_pass` try the long-reach burr: the recipe is relaxed where it fails
    (``options.relax``) and the run asked for no burr (``config.tool`` None)."""
    return bool(options.relax) and config.tool is None


def hub_pass(plan_in: Callable[[str | None, set[int] | None], PlanDraft],
             windows: Sequence[int], cell, *, long_reach: bool,
             t_start: float | None = None,
             refused_in: Callable[[str, list[int]], dict] | None = None) -> PlanDraft:
    """The hub's plan: in the given cell (``plan_in(None, None)``), and when ``long_reach`` and
    a failure names the standard burr's body (:func:`drakedeburr.plan.relax.reach_may_help`)
    again with the long-reach burr (:func:`long_reach_pass` on ``plan_in(LONG_REACH, only)``);
    the retry's timings are recorded (the standard burr's from ``t_start``, default now).

    Args:
        plan_in: (burr: None for the cell's own, or a tool variant name; only: window indices
            or None) -> the PlanDraft of the hub in that cell (:func:`cell_pass` there).
        windows: the hub's planned windows' indices. cell: the cell (its ``tool``).
        long_reach: may the long-reach burr be tried (relaxation on, no burr asked for).
        refused_in: (burr, window indices) -> {window: refusal} of the windows that burr's
            tool pre-check refuses in every tilt box (:func:`long_reach_pass`), or None.
    """
    t0 = time.perf_counter() if t_start is None else t_start
    plan = plan_in(None, None)
    if long_reach and relax.reach_may_help(plan, cell):
        t1 = time.perf_counter()
        plan = long_reach_pass(plan, windows, lambda only: plan_in(relax.LONG_REACH, only),
                               None if refused_in is None
                               else lambda ws: refused_in(relax.LONG_REACH, ws))
        plan = plan.with_timings(standard_burr_seconds=t1 - t0,
                                 long_reach_seconds=time.perf_counter() - t1)
    return plan


def relief_deviation(stats: dict) -> Deviation:
    """The recipe deviation of a window whose tool points were moved out of the material
    (``stats``: its ``plan.meta["windows"]`` figures with ``chamfer_relief``,
    :mod:`drakedeburr.plan.burr_depth`)."""
    r = stats["chamfer_relief"]
    left = (f"; still {r['excess_left_mm']:.3f} mm too deep" if r["excess_left_mm"] > 0
            else "")
    return Deviation(
        window=int(stats["window"]), item="tool point", default="the depth of cut's",
        used=f"moved out of the material by up to {r['max_mm']:.3f} mm at {r['cl_points']} "
             f"CL points",
        reason=f"the burr reached {r['depth_read_mm']:.3f} mm into the hub where "
               f"{r['bound_mm']:.3f} mm is allowed (depth of cut + the edge tolerance; the "
               f"planner keeps {1e3 * MARGIN:.2f} mm inside it): a rounded or acute edge{left}")
