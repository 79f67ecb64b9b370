"""CLI: ``drakedeburr plan`` (plan a hub in a cell) and ``drakedeburr export`` (plan -> robot
program)."""

from __future__ import annotations

import argparse
import json
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
    from drakedeburr.plan.io import save_plan, write_joint_csv
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    options = replace(PlanOptions(), windows=_parse_windows(args.windows))
    if args.fillets:
        from drakedeburr.plan.fillets import FilletOptions

        options = replace(options, fillets=FilletOptions())
    plan = plan_hub(args.scenario, args.hub, args.mode, source=args.source, options=options,
                    progress=tqdm_progress("plan"), robot=args.robot)
    out = Path(args.output or f"plan_{plan.hub}_{plan.mode}")
    save_plan(plan, out)
    write_joint_csv(plan, out / "joints.csv")
    if args.html:
        from drakedeburr.viz.playback import save_plan_html

        save_plan_html(plan, args.html)
    m = plan.meta
    print(f"plan written to {out}: {len(m['windows'])} windows, cycle {m['cycle_seconds']:.2f} s "
          f"(cutting {m['cutting_seconds']:.2f} s vs {m['physical_cut_seconds']:.2f} s at "
          f"{m['options']['params']['grinding_speed'] * 1e3:.0f} mm/s), "
          f"{len(plan.failures)} failure records")
    for w in m["windows"]:
        print(f"  window {w['window']} ({w['kind']}): {w['reached']}/{w['cl_points']} CL, "
              f"J4/J5/J6 range {w['j4_range_deg']:.1f}/{w['j5_range_deg']:.1f}/"
              f"{w['j6_range_deg']:.1f} deg, clearance {w['min_clearance_m'] * 1e3:.2f} mm, "
              f"speed in band {100 * w['speed_in_band_fraction']:.0f} %")
    for f in plan.failures[:10]:
        print(f"  FAILURE {f}", file=sys.stderr)
    return 0 if not plan.failures else 1


def _verification_state(folder: Path) -> tuple[bool | None, str]:
    report = folder / "report.json"
    if report.is_file():
        try:
            passed = bool(json.loads(report.read_text()).get("passed"))
        except (json.JSONDecodeError, AttributeError):
            return False, f"{report} is unreadable"
        return passed, f"verification report {report}: {'passed' if passed else 'FAILED'}"
    return None, "no verification report beside the plan"


def plan_program(plan, name: str, *, flag: str = "", flag_reason: str = "",
                 verified: bool = False, robot: str | None = None):
    """The plan's program with the loads of its cell's tool (and workpiece) models."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.errors import InputError
    from drakedeburr.programs import plan_robot, program_from_plan

    spec = plan_robot(plan)
    try:
        cell = load_cell(plan.scenario, plan.hub, robot=spec.name)
    except FileNotFoundError as exc:
        raise InputError(f"the plan's cell ({plan.scenario}, hub {plan.hub}) is needed for the "
                         f"tool's mass and centre of gravity: {exc}") from exc
    return program_from_plan(plan, name, robot=robot, loads=cell.flange_loads(),
                             verified=verified, flag=flag, flag_reason=flag_reason)


def _run_export(args: argparse.Namespace) -> int:
    from drakedeburr.errors import InputError
    from drakedeburr.plan.io import load_plan
    from drakedeburr.programs import write_program

    folder = Path(args.plan)
    plan = load_plan(folder)
    folder = folder.parent if folder.name == "plan.json" else folder
    passed, why = _verification_state(folder)
    flag = reason = ""
    if passed is False or (passed is None and plan.failures):
        what = why if passed is False else f"the plan records {len(plan.failures)} failures"
        if not args.force:
            raise InputError(f"{folder}: refusing to export: {what} (use --force to export anyway)")
        flag, reason = "FORCED", f"exported with --force although {what}"
    elif passed is None:
        flag, reason = "UNVERIFIED", "no verification report; run drakedeburr verify"
    program = plan_program(plan, args.name, flag=flag, flag_reason=reason, robot=args.robot)
    paths = write_program(program, args.output, args.format)
    print("wrote " + ", ".join(str(p) for p in paths) + (f" [{flag}]" if flag else ""))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "plan", help="plan a hub's windows in a cell (IK, smoothing, timing) -> plan folder",
        description="Plan every window of a hub: CL points, tool axes, cone-constrained IK, "
                    "the executed linear motion, approach/retract/transitions, timing at "
                    "process speed. Writes plan.json + arrays.npz + joints.csv. Exit 1 when "
                    "any point failed (the plan is still written, failures listed).")
    p.add_argument("scenario", nargs="?", default="tool_in_hand",
                   help="bundled scenario name or YAML path (default tool_in_hand)")
    p.add_argument("--hub", default=None, help="bundled hub name or folder (default: first)")
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
    p.add_argument("--fillets", action="store_true",
                   help="re-plan the tool orientation by a KTO where a cut slows at a fillet "
                        "(faster cut, several times the planning time; docs/plan.md)")
    p.set_defaults(_run=_run_plan)

    e = subparsers.add_parser(
        "export", help="write a plan as a robot program (RAPID, KRL, FANUC LS)",
        description="Writes the program of the plan's arm (RAPID for ABB, KRL for KUKA, LS for "
                    "FANUC; tool in hand or stationary tool); every move carries its planned "
                    "speed and zone. Refuses a plan whose verification failed (report.json "
                    "beside it) or, "
                    "without a report, a plan with failures recorded, unless --force; the "
                    "program header then says FORCED (or UNVERIFIED without a report).")
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
    e.add_argument("--force", action="store_true", help="export even if verification failed")
    e.set_defaults(_run=_run_export)
