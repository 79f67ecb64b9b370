"""Windows planned at once (drakedeburr.plan.parallel): the same plan, bit for bit, with one
process or two, and each window the same whether it is planned alone or after others."""

import json

import numpy as np
import pytest

from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif("h5_straight" not in hub_names(), reason="no bundled hub")


def test_worker_count():
    from drakedeburr.plan.parallel import worker_count

    assert worker_count(1, 5) == 1
    assert worker_count(8, 3) == 3
    assert worker_count(None, 1) == 1
    assert worker_count(None, 64) >= 1


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
    from drakedeburr.plan.parallel import worker_count

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

    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.parallel import cell_fingerprint, worker_cell
    from drakedeburr.resources import hub_dir

    hub = tmp_path / "hub"
    shutil.copytree(hub_dir("h5_straight"), hub)
    first = load_cell("tool_in_hand", hub)
    recipe, fp1 = dict(first._cache["load_args"]), cell_fingerprint(first)
    cache: dict = {}
    cell, built = worker_cell(recipe, fp1, cache, lambda c: "built")
    assert cell_fingerprint(cell) == fp1 and built == "built"
    assert worker_cell(recipe, fp1, cache, lambda c: "again")[0] is cell  # kept
    piece = hub / "collision" / "piece_000.obj"  # the hub regenerated: one piece smaller
    lines = [(" ".join(["v"] + [repr(0.7 * float(x)) for x in ln.split()[1:4]])
              if ln.startswith("v ") else ln) for ln in piece.read_text().splitlines()]
    piece.write_text("\n".join(lines) + "\n")
    fp2 = cell_fingerprint(load_cell("tool_in_hand", hub))
    assert fp2 != fp1
    cell2, _ = worker_cell(recipe, fp2, cache, lambda c: "built")
    assert cell2 is not cell and cell_fingerprint(cell2) == fp2
    with pytest.raises(RuntimeError, match="differs"):
        worker_cell(recipe, fp1, cache, lambda c: "built")


def test_map_tasks_runs_failed_tasks_here_and_does_not_wait_for_a_warm_up():
    """Every task's result in order; a worker busy with a warm-up when the tasks are done is not
    waited for (its reply is dropped by a later call); a task the worker fails runs here."""
    import time

    from drakedeburr.plan import parallel

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
