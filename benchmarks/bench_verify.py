"""Benchmark of the verification stage.

1. Verification time per hub: the reference plan of every window of a hub (tool-in-hand,
   75 mm/s), verified at the default dense sampling; seconds per hub, per window, per sample.
2. Distances per sample: Drake's ``ComputeSignedDistancePairwiseClosestPoints`` (the default)
   vs the culled narrow phase kept as cross-check (same answers, see the tests).
3. verify-all speed-up: the same jobs with 1 and 2 worker processes.

Run:  PYTHONPATH=. python benchmarks/bench_verify.py [--quick]
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import Config, ProcessParameters, Recipe, default_tolerances
from drakedeburr.hub.model import load_hub
from drakedeburr.verify.batch import verify_all
from drakedeburr.verify.checks import verify_plan
from drakedeburr.verify.distances import DistanceProbe
from drakedeburr.verify.synthetic import reference_plan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2 windows, 2 batch hubs, quick batch")
    ap.add_argument("--hub", default="h5_straight")
    args = ap.parse_args()
    params = ProcessParameters(grinding_speed=0.075)

    hub = load_hub(args.hub)
    windows = [0, 1] if args.quick else [w.index for w in hub.windows]
    t0 = time.perf_counter()
    plan = reference_plan("tool_in_hand", args.hub, windows, params=params)
    t_plan = time.perf_counter() - t0
    t0 = time.perf_counter()
    cell = load_cell(plan.scenario, plan.hub)
    t_load = time.perf_counter() - t0
    t0 = time.perf_counter()
    config = Config("tool_in_hand", args.hub, Recipe(process=params), default_tolerances())
    report = verify_plan(plan, config, expected_windows=windows, cell=cell, hub_model=hub)
    t_verify = time.perf_counter() - t0
    n = report.settings["samples"]
    print("## 1. verification time per hub")
    print(f"hub {args.hub}, {len(windows)} windows, {len(plan.targets)} targets, "
          f"{plan.trajectory.duration:.1f} s cycle, verdict "
          f"{'PASS' if report.passed else 'FAIL ' + ','.join(report.failed)}")
    print(f"{'step':<26}{'seconds':>10}{'per window':>12}{'ms/sample':>11}")
    print(f"{'reference plan (build)':<26}{t_plan:>10.2f}{t_plan / len(windows):>12.2f}")
    print(f"{'load cell':<26}{t_load:>10.2f}")
    print(f"{'verify_plan':<26}{t_verify:>10.2f}{t_verify / len(windows):>12.2f}"
          f"{1e3 * t_verify / n:>11.2f}   ({n} samples)")

    print("\n## 2. distances per sample (ms): 300 samples over the plan / 300 on one cut")
    cut = next(sg for sg in plan.segments if sg.kind == "cut")
    sets = {"whole plan": plan.trajectory.value(np.linspace(0, plan.trajectory.duration, 300)),
            "cut only": plan.trajectory.value(np.linspace(*cut.t_range, 300))}
    print(f"{'method':<44}{'whole plan':>12}{'cut only':>10}{'ratio (cut)':>13}")
    base = {}
    for method, label in (("pairwise", "Drake pairwise query (default, baseline)"),
                          ("culled", "culled narrow phase (cross-check)")):
        probe = DistanceProbe(cell, 0.02, method=method)
        row = []
        for qs in sets.values():
            probe.measure(qs[0])
            t0 = time.perf_counter()
            for q in qs:
                probe.measure(q)
            row.append(1e3 * (time.perf_counter() - t0) / len(qs))
        base.setdefault("cut", row[1])
        print(f"{label:<44}{row[0]:>12.2f}{row[1]:>10.2f}{row[1] / base['cut']:>13.2f}")

    hubs = ["h5_straight", "h5_split"] if args.quick else \
        ["h5_straight", "h5_deepdish", "h5_split", "h6_curved"]
    scope = "window 0" if args.quick else "all windows"
    print(f"\n## 3. verify-all speed-up (reference plans of {scope}, tool-in-hand, "
          f"{len(hubs)} hubs)")
    opts = {"scenarios": ["tool_in_hand"], "planner": "reference",
            "windows": [0] if args.quick else None, "quick": args.quick,
            "grinding_speed": 0.075}
    times = {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            summary = verify_all(hubs, tmp, workers=workers, **opts)
            times[workers] = time.perf_counter() - t0
            verdicts = ",".join("P" if r["passed"] else ("E" if r["error"] else "F")
                                for r in summary["rows"])
        print(f"workers={workers}: {times[workers]:.1f} s for {len(hubs)} hubs ({verdicts})")
    print(f"speed-up 2 vs 1 workers: {times[1] / times[2]:.2f}x")


if __name__ == "__main__":
    main()
