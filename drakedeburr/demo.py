"""``drakedeburr demo``: the main job on the bundled default hub.

hub model -> window edges -> CL points (four planners, the paper's Tab. 1-2 style table) ->
inner-side normals and tool orientation -> Drake plan (cone-constrained IK, executed motion,
timing) -> independent verification (JSON + HTML report) -> robot program (ABB RAPID) and a
Meshcat replay. The program is written only when verification passes, unless ``force`` is
given, and then its header says so.
"""

from __future__ import annotations

import argparse
import json
import logging
import time
from collections.abc import Callable
from pathlib import Path

__all__ = ["DEFAULT_SCENARIO", "demo_program_path", "register", "run_demo"]

log = logging.getLogger(__name__)

DEFAULT_SCENARIO = "tool_in_hand"

Progress = Callable[[int, int, str], None] | None


def _default_hub() -> str:
    from drakedeburr.hub import DEFAULT_HUB

    return DEFAULT_HUB


def demo_program_path(out: Path, hub: str, program_format: str) -> tuple[str, Path]:
    """(program name, file) of the demo's program: ``Deburr_<hub>`` in ``out/deburr_<hub>``,
    the hub's folder name cleaned into an identifier of the format's language (a derived
    name: :func:`drakedeburr.programs.names.clean_identifier`), so a hub folder's name never
    becomes program code."""
    from drakedeburr.programs.names import clean_identifier

    name = clean_identifier(f"Deburr_{Path(str(hub)).name}", program_format, fallback="Deburr")
    suffix = {"rapid": "mod", "krl": "src", "ls": "ls"}[program_format]
    return name, Path(out) / f"d{name[1:]}.{suffix}"


def run_demo(
    out_dir: str | Path,
    hub: str | None = None,
    scenario: str = DEFAULT_SCENARIO,
    *,
    test_mode: bool = False,
    force: bool = False,
    program_format: str | None = None,
    robot: str | None = None,
    progress: Progress = None,
) -> dict:
    """Run the whole chain on ``hub`` in ``scenario`` and write every output to ``out_dir``.

    Args:
        out_dir: output folder (created).
        hub: bundled hub name (default: the bundled default hub).
        scenario: bundled scenario name or YAML path.
        test_mode: plan and verify only the first window (CI).
        force: write the robot program even if verification fails (the header says FORCED).
        program_format: "rapid", "krl" or "ls"; default: the arm's controller's format.
        robot: registered arm (``drakedeburr robots``); default: the scenario's.
        progress: optional callback (done, total, label) for the planning stage.

    Returns:
        Summary mapping: hub, scenario, passed, timings [s] and ``outputs`` (name -> path).
    """
    from drakedeburr._io import atomic_write_json
    from drakedeburr.config import load_config
    from drakedeburr.path import cl_table
    from drakedeburr.plan import PlanOptions, plan_hub, save_plan
    from drakedeburr.post.export import ExportRefused, export_plan
    from drakedeburr.programs import plan_robot
    from drakedeburr.verify import verify_plan
    from drakedeburr.verify.html import write_report_files

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    hub = hub or _default_hub()
    from drakedeburr.cell.loads import arm_or_rated_default

    config = load_config(scenario, hub, robot=arm_or_rated_default(robot, scenario, hub))
    outputs: dict[str, str] = {}
    timings: dict[str, float] = {}

    t0 = time.perf_counter()
    log.info("demo 1/4: CL points on every window of %s (four planners)", hub)
    table = cl_table(hub)
    outputs["cl_table"] = str(atomic_write_json(out / "cl_table.json", table))
    timings["cl_points"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    windows = (0,) if test_mode else None
    log.info("demo 2/4: planning %s in %s (%s)", hub, scenario,
             "window 0 only (test mode)" if test_mode else "all windows")
    plan = plan_hub(config, options=PlanOptions(windows=windows), progress=progress)
    folder = save_plan(plan, out / "plan")
    outputs["plan"] = str(folder)
    timings["plan"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    log.info("demo 3/4: independent verification")
    from drakedeburr.cell.station import load_plan_cell

    cell = load_plan_cell(plan)  # built once: the verification and the report's replay
    report = verify_plan(plan, config, expected_windows=list(windows) if windows else None,
                         cell=cell)
    written = write_report_files(report, folder, plan=plan, cell=cell)
    outputs.update(report_json=str(written[0]), report_html=str(written[1]))
    timings["verify"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    program_format = program_format or plan_robot(plan).program_format
    name, program_path = demo_program_path(out, hub, program_format)
    try:
        done = export_plan(folder, program_path, program_format, name=name,
                           force=force, plan=plan)
        outputs["program"] = str(done.paths[0])
        log.info("demo 4/4: %s program %s%s", program_format, done.paths[0],
                 f" ({done.flag}: {done.reason})" if done.flag else "")
    except ExportRefused as exc:
        log.warning("demo 4/4: no robot program written: %s", exc)
    timings["program"] = time.perf_counter() - t0

    summary = {
        "hub": hub,
        "scenario": scenario,
        "robot": plan_robot(plan).name,
        "test_mode": test_mode,
        "passed": bool(report.passed),
        "plan_failures": len(plan.failures),
        "windows_planned": sorted({s.window_index for s in plan.segments
                                   if s.window_index >= 0}),
        "cycle_seconds": plan.trajectory.duration,
        "timings_s": timings,
        "outputs": outputs,
    }
    atomic_write_json(out / "summary.json", summary)
    outputs["summary"] = str(out / "summary.json")
    return summary


def _check_args(args: argparse.Namespace) -> None:
    """The cell, hub, arm and output folder, before any work."""
    from drakedeburr import argcheck
    from drakedeburr.resources import resolve_hub_dir, scenario_path

    scenario_path(args.scenario)
    resolve_hub_dir(args.hub or _default_hub())
    if args.robot is not None:
        from drakedeburr.robots import get_robot

        get_robot(args.robot)
    from drakedeburr.plan.io import is_plan_folder

    argcheck.output_folder(args.out, "-o/--out")
    argcheck.output_folder(Path(args.out) / "plan", "-o/--out", is_ours=is_plan_folder)
    argcheck.free_space(args.out, 8_000_000, "-o/--out")


def _run(args: argparse.Namespace) -> int:
    from drakedeburr.cli import tqdm_progress

    _check_args(args)

    summary = run_demo(Path(args.out), hub=args.hub, scenario=args.scenario,
                       test_mode=args.test_mode, force=args.force,
                       program_format=args.format, robot=args.robot,
                       progress=tqdm_progress("plan"))
    print(json.dumps({k: summary[k] for k in ("hub", "scenario", "passed", "plan_failures",
                                               "cycle_seconds")}, indent=2))
    for name, path in summary["outputs"].items():
        print(f"{name}: {path}")
    return 0 if summary["passed"] else 1


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "demo", help="run the whole chain on the bundled default hub",
        description="hub -> CL points -> orientation -> Drake plan -> verification report -> "
                    "robot program + Meshcat replay, written to --out")
    p.add_argument("--hub", default=None, help="bundled hub name (default: the default hub)")
    p.add_argument("--scenario", default=DEFAULT_SCENARIO,
                   help="bundled scenario or YAML path (default %(default)s)")
    p.add_argument("-o", "--out", default="out/demo", help="output folder (default %(default)s)")
    p.add_argument("--robot", default=None, metavar="NAME|FILE",
                   help="registered arm (drakedeburr robots) or an arm file (*.yaml, "
                        "docs/robots.md); default: the scenario's")
    p.add_argument("--format", default=None, choices=("rapid", "krl", "ls"),
                   help="robot program format (default: the arm's: RAPID for ABB, KRL for KUKA, "
                        "LS for FANUC)")
    p.add_argument("--force", action="store_true",
                   help="write the program even if verification fails (header says FORCED)")
    p.add_argument("--test-mode", action="store_true", help="first window only (CI)")
    p.set_defaults(_run=_run)
