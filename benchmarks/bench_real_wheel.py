"""Plan + verify of the real wheel meshes in ../shared/extdata/wheel_models (issue 42).

Per mesh: the import (``hub import``, cached in the run's folder; timed apart), then
``plan_hub`` (tool-in-hand, defaults) and ``verify_plan`` of the whole wheel, wall time; the
windows planned, passing, refused before their IK (``plan.window.tool_refusal``) and why. The
baseline, in the same run: window 1 of the first mesh planned with the pre-check
(``PlanOptions.tool_precheck``) and without it (every target through the IK, its probes, the
milder tilt boxes and the long-reach burr), the ratio of the two plan times.

    PYTHONPATH=. python benchmarks/bench_real_wheel.py [--quick] [--out DIR]

``--quick``: the audibot rim only. Target (issue 42): the median plan + verify <= 3 min a
wheel on the 2 shared cores.
"""

from __future__ import annotations

import argparse
import logging
import tempfile
import time
from pathlib import Path

import numpy as np

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ("--out", "{tmp}")
QUICK_ARGS = ("--quick", "--out", "{tmp}")

MESHES = ("audibot__wheel_rim_only_DERIVED_m.stl", "dbw_mkz13_rim_mm.stl",
          "dbw_mondeo15_rim_mm.stl")


def _plan(folder: Path, precheck: bool, windows=None):
    from drakedeburr.config import load_config
    from drakedeburr.plan.options import PlanOptions
    from drakedeburr.plan.planner import plan_hub

    config = load_config("tool_in_hand", str(folder))
    t0, c0 = time.perf_counter(), time.process_time()
    plan = plan_hub(config, options=PlanOptions(tool_precheck=precheck, windows=windows))
    _CPU["plan"] = time.process_time() - c0
    return config, plan, time.perf_counter() - t0


_CPU: dict = {}  # CPU seconds of this process in the last plan (the pool's workers apart)


def _refused(plan) -> list:
    return [f for f in plan.failures if f.kind == "window" and "every tool axis" in f.reason]


def wheel(mesh: Path, out: Path) -> dict:
    """Import, plan and verify one wheel."""
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.verify.checks import verify_plan

    t0 = time.perf_counter()
    res = import_mesh(mesh, out)
    t_import = time.perf_counter() - t0
    config, plan, t_plan = _plan(res.dir, True)
    cpu_plan = _CPU["plan"]
    t1 = time.perf_counter()
    report = verify_plan(plan, config)
    t_verify = time.perf_counter() - t1
    failing = {f.window for f in plan.failures}
    planned = [w for w in range(res.window_count) if w not in failing]
    return {"mesh": mesh.name, "dir": res.dir, "windows": res.window_count,
            "import_s": t_import, "plan_s": t_plan, "verify_s": t_verify,
            "plan_cpu_s": cpu_plan, "timings": dict(plan.run.get("timings", {})),
            "passed": report.passed, "planned": planned,
            "refused": sorted({f.window for f in _refused(plan)}),
            "first_refusal": next(iter(_refused(plan)), None)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the audibot rim only")
    ap.add_argument("--out", default=None, help="folder for the imports")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    from drakedeburr.resources import extdata_dir

    out = Path(args.out or tempfile.mkdtemp(prefix="bench_real_wheel_"))
    meshes = MESHES[:1] if args.quick else MESHES
    rows = [wheel(extdata_dir() / "wheel_models" / m, out) for m in meshes]
    print("| mesh | windows | import s | plan s | verify s | plan + verify s | passed "
          "| windows without a failure | refused before the IK |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mesh']} | {r['windows']} | {r['import_s']:.0f} | {r['plan_s']:.0f} | "
              f"{r['verify_s']:.0f} | {r['plan_s'] + r['verify_s']:.0f} | "
              f"{'yes' if r['passed'] else 'no'} | {r['planned']} | {r['refused']} |")
    for r in rows:
        print(f"\n{r['mesh']}: plan CPU {r['plan_cpu_s']:.0f} s in this process (the pool's "
              f"workers apart); the plan's stage timings [s]: " + ", ".join(
                  f"{k} {v:.0f}" for k, v in r["timings"].items()
                  if isinstance(v, int | float)))
    med = float(np.median([r["plan_s"] + r["verify_s"] for r in rows]))
    print(f"\nmedian plan + verify: {med:.0f} s a wheel (target <= 180 s on 2 shared cores: "
          f"{'met' if med <= 180 else 'NOT met'}); import apart: median "
          f"{np.median([r['import_s'] for r in rows]):.0f} s")
    first = rows[0]
    if first["first_refusal"] is not None:
        print(f"\nfirst refusal ({first['mesh']}): window {first['first_refusal'].window}: "
              f"{first['first_refusal'].reason}")
    # baseline: window 1 of the first mesh with and without the pre-check
    _, with_plan, t_with = _plan(first["dir"], True, windows=(1,))
    _, without_plan, t_without = _plan(first["dir"], False, windows=(1,))
    print(f"\nbaseline, {first['mesh']} window 1 alone: plan with the pre-check {t_with:.0f} s "
          f"({len(with_plan.failures)} failure records), without it {t_without:.0f} s "
          f"({len(without_plan.failures)} failure records; windows failing with: "
          f"{sorted({f.window for f in with_plan.failures})}, without: "
          f"{sorted({f.window for f in without_plan.failures})}); ratio with / without "
          f"{t_with / t_without:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
