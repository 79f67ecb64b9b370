"""verify-all: local process pool and a Dask LocalCluster give the same verdicts."""

from __future__ import annotations

import json

import pytest

import drakedeburr.verify.batch as mut

HUBS = ["h5_straight", "h5_split"]
SETTINGS = mut.JobSettings(planner="reference", windows=(0,), quick=True, grinding_speed=0.075)


def test_process_pool_then_dask_cluster(tmp_path):
    from dataclasses import replace

    pool = mut.verify_all(HUBS, tmp_path / "pool", scenarios=["tool_in_hand"], workers=2,
                          settings=replace(SETTINGS, keep_failed_plans=True))
    assert pool["executor"] == "processes(2)"
    assert [r["hub"] for r in pool["rows"]] == sorted(HUBS)
    for r in pool["rows"]:
        assert r["error"] is None, r
        doc = json.loads((tmp_path / "pool" / "tool_in_hand" / r["hub"] / "report.json")
                         .read_text())
        assert doc["passed"] == r["passed"]
        assert doc["summary"]["failed"] == r["failed"]
        # the plan of a hub that fails is kept to look into, and loads
        kept = tmp_path / "pool" / "tool_in_hand" / r["hub"] / "plan"
        assert kept.is_dir() == (not r["passed"])
        if kept.is_dir():
            from drakedeburr.plan.io import load_plan

            assert load_plan(kept).hub == doc["plan"]["hub"]
    assert (tmp_path / "pool" / "summary.md").read_text().startswith("| scenario | hub |")
    summary = json.loads((tmp_path / "pool" / "summary.json").read_text())
    assert summary["passed"] == all(r["passed"] for r in pool["rows"])

    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        dask = mut.verify_all(HUBS[:1], tmp_path / "dask", scenarios=["tool_in_hand"],
                              scheduler=client, settings=SETTINGS)
    assert dask["executor"] == "dask"
    a = next(r for r in pool["rows"] if r["hub"] == HUBS[0])
    b = dask["rows"][0]
    assert (a["passed"], a["failed"], a["samples"]) == (b["passed"], b["failed"], b["samples"])
    same = [(tmp_path / d / "tool_in_hand" / HUBS[0] / "report.json").read_text()
            for d in ("pool", "dask")]
    strip = [json.dumps({k: v for k, v in json.loads(t).items() if k != "run"}) for t in same]
    assert strip[0] == strip[1]


def test_hub_folders_and_errors(tmp_path):
    from drakedeburr.errors import InputError
    from drakedeburr.resources import hubs_dir

    names = [p.name for p in mut.hub_folders(hubs_dir())]
    assert names == sorted(names) and "h5_straight" in names
    with pytest.raises(FileNotFoundError, match="no such hub catalogue"):
        mut.hub_folders(tmp_path / "nope")
    with pytest.raises(InputError, match="no hub model folders"):
        mut.hub_folders(tmp_path)
    row = mut.run_job(mut.BatchJob("tool_in_hand", "no_such_hub", str(tmp_path / "x"),
                                   mut.JobSettings(planner="reference")))
    assert row["error"] and not row["passed"]


def test_a_cluster_job_plans_and_verifies_in_its_own_process(tmp_path, monkeypatch):
    """verify-all on a Dask cluster runs each job with one_process: no pool of worker
    processes, whatever the cluster worker's environment (its threads would otherwise share
    one pool); a job without it may use the cores."""
    import os

    from drakedeburr import pool as parallel

    parallel.shutdown_pool(kill=True)
    monkeypatch.delenv("DRAKEDEBURR_WORKERS")
    assert parallel.worker_count(None, 5) == min(5, len(os.sched_getaffinity(0)))
    job = mut.BatchJob(scenario="tool_in_hand", hub=HUBS[0], out_dir=str(tmp_path / "j"),
                       settings=mut.JobSettings(planner="reference", windows=(0,), quick=True,
                                                grinding_speed=0.075),
                       one_process=True)
    row = mut.run_job(job)
    assert row["error"] is None and row["passed"], row
    assert os.environ["DRAKEDEBURR_WORKERS"] == "1" and parallel.running_workers() == 0


def test_a_job_without_an_arm_uses_one_rated_for_its_load(tmp_path, monkeypatch):
    """verify-all picks the arm as plan/verify do: the workpiece cell's IRB 1600 (10 kg) cannot
    carry a bundled hub on its gripper, so the job runs on the first rated arm mounted there
    (the catalogue's workpiece jobs all failed `payload` before); a named arm is kept."""
    from drakedeburr.cell.loads import cell_load, rated_default_arm
    from drakedeburr.cell.station import load_cell
    from drakedeburr.robots import ROBOTS
    from drakedeburr.robots.payload import payload_figures

    seen = []

    def make_plan(config, planner, windows, progress=None):
        seen.append(config.robot)
        raise RuntimeError("stop after the configuration")

    monkeypatch.setattr(mut, "make_plan", make_plan)
    expected = rated_default_arm("workpiece_in_hand", "h5_straight")
    assert expected is not None  # the scenario's own arm is over its rating here
    assert cell_load(load_cell("workpiece_in_hand", "h5_straight")).mass > \
        ROBOTS["irb1600"].payload_kg
    for robot, want in ((None, expected), ("irb2600", "irb2600")):
        row = mut.run_job(mut.BatchJob("workpiece_in_hand", "h5_straight",
                                       str(tmp_path / str(robot)), robot=robot))
        assert row["robot"] == want and seen[-1] == want and "stop after" in row["error"]
        cell = load_cell("workpiece_in_hand", "h5_straight", robot=want)
        assert all(f.ok for f in payload_figures(ROBOTS[want], cell_load(cell)))
