"""One timed planning run for benchmarks/bench_plan.py (run in a subprocess, so that the
previous implementation can be imported from another source tree through PYTHONPATH).

Prints one JSON line: wall and CPU time of ``plan_hub`` (this process and, once they have
ended, its worker processes), per-stage wall and CPU times (exclusive: a stage nested in another
is not counted twice), the plan's figures and its content digest.

Run:  python benchmarks/plan_run.py SCENARIO HUB [--workers N] [--no-fillets]
"""

from __future__ import annotations

import argparse
import importlib
import json
import resource
import time
from collections import defaultdict

# (stage, module, function): wrapped where the planner calls them; nested ones are subtracted
STAGES = [
    ("load cell", "drakedeburr.cell.station", "load_cell"),
    ("targets (CL + orientation)", "drakedeburr.plan.planner", "window_targets_for_hub"),
    ("hub placement", "drakedeburr.plan.placement", "place_hub"),
    ("IK at CL targets", "drakedeburr.plan.window", "solve_window_ik"),
    ("executed cut + clearance + program", "drakedeburr.plan.window", "execute_cut"),
    ("fillet repair", "drakedeburr.plan.fillets", "repair_fillets"),
    ("approach/retract + timing", "drakedeburr.plan.window", "finish_window"),
    ("transitions", "drakedeburr.plan.planner", "joint_stretch"),
]

WALL: dict = defaultdict(float)
CPU: dict = defaultdict(float)
_stack: list = []


def _wrap(stage: str, module: str, name: str) -> None:
    try:
        mod = importlib.import_module(module)
        fn = getattr(mod, name)
    except (ImportError, AttributeError):
        return  # not in this implementation

    def timed(*args, **kwargs):
        _stack.append([0.0, 0.0])  # time of nested stages
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            dw, dc = time.perf_counter() - w0, time.process_time() - c0
            inner = _stack.pop()
            WALL[stage] += dw - inner[0]
            CPU[stage] += dc - inner[1]
            if _stack:
                _stack[-1][0] += dw
                _stack[-1][1] += dc

    setattr(mod, name, timed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("hub")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--no-fillets", action="store_true")
    args = ap.parse_args()
    for st in STAGES:
        _wrap(*st)
    from dataclasses import fields, replace

    import drakedeburr
    from drakedeburr.config import load_config
    from drakedeburr.plan.io import plan_digest
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    options = PlanOptions()
    names = {f.name for f in fields(PlanOptions)}
    if "workers" in names:
        options = replace(options, workers=args.workers)
    if args.no_fillets:
        options = replace(options, fillets=None)
    config = load_config(args.scenario, args.hub)
    w0, c0 = time.perf_counter(), time.process_time()
    plan = plan_hub(config, options=options)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    try:  # the worker processes' CPU counts once they have ended
        from drakedeburr.pool import shutdown_pool

        shutdown_pool()
    except ImportError:
        pass
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    ws = plan.meta["windows"]
    print(json.dumps(dict(
        source=drakedeburr.__file__, wall=wall, cpu=cpu,
        cpu_children=children.ru_utime + children.ru_stime,
        stages_wall=dict(WALL), stages_cpu=dict(CPU), failures=len(plan.failures),
        digest=plan_digest(plan)[:16],
        windows=[dict(window=w["window"], cut=w["cut_seconds"],
                      in_band=w["speed_in_band_fraction"],
                      bound=w.get("speed_in_band_bound")) for w in ws],
        cycle=plan.meta["cycle_seconds"])))


if __name__ == "__main__":
    main()
