"""CLI: ``drakedeburr plan`` (plan a hub in a cell) and ``drakedeburr export`` (plan -> robot
program)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXPORT_FORMATS = ("rapid", "krl", "ls")


#: bytes a plan folder takes at least, per window (plan.json, arrays.npz, joints.csv: ~0.2 MB
#: per window measured on the bundled hubs, doubled), and a Meshcat replay
_PLAN_BYTES_PER_WINDOW = 400_000
_HTML_BYTES = 4_000_000


def _default_output(scenario: str, hub: str) -> Path:
    """``plan_<hub>_<mode>``, the mode from the bundled scenario's name or the cell."""
    from drakedeburr.resources import scenario_names

    if scenario in scenario_names():
        mode = "workpiece" if scenario.startswith("workpiece") else "tool"
    else:
        from drakedeburr.cell.station import load_cell

        mode = load_cell(scenario, hub).mode
    return Path(f"plan_{Path(hub).name}_{mode}")


def _check_plan_args(args: argparse.Namespace, scenario: str, hub: str) -> tuple:
    """Everything checked before planning: scenario, hub, windows, outputs. Returns
    (windows, output folder)."""
    from drakedeburr import argcheck
    from drakedeburr.plan.io import is_plan_folder
    from drakedeburr.resources import resolve_hub_dir, scenario_path

    scenario_path(scenario)
    resolve_hub_dir(hub)
    windows = argcheck.parse_windows(args.windows)
    have = argcheck.hub_windows(hub)
    argcheck.check_windows(windows, have, Path(hub).name)
    out = Path(args.output) if args.output else _default_output(scenario, hub)
    argcheck.output_folder(out, "-o/--output", is_ours=is_plan_folder)
    argcheck.output_file(args.html, "--html")
    scenario_file = Path(scenario) if Path(scenario).suffix in (".yaml", ".yml") else None
    argcheck.separate_outputs({"--html": args.html}, inputs={"the scenario": scenario_file},
                              input_folders={"the hub folder": resolve_hub_dir(hub)},
                              output_folders={"-o/--output": out})
    argcheck.free_space(out, _PLAN_BYTES_PER_WINDOW * len(windows or have), "-o/--output")
    if args.html:
        argcheck.free_space(Path(args.html).parent, _HTML_BYTES, "--html")
    return windows, out


def add_tool_argument(p) -> None:
    """``--tool``: the burr on the bundled spindle (plan and verify of a hub)."""
    from drakedeburr.cell.tools import TOOL_VARIANTS

    p.add_argument("--tool", choices=tuple(TOOL_VARIANTS), default=None,
                   help="burr on the bundled spindle (default: the standard burr, and the "
                        "long-reach one for a hub the standard cannot cut: docs/cell.md)")


def _run_plan(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from drakedeburr.cli import tqdm_progress
    from drakedeburr.config import load_config
    from drakedeburr.hub import DEFAULT_HUB
    from drakedeburr.plan.io import save_plan
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    scenario = args.scenario
    if args.mode is not None:
        scenario = "tool_in_hand" if args.mode == "tool" else "workpiece_in_hand"
    hub = args.hub or DEFAULT_HUB
    windows, out = _check_plan_args(args, scenario, hub)
    options = replace(PlanOptions(), windows=windows)
    if args.fillets == "off":
        options = replace(options, fillets=None)
    elif args.fillets == "kto":
        options = replace(options, fillets=replace(options.fillets, method="kto"))
    from drakedeburr.cell.loads import arm_or_rated_default

    # no --robot: the scenario's arm, or one rated for what it carries (workpiece in hand)
    robot = arm_or_rated_default(args.robot, scenario, hub)
    config = load_config(scenario, hub, robot=robot, tool=args.tool)
    plan = plan_hub(config, source=args.source, options=options, progress=tqdm_progress("plan"))
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


def _check_export_args(args: argparse.Namespace):
    """The output file, then the plan (read and checked), the format for its arm, the program
    name the file gives and the file's suffix: all before the gate and any writing. Returns
    (plan folder, plan, format)."""
    from drakedeburr import argcheck
    from drakedeburr.errors import InputError
    from drakedeburr.plan.io import load_plan
    from drakedeburr.programs import plan_robot
    from drakedeburr.programs.common import SUFFIXES, program_name_for
    from drakedeburr.programs.names import check_identifier
    from drakedeburr.robots import get_robot

    out = argcheck.output_file(args.output, "-o/--output")
    folder = Path(args.plan)
    folder = folder.parent if folder.name == "plan.json" else folder
    if not folder.exists():
        raise InputError(f"{folder}: no such plan folder")
    plan = load_plan(folder)
    dat = out.with_suffix(".dat") if out.suffix.lower() == ".src" else None
    argcheck.separate_outputs(
        {"-o/--output": out, "-o/--output (.dat beside the .src)": dat},
        inputs={f"the plan's {f.name}": f for f in sorted(folder.iterdir()) if f.is_file()})
    spec = plan_robot(plan)
    if args.robot is not None and get_robot(args.robot) is not spec:
        raise InputError(f"--robot {args.robot}: the plan {folder} was made for {spec.name}")
    fmt = args.format or spec.program_format
    if fmt != spec.program_format:
        raise InputError(f"--format {fmt}: the plan's arm {spec.name} runs "
                         f"{spec.program_format.upper()} (--format {spec.program_format})")
    if out.suffix.lower() not in SUFFIXES[fmt]:
        raise InputError(f"{out}: a {fmt.upper()} program file ends in "
                         f"{' or '.join(SUFFIXES[fmt])}")
    if fmt in ("krl", "ls"):
        program_name_for(out, fmt)
    else:
        check_identifier(args.name, "rapid", "--name", "module name")
    if fmt == "krl":
        argcheck.output_file(out.with_suffix(".dat"), "-o/--output (.dat beside the .src)")
    argcheck.free_space(out.parent, 400 * len(plan.targets), "-o/--output")
    return folder, plan, fmt


def _run_export(args: argparse.Namespace) -> int:
    from drakedeburr.post.export import ExportRefused, export_plan

    folder, plan, fmt = _check_export_args(args)
    try:
        done = export_plan(folder, args.output, fmt, name=args.name, force=args.force,
                           robot=args.robot, plan=plan, partial=args.partial)
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
    p.add_argument("--robot", default=None, metavar="NAME|FILE",
                   help="registered arm (drakedeburr robots) or an arm file (*.yaml, "
                        "docs/robots.md); default: the scenario's")
    add_tool_argument(p)
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
    e.add_argument("--robot", default=None, metavar="NAME|FILE",
                   help="check that the plan was made for this arm (the arm comes from the plan)")
    e.add_argument("--force", action="store_true",
                   help="write even when the gate refuses (the header says why)")
    e.add_argument("--partial", action="store_true",
                   help="write a plan whose verification failed only on uncut_edge (partial "
                        "windows; every other required check passed on the motion planned): "
                        "the header says PARTIAL and lists the uncut stretches")
    e.set_defaults(_run=_run_export)
