"""Windows planned at once (drakedeburr.plan.parallel): the same plan, bit for bit, with one
process or two, and each window the same whether it is planned alone or after others."""

import json

import numpy as np
import pytest
from pool_support import wait_until

from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif("h5_straight" not in hub_names(), reason="no bundled hub")


def test_worker_count(monkeypatch):
    import os

    from drakedeburr.errors import InputError
    from drakedeburr.pool import worker_count

    monkeypatch.delenv("DRAKEDEBURR_WORKERS", raising=False)
    assert worker_count(1, 5) == 1
    assert worker_count(8, 3) == 3
    assert worker_count(None, 1) == 1
    if hasattr(os, "sched_getaffinity"):  # unrequested: the cores this process may use
        monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 2, 5})
        assert worker_count(None, 64) == 3
        assert worker_count(None, 2) == 2  # at most one per window
    monkeypatch.setenv("DRAKEDEBURR_WORKERS", "4")  # the variable wins over the cores
    assert worker_count(None, 64) == 4
    assert worker_count(None, 3) == 3
    assert worker_count(2, 64) == 2  # an explicit request wins over the variable
    for bad in ("0", "two"):
        monkeypatch.setenv("DRAKEDEBURR_WORKERS", bad)
        with pytest.raises(InputError, match="DRAKEDEBURR_WORKERS"):
            worker_count(None, 5)


@pytest.mark.slow
def test_same_plan_with_one_or_two_processes_and_in_any_company():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import load_config
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.io import plan_digest
    from drakedeburr.plan.planner import PlanOptions, plan_windows, window_targets_for_hub

    config = load_config("tool_in_hand", "h5_straight")
    cell = load_cell(config.scenario, config.hub)
    wts = window_targets_for_hub(load_hub("h5_straight"), windows=[1, 3])
    options = PlanOptions(placement=False)
    one, two = (plan_windows(cell, wts, config, options=PlanOptions(placement=False, workers=n))
                for n in (1, 2))
    assert plan_digest(one) == plan_digest(two)
    assert not one.failures
    alone = plan_windows(cell, wts[1:], config, options=options)  # window 3 without window 1

    def window(plan, w):
        stats = next(s for s in plan.meta["windows"] if s["window"] == w)
        stats = {k: v for k, v in stats.items() if k != "transition_method"}
        qs = [t.q for t in plan.targets if t.window_index == w]
        return json.dumps(stats, sort_keys=True), np.array(qs)

    (s1, q1), (s2, q2) = window(one, 3), window(alone, 3)
    assert s1 == s2 and np.array_equal(q1, q2)


def test_worker_count_reads_the_environment(monkeypatch):
    """$DRAKEDEBURR_WORKERS sets the default pool (a batch or a test suite that already fills
    the cores); an explicit request wins; at most one process per window; nonsense refused."""
    from drakedeburr.errors import InputError
    from drakedeburr.pool import worker_count

    monkeypatch.setenv("DRAKEDEBURR_WORKERS", "3")
    assert worker_count(None, 5) == 3 and worker_count(None, 2) == 2
    assert worker_count(1, 5) == 1
    monkeypatch.setenv("DRAKEDEBURR_WORKERS", "0")
    with pytest.raises(InputError, match="DRAKEDEBURR_WORKERS='0'"):
        worker_count(None, 5)
    monkeypatch.delenv("DRAKEDEBURR_WORKERS")
    assert worker_count(None, 64) >= 1


def test_a_worker_never_takes_a_rewritten_model_for_the_callers(tmp_path):
    """A worker keeps the cell it built for later tasks. When the hub is regenerated at the same
    path, the caller's cell fingerprint changes, so the worker builds the cell again. A worker
    whose fresh build still differs from the caller's cell refuses the task."""
    import shutil

    from drakedeburr.cell.fingerprint import geometry_digest
    from drakedeburr.cell.station import load_cell
    from drakedeburr.pool import worker_cell
    from drakedeburr.resources import hub_dir

    hub = tmp_path / "hub"
    shutil.copytree(hub_dir("h5_straight"), hub)
    first = load_cell("tool_in_hand", hub)
    recipe, fp1 = dict(first.recipe), geometry_digest(first)
    cache: dict = {}
    cell, built = worker_cell(recipe, fp1, cache, lambda c: "built")
    assert geometry_digest(cell) == fp1 and built == "built"
    assert worker_cell(recipe, fp1, cache, lambda c: "again")[0] is cell  # kept
    piece = hub / "collision" / "piece_000.obj"  # the hub regenerated: one piece smaller
    lines = [(" ".join(["v"] + [repr(0.7 * float(x)) for x in ln.split()[1:4]])
              if ln.startswith("v ") else ln) for ln in piece.read_text().splitlines()]
    piece.write_text("\n".join(lines) + "\n")
    fp2 = geometry_digest(load_cell("tool_in_hand", hub))
    assert fp2 != fp1
    cell2, _ = worker_cell(recipe, fp2, cache, lambda c: "built")
    assert cell2 is not cell and geometry_digest(cell2) == fp2
    with pytest.raises(RuntimeError, match="differs"):
        worker_cell(recipe, fp1, cache, lambda c: "built")


def test_map_tasks_runs_failed_tasks_here_and_does_not_wait_for_a_warm_up():
    """Every task's result in order; a worker busy with a warm-up when the tasks are done is not
    waited for (its reply is dropped by a later call); a task the worker fails runs here."""
    import time

    from drakedeburr import pool as parallel

    parallel.shutdown_pool(kill=True)
    try:
        parallel.warm_pool(time.sleep, (60.0,), workers=2)
        pool = parallel._pool(1)
        assert pool[0].task == parallel._WARM
        out = parallel.map_tasks(4, lambda k: k * k, lambda k: (divmod, (k, 0)), 2)
        assert out == [0, 1, 4, 9]
        assert pool[0].task == parallel._WARM  # still sleeping: not waited for
        parallel.shutdown_pool(kill=True)
        # a worker that raises (divmod by zero): the task runs here, same result
        out = parallel.map_tasks(3, lambda k: -k, lambda k: (divmod, (k, 0)), 2)
        assert out == [0, -1, -2]
    finally:
        parallel.shutdown_pool(kill=True)


def test_a_worker_gets_its_next_task_while_this_process_is_busy(tmp_path):
    """map_tasks feeds the workers from a thread: a worker that finishes a task gets the next
    one at once, not when this process ends its own. Here this process's first task waits for
    the worker to have done every other task (each touches a file); fed only between this
    process's tasks, the worker would do one and the wait would time out."""
    from pathlib import Path

    from drakedeburr import pool as parallel

    parallel.shutdown_pool(kill=True)
    files = [tmp_path / f"task{k}" for k in range(5)]
    ran_here = []

    def here(k):
        ran_here.append(k)
        if k == 0:
            wait_until(lambda: all(f.exists() for f in files[1:]),
                       "the worker was not fed while this task ran")
        return f"here {k}"

    try:
        out = parallel.map_tasks(5, here, lambda k: (Path.touch, (files[k],)), 2)
    finally:
        parallel.shutdown_pool(kill=True)
    assert ran_here == [0]
    assert out == ["here 0", None, None, None, None]
    assert all(f.exists() for f in files[1:]) and not files[0].exists()


def test_a_task_only_this_process_runs(tmp_path):
    """remote(k) None: task k is never sent; the worker still gets the tasks before it (the
    last sendable one first), and every result comes back in order. This process's first
    task waits for the worker to have done tasks 1 and 2."""
    from pathlib import Path

    from drakedeburr import pool as parallel

    files = [tmp_path / f"task{k}" for k in range(4)]
    ran_here = []

    def here(k):
        ran_here.append(k)
        if k == 0:
            wait_until(lambda: files[1].exists() and files[2].exists(),
                       "the tasks before the last were not sent")
        return ("here", k)

    parallel.shutdown_pool(kill=True)
    try:
        out = parallel.map_tasks(4, here, lambda k: None if k == 3 else (Path.touch, (
            files[k],)), 2)
    finally:
        parallel.shutdown_pool(kill=True)
    assert ran_here == [0, 3]
    assert out == [("here", 0), None, None, ("here", 3)]
    assert not files[3].exists()


def test_a_plans_cell_recipe_is_the_one_its_cell_records():
    """verify starts its workers building the plan's cell from plan_cell_args before this
    process builds it: the recipe must be the one the built cell records (the workers' cache
    key), and a cell built by the warm-up (no fingerprint yet) is kept for the checked task."""
    from types import SimpleNamespace

    from drakedeburr.cell.fingerprint import geometry_digest
    from drakedeburr.cell.recipe import plan_cell_args
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.pool import worker_cell

    X = np.eye(4)
    X[:3, 3] = [0.001, -0.002, 0.0]  # as a placement search leaves it, in plan.json (lists)
    plan = SimpleNamespace(scenario="tool_in_hand", hub="h5_straight", meta={
        "hub_pose": X.tolist(), "q_home": [0.1, 0.2, 0.3, 0, 0.5, 0.0]})
    cell = load_plan_cell(plan)
    recipe = plan_cell_args(plan)

    def key(r):
        return repr(sorted((k, repr(v)) for k, v in r.items()))

    assert key(recipe) == key(cell.recipe)
    cache: dict = {}
    warm, _ = worker_cell(recipe, None, cache, lambda c: "built")  # the warm-up
    assert worker_cell(recipe, geometry_digest(cell), cache, lambda c: "again")[0] is warm
    assert geometry_digest(warm) == geometry_digest(cell)


def test_a_task_that_cannot_be_sent_runs_here(caplog):
    """A task whose arguments cannot be pickled (pickled in the calling thread, before any is
    sent) is run here with a warning; the worker stays up."""
    import logging

    from drakedeburr import pool as parallel

    parallel.shutdown_pool(kill=True)
    try:
        with caplog.at_level(logging.WARNING, logger="drakedeburr.pool"):
            out = parallel.map_tasks(3, lambda k: ("here", k),
                                     lambda k: (divmod, (lambda: 0, 1)), 2)
        assert parallel.running_workers() == 1
    finally:
        parallel.shutdown_pool(kill=True)
    assert out == [("here", 0), ("here", 1), ("here", 2)]
    assert caplog.text.count("cannot be sent to a worker") == 3


#: run by a worker (builtins.exec, ``mark`` a path in its globals): marks that it runs, writes
#: half a pickled reply on the caller's stream (drakedeburr.pool_worker.STATE, the worker
#: module running as __main__), then dies
HALF_A_REPLY = """
import os, pickle, sys
open(mark, "w").close()
out = sys.modules["__main__"].STATE["out"]
data = pickle.dumps(("ok", list(range(100000))))
out.write(data[:len(data) // 2])
out.flush()
os._exit(17)
"""


def test_a_reply_cut_short_is_an_error_and_never_reaches_a_later_call(caplog, tmp_path):
    """A worker killed while writing its reply (a truncated pickle, not an EOF): the task runs
    here with a warning, that worker is stopped and holds no task of the first call; the
    second call gets only its own results. This process's task waits for the worker's to
    have started."""
    import logging

    from drakedeburr import pool as parallel

    mark = tmp_path / "started"

    def here(k):
        if k == 0:
            wait_until(mark.exists, "the worker never started its task")
        return ("here", k)

    parallel.shutdown_pool(kill=True)
    try:
        with caplog.at_level(logging.WARNING, logger="drakedeburr.pool"):
            out = parallel.map_tasks(2, here, lambda k: (exec, (HALF_A_REPLY, {
                "mark": str(mark)})) if k == 1 else None, 2)
        assert "could not be read" in caplog.text
        assert out == [("here", 0), ("here", 1)]
        assert all(w.task is None for w in parallel._POOL.get("workers", []))
        out = parallel.map_tasks(3, lambda k: ("again", k), lambda k: (abs, (-k,)), 3)
        assert all(v in (("again", k), k) for k, v in enumerate(out)), out  # no stale reply
    finally:
        parallel.shutdown_pool(kill=True)
