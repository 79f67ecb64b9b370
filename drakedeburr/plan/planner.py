"""The planner: window targets -> cone-constrained IK -> executed motion -> timed Plan.

Per window, in order (:mod:`drakedeburr.plan.window`):

1. tool-point targets from the CL points (:mod:`drakedeburr.plan.targets`);
2. Drake IK at every CL target (:mod:`drakedeburr.plan.ik`), from the best of a few start
   configurations: the freedom (axis inside the cone, spin about it) exists only there;
3. the executed cut (:mod:`drakedeburr.plan.cut`): a smooth path through the targets' tool
   points with corners blended, the smoothest axis inside the cones and the spin chosen by
   dynamic programming, tracked by the analytic IK on the window's configuration and checked
   for clearance and joint jumps; its program with via targets where the controller's slerp
   would stray from it (:mod:`drakedeburr.plan.program_fit`);
4. approach and retract along the tool axis, timing (:mod:`drakedeburr.plan.finish`);

then a joint move from the previous window (or home) to each window and back home
(:mod:`drakedeburr.plan.transitions`), all timed within the joint limits at the recipe's speeds
(:mod:`drakedeburr.plan.timing`: 150 mm/s along the window, 450 mm/s between windows, 600 mm/s
home).

Both cells are the same code: only :class:`CellKinematics` knows which of T and H rides on
the flange. Failures are :class:`drakedeburr.plan.types.FailureRecord` in ``Plan.failures``.

Which passes plan the hub (first pass, recipe relaxation, the long-reach burr, report-only
re-runs) is :mod:`drakedeburr.plan.policy`'s; this module gives it the cell's passes
(:func:`cell_passes`) and makes the Plan once from the kept
:class:`~drakedeburr.plan.results.PlanDraft`.
"""

from __future__ import annotations

import functools
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace

import numpy as np

from drakedeburr.cell.tools import DEFAULT_TOOL, tool_variant
from drakedeburr.config import Config, ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.plan import relax
from drakedeburr.plan.io import jsonable
from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
from drakedeburr.plan.options import PlanContext, PlanOptions, RunMode
from drakedeburr.plan.order import air_costs, best_order, move_seconds
from drakedeburr.plan.parallel import map_windows, plan_all_windows
from drakedeburr.plan.policy import (
    CellPasses,
    cell_pass,
    hub_pass,
    long_reach_allowed,
    relief_deviation,
)
from drakedeburr.plan.results import (
    PlanDraft,
    PlanMotion,
    PlanRecord,
    PlanStats,
    Stretch,
    WindowStatus,
)
from drakedeburr.plan.stretch import joint_stretch, make_target
from drakedeburr.plan.targets import contact_geometry
from drakedeburr.plan.tool_paths import CL_COUNT_BUDGET, CL_DELTA, tool_path
from drakedeburr.plan.types import FailureRecord, JointTrajectory, Plan, PlanSegment
from drakedeburr.plan.window_targets import WindowTargets
from drakedeburr.pool import map_calls, warm_pool, worker_count

__all__ = ["PlanOptions", "plan_windows", "plan_hub", "window_targets_for_hub", "CL_DELTA",
           "CL_COUNT_BUDGET", "plan_in_cell", "placed_cell", "PlacedCell", "refused_in_cell",
           "assemble_windows", "cell_passes"]

log = logging.getLogger(__name__)

Progress = Callable[[int, int, str], None] | None



def plan_windows(
    cell,
    windows: Sequence[WindowTargets],
    config: Config,
    *,
    options: PlanOptions | None = None,
    progress: Progress = None,
    q_refs: dict | None = None,
) -> Plan:
    """Plan the given windows of a loaded cell, from home and back.

    Args:
        cell: :class:`drakedeburr.cell.Cell` (tool- or workpiece-in-hand).
        windows: the windows' targets, in execution order.
        config: the run's configuration (recipe: speeds, TCP acceleration; tolerances:
            clearance, wrist margin, program orientation); its scenario and hub are recorded.
        options: planner settings.
        progress: optional callback (done, total, label) per window.
        q_refs: window -> (6,) a configuration on the branch to cut it on (the placement
            search's choice, :mod:`drakedeburr.plan.placement`); the window's IK starts are
            ranked from it first.

    Returns:
        Plan; ``failures`` lists every point/move that failed (empty when all planned).
    """
    t_start = time.perf_counter()
    ctx = _context(cell, config, options or PlanOptions(), q_refs)
    results = plan_all_windows(ctx, windows, ctx.options.workers, progress)
    return assemble_windows(ctx, windows, results, progress, t_start).plan()


def _context(cell, config: Config, options: PlanOptions, q_refs: dict | None) -> PlanContext:
    # moves that do not cut keep the burr head clear of the hub too
    tol = config.tolerances
    return PlanContext(cell=cell, kin=cell_kinematics(cell),
                       checker=ClearanceChecker(cell, tolerances=tol),
                       free_checker=ClearanceChecker(cell, filter_burr_contact=False,
                                                     tolerances=tol),
                       config=config, options=options, q_refs=dict(q_refs or {}))


def assemble_windows(ctx: PlanContext, windows: Sequence[WindowTargets], results: Sequence,
                     progress: Progress, t_start: float) -> PlanDraft:
    """The plan of independently planned windows (one result per window, in the given
    order): from home through every planned window and back, with its transitions; the
    planned windows cut in the order of least air time (:func:`chosen_order`); its record
    holds the cell's frames, the figures, the tool points moved out of the material
    (deviations), the order chosen and the timings since ``t_start``
    (``time.perf_counter()``)."""
    failures = []
    for wt, res in zip(windows, results, strict=True):
        failures += res.failures
        if res.status is WindowStatus.ABANDONED:  # abandoned for relaxation (policy)
            log.debug("window %d: an IK target failed under the recipe", wt.window_index)
        elif not res.status.planned:
            log.warning("window %d not planned (%s): %s", wt.window_index, res.status.value,
                        res.failures[-1].reason if res.failures else "")
        else:
            st = res.stats
            log.info("window %d: %s, cut %.2f s, %.0f %% at the feed, %d/%d CL points, %d via "
                     "targets%s", wt.window_index, res.status.value, st.cut_seconds,
                     100 * st.speed_in_band_fraction, st.reached, st.cl_points + 1,
                     st.via_targets,
                     f", {len(res.failures)} failure records" if res.failures else "")
    planned = [k for k, res in enumerate(results) if res.status.planned]
    t0 = time.perf_counter()
    given = _chain(ctx, [(windows[k], results[k]) for k in planned])
    chain, order_record = given, None
    if len(planned) > 1:
        order = chosen_order(ctx, [results[k] for k in planned])
        if order != list(range(len(planned))):
            other = _chain(ctx, [(windows[planned[i]], results[planned[i]]) for i in order])
            kept = (len(other.failures), other.air_seconds) < (len(given.failures),
                                                               given.air_seconds - 1e-3)
            chain = other if kept else given
            order_record = {"given": [windows[k].window_index for k in planned],
                            "chosen": [windows[planned[i]].window_index for i in order],
                            "given_air_s": given.air_seconds, "chosen_air_s": other.air_seconds,
                            "kept": "chosen" if kept else "given"}
            log.info("window order %s: moves off the cut %.3f s (given order %s: %.3f s)%s",
                     order_record["chosen"], other.air_seconds, order_record["given"],
                     given.air_seconds, "" if kept else "; the given order kept")
    t_transitions = time.perf_counter() - t0
    if progress is not None:
        progress(len(windows), len(windows), "done")
    stats = PlanStats(total_seconds=time.perf_counter() - t_start,
                      transition_seconds=t_transitions)
    ordered = list(chain.windows) + [wt for k, wt in enumerate(windows) if k not in planned]
    home = make_target(ctx.kin, ctx.kin.q_home, -1, "home", -1, ctx.config.process.home_speed,
                       "joint")
    draft = _assemble(ctx, chain.stretches, home, chain.window_stats,
                      failures + chain.failures, ordered, order_record)
    return draft.with_record(timings=stats, window_seconds=chain.window_seconds)


@dataclass(frozen=True)
class _Chain:
    """Planned windows joined from home and back: the stretches, the windows (in cutting
    order) with their figures and planning times, the moves' failure records and the moves'
    time [s] (home, transitions, approaches and retracts)."""

    stretches: list
    windows: tuple
    window_stats: list
    window_seconds: tuple
    failures: list
    air_seconds: float


def _chain(ctx: PlanContext, pairs: Sequence[tuple]) -> _Chain:
    """The planned windows ``pairs`` ((targets, WindowPlan), in cutting order) joined by
    joint moves from home, between them and back home (:func:`joint_stretch`)."""
    kin, process = ctx.kin, ctx.config.process
    q_cur = kin.q_home.copy()
    stretches, window_stats, window_seconds, failures = [], [], [], []
    for wt, res in pairs:
        speed = process.home_speed if not stretches else process.window_switch_speed
        kind = "home" if not stretches else "transition"
        js, mv, recs = joint_stretch(ctx, q_cur, res.q_start, speed, kind,
                                     f"to window {wt.window_index}")
        failures += recs
        stretches += [js, *res.stretches]
        window_stats.append({**res.stats.to_dict(), "transition_method": mv.method})
        window_seconds.append(res.seconds)
        q_cur = res.stretches[-1].timed.q[-1]
    js, mv, recs = joint_stretch(ctx, q_cur, kin.q_home, process.home_speed, "home",
                                 "return home")
    failures += recs
    stretches.append(js)
    air = sum(float(st.timed.t[-1]) for st in stretches if st.kind != "cut")
    return _Chain(stretches=stretches, windows=tuple(wt for wt, _ in pairs),
                  window_stats=window_stats, window_seconds=tuple(window_seconds),
                  failures=failures, air_seconds=air)


def chosen_order(ctx: PlanContext, results: Sequence) -> list[int]:
    """The order (positions into ``results``, planned windows) of least estimated air time
    (:func:`drakedeburr.plan.order.best_order`; each move by
    :func:`drakedeburr.plan.order.move_seconds`: rest to rest at the joint limits the planner
    times air moves with, and the straight tool-point distance at the move's programmed
    speed)."""
    process = ctx.config.process
    speed = {"home": process.home_speed, "transition": process.window_switch_speed}
    lim = ctx.limits(1.0)
    v_max = np.asarray(lim.v_max) * lim.velocity_fraction
    a_max = np.asarray(lim.a_max) * lim.acceleration_fraction

    def seconds(q0, q1, kind: str) -> float:
        p = ctx.kin.p_HT(np.stack([q0, q1]))
        return move_seconds(np.asarray(q1, float) - np.asarray(q0, float), v_max, a_max,
                            float(np.linalg.norm(p[1] - p[0])), speed[kind])

    costs = air_costs(ctx.kin.q_home, [r.q_start for r in results],
                      [r.stretches[-1].timed.q[-1] for r in results], seconds)
    return best_order(costs)


_REST_SECONDS = 0.1  # [s] a plan that moves nowhere holds home this long (a trajectory has pieces)


def _concatenate(kin, stretches: list[Stretch], home):
    """The stretches end to end: (targets, segments, joint trajectory)."""
    t_all, c_all = [np.zeros(1)], [np.zeros((7, 0, 6))]
    targets, segments = [home], []
    t_off = 0.0
    for st in stretches:
        tp = st.timed
        first = len(targets)
        targets.extend(st.targets)
        keep = np.diff(tp.t) > 1e-9  # zero-length pieces
        if keep.any():
            t_all.append(t_off + tp.t[1:][keep])
            c_all.append(tp.c[:, keep])
        t_end = t_off + float(tp.t[-1])
        segments.append(PlanSegment(window_index=st.window_index, kind=st.kind,
                                    target_range=(first, len(targets)), t_range=(t_off, t_end)))
        t_off = t_end
    if len(t_all) == 1:  # nothing moves (no window planned): the robot rests at home
        rest = np.zeros((7, 1, 6))
        rest[-1, 0] = np.asarray(home.q, float)
        t_all.append(np.array([_REST_SECONDS]))
        c_all.append(rest)
        if segments:
            segments[-1] = replace(segments[-1], t_range=(0.0, _REST_SECONDS))
    return targets, segments, JointTrajectory(t=np.concatenate(t_all),
                                              c=np.concatenate(c_all, axis=1))


def _options_record(options: PlanOptions) -> dict:
    """The plan's record of its options: all but ``workers`` (no effect on the plan) and
    ``partial_windows`` when on (the default; each partial window says so in its own figures,
    ``WindowStats.partial``, so plans without one keep the record they had before the
    option)."""
    out = {k: v for k, v in asdict(options).items() if k != "workers"}
    if out.get("partial_windows"):
        del out["partial_windows"]
    return out


def _assemble(ctx: PlanContext, stretches, home, window_stats, failures, windows,
              order_record: dict | None = None) -> PlanDraft:
    kin, cell, config = ctx.kin, ctx.cell, ctx.config
    targets, segments, traj = _concatenate(kin, stretches, home)
    v_g = config.process.grinding_speed
    edge_total = sum(s["tool_travel_m"] for s in window_stats)
    cut_time = sum(s["cut_seconds"] for s in window_stats)
    seg_time: dict[str, float] = {}
    for sgm in segments:
        seg_time[sgm.kind] = seg_time.get(sgm.kind, 0.0) + sgm.t_range[1] - sgm.t_range[0]
    r_c, lift = contact_geometry(ctx.options.contact_radius)
    figures = dict(
        windows=window_stats,
        window_sources=[w.source for w in windows],
        depth_of_cut={str(w.window_index): w.depth_of_cut for w in windows},
        cycle_seconds=traj.duration,
        segment_seconds=seg_time,
        cutting_seconds=cut_time,
        physical_cut_seconds=edge_total / v_g,
        cut_time_ratio=cut_time / (edge_total / v_g) if edge_total else None,
    )
    if order_record is not None:  # the windows cut in another order than given
        figures["window_order"] = order_record
    other_tool = cell.tool not in (None, DEFAULT_TOOL)
    record = PlanRecord(
        config=config.to_record(),
        options=jsonable(_options_record(ctx.options)),
        robot=cell.arm.ref, tool=cell.tool if other_tool else None,
        tool_title=tool_variant(cell.tool).title if other_tool else None,
        X_FT=kin.X_FT.copy(), X_FH=kin.X_FH.copy(), X_WT=kin.X_WT.copy(), X_WB=kin.X_WB.copy(),
        contact_radius_m=r_c, contact_lift_m=lift, figures=figures,
        deviations=tuple(relief_deviation(s) for s in window_stats if s.get("chamfer_relief")))
    tool_paths = tuple(w.tool_path for w in windows) if any(w.tool_path is not None
                                                           for w in windows) else None
    motion = PlanMotion(scenario=str(config.scenario), hub=str(config.hub), mode=cell.mode,
                        X_WH=kin.X_WH.copy(), targets=tuple(targets), segments=tuple(segments),
                        trajectory=traj, tool_path=tool_paths)
    return PlanDraft(failures=tuple(failures), record=record, motion=motion)


def cell_passes(ctx: PlanContext, progress: Progress, t_start: float,
                cl_paths: dict | None = None) -> CellPasses:
    """How the hub-level policy (:mod:`drakedeburr.plan.policy`) plans and assembles windows
    in ``ctx``'s cell: each window by :func:`drakedeburr.plan.window.plan_window` in the
    policy's run mode, on the pool's workers (:func:`drakedeburr.plan.parallel.map_windows`),
    the milder recipes' ladders by :func:`drakedeburr.plan.relax.plan_ladder`, the plans by
    :func:`assemble_windows` (timed from ``t_start``). ``cl_paths``: window -> the ClPath of
    its first pass's targets (:func:`drakedeburr.plan.relax.first_cl_paths`), which the
    milder recipes orient again instead of planning the CL points anew."""
    from drakedeburr.plan.window import plan_window

    params, workers = ctx.config.process, ctx.options.workers

    def plan(wts, mode: RunMode, shown: Progress) -> list:
        return map_windows(ctx, functools.partial(plan_window, mode=mode), wts, workers,
                           shown, name=lambda wt: f"window {wt.window_index}")

    def ladders(edges, mode: RunMode) -> list:
        return map_windows(ctx, functools.partial(relax.plan_ladder, mode=mode),
                           [(e, params, (cl_paths or {}).get(e.index)) for e in edges],
                           workers,
                           name=lambda item: f"window {item[0].index}'s milder recipes")

    return CellPasses(plan=plan, ladders=ladders,
                      assemble=lambda wts, results: assemble_windows(ctx, wts, results,
                                                                     progress, t_start),
                      params=params, progress=progress)


def window_targets_for_hub(hub_model, *, source: str = "auto",
                           params: ProcessParameters | None = None,
                           windows: Sequence[int] | None = None,
                           progress: Progress = None,
                           skipped: list | None = None) -> list[WindowTargets]:
    """Targets of a hub's windows: hub edges -> CL points -> orientation (-> WindowTargets).

    Args:
        hub_model: ``drakedeburr.hub.HubModel``.
        source: "toolpath" (path + orientation stages), "edges" (ground-truth edges with a fixed
            tilt, no upstream stages), or "auto" (the toolpath chain; the edges stand-in only
            when the upstream stages cannot be imported, with a logged warning - a ToolPath
            that is wrong raises, as with "toolpath").
        params: process parameters (default: the hub's, ``hub_model.process``).
        windows: window indices (default all).
        skipped: when given, a window whose ToolPath cannot give targets (an axis pointing
            into the hub on this part) is left out and its FailureRecord appended here
            instead of raising: a result of planning this hub, not bad input.
    """
    params = params or hub_model.process
    chosen = [w for w in hub_model.windows if windows is None or w.index in set(windows)]
    if progress is not None:
        progress(0, len(chosen), "targets")
    # the windows at once on the pool's running workers (each the same targets wherever
    # they are made)
    made = map_calls(len(chosen), lambda k: (_window_targets, (chosen[k], source, params)),
                     name=lambda k: f"targets of window {chosen[k].index}")
    out = []
    for edge, (wt, why) in zip(chosen, made, strict=True):
        if wt is None:
            if skipped is None:
                raise InputError(why)
            log.warning("window %d not planned: %s", edge.index, why)
            skipped.append(FailureRecord(window=edge.index, kind="window",
                                         reason=f"no tool path: {why}",
                                         tried=("orientation stage (recipe's theta box)",)))
            continue
        out.append(wt)
    if progress is not None:
        progress(len(chosen), len(chosen), "targets")
    return out


def _window_targets(edge, source: str, params: ProcessParameters):
    """One window's targets (:func:`window_targets_for_hub`) -> (WindowTargets, None), or
    (None, why) when its ToolPath cannot give targets."""
    if source in ("toolpath", "auto"):
        try:
            return WindowTargets.from_tool_path(tool_path(edge, params)), None
        except InputError as exc:
            return None, str(exc)
        except ImportError as exc:
            if source == "toolpath":
                raise
            log.warning("window %d: path/orientation stage unavailable (%s); using the "
                        "ground-truth edge with a fixed tilt instead", edge.index, exc)
    return WindowTargets.from_window_edge(edge, params=params), None


def plan_hub(
    config: Config,
    *,
    options: PlanOptions | None = None,
    source: str = "auto",
    progress: Progress = None,
) -> Plan:
    """Plan a whole hub end to end: hub -> CL -> orientation -> IK -> timed Plan.

    The hub is planned with ``config.tool`` on the cell's spindle; when that is not given and
    the standard burr leaves windows failing where the spindle body, clamp or collet meets
    something (a deep dish), the hub is planned again with the long-reach burr and that
    plan kept when it cuts the hub better (:func:`drakedeburr.plan.relax.choose_tool`:
    one burr for the whole hub, no tool change within a program); the failing windows are
    planned with it first, and the rest only when it cuts one of them
    (:func:`drakedeburr.plan.policy.hub_pass`, :func:`~drakedeburr.plan.policy.long_reach_pass`),
    and not at all when its tool pre-check refuses every failing window in every tilt box
    (:func:`refused_in_cell`, in the long-reach cell placed for the hub, the same placement
    its plan would be made in: each cell is placed once, :func:`placed_cell`).

    Args:
        config: the run's configuration (:func:`drakedeburr.config.load_config`): scenario,
            hub, recipe and tolerances.
        options: planner settings (``options.windows`` limits the windows).
        source: where the tool axes come from (see :func:`window_targets_for_hub`).
        progress: callback (done, total, label).

    Returns:
        The Plan (check ``plan.failures``).
    """
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import load_hub

    options = options or PlanOptions()
    if worker_count(options.workers, 2) > 1:  # the pool imports while this process loads
        warm_pool(_import_planning, (), options.workers)  # (the targets, placement use it)
    cell = load_cell(config.scenario, config.hub, robot=config.robot, tool=config.tool)
    hub_model = load_hub(cell.hub_sdf.parent)
    t0 = time.perf_counter()
    skipped: list[FailureRecord] = []
    wts = window_targets_for_hub(hub_model, source=source, params=config.process,
                                 windows=options.windows, skipped=skipped)
    t_targets = time.perf_counter() - t0
    cells = {None: cell}
    placed: dict = {}  # burr -> its cell placed for the hub (deterministic: made once)

    def placed_in(tool: str | None) -> PlacedCell:
        if tool not in placed:
            base = cells.get(tool) or load_cell(config.scenario, config.hub, robot=config.robot,
                                                tool=tool)
            placed[tool] = placed_cell(base, hub_model, wts, config, options)
        return placed[tool]

    def plan_in(tool: str | None, only: set[int] | None) -> PlanDraft:
        return plan_in_cell(placed_in(tool), hub_model, wts, progress, only=only)

    def refused_in(tool: str, windows: list[int]) -> dict:
        return refused_in_cell(placed_in(tool).ctx, hub_model, wts, windows)

    draft = hub_pass(plan_in, [wt.window_index for wt in wts], cell,
                     long_reach=long_reach_allowed(options, config), t_start=t0,
                     refused_in=refused_in)
    if skipped:  # windows without a tool path are failures of this plan, reported as such
        draft = replace(draft, failures=(*skipped, *draft.failures))
    return draft.with_timings(targets_seconds=t_targets).plan()


def _import_planning() -> None:
    """A worker's warm-up at the start of :func:`plan_hub`: the modules of the tasks it gets
    (window targets, placement candidates, windows)."""
    import drakedeburr.cell.station
    import drakedeburr.orientation.orient
    import drakedeburr.path.cl_planning
    import drakedeburr.plan.window  # noqa: F401


def refused_in_cell(ctx: PlanContext, hub_model, wts, windows: Sequence[int]) -> dict:
    """{window: refusal} of those among ``windows`` (indices of ``wts``) whose targets the tool
    pre-check refuses in ``ctx`` (a :class:`PlacedCell`'s: the context the windows would be
    planned in) in the recipe's tilt box and in every milder one
    (:func:`drakedeburr.plan.relax.refused_in_every_box`, the windows at once on the pool's
    workers). Empty when the pre-check is off."""
    if not ctx.options.tool_precheck:
        return {}
    chosen = [wt for wt in wts if wt.window_index in set(windows)]
    edges = {e.index: e for e in hub_model.windows}
    cls = relax.first_cl_paths(chosen)
    items = [(edges[wt.window_index], ctx.config.process, cls.get(wt.window_index), wt)
             for wt in chosen if wt.window_index in edges]
    found = map_windows(ctx, relax.refused_in_every_box, items, ctx.options.workers,
                        name=lambda it: f"window {it[0].index}'s pre-check in every box")
    return {it[0].index: rec for it, rec in zip(items, found, strict=True) if rec is not None}


@dataclass(frozen=True)
class PlacedCell:
    """A cell placed for a hub (:func:`placed_cell`): the planning context of its windows
    (the placed cell, its home cleared of the hub), the placement (None: not searched) and its
    search time [s], the home's move (a Deviation) and the home it moved to, or None."""

    ctx: PlanContext
    placement: object = None
    placement_seconds: float = 0.0
    home_moved: object = None
    q_home: np.ndarray | None = None


def placed_cell(cell, hub_model, wts, config: Config, options: PlanOptions) -> PlacedCell:
    """Where the hub sits in ``cell`` (placement search for the windows ``wts``) and the home
    it is planned from (:mod:`drakedeburr.plan.home`): the windows' planning context."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.home import clear_home
    from drakedeburr.plan.placement import place_hub

    placement, t_place = None, 0.0
    if options.placement and wts:
        t1 = time.perf_counter()
        placement = place_hub(cell, hub_model, wts, config, options)
        cell = placement.cell if placement.cell is not None else load_cell(
            config.scenario, config.hub, robot=config.robot, tool=cell.tool,
            hub_pose=placement.hub_pose)
        t_place = time.perf_counter() - t1
    q_refs = placement.q_refs if placement else None
    ctx = _context(cell, config, options, q_refs)
    q_home, home_moved = clear_home(cell, ctx.free_checker)
    if home_moved is not None:  # the hub leaves the cell's home without clearance
        cell = load_cell(**{**cell.recipe, "q_home": q_home})
        ctx = _context(cell, config, options, q_refs)
    return PlacedCell(ctx, placement, t_place, home_moved,
                      None if home_moved is None else q_home)


def plan_in_cell(placed: PlacedCell, hub_model, wts, progress: Progress,
                 only: set[int] | None = None) -> PlanDraft:
    """The hub's plan in one cell placed for it (:func:`placed_cell`): the windows and the
    recipe's relaxation where it fails (:func:`drakedeburr.plan.policy.cell_pass`).
    ``only``: the windows planned (the placement is still the whole hub's). Returns the
    PlanDraft (``.plan()`` makes the Plan) with the home, hub pose and placement recorded."""
    ctx, placement, home_moved = placed.ctx, placed.placement, placed.home_moved
    t_windows = time.perf_counter()
    if only is not None:
        wts = [wt for wt in wts if wt.window_index in only]
    draft = cell_pass(cell_passes(ctx, progress, t_windows, relax.first_cl_paths(wts)),
                      {e.index: e for e in hub_model.windows}, wts, ctx.options.relax)
    if home_moved is not None:
        draft = draft.with_deviations(front=(home_moved,)).with_record(
            q_home=placed.q_home.copy())
    if placement is not None:
        draft = draft.with_record(hub_pose=placement.hub_pose.copy(),
                                  placement=placement.record()).with_timings(
            placement_seconds=placed.placement_seconds)
    return draft
