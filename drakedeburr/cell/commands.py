"""CLI: ``drakedeburr cell study``: compare spindle mounts and fixture heights by the planned
cycle and the wrist travel (:mod:`drakedeburr.cell.study`), and write the recommended cell as
a scenario file.

The evaluator lives here, not in :mod:`drakedeburr.cell.study`: it plans and verifies, which
the cell stage (built before the planner) does not import; a command module runs the pipeline
as :mod:`drakedeburr.demo` does.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

__all__ = ["register", "evaluate_candidate", "number_list", "study_setup", "study_table"]


def evaluate_candidate(candidate, scenario_file: Path, hub: str,
                       windows: tuple[int, ...] | None = None) -> dict:
    """Plan and verify ``hub`` in ``scenario_file`` (the candidate's cell): its figures for
    :func:`drakedeburr.cell.study.run_study`. A cell that cannot be built or planned is a
    failing candidate (``failing`` names why), not an error of the study."""
    import numpy as np

    from drakedeburr.config import load_config
    from drakedeburr.errors import InputError
    from drakedeburr.plan import PlanOptions, plan_hub
    from drakedeburr.verify import verify_plan

    t0 = time.perf_counter()
    try:
        config = load_config(str(scenario_file), hub)
        plan = plan_hub(config, options=PlanOptions(windows=windows))
        t_plan = time.perf_counter() - t0
        report = verify_plan(plan, config, expected_windows=list(windows) if windows else None)
    except InputError as exc:
        return {"passed": False, "failing": [f"cell: {exc}"], "cycle_s": None,
                "worst_wrist_travel_deg": None}
    failing = [i.name for i in report.items if i.required and not i.passed]
    if plan.failures:
        failing.append(f"planning ({len(plan.failures)} failure records)")
    wrist = report.item("j4_j6_range").per_window or {}
    per_window = {str(w): [math.degrees(r[f"J{j}_range_rad"]) for j in (4, 5, 6)]
                  for w, r in sorted(wrist.items(), key=lambda kv: int(kv[0]))}
    band = report.item("tcp_speed_band")
    cycle = report.item("cycle_time")
    return {
        "passed": bool(report.passed) and not plan.failures, "failing": failing,
        "cycle_s": float(plan.trajectory.duration),
        "cycle_ratio": None if cycle.value is None else float(cycle.value),
        "feed_held_worst": None if band.value is None else float(band.value),
        "feed_held_per_window": {str(w): float(v["fraction_in_band"])
                                 for w, v in (band.per_window or {}).items()},
        "j4_j6_deg_per_window": per_window,
        "worst_wrist_travel_deg": (float(max(sum(v) for v in per_window.values()))
                                   if per_window else None),
        "worst_j6_deg": (float(max(v[2] for v in per_window.values())) if per_window
                         else None),
        "mean_j6_deg": (float(np.mean([v[2] for v in per_window.values()])) if per_window
                        else None),
        "plan_s": t_plan, "tool": plan.meta.get("tool") if plan.meta else None,
    }


def _fmt(x, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def _percent(x):
    return None if x is None else 100 * x


def study_table(ranking: list[dict]) -> str:
    """The ranking as a fixed-width text table (rank order)."""
    head = (f"{'rank':>4}  {'candidate':<15} {'mount':>5} {'offset':>6} {'fixture':>7} "
            f"{'cycle s':>8} {'ratio':>6} {'feed held':>9} {'J6 max':>6} {'J6 mean':>7} "
            f"{'J4+J5+J6':>8}  verdict")
    rows = [head]
    for r in ranking:
        verdict = "passed" if r.get("passed") else "FAILED " + ", ".join(r.get("failing") or [])
        rows.append(
            f"{r['rank']:>4}  {r['name']:<15} {math.degrees(r['mount_angle']):>5.0f} "
            f"{r['offset'] * 1e3:>6.0f} {r['fixture_shift'] * 1e3:>+7.0f} "
            f"{_fmt(r.get('cycle_s'), '8.3f')} {_fmt(r.get('cycle_ratio'), '6.3f')} "
            f"{_fmt(_percent(r.get('feed_held_worst')), '8.1f')}% "
            f"{_fmt(r.get('worst_j6_deg'), '6.1f')} {_fmt(r.get('mean_j6_deg'), '7.1f')} "
            f"{_fmt(r.get('worst_wrist_travel_deg'), '8.1f')}  {verdict}")
    return "\n".join(rows)


def number_list(text: str, option: str) -> tuple[float, ...]:
    from drakedeburr.errors import InputError

    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise InputError(f"{option} {text!r}: expected comma-separated numbers") from None
    if not all(math.isfinite(v) for v in values) or len(set(values)) != len(values):
        raise InputError(f"{option} {text!r}: expected distinct finite numbers")
    return values


def study_setup(args: argparse.Namespace) -> tuple:
    """(hub, windows or None, candidates) from the study's options (``hub``, ``windows``,
    ``quick``, ``angles`` (``none``: no wedge candidates), ``offsets``, ``fixture_heights``,
    ``coaxial``: the coaxial bracket at each fixture height too), checked.

    Raises:
        InputError: a list is malformed, a candidate out of range, a window not the hub's.
    """
    from drakedeburr import argcheck
    from drakedeburr.cell.study import candidate_grid, coaxial_candidates, quick_grid
    from drakedeburr.errors import InputError
    from drakedeburr.hub import DEFAULT_HUB
    from drakedeburr.resources import resolve_hub_dir

    hub = args.hub or DEFAULT_HUB
    resolve_hub_dir(hub)
    windows = argcheck.parse_windows(args.windows)
    if args.quick:
        candidates, windows = quick_grid(), windows or (0,)
    else:
        heights = number_list(args.fixture_heights, "--fixture-heights")
        candidates = [] if args.angles.strip().lower() == "none" else candidate_grid(
            number_list(args.angles, "--angles"), number_list(args.offsets, "--offsets"),
            heights)
        if getattr(args, "coaxial", False):
            candidates += coaxial_candidates(heights)
        if not candidates:
            raise InputError("cell study: no candidates (--angles none without --coaxial)")
    argcheck.check_windows(windows, argcheck.hub_windows(hub), Path(hub).name)
    return hub, windows, candidates


def _run_study(args: argparse.Namespace) -> int:
    from drakedeburr import argcheck
    from drakedeburr._io import atomic_write_json
    from drakedeburr.cell.study import run_study

    hub, windows, candidates = study_setup(args)
    out = argcheck.output_folder(Path(args.out), "-o/--out")
    result = run_study(candidates, lambda c, f: evaluate_candidate(c, f, hub, windows), out)
    result.update(hub=str(hub), windows=None if windows is None else list(windows))
    atomic_write_json(out / "study.json", result)
    print(study_table(result["ranking"]))
    if result["recommended"] is None:
        print("no candidate passes every required check: nothing recommended")
        return 1
    print(f"recommended: {result['recommended']} -> {result['recommended_scenario']}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "cell", help="cell design: compare spindle mounts and fixture heights (cell study)",
        description="The deburring cell's design (docs/cell.md).")
    sub = p.add_subparsers(dest="cell_command", metavar="SUBCOMMAND")
    sub.required = True
    s = sub.add_parser(
        "study", help="rank spindle mounts x fixture heights by planned cycle and wrist travel",
        description="Plan and verify the hub in every candidate tool-in-hand cell (spindle "
                    "mount angle and offset on a wedge adapter or the coaxial straight bracket, "
                    "fixture height), rank the "
                    "candidates that pass every required check by cycle time, then the worst "
                    "window's J4+J5+J6 travel, then name, and write the best as "
                    "OUT/recommended.yaml (load it with --scenario). Exit 1 when none passes.")
    s.add_argument("--hub", default=None, help="bundled hub name or folder (default: the "
                                               "default hub)")
    s.add_argument("--angles", default="30,45,60", help="wedge mount angles [deg], or none "
                                                        "(default %(default)s)")
    s.add_argument("--coaxial", action="store_true",
                   help="add the coaxial straight bracket (burr axis on the flange axis) at "
                        "each fixture height")
    s.add_argument("--offsets", default="0,50", help="mount stand-offs [mm] (default "
                                                     "%(default)s)")
    s.add_argument("--fixture-heights", default="-50,0,50",
                   help="fixture height changes [mm], a list starting with a minus sign "
                        "written --fixture-heights=-50,0 (default %(default)s)")
    s.add_argument("--windows", default=None, help="comma-separated windows (default all)")
    s.add_argument("--quick", action="store_true",
                   help="two candidates (45 and 60 deg), window 0 only (tests)")
    s.add_argument("-o", "--out", default="out/cell_study", help="output folder (default "
                                                                 "%(default)s)")
    s.set_defaults(_run=_run_study)

