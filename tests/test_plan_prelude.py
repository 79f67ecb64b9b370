"""The planner's prelude on the pool (issue 19 item 1): the windows' targets and the placement
search's candidate clearances are read on the workers already running as well as here, with
the same result bit for bit; a candidate that cannot win is not built."""

import logging
from pathlib import Path

import numpy as np
import pytest
from pool_support import wait_until

from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif("h5_split" not in hub_names(), reason="no bundled hub")

_FIELDS = ("p_HC", "n_H", "t_H", "retract_H", "cone_retract_H")


def _same_targets(a, b) -> bool:
    return len(a) == len(b) and all(
        x.window_index == y.window_index and all(
            np.array_equal(getattr(x, f), getattr(y, f), equal_nan=True) for f in _FIELDS)
        for x, y in zip(a, b, strict=True))


def _same_placement(a, b) -> bool:
    return (np.array_equal(a.hub_pose, b.hub_pose) and a.clearance == b.clearance
            and a.candidates == b.candidates and a.q_refs.keys() == b.q_refs.keys()
            and all(np.array_equal(a.q_refs[w], b.q_refs[w]) for w in a.q_refs))


def _by_worker(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.getMessage().endswith("done by a worker")]


def test_targets_and_placement_on_a_worker_are_the_ones_made_here(caplog, monkeypatch, tmp_path):
    from drakedeburr import pool as parallel
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import load_config
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.placement import place_hub
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub

    config = load_config("tool_in_hand", "h5_split")
    cell = load_cell(config.scenario, config.hub)
    hub = load_hub(cell.hub_sdf.parent)
    wts = window_targets_for_hub(hub, params=config.process)  # this process alone
    alone = place_hub(cell, hub, wts, config, PlanOptions(workers=1))
    parallel.shutdown_pool(kill=True)
    caplog.set_level(logging.DEBUG, logger="drakedeburr.pool")
    try:
        # a worker running and idle (map_calls uses only those): this process's task waits
        # until the worker has done the other
        mark = tmp_path / "worker"

        def here(k):
            if k == 0:
                wait_until(mark.exists, "no worker took the task")

        parallel.map_tasks(2, here, lambda k: (Path.touch, (mark,)), 2)
        caplog.clear()
        both = place_hub(cell, hub, wts, config, PlanOptions(workers=2))
        assert _by_worker(caplog) == ["placement candidate 1: done by a worker"]
        assert _same_placement(alone, both)
        # the winner's cell is this process's, with the chosen pose
        assert np.array_equal(both.cell.recipe["hub_pose"], both.hub_pose)
        caplog.clear()
        monkeypatch.setenv("DRAKEDEBURR_WORKERS", "2")
        shared = window_targets_for_hub(hub, params=config.process)
        assert _by_worker(caplog)  # the worker made some of them
        assert _same_targets(wts, shared)
    finally:
        parallel.shutdown_pool(kill=True)


def test_a_candidate_that_cannot_win_is_not_built(monkeypatch):
    """With the first candidate's clearance share at 1.0 the second (fewer windows, or as many
    with a smaller margin) cannot be chosen: one cell is built, and the placement is the one
    the full comparison of both gives."""
    from drakedeburr.cell import station
    from drakedeburr.config import load_config
    from drakedeburr.hub import load_hub
    from drakedeburr.plan import placement
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub

    config = load_config("tool_in_hand", "h5_split")
    cell = station.load_cell(config.scenario, config.hub)
    hub = load_hub(cell.hub_sdf.parent)
    wts = window_targets_for_hub(hub, params=config.process)
    built, shares = [], []
    real_load, real_share = station.load_cell, placement._clear_share

    def counting_load(*a, **k):
        built.append(k.get("hub_pose"))
        return real_load(*a, **k)

    def recording_share(*a, **k):
        shares.append(real_share(*a, **k))
        return shares[-1]

    monkeypatch.setattr(station, "load_cell", counting_load)
    monkeypatch.setattr(placement, "_clear_share", recording_share)
    short = placement.place_hub(cell, hub, wts, config, PlanOptions(workers=1))
    assert round(shares[0][0], 2) == 1.0 and len(built) == 1 and len(shares) == 1
    # the full comparison: both candidates read, the larger key wins
    monkeypatch.setattr(placement, "_may_win", lambda *a: True)
    built.clear()
    shares.clear()
    full = placement.place_hub(cell, hub, wts, config, PlanOptions(workers=1))
    assert len(built) == 2 and len(shares) == 2
    assert _same_placement(short, full)
