"""Issue 16's seeded subset in CI: a hub of the random catalogue, generated here, through
``drakedeburr verify HUB -o DIR`` as a user runs it (placement search, planning with
relaxation, verification with the clearance certificate). The full catalogue (>= 60 hubs, both
cells) is ``benchmarks/bench_catalogue.py``; figures in benchmarks/RESULTS.md.

One hub keeps CI's time (about 35 s to generate, 60 s to plan and verify on a shared 2-core
machine): seed 20261127 #7 (16 in, 5 curved spokes, 4 mm dish), not one the planner was tuned on.
"""

from __future__ import annotations

import json

import pytest

SEED, INDEX = 20261127, 7


@pytest.mark.slow
def test_a_random_catalogue_hub_is_planned_and_verified(tmp_path):
    from drakedeburr.cli import main
    from drakedeburr.hub.randomhub import random_catalogue, random_spec

    hub = random_catalogue(SEED, 1, tmp_path / "hubs", start=INDEX)[0]
    assert hub.dir.name == random_spec(SEED, INDEX).name
    out = tmp_path / "out"
    rc = main(["-q", "verify", str(hub.dir), "--scenario", "tool_in_hand", "-o", str(out)])
    report = json.loads((out / "report.json").read_text())
    items = {it["name"]: it for it in report["items"]}
    failed = [f"{n}: {it['detail']}" for n, it in items.items()
              if it["required"] and not it["passed"]]
    assert rc == 0 and report["passed"], failed
    # every window the generator made is cut (the verifier reads them from the hub model)
    windows = items["windows"]["per_window"]
    assert len(windows) == hub.summary["window_count"] > 0
    assert all(w["cut"] for w in windows.values())
    # the clearance proven over the whole trajectory, not only sampled
    cert = items["clearance_certificate"]
    assert cert["value"] >= cert["limit"] == 2e-3
    assert cert["value"] <= items["clearance"]["value"] + 1e-9
    # the verified plan is saved with its report
    assert (out / "plan.json").is_file() and (out / "report.html").is_file()
