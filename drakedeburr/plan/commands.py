"""CLI: ``drakedeburr plan`` (plan a hub in a cell) and ``drakedeburr export`` (plan -> robot
program)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXPORT_FORMATS = ("rapid", "krl", "ls")


def _parse_windows(text: str | None) -> tuple[int, ...] | None:
    if not text:
        return None
    from drakedeburr.errors import InputError

    try:
        return tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError as exc:
        raise InputError(f"--windows: expected comma-separated window numbers, "
                         f"got {text!r}") from exc


def _run_plan(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from drakedeburr.cli import tqdm_progress
    from drakedeburr.plan.io import save_plan
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    options = replace(PlanOptions(), windows=_parse_windows(args.windows))
    if args.fillets == "off":
        options = replace(options, fillets=None)
    elif args.fillets == "kto":
        options = replace(options, fillets=replace(options.fillets, method="kto"))
    scenario = args.scenario
    if args.mode is not None:
        scenario = "tool_in_hand" if args.mode == "tool" else "workpiece_in_hand"
    from drakedeburr.config import load_config
    from drakedeburr.hub import DEFAULT_HUB

    config = load_config(scenario, args.hub or DEFAULT_HUB, robot=args.robot)
    plan = plan_hub(config, source=args.source, options=options, progress=tqdm_progress("plan"))
    out = Path(args.output or f"plan_{Path(plan.hub).name}_{plan.mode}")
    save_plan(plan, out)
    if args.html:
        from drakedeburr.viz.playback import save_plan_html

        save_plan_html(plan, args.html)
    m = plan.meta
    print(f"plan written to {out}: {len(m['windows'])} windows, cycle {m['cycle_seconds']:.2f} s "
          f"(cutting {m['cutting_seconds']:.2f} s vs {m['physical_cut_seconds']:.2f} s at "
          f"{config.process.grinding_speed * 1e3:.0f} mm/s), "
          f"{len(plan.failures)} failure records")
    for w in m["windows"]:
        print(f"  window {w['window']} ({w['kind']}): {w['reached']}/{w['cl_points']} CL, "
              f"J4/J5/J6 range {w['j4_range_deg']:.1f}/{w['j5_range_deg']:.1f}/"
              f"{w['j6_range_deg']:.1f} deg, clearance {w['min_clearance_m'] * 1e3:.2f} mm, "
              f"speed in band {100 * w['speed_in_band_fraction']:.0f} %")
    for f in plan.failures[:10]:
        print(f"  FAILURE {f}", file=sys.stderr)
    return 0 if not plan.failures else 1


def _run_export(args: argparse.Namespace) -> int:
    from drakedeburr.post.export import ExportRefused, export_plan

    try:
        done = export_plan(args.plan, args.output, args.format, name=args.name, force=args.force,
                           robot=args.robot)
    except ExportRefused as exc:
        print(f"drakedeburr export: {exc}", file=sys.stderr)
        return 1
    print("wrote " + ", ".join(str(p) for p in done.paths) + (f" [{done.flag}: {done.reason}]"
                                                              if done.flag else ""))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "plan", help="plan a hub's windows in a cell (IK, smoothing, timing) -> plan folder",
        description="Plan every window of a hub: CL points, tool axes, cone-constrained IK, "
                    "the executed linear motion, approach/retract/transitions, timing at "
                    "process speed. Writes the plan folder (plan.json, arrays.npz, joints.csv, "
                    "run.json) as one transaction: an existing plan folder is replaced whole "
                    "(with its verification report), any other existing folder is refused. "
                    "Exit 1 when any point failed (the plan is still written, failures "
                    "listed).")
    p.add_argument("scenario", nargs="?", default="tool_in_hand",
                   help="bundled scenario name or YAML path (default tool_in_hand)")
    p.add_argument("--hub", default=None,
                   help="bundled hub name or folder (default: the default hub)")
    p.add_argument("--mode", choices=("tool", "workpiece"), default=None,
                   help="use the bundled tool_in_hand / workpiece_in_hand scenario")
    p.add_argument("--windows", default=None, help="comma-separated window numbers (default all)")
    p.add_argument("--source", choices=("auto", "toolpath", "edges"), default="auto",
                   help="tool axes from the orientation stage, from the edges (fixed tilt), or "
                        "auto (orientation stage when usable)")
    p.add_argument("-o", "--output", default=None, help="plan folder (default plan_<hub>_<mode>)")
    p.add_argument("--html", default=None, help="also write a static Meshcat replay (HTML)")
    p.add_argument("--robot", default=None, metavar="NAME",
                   help="registered arm (drakedeburr robots; default: the scenario's, irb1600)")
    p.add_argument("--fillets", choices=("program", "kto", "off"), default="program",
                   help="where a cut slows below the feed band at a fillet, re-plan the tool "
                        "orientation so the feed holds where it can: by the feed program "
                        "(default), by a KinematicTrajectoryOptimization (several times the "
                        "planning time), or not (docs/plan.md)")
    p.set_defaults(_run=_run_plan)

    e = subparsers.add_parser(
        "export", help="write a plan as a robot program (RAPID, KRL, FANUC LS)",
        description="Writes the program of the plan's arm (RAPID for ABB, KRL for KUKA, LS for "
                    "FANUC; tool in hand or stationary tool); every move carries its planned "
                    "speed and zone. The gate: refuses (exit 1, nothing written) unless the plan "
                    "folder's report.json (drakedeburr verify FOLDER) passed and was made for "
                    "this very plan and cell by this drakedeburr version; --force writes "
                    "anyway and the program header then says FORCED (verification failed) or "
                    "UNVERIFIED (no report, or one for another plan or cell).")
    e.add_argument("plan", help="plan folder (or its plan.json)")
    e.add_argument("--format", choices=EXPORT_FORMATS, default=None,
                   help="program format (default: the plan's arm's: RAPID for ABB, KRL for "
                        "KUKA, LS for FANUC; another one is refused)")
    e.add_argument("-o", "--output", required=True,
                   help="program file (.mod, .src (+ .dat), .ls); KRL and LS programs are named "
                        "after the file")
    e.add_argument("--name", default="Deburr", help="RAPID module name")
    e.add_argument("--robot", default=None, metavar="NAME",
                   help="check that the plan was made for this arm (the arm comes from the plan)")
    e.add_argument("--force", action="store_true",
                   help="write even when the gate refuses (the header says why)")
    e.set_defaults(_run=_run_export)
