"""CLI: ``drakedeburr verify`` and ``drakedeburr verify-all``.

``verify TARGET`` where TARGET is
  * a saved plan (folder or file, read with ``drakedeburr.plan.io.load_plan``),
  * ``SCENARIO/HUB`` (bundled names, e.g. ``tool_in_hand/h5_straight``) or a hub folder, or
  * a hub mesh file (``.stl``/``.obj``/``.ply``): imported into a hub model folder first
    (``drakedeburr hub import``: window edges, CoACD collision pieces; cached under
    ``--hub-cache``, default OUT_hub_import beside OUT, beside --json/--html, else the user
    cache);
for a hub or mesh the hub is planned first, then verified. Exit 0 pass, 1 fail, 2 bad input.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from drakedeburr.argcheck import number
from drakedeburr.hub.mesh_io import MESH_TARGET_SUFFIXES
from drakedeburr.units import m_from_mm

log = logging.getLogger(__name__)



def _windows(text: str | None) -> list[int] | None:
    from drakedeburr.argcheck import parse_windows

    windows = parse_windows(text)
    return None if windows is None else list(windows)


#: bytes the outputs take at least: a plan folder per window, an HTML report with the replay
_PLAN_BYTES_PER_WINDOW = 400_000
_HTML_BYTES = 4_000_000


def _is_output_folder(folder: Path) -> bool:
    """-o/--out holds our plan, or our report of a mesh with nothing to cut."""
    from drakedeburr.plan.io import is_plan_folder
    from drakedeburr.verify.report import is_report_folder

    return is_plan_folder(folder) or is_report_folder(folder)


def _check_outputs(args: argparse.Namespace, kind: str, target, hub=None) -> None:
    """Output paths and the program file, before any work."""
    from drakedeburr import argcheck
    from drakedeburr.errors import InputError

    argcheck.output_file(args.json, "--json")
    argcheck.output_file(args.html, "--html")
    if args.html:
        argcheck.free_space(Path(args.html).parent, _HTML_BYTES, "--html")
    if kind == "plan":
        if args.out:
            raise InputError(f"-o/--out {args.out}: only for a hub or mesh target; the report "
                             f"of the plan {target} goes into its folder")
        argcheck.output_folder(target, "the plan folder (its report is written into it)")
    else:
        argcheck.output_folder(args.out, "-o/--out", is_ours=_is_output_folder)
        if args.out:
            argcheck.free_space(args.out, _PLAN_BYTES_PER_WINDOW + _HTML_BYTES, "-o/--out")
        argcheck.output_folder(args.hub_cache, "--hub-cache")
    if args.program:
        argcheck.input_file(args.program, "--program file")
    files = {"--json": args.json, "--html": args.html}
    program = {"the --program file": args.program}
    if kind == "plan":
        argcheck.separate_outputs(files, inputs=program,
                                  input_folders={"the plan folder": target})
    else:
        hub = Path(hub or "")
        mesh = hub.suffix.lower() in MESH_TARGET_SUFFIXES
        argcheck.separate_outputs(
            files, inputs={**program, "the hub mesh": hub if mesh else None},
            input_folders={"the hub folder": hub if hub.is_dir() else None},
            output_folders={"-o/--out": args.out})


def _resolve_target(target: str, scenario: str | None):
    """-> ("plan", path) or ("hub", scenario, hub)."""
    from drakedeburr.errors import InputError
    from drakedeburr.resources import hub_names, scenario_names

    path = Path(target)
    if path.suffix.lower() in MESH_TARGET_SUFFIXES:
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such hub mesh file")
        from drakedeburr._io import check_regular_file

        check_regular_file(path, "hub mesh", "mesh")
        return ("hub", scenario or "tool_in_hand", str(path))
    if path.is_dir() and (path / "hub.yaml").is_file():
        return ("hub", scenario or "tool_in_hand", str(path))
    if path.exists():
        return ("plan", path)
    parts = target.split("/")
    if len(parts) == 2 and parts[0] in scenario_names():
        return ("hub", parts[0], parts[1])
    if target in hub_names():
        return ("hub", scenario or "tool_in_hand", target)
    raise InputError(f"{target!r} is neither a plan, a hub folder or mesh file, nor "
                     f"SCENARIO/HUB with SCENARIO in {scenario_names()} (hubs: {hub_names()})")


def _load_plan(path: Path):
    from drakedeburr.errors import InputError

    try:
        from drakedeburr.plan.io import load_plan
    except ImportError as exc:
        raise InputError(f"{path}: reading saved plans needs drakedeburr.plan.io.load_plan "
                         "(planning stage)") from exc
    return load_plan(path)


def _hub_cache(args: argparse.Namespace) -> Path:
    """Where an imported mesh's hub folder goes: --hub-cache, else beside the outputs, else
    the user cache (never the package's models folder)."""
    if args.hub_cache:
        return Path(args.hub_cache)
    if args.out:  # beside the plan folder (which is replaced whole on every run)
        out = Path(args.out).resolve()
        return out.parent / f"{out.name}_hub_import"
    for f in (args.json, args.html):
        if f:
            return Path(f).resolve().parent / "hub_import"
    import os

    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "drakedeburr" / "hubs"


def _import_mesh(mesh: str, args: argparse.Namespace) -> tuple[str, list[str]]:
    """Import a hub mesh file (cached): its hub folder and what the import changed (a tyre
    dropped; said again when the folder comes from the cache)."""
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.hub.import_mesh import ImportOptions, import_mesh
    from drakedeburr.units import m_from_mm as mm

    width = args.min_window_width_mm
    options = ImportOptions(unit=args.unit, front=args.front, burr_diameter=mm(args.burr_mm),
                            clearance=mm(args.clearance_mm),
                            min_window_width=None if width is None else mm(width))
    res = import_mesh(mesh, _hub_cache(args), options=options,
                      progress=tqdm_progress("import mesh"))
    log.info("%s: %s hub folder %s (%d windows, %d collision pieces)", mesh,
             "cached" if res.cached else "imported", res.dir, res.window_count,
             res.piece_count)
    notes = [n for n in [res.summary.get("import", {}).get("dropped")] if n]
    if res.cached:
        for note in notes:
            log.warning("%s: %s", mesh, note)
    return str(res.dir), notes


def _config(args: argparse.Namespace, scenario: str, hub: str):
    from drakedeburr.config import load_config

    speed = None if args.grinding_speed is None else m_from_mm(args.grinding_speed)
    from drakedeburr.cell.loads import arm_or_rated_default

    # no --robot: the scenario's arm, or one rated for what it carries (workpiece in hand)
    robot = arm_or_rated_default(getattr(args, "robot", None), scenario, hub)
    return load_config(scenario, hub, tolerances=_tolerances(args), grinding_speed=speed,
                       robot=robot, tool=getattr(args, "tool", None))


def _same_robot(plan, robot: str | None) -> None:
    """A plan is verified for the arm it was made for: --robot must name it (or be left out)."""
    if robot is None:
        return
    from drakedeburr.errors import InputError
    from drakedeburr.programs.plan_program import plan_robot
    from drakedeburr.robots import get_robot

    made_for = plan_robot(plan)
    if get_robot(robot) is not made_for:
        raise InputError(f"--robot {robot}: the plan was made for {made_for.name}; re-plan the "
                         "hub with --robot to verify it for another arm")


def _tolerances(args: argparse.Namespace):
    from drakedeburr.config import default_tolerances
    from drakedeburr.verify.checks import QUICK_SAMPLING

    return default_tolerances(**QUICK_SAMPLING) if args.quick else None


def _read_program_file(path: str | None):
    """The --program file read (strictly) before any work, or None."""
    if path is None:
        return None
    from drakedeburr.programs import read_program

    return read_program(path)


def _program_item(plan, actual):
    """The program_file item (kept for callers; :mod:`drakedeburr.post.program_check`)."""
    from drakedeburr.post.program_check import program_file_item

    return program_file_item(plan, actual)


def _print_report(report) -> None:
    width = max(len(i.name) for i in report.items)
    for it in report.items:
        mark = "PASS" if it.passed else ("FAIL" if it.required else "miss")
        value = "" if it.value is None else f"{it.value:.4g} {it.unit}"
        limit = "" if it.limit is None else f"{it.comparison} {it.limit:.4g}"
        where = "" if it.window is None else f" [window {it.window}" + (
            f", t={it.time:.3f} s" if it.time is not None else "") + "]"
        pair = f" {it.pair[0]} <-> {it.pair[1]}" if it.pair and not it.passed else ""
        print(f"{mark}  {it.name:<{width}}  {value:>16} {limit:<14}{where}{pair}")
        if (it.name in ("program_file", "windows") or it.name.startswith("controller_")) and (
                not it.passed or it.comparison == "info") and it.detail:
            print(f"      {it.detail}")
    print("PASSED" if report.passed else "FAILED: " + ", ".join(report.failed))


def _run_verify(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from drakedeburr.argcheck import check_windows, hub_windows

    windows = _windows(args.windows)
    kind, *rest = _resolve_target(args.target, args.scenario)
    folder, import_notes = None, []
    if kind == "plan":
        folder = Path(rest[0])
        folder = folder.parent if folder.name == "plan.json" else folder
        _check_outputs(args, kind, folder)
        plan = _load_plan(folder)
        _same_robot(plan, getattr(args, "robot", None))
        check_windows(windows, hub_windows(plan.hub), Path(plan.hub).name)
    else:
        scenario, hub = rest
        _check_outputs(args, kind, None, hub)
        from drakedeburr.resources import scenario_path

        scenario_path(scenario)
    program = _read_program_file(args.program)
    if kind == "plan" and len(plan.trajectory.t) >= 2:
        from drakedeburr.verify.sweep import warm_workers_for_plan

        # the sweep's workers start now, their imports and cell overlapping this process's
        # (hence before the imports below)
        warm_workers_for_plan(plan)
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.plan.io import save_plan
    from drakedeburr.verify.batch import make_plan
    from drakedeburr.verify.checks import config_for_plan, verify_plan
    from drakedeburr.verify.html import write_report_files
    from drakedeburr.verify.report import write_report_json

    if kind == "plan":
        speed = None if args.grinding_speed is None else m_from_mm(args.grinding_speed)
        config = config_for_plan(plan, tolerances=_tolerances(args), grinding_speed=speed)
    else:
        if Path(hub).suffix.lower() in MESH_TARGET_SUFFIXES:
            from drakedeburr.errors import NoCuttableWindow

            try:
                hub, import_notes = _import_mesh(hub, args)
            except NoCuttableWindow as exc:
                return _no_window(args, exc, scenario)
        check_windows(windows, hub_windows(hub), Path(hub).name)
        config = _config(args, scenario, hub)
        plan = make_plan(config, args.planner, windows, progress=tqdm_progress("plan"))
        if args.out:
            folder = save_plan(plan, args.out, is_ours=_is_output_folder)
    from drakedeburr.cell.station import load_plan_cell

    cell = load_plan_cell(plan)  # built once: the sampling and the report's replay share it
    report = verify_plan(plan, config, expected_windows=windows, cell=cell,
                         progress=tqdm_progress("verify"))
    if import_notes:  # what the mesh import changed (a tyre dropped) goes with the report
        report = replace(report, plan_info={**report.plan_info, "import_notes": import_notes})
    if program is not None:
        from drakedeburr.post.program_check import program_items

        items = (*report.items, *program_items(plan, program, cell, config.tolerances,
                                               config=config))
        report = replace(report, items=items,
                         passed=all(i.passed for i in items if i.required))
    written = ()
    if folder is not None:
        written = write_report_files(report, folder, plan=plan, replay=not args.no_replay,
                                     cell=cell)
        for path in written:
            log.info("wrote %s", path)
    if args.json:
        write_report_json(report, args.json)
    if args.html and written:  # the page just written into the folder: not drawn again
        from drakedeburr._io import atomic_write_bytes
        from drakedeburr.verify.gate import REPORT_HTML

        atomic_write_bytes(Path(args.html), (folder / REPORT_HTML).read_bytes())
    elif args.html:
        from drakedeburr.verify.html import meshcat_replay_html, write_report_html

        write_report_html(report, args.html,
                          replay_html=None if args.no_replay else meshcat_replay_html(plan,
                                                                                      cell))
    _print_report(report)
    return 0 if report.passed else 1


def _no_window(args: argparse.Namespace, exc, scenario: str) -> int:
    """A readable mesh with nothing to cut: the report says why (every opening and outline
    with its reason) into -o (a report-only folder, written whole), --json and --html;
    exit 1."""
    from drakedeburr._io import atomic_folder
    from drakedeburr.config import default_tolerances
    from drakedeburr.verify.checks import no_window_report
    from drakedeburr.verify.html import write_report_files
    from drakedeburr.verify.report import write_report_json

    report = no_window_report(exc, scenario, _tolerances(args) or default_tolerances())
    if args.out:
        with atomic_folder(args.out, is_ours=_is_output_folder) as tmp:
            write_report_files(report, tmp)
        log.info("wrote the report into %s", args.out)
    if args.json:
        write_report_json(report, args.json)
    if args.html:
        from drakedeburr.verify.html import write_report_html

        write_report_html(report, args.html)
    _print_report(report)
    print(f"{exc.source}: no window can be cut (pass --front if the face taken is the wrong "
          "one)")
    return 1


def _run_verify_all(args: argparse.Namespace) -> int:
    from drakedeburr import argcheck
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.errors import InputError
    from drakedeburr.resources import scenario_path
    from drakedeburr.verify.batch import JobSettings, summary_markdown, verify_all

    if not Path(args.hubs).is_dir():
        raise InputError(f"{args.hubs}: no such catalogue folder (a folder of hub folders)")
    argcheck.output_folder(args.out, "-o/--out")
    for scenario in args.scenario or []:
        scenario_path(scenario)
    argcheck.scheduler_address(args.scheduler)
    from drakedeburr._io import check_path_name
    from drakedeburr.verify.batch import hub_folders

    for hub in hub_folders(args.hubs):  # each becomes OUT/SCENARIO/HUB
        check_path_name(hub.name, f"{args.hubs}: hub folder")

    scenarios = args.scenario or ["tool_in_hand", "workpiece_in_hand"]
    settings = JobSettings(
        planner=args.planner, windows=_windows(args.windows), quick=args.quick, html=args.html,
        grinding_speed=None if args.grinding_speed is None else m_from_mm(args.grinding_speed))
    summary = verify_all(
        args.hubs, args.out, scenarios=scenarios, workers=args.workers,
        scheduler=args.scheduler, settings=settings, progress=tqdm_progress("verify-all"))
    print(summary_markdown(summary), end="")
    return 0 if summary["passed"] else 1


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--planner", choices=("plan_hub", "reference"), default="plan_hub",
                   help="who plans a hub before verification: the planning stage (default) or "
                        "the verifier's reference plan (fixed axis, for testing the verifier)")
    p.add_argument("--windows", help="comma-separated window indices to plan and expect "
                                     "(default: all windows of the hub)")
    p.add_argument("--quick", action="store_true",
                   help="coarse sampling (2 mm / 0.1 s): a smoke test, not a certificate")
    p.add_argument("--grinding-speed", type=number(0, lo_open=True, unit="mm/s"), default=None,
                   metavar="MM_PER_S", help="process speed [mm/s], > 0 (default: the hub's "
                                            "recipe, 150)")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "verify", help="re-check a plan densely and independently (plan first for a hub)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", help="plan folder/file, SCENARIO/HUB, hub folder or mesh file")
    p.add_argument("--scenario", help="cell for a hub folder/mesh (default tool_in_hand)")
    p.add_argument("--json", help="write the JSON report here")
    p.add_argument("--html", help="write the self-contained HTML report here")
    p.add_argument("-o", "--out", help="for a hub or mesh: the plan folder to write (the plan, "
                                       "report.json and report.html); a plan folder target "
                                       "always gets its report written into it")
    p.add_argument("--program", metavar="FILE",
                   help="also read this RAPID/KRL/LS program back and check it against the "
                        "plan (a changed speed, zone, pose, configuration or move order fails, "
                        "naming the line)")
    p.add_argument("--no-replay", action="store_true", help="HTML without the Meshcat replay")
    p.add_argument("--hub-cache", help="folder for the hub model imported from a mesh target "
                                       "(default: OUT_hub_import beside OUT, beside "
                                       "--json/--html, or ~/.cache/drakedeburr/hubs)")
    p.add_argument("--unit", choices=("m", "mm"),
                   help="unit of a mesh target (default: detected from its size)")
    from drakedeburr.hub.commands import add_front_and_burr

    add_front_and_burr(p)  # mesh target: --front, --burr-mm, --clearance-mm, ...
    p.add_argument("--robot", metavar="NAME|FILE", default=None,
                   help="hub or mesh target: the arm to plan for (drakedeburr robots, or an "
                        "arm file *.yaml; default "
                        "the scenario's); a plan is verified for the arm it was made for")
    from drakedeburr.plan.commands import add_tool_argument

    add_tool_argument(p)
    _common(p)
    p.set_defaults(_run=_run_verify)

    p = subparsers.add_parser(
        "verify-all", help="verify every hub model of a catalogue (parallel / Dask)",
        description="Plan and verify every hub folder (*/hub.yaml) under HUBS in each cell; "
                    "write OUT/summary.json, OUT/summary.md and one report per hub.")
    p.add_argument("hubs", help="catalogue folder, e.g. models/hubs")
    p.add_argument("-o", "--out", default="verify-all", help="output folder")
    p.add_argument("--scenario", action="append",
                   help="cell(s) to verify in (repeatable; default: both bundled cells)")
    p.add_argument("-j", "--workers", type=number(1, integer=True), default=1,
                   help="local processes (>= 1)")
    p.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786)")
    p.add_argument("--html", action="store_true", help="also write report.html per hub")
    _common(p)
    p.set_defaults(_run=_run_verify_all)
