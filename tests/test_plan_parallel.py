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
