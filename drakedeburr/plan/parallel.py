"""Windows planned at once on the machine's cores, each window the same plan whichever process
plans it and in whatever order.

A window's plan is a function of the cell, its targets, the options and its branch reference
(:func:`drakedeburr.plan.window.window_reference`), not of the windows planned before it, so the
windows are independent tasks. This process plans windows from the front of the list while
``workers - 1`` worker processes of the shared pool (:mod:`drakedeburr.pool`) take them from
the back. Each worker builds the same cell from the arguments it was loaded with
(``Cell.recipe``, recorded by :func:`drakedeburr.cell.load_cell`) once and keeps it, and the
workers stay up for later runs; the log records a worker emits while planning a window are
handed back and emitted here.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

from drakedeburr.cell.fingerprint import geometry_digest
from drakedeburr.pool import logged_call, map_tasks, replay_records, worker_cell, worker_count

__all__ = ["plan_all_windows", "map_windows", "planning_cell"]

log = logging.getLogger(__name__)

_WORKER: dict = {}  # in a worker: recipe key -> (cell, {tolerances: (kin, checkers)})


def _recipe(ctx) -> dict | None:
    args = ctx.cell.recipe
    return None if args is None else dict(args)


def planning_cell(recipe: dict, fingerprint: str | None = None) -> tuple:
    """In a worker: (the planner's cell of ``recipe``, its per-tolerances cache), kept for the
    worker's later planning tasks (:func:`worker_cell`)."""
    return worker_cell(recipe, fingerprint, _WORKER, lambda cell: {})


def _worker_context(recipe: dict, fingerprint: str, config, options, q_refs):
    """The worker's :class:`PlanContext` for a recipe (built once per cell and tolerances)."""
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.options import PlanContext

    tol = config.tolerances  # the checkers' certification depends on these two
    cell, per_tol = planning_cell(recipe, fingerprint)
    key = (tol.min_clearance, tol.narrowphase_resolve)
    if key not in per_tol:
        per_tol[key] = (cell_kinematics(cell), ClearanceChecker(cell, tolerances=tol),
                        ClearanceChecker(cell, filter_burr_contact=False, tolerances=tol))
    kin, checker, free = per_tol[key]
    return PlanContext(cell=cell, kin=kin, checker=checker, free_checker=free, config=config,
                       options=options, q_refs=dict(q_refs))


def _in_run_context(recipe: dict, fingerprint: str, config, options, q_refs, fn: Callable,
                    item, level: int):
    """Task of a worker: (``fn(ctx, item)`` in the worker's context of the run, the log
    records emitted while making it)."""
    ctx = _worker_context(recipe, fingerprint, config, options, q_refs)
    return logged_call(level, fn, (ctx, item))


def plan_all_windows(ctx, windows: Sequence, workers: int | None,
                     progress: Callable[[int, int, str], None] | None = None) -> list:
    """Every window planned (:func:`drakedeburr.plan.window.plan_window`), in their order.

    Args:
        ctx: the run's :class:`drakedeburr.plan.options.PlanContext`.
        windows: the windows' targets.
        workers: processes to use (see :func:`worker_count`); 1 plans them here, in order.
        progress: optional callback (done, total, label) as windows finish.

    Returns:
        One :class:`drakedeburr.plan.results.WindowPlan` per window, in the given order.
    """
    from drakedeburr.plan.window import plan_window

    return map_windows(ctx, plan_window, windows, workers, progress,
                       name=lambda wt: f"window {wt.window_index}")


def map_windows(ctx, fn: Callable, items: Sequence, workers: int | None,
                progress: Callable[[int, int, str], None] | None = None, *,
                name: Callable[[object], str]) -> list:
    """``fn(ctx, item)`` for every item, in their order, on the pool's workers (each in its own
    context of the run: the same cell, checked by its fingerprint) and here. ``fn`` is a
    module-level function, so a worker can import it; its log records are emitted here.
    ``name(item)`` labels the progress and the log."""
    n = len(items)
    recipe = _recipe(ctx)
    level = logging.getLogger().getEffectiveLevel()
    count = [0]

    def finished(k: int, res):
        count[0] += 1
        if progress is not None:
            progress(count[0], n, name(items[k]))
        return res

    serial = recipe is None or worker_count(workers, n) == 1

    def here(k: int):
        if not serial:
            return finished(k, fn(ctx, items[k]))
        if progress is not None:
            progress(k, n, name(items[k]))
        return fn(ctx, items[k])

    def remote(k: int) -> tuple:
        return _in_run_context, (recipe, geometry_digest(ctx.cell), ctx.config, ctx.options,
                                 ctx.q_refs, fn, items[k], level)

    def done(k: int, value):
        replay_records(value[1])
        return finished(k, value[0])

    return map_tasks(n, here, None if recipe is None else remote, workers, done,
                     name=lambda k: name(items[k]))
