"""Recipe relaxation: a window the default recipe cannot cut is planned again with a milder
one, and the deviation is recorded (:class:`~drakedeburr.plan.results.Deviation` in the plan's
record, ``plan.meta["recipe_deviations"]``) and shown in the report. When each is tried is the
hub-level policy's (:mod:`drakedeburr.plan.policy`).

What is relaxed, in order, for a window whose plan leaves failure records:

1. the tool tilt: the large windows' (theta_A, theta_B) box of the source (0.26-0.44 rad) is
   meant for a flat face; on a dished or rising face the spindle body leans into the face
   beyond the opening (the bundled deep-dish hub needed exactly this, by hand). The window is
   oriented again with the small windows' box (0.09-0.26 rad), then with 0-0.15 rad, then with
   0-0.44 rad: every tilt of the source's two boxes and the milder ones, whose cone (about
   twice as wide) lets the IK lean the spindle where a narrow cone around any one tilt meets
   the dish (on an unseen 15 in hub with an 84 mm dish, no axis of the 0-0.15 rad cone kept
   the 80 mm spindle body 2 mm off the dish wall at some targets of every window; the whole
   range cut window 0 without a failure record);
2. the burr, for the whole hub (:func:`choose_tool`, called by
   :func:`drakedeburr.plan.policy.hub_pass`): where windows still fail with the spindle body,
   its clamp or the collet against something (a deep dish: the spindle body meets
   the dish wall whatever the tilt), the hub is planned again with the long-reach burr (the
   same head, 50 mm further out: ``drakedeburr.cell.tools.TOOL_VARIANTS``) and that plan kept
   when it cuts better (:func:`better_cut`: a program whose moves all keep the clearance
   beats one with a failing move; else no less edge, no window left wholly uncut that the
   standard burr cut in part, and fewer windows failing or more edge cut). One burr serves
   the whole hub (no tool change within a program); the standard burr is stiffer, so it
   stays the default;
3. nothing else is tried automatically: a slower feed does not make a motion feasible (the
   timing already slows wherever a limit binds), and a smaller head would cut another chamfer
   (a recipe change, the part's to make).

Each failing window's variants are planned in turn, milder each step, up to the first that
plans without a failure record (its *ladder*, :func:`window_ladder`); the ladders of all
failing windows are planned at once (one task each, in parallel where the planner has
workers). Windows are planned independently (the same plan whichever process plans them), so
the hub is not planned again: its plan is assembled anew (transitions, timing) from the first
pass's windows and the relaxed ones.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass, replace

from drakedeburr.cell.tools import DEFAULT_TOOL, tool_variant
from drakedeburr.config import OrientationBounds
from drakedeburr.plan.options import RunMode
from drakedeburr.plan.results import Deviation, WindowPlan, WindowStatus
from drakedeburr.plan.types import FailureRecord

__all__ = ["Deviation", "TILT_STEPS", "LONG_REACH", "relax_windows", "window_ladder",
           "milder_boxes", "box_targets", "refused_in_every_box", "keep_refused",
           "plan_ladder", "oriented", "first_cl_paths", "reach_may_help", "choose_tool",
           "keep_standard", "failing_windows", "long_reach", "MOVE_KINDS", "EDGE_TIE",
           "CutTally", "cut_tally", "better_cut"]

log = logging.getLogger(__name__)

#: tilt boxes tried in turn, milder each step [rad]
TILT_STEPS = (OrientationBounds(0.09, 0.26), OrientationBounds(0.0, 0.15),
              OrientationBounds(0.0, 0.44))

#: the burr tried for a hub the standard one cannot cut
LONG_REACH = "long_reach"
#: tool geometries a longer stick-out moves back from the cut (the generated tool models')
#: (not the shank: a longer one reaches further down, where it met the hub)
_TOOL_BODY = frozenset({"spindle_body", "clamp", "collet", "bracket", "adapter_plate"})


def _box(b: OrientationBounds) -> str:
    return f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"


def relax_windows(edges, params, failed_reasons: dict, ladders):
    """Milder recipes for several windows: each window's variants planned in turn, milder each
    step, up to the first that plans without a failure record (:func:`window_ladder`); the
    windows' ladders at once (``ladders(list of WindowEdge)`` -> per window its ladder, e.g.
    :func:`plan_ladder` on the pool's workers). A window's plan depends only on its own
    targets, so each ladder is what one batch per tilt step gave, and no window waits for the
    slowest variant of a step.

    Args:
        edges: the failing windows' WindowEdges. params: the recipe's ProcessParameters.
        failed_reasons: window -> why the default failed (for the record).
        ladders: callable planning the windows' ladders.

    Returns:
        (accepted: window -> (WindowTargets, result, Deviation), tried: window -> [(recipe
        item, the first failure it left)] per variant that failed).
    """
    accepted, tried = {}, {e.index: [] for e in edges}
    for edge, ladder in zip(edges, ladders(list(edges)), strict=True):
        for box, wt, res in ladder:
            if wt is None:  # the milder box gives no targets (res: why)
                tried[edge.index].append((_box(box), res))
                continue
            log.info("window %d: relaxed to %s: %d failure records", edge.index, _box(box),
                     len(res.failures))
            if not res.failures:
                accepted[edge.index] = (wt, res, Deviation(
                    edge.index, "tool tilt", _box(params.bounds(edge.kind)), _box(box),
                    f"the recipe's box failed: {failed_reasons.get(edge.index, '')}"))
            else:
                tried[edge.index].append((_box(box), str(res.failures[0])))
    return accepted, tried


def oriented(edge, cl, params):
    """The ToolPath of ``edge`` from its CL points ``cl`` (a ClPath, which the box does not
    change) in the box of ``params``: :func:`drakedeburr.plan.tool_paths.oriented`, the
    orientation stage of :func:`~drakedeburr.plan.tool_paths.tool_path` alone."""
    from drakedeburr.plan import tool_paths

    return tool_paths.oriented(edge, cl, params)


def window_ladder(edge, params, plan_one, cl=None, refused=None) -> list:
    """One window's milder variants (:data:`TILT_STEPS`, those milder than the recipe's own
    box), each planned by ``plan_one(WindowTargets)`` in turn up to the first without a failure
    record -> [(box, WindowTargets, result)] in the order planned; a box whose tool path gives
    no targets (InputError: e.g. an axis into the part) is ``(box, None, why)`` and the next box
    is tried, so the window keeps its first-pass failure and the hub its report.

    ``cl``: the window's CL points (the ClPath of its first pass's ToolPath), or None. The
    path stage (edge fit, adaptive CL points) reads only the edge, not the tilt box, and is
    deterministic, so each box's ToolPath is the orientation of that same ClPath
    (:func:`oriented`): the same targets as :func:`~drakedeburr.plan.tool_paths.tool_path`
    would make, without planning the CL points again per box.

    ``refused``: ``refused(WindowTargets)`` -> the tool pre-check's refusal of the box's
    targets or None (:func:`drakedeburr.plan.window.precheck`), or None (not asked). A box
    whose targets the pre-check refuses (CL points where every axis of the box's own cone
    puts the round tool parts under the clearance) cannot plan without a failure record: its
    window is cut in part at best, and a part is a failure record
    (:mod:`drakedeburr.plan.partial`), so it is never the box kept. Its result is the refusal
    alone (``IK_FAILED``), the window's stretches not planned, and the next box is tried, as
    a planned box with failure records is."""
    out = []
    for box in milder_boxes(edge, params):
        wt = box_targets(edge, params, box, cl)
        if isinstance(wt, str):
            log.info("window %d: %s gives no targets: %s", edge.index, _box(box), wt)
            out.append((box, None, f"no targets: {wt}"))
            continue
        why = None if refused is None else refused(wt)
        if why is not None:
            log.info("window %d: %s: the tool pre-check refuses its targets (at best a cut in "
                     "part, a failure record); its stretches not planned", edge.index,
                     _box(box))
            out.append((box, wt, WindowPlan.skipped(edge.index, WindowStatus.IK_FAILED,
                                                    [why])))
            continue
        res = plan_one(wt)
        out.append((box, wt, res))
        if not res.failures:
            break
    return out


def milder_boxes(edge, params) -> list[OrientationBounds]:
    """The tilt boxes of :data:`TILT_STEPS` milder than the recipe's own for ``edge``'s kind
    (those :func:`window_ladder` tries), in order."""
    default = params.bounds(edge.kind)
    return [box for box in TILT_STEPS
            if not (box.theta_max >= default.theta_max and box.theta_min >= default.theta_min)]


def box_targets(edge, params, box: OrientationBounds, cl=None):
    """The WindowTargets of ``edge`` with the tilt box ``box`` (from its ClPath ``cl`` when
    given: :func:`window_ladder`), or why its tool path gives none (str: the InputError)."""
    from drakedeburr.errors import InputError
    from drakedeburr.plan.tool_paths import tool_path
    from drakedeburr.plan.window_targets import WindowTargets

    p = replace(params, bounds_large=box, bounds_small=box)
    try:
        return WindowTargets.from_tool_path(tool_path(edge, p) if cl is None
                                            else oriented(edge, cl, p))
    except InputError as exc:
        return str(exc)


def refused_in_every_box(ctx, item) -> FailureRecord | None:
    """``item`` = (WindowEdge, ProcessParameters, its ClPath or None, its recipe's
    WindowTargets): the tool pre-check's refusal of the recipe's targets in ``ctx``
    (:func:`drakedeburr.plan.window.precheck`) when it also refuses the targets of every
    milder box (:func:`milder_boxes`; a box without targets counts as refused; a milder box
    searched up to its first proven CL point, the recipe's blocked ones first:
    :func:`drakedeburr.plan.window.blocked_anywhere`), else None.
    A window so refused plans with a failure record in ``ctx``'s cell whatever the recipe's
    relaxation does (:func:`window_ladder`): the first pass cuts it in part at best, and no
    box is kept. A task for :func:`drakedeburr.plan.parallel.map_windows`."""
    from drakedeburr.plan.window import blocked_anywhere, precheck

    edge, params, cl, wt = item
    first = precheck(ctx, wt)
    if first is None:
        return None
    hint = first.where.get("blocked_points", ())
    for box in milder_boxes(edge, params):
        other = box_targets(edge, params, box, cl)
        if not isinstance(other, str) and blocked_anywhere(ctx, other, hint) is None:
            return None
    return first


def plan_ladder(ctx, item, mode: RunMode = RunMode.FULL) -> list:
    """:func:`window_ladder` of ``item`` = (WindowEdge, ProcessParameters) or (WindowEdge,
    ProcessParameters, its ClPath or None), each variant by
    :func:`drakedeburr.plan.window.plan_window` in ``ctx`` and run mode ``mode``, a variant
    the tool pre-check refuses not planned (:func:`drakedeburr.plan.window.blocked_anywhere`:
    searched up to its first proven CL point) (a task for
    :func:`drakedeburr.plan.parallel.map_windows`)."""
    from drakedeburr.plan.window import blocked_anywhere, plan_window

    edge, params, *cl = item
    return window_ladder(edge, params, functools.partial(plan_window, ctx, mode=mode),
                         cl[0] if cl else None, functools.partial(blocked_anywhere, ctx))


def first_cl_paths(wts) -> dict:
    """Window -> the ClPath of its targets' ToolPath (``wt.tool_path.cl_path``), for the
    windows whose targets came from the path and orientation stages (:func:`window_ladder`)."""
    out = {}
    for wt in wts:
        cl = getattr(getattr(wt, "tool_path", None), "cl_path", None)
        if cl is not None:
            out[wt.window_index] = cl
    return out


def long_reach():
    """The long-reach burr's :class:`~drakedeburr.cell.tools.ToolVariant`."""
    return tool_variant(LONG_REACH)


#: failure kinds of a move off the cut (approach, retract, a joint move between stretches,
#: windows or home) that misses the clearance: the program would run the arm or the tool body
#: closer to the cell than the bound, so it cannot run as planned
MOVE_KINDS = frozenset({"approach", "retract", "transition", "home"})
#: two plans' cut edge lengths closer than this are the same cut [m] (well under one CL
#: spacing: the same CL points cut give the same length to rounding)
EDGE_TIE = 1e-3


@dataclass(frozen=True)
class CutTally:
    """What a hub's plan cuts, as a cell engineer compares two plans of it.

    Attributes:
        runs: no move off the cut misses the clearance (no record of :data:`MOVE_KINDS`).
        cut_m: window -> its edge cut [m] (a window cut whole: its loop; in part: the edge
            of its planned stretches), for each window cut at least in part.
        failing: the number of windows with failure records (-1, a move between windows or
            home, counts as one).
    """

    runs: bool
    cut_m: dict
    failing: int

    @property
    def edge_m(self) -> float:
        """The edge cut over all windows [m]."""
        return float(sum(self.cut_m.values()))

    def text(self) -> str:
        """One line: edge cut, windows cut, failing windows, whether it runs."""
        return (f"{1e3 * self.edge_m:.1f} mm of edge in {len(self.cut_m)} window(s), "
                f"{self.failing} failing" + ("" if self.runs else ", a move off the cut "
                                                                 "under the clearance"))


def cut_tally(plan, windows=None) -> CutTally:
    """The :class:`CutTally` of a :class:`~drakedeburr.plan.results.PlanDraft` (its failure
    records and its figures' per-window statistics; a draft without figures cuts nothing
    that is counted, so two such are compared by their failing windows alone); ``windows``:
    of those windows alone (their records and the moves between windows), or None: all."""
    keep = (lambda w: True) if windows is None else (lambda w: w in set(windows) or w == -1)
    cut = {}
    for s in (plan.record.figures or {}).get("windows") or ():
        part = s.get("partial")
        m = 1e-3 * float(part["cut_mm"]) if part else float(s.get("edge_length_m") or 0.0)
        if m > 0 and keep(int(s["window"])):
            cut[int(s["window"])] = m
    failures = [f for f in plan.failures if keep(f.window)]
    return CutTally(runs=not any(f.kind in MOVE_KINDS for f in failures), cut_m=cut,
                    failing=len({f.window for f in failures}))


def better_cut(alt: CutTally, base: CutTally) -> bool:
    """Does the plan tallied ``alt`` cut the hub better than ``base`` (a tie keeps ``base``)?

    1. A program whose moves all keep the clearance beats one that does not (a move under
       the clearance is a collision risk: that program is not run, whatever it would cut).
    2. Else ``alt`` must cut no less edge (within :data:`EDGE_TIE`) and every window
       ``base`` cuts at least in part (a window wholly uncut is a part sent back), and then
       leave fewer windows failing or cut more edge.
    """
    if alt.runs != base.runs:
        return alt.runs
    if alt.edge_m < base.edge_m - EDGE_TIE or not set(base.cut_m) <= set(alt.cut_m):
        return False
    return alt.failing < base.failing or alt.edge_m > base.edge_m + EDGE_TIE


def failing_windows(plan) -> list[int]:
    """The windows with failure records (-1: a move between windows or home)."""
    return sorted({f.window for f in plan.failures})


def _pair(f: FailureRecord) -> list[str]:
    return [str(p) for p in (f.where.get("blocking_pair") or f.where.get("pair") or ())]


def reach_may_help(plan, cell) -> bool:
    """Could a longer burr help: the cell carries the standard burr on a bundled spindle and a
    failure names a tool-body geometry (spindle body, clamp, collet) in the pair that
    blocked it. Pair names are ``model::body/model::geometry``."""
    if cell.tool != DEFAULT_TOOL:
        return False
    return any(n.rsplit("::", 1)[-1] in _TOOL_BODY for f in plan.failures for n in _pair(f))


def keep_standard(plan, first):
    """The standard burr's ``plan`` kept: the long-reach burr, tried first on the windows it
    left failing (``first``: the plan of those windows alone, placed for the whole hub), cut
    them no better (:func:`better_cut` against the standard plan's tally of those windows);
    a failure record per window says so."""
    mine = cut_tally(plan, [w for w in failing_windows(plan) if w >= 0])
    return _standard_kept(plan, _first_records(first), failing_windows(first),
                          f"was tried on window(s) {failing_windows(plan)} first "
                          "(the hub placed for it as a whole) and cut them no "
                          f"better ({cut_tally(first).text()}; the standard burr "
                          f"{mine.text()}), so the hub was not planned again with it")


def keep_refused(plan, refused: dict):
    """The standard burr's ``plan`` kept without planning the long-reach burr: its tool
    pre-check refuses each window the standard burr left failing in the recipe's box and in
    every milder one (``refused``: window -> the recipe box's refusal,
    :func:`refused_in_every_box` in the long-reach cell), so each of them fails with it too
    and it cannot leave fewer windows failing (:func:`choose_tool` keeps the standard burr
    on a tie); a failure record per window says so, with the long-reach refusal."""
    return _standard_kept(plan, refused, sorted(refused),
                          "was not planned: its tool pre-check proves CL points of window(s) "
                          f"{failing_windows(plan)} blocked over the whole cone of the "
                          "recipe's tilt box and of every milder one (they fail with it too)")


def on_uncut_edge(failures, notes: list) -> list:
    """``notes`` (relaxation records: what else was tried) with those of a window cut in part
    (its partial record among ``failures``, :mod:`drakedeburr.plan.partial`) marked as about
    its uncut edge (``where["uncut_edge"]``): the verifier's ``uncut_edge`` item names them
    with the edge they did not cut; the planned motion's own records stay in
    ``planner_failures``."""
    partial = {f.window for f in failures if "partial" in (f.where or {})}
    return [replace(n, where={**n.where, "uncut_edge": True}) if n.window in partial else n
            for n in notes]


def _first_records(plan) -> dict:
    """Window -> its first failure record in ``plan``."""
    out: dict = {}
    for f in plan.failures:
        out.setdefault(f.window, f)
    return out


def _standard_kept(plan, own: dict, left: list, how: str):
    """``plan`` with a relaxation record per failing window: the long-reach burr ``how``
    (``own``: window -> the record that gives its own reason there; ``left``: the windows
    it leaves failing, for the log)."""
    lr = long_reach()
    notes = []
    for w in failing_windows(plan):
        rec = own.get(w)
        notes.append(FailureRecord(
            window=w, kind="relaxation", tried=(lr.title,),
            reason=f"the {lr.title} {how}" + ("" if rec is None else f"; here: {rec.reason}")))
    log.info("the %s leaves window(s) %s failing: kept the standard burr", lr.title, left)
    return replace(plan, failures=(*plan.failures, *on_uncut_edge(plan.failures, notes)))


def choose_tool(plan, alt):
    """The standard burr's plan or the long-reach one's (``alt``), both
    :class:`~drakedeburr.plan.results.PlanDraft`: the long-reach plan only when it cuts the
    hub better (:func:`better_cut` of their :func:`cut_tally`: a tie keeps the standard burr,
    the stiffer). The kept plan records the choice: a recipe deviation when it is the
    long-reach burr, else a failure record per failing window saying what the long-reach burr
    left failing and cut."""
    a, b = failing_windows(plan), failing_windows(alt)
    ta, tb = cut_tally(plan), cut_tally(alt)
    std, lr = tool_variant(DEFAULT_TOOL), long_reach()
    if better_cut(tb, ta):
        first = plan.failures[0] if plan.failures else None
        dev = Deviation(-1, "burr", std.title, lr.title,
                        f"the standard burr left window(s) {a} failing ({len(plan.failures)} "
                        "records" + ("" if first is None else
                                     f"; first: window {first.window}, {first.reason}")
                        + f"); it cuts {ta.text()}, the {lr.title} {tb.text()}")
        log.warning("burr changed for the hub: %s -> %s: %d -> %d window(s) failing "
                    "(cut: %s -> %s)", std.title, lr.title, len(a), len(b), ta.text(),
                    tb.text())
        return alt.with_deviations(back=(dev,))
    return _standard_kept(plan, _first_records(alt), b,
                          f"was tried for the hub and left {len(b)} window(s) failing {b} "
                          f"(it cuts {tb.text()}; the standard burr {ta.text()})")
