"""Benchmark of ``verify --program``: the program as the controller runs it, checked like a plan
(:func:`drakedeburr.post.program_check.program_items`), against plan-only verification
(:func:`drakedeburr.verify.checks.verify_plan`) measured in the same run, on the same plan and
cell, for the default hub's program in RAPID (IRB 1600), KRL (KR 6 R700) and LS (M-10iA).

Per format: the plan verified alone; the program written and read back; ``program_items`` with
its stages (the controller's re-simulation: joints solved along every move; its sampling as a
plan with the clearance certificate; the rest); the ratio program check / plan verification
and ``verify --program`` (both) / plan verification. Wall and CPU time of this process (the
machine is shared; a pool worker's share of the distance sweep is in the wall time only).

The plans are made with ``plan_hub`` defaults (tool in hand, one per arm) into ``--plans DIR``
and reused from there on later runs. ``--quick``: window 0 only and the verifier's quick
sampling (``QUICK_SAMPLING``), a smoke run.

Run:  PYTHONPATH=. python benchmarks/bench_program_check.py [--quick] [--plans DIR]
      [--formats rapid,krl,ls]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

ARMS = {"rapid": ("irb1600", ".mod"), "krl": ("kr6_r700", ".src"), "ls": ("m10ia", ".ls")}


class Clock:
    """Wall and CPU time of wrapped functions, per label (calls summed)."""

    def __init__(self) -> None:
        self.t: dict[str, list[float]] = {}

    def wrap(self, module, name: str, label: str) -> None:
        fn = getattr(module, name)

        def timed(*a, **k):
            w, c = time.perf_counter(), time.process_time()
            try:
                return fn(*a, **k)
            finally:
                acc = self.t.setdefault(label, [0.0, 0.0])
                acc[0] += time.perf_counter() - w
                acc[1] += time.process_time() - c

        setattr(module, name, timed)


def _timed(fn, *a, **k):
    w, c = time.perf_counter(), time.process_time()
    out = fn(*a, **k)
    return out, time.perf_counter() - w, time.process_time() - c


def _plan(hub: str, robot: str, plans: Path, quick: bool):
    from drakedeburr.config import load_config
    from drakedeburr.plan.io import load_plan, save_plan
    from drakedeburr.plan.options import PlanOptions
    from drakedeburr.plan.planner import plan_hub

    folder = plans / f"tool_in_hand_{hub}_{robot}{'_quick' if quick else ''}"
    if not (folder / "plan.json").exists():
        config = load_config("tool_in_hand", hub, robot=robot)
        options = PlanOptions(windows=[0]) if quick else None
        t0 = time.perf_counter()
        save_plan(plan_hub(config, options=options), folder)
        print(f"  planned {hub} on {robot} in {time.perf_counter() - t0:.1f} s -> {folder}")
    return load_plan(folder)


def bench_format(fmt: str, hub: str, plans: Path, quick: bool) -> tuple[float, float] | None:
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.config import default_tolerances
    from drakedeburr.post import program_check
    from drakedeburr.post.program_check import plan_program
    from drakedeburr.programs import controller, read_program, write_program
    from drakedeburr.verify.checks import QUICK_SAMPLING, config_for_plan, verify_plan

    robot, suffix = ARMS[fmt]
    print(f"\n{fmt.upper()} ({robot}), hub {hub}{' (quick)' if quick else ''}")
    try:
        plan = _plan(hub, robot, plans, quick)
    except Exception as exc:  # an arm that cannot plan the hub: said, the others still run
        print(f"  no plan on {robot}: {exc}")
        return None
    tol = default_tolerances(**(QUICK_SAMPLING if quick else {}))
    config = config_for_plan(plan, tolerances=tol)
    cell = load_plan_cell(plan)
    windows = sorted({s.window_index for s in plan.segments if s.kind == "cut"})
    report, w_plan, c_plan = _timed(verify_plan, plan, config, expected_windows=windows,
                                    cell=cell)
    with tempfile.TemporaryDirectory() as tmp:
        paths = write_program(plan_program(plan, "deburr", cell=cell),
                              Path(tmp) / f"deburr{suffix}", fmt)
        read = read_program(paths[0])
        clock = Clock()
        clock.wrap(controller, "controller_motion", "controller re-simulation (IK)")
        clock.wrap(program_check, "controller_sampled", "controller sampled + certificate")
        items, w_prog, c_prog = _timed(program_check.program_items, plan, read, cell, tol,
                                       config=config)
    failed = [i.name for i in items if i.required and not i.passed]
    print(f"  plan: {len(plan.targets)} targets, {len(read.moves)} moves; plan verification "
          f"{'PASS' if report.passed else 'FAIL'}, program items "
          f"{'PASS' if not failed else 'FAIL ' + ', '.join(failed)}")
    print(f"  {'stage':<40}{'wall s':>9}{'cpu s':>9}")
    print(f"  {'plan-only verification':<40}{w_plan:>9.2f}{c_plan:>9.2f}")
    for label, (w, c) in clock.t.items():
        print(f"  {'  ' + label:<40}{w:>9.2f}{c:>9.2f}")
    rest = (w_prog - sum(v[0] for v in clock.t.values()),
            c_prog - sum(v[1] for v in clock.t.values()))
    print(f"  {'    rest (file compare, path, zones)':<40}{rest[0]:>9.2f}{rest[1]:>9.2f}")
    print(f"  {'program check (program_items)':<40}{w_prog:>9.2f}{c_prog:>9.2f}")
    print(f"  ratio program check / plan verification: {w_prog / w_plan:.2f} wall, "
          f"{c_prog / c_plan:.2f} cpu; verify --program / verify: "
          f"{(w_plan + w_prog) / w_plan:.2f} wall, {(c_plan + c_prog) / c_plan:.2f} cpu")
    return w_plan, w_prog


def main() -> None:
    from drakedeburr.hub.catalogue import DEFAULT_HUB

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="window 0, quick sampling")
    ap.add_argument("--plans", type=Path, default=Path(tempfile.gettempdir())
                    / "bench_program_check_plans")
    ap.add_argument("--formats", default="rapid,krl,ls")
    ap.add_argument("--hub", default=DEFAULT_HUB)
    args = ap.parse_args()
    args.plans.mkdir(parents=True, exist_ok=True)
    for fmt in args.formats.split(","):
        bench_format(fmt.strip(), args.hub, args.plans, args.quick)


if __name__ == "__main__":
    main()
