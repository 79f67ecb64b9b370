"""``drakedeburr post``: CL/APT file -> ABB RAPID, KUKA KRL or FANUC LS program.

Exit codes: 0 written; 1 ran but points are unreachable (nothing written, or with --force the
reachable part, flagged FORCED); 2 bad input (one line naming file, item and what is wrong);
130 interrupted (earlier outputs untouched: files are written atomically).

The options are built in groups (:func:`add_input_options`, :func:`add_cell_options`,
:func:`add_output_options`) and turned into library settings by :func:`settings_from_args`,
so a new cell option (a robot, workpiece in hand) is one argument plus one line there.
"""

from __future__ import annotations

import argparse
import logging
import os
from pathlib import Path

__all__ = ["register", "add_input_options", "add_cell_options", "add_output_options",
           "settings_from_args", "program_name"]

log = logging.getLogger(__name__)

_WORDS_SHOWN = 30  # words-not-applied lines shown on the console


def add_input_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("cl_file", help="the .cl / CLSF / APT file")
    p.add_argument("--units", default="mm", choices=["mm", "inch"],
                   help="CL length unit until a UNITS statement (NX CLSF files: often inch); "
                        "a UNITS switch after moves is honoured and reported")
    p.add_argument("--ignore-cutcom", action="store_true",
                   help="accept CUTCOM/TLCOMP (cutter compensation) by taking the CL points as "
                        "the tool centre; without it such files are refused")


def add_cell_options(p: argparse.ArgumentParser) -> None:
    from drakedeburr.argcheck import six_numbers
    from drakedeburr.robots import robot_names

    p.add_argument("--robot", default="irb1600", metavar="NAME|FILE",
                   help=f"registered arm ({', '.join(robot_names())}; drakedeburr robots) or "
                        "an arm file (*.yaml, docs/robots.md); its controller's format is the "
                        "default --format")
    p.add_argument("--workpiece-in-hand", action="store_true",
                   help="the robot holds the part against a stationary spindle: --tool is the "
                        "spindle's TCP in the robot base (required), --wobj the part's CL "
                        "frame in the flange frame (default: the flange frame); the program "
                        "uses a stationary tool (ABB), an external TCP (KUKA), RTCP (FANUC)")
    p.add_argument("--virtual-tcp", action="store_true",
                   help="with --workpiece-in-hand: the paper's virtual-TCP program instead "
                        "(source 000; no RTCP / external-TCP option): an ordinary TCP set "
                        "at a reference pose, user frame = the spindle, targets = the CL "
                        "points mirrored; the CL tool axis must be constant")
    p.add_argument("--reference", type=six_numbers, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="with --virtual-tcp: the part's CL frame in the spindle's TCP frame at "
                        "the reference pose (mm, deg; default: on the TCP, the CL axis onto "
                        "-Z, the spin about it chosen for reach and least joint travel)")
    p.add_argument("--wobj", type=six_numbers, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="work object (CL frame, after MSYS) in the robot base: mm, deg, "
                        "R = Rz Ry Rx (with --workpiece-in-hand: in the flange frame)")
    p.add_argument("--tool", type=six_numbers, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="TCP in the flange frame: mm, deg (default 0,0,200,0,0,0); with "
                        "--workpiece-in-hand the stationary spindle's TCP in the robot base")
    p.add_argument("--spin", default="min_travel",
                   choices=["min_travel", "greedy", "theta6_zero"],
                   help="rule for the free rotation about the tool axis")
    p.add_argument("--zone", type=float, default=1.0, help="corner zone of feed moves [mm]")
    p.add_argument("--feed", type=float, default=None,
                   help="feed-move TCP speed [mm/s] (default: the file's FEDRAT); within what "
                        "the arm can move and the language holds (RAPID 7000, KRL and LS "
                        "2000 mm/s), else refused")
    p.add_argument("--force", action="store_true",
                   help="write the program even if points are unreachable (they are left out)")
    p.add_argument("--io", type=Path, default=None, metavar="YAML",
                   help="outputs for the file's SPINDL / COOLNT (PostIO fields: spindle_do, "
                        "spindle_ao, spindle_rpm_full_scale, coolant_do, RAPID signal names, "
                        "AO full scales; docs/post.md); without it they are not written")


def add_output_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--format", dest="fmt", default=None, choices=["rapid", "krl", "ls"],
                   help="program format (default: the arm's controller's: RAPID for ABB, KRL "
                        "for KUKA, LS for FANUC; another one is refused)")
    p.add_argument("-o", "--output", required=True,
                   help="program file (.mod / .src (+ .dat beside it) / .ls)")
    p.add_argument("--name", default=None, help="program name (default from the file name)")
    p.add_argument("--max-moves", type=int, default=None, metavar="N",
                   help="moves per program file (default 100000); a longer program is written "
                        "as numbered parts FILE_001, FILE_002, ... each continuing the last")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "post", help="post-process a CL/APT file into a robot program",
        description="Read a CAM cutter-location file (NX CLSF, Creo, APT): every tool path in "
                    "file order, MSYS and UNITS applied, drilling cycles expanded into moves; "
                    "solve the robot's joints with the analytic IK and write an ABB RAPID, "
                    "KUKA KRL or FANUC LS program. CL coordinates are in the robot base frame "
                    "unless --wobj is given. Words of the file not in the program are listed "
                    "once each. Unreachable points are listed with their CL line numbers and "
                    "no program is written unless --force (then the header says FORCED). "
                    "Exit codes: 0 written, 1 unreachable points, 2 bad input, 130 "
                    "interrupted.")
    add_input_options(p)
    add_cell_options(p)
    add_output_options(p)
    p.set_defaults(_run=_run_post)
    from drakedeburr.post.calibrate_cmd import register as register_calibrate

    register_calibrate(subparsers)


def program_name(cl_file: str, name: str | None, fmt: str = "rapid") -> str:
    """The program name: ``--name`` if it is an identifier of the format's language (else
    refused, exit 2), otherwise the CL file's name cleaned into one (at most 24 characters;
    :mod:`drakedeburr.programs.names`). KRL and LS programs take their output file's name when
    written."""
    from drakedeburr.programs.names import check_identifier, clean_identifier

    if name is not None:
        check_identifier(name, fmt, "--name", "program name")
        if len(name) > 24:
            from drakedeburr.errors import InputError

            raise InputError(f"--name {name!r}: at most 24 characters (a long program is "
                             "written in parts named NAME_001, ...)")
        return name
    return clean_identifier(Path(cl_file).name.split(".")[0], fmt, fallback="Deburr",
                            max_length=24)


def _check_args(args) -> None:
    """Everything that can be checked before reading the file."""
    from drakedeburr.errors import InputError

    cl = Path(args.cl_file)
    if not cl.exists():
        raise InputError(f"{cl}: CL file not found")
    from drakedeburr._io import check_regular_file

    check_regular_file(cl, "CL file", "cl")  # a regular file within READ_LIMITS["cl"]
    if not args.zone >= 0:
        raise InputError(f"--zone must be >= 0 mm, got {args.zone}")
    if args.workpiece_in_hand and args.tool is None:
        raise InputError("--workpiece-in-hand: give the stationary spindle's TCP in the robot "
                         "base with --tool X,Y,Z,RX,RY,RZ (mm, deg)")
    if getattr(args, "virtual_tcp", False) and not args.workpiece_in_hand:
        raise InputError("--virtual-tcp: the virtual TCP is for a held part: add "
                         "--workpiece-in-hand (and the spindle's TCP with --tool)")
    if getattr(args, "reference", None) is not None and not getattr(args, "virtual_tcp", False):
        raise InputError("--reference: only with --virtual-tcp")
    if args.max_moves is not None and args.max_moves < 1:
        raise InputError(f"--max-moves must be >= 1, got {args.max_moves}")
    out = Path(args.output)
    if out.is_dir():
        raise InputError(f"{out}: --output is a folder, give a file name")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"{out}: the output folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise InputError(f"{out}: the output folder {parent} is not writable")


def settings_from_args(args):
    """:class:`~drakedeburr.post.cl_post.PostSettings` from the parsed options."""
    from drakedeburr.post.cl_post import PostSettings, pose_from_mm_deg, robot_kinematics
    from drakedeburr.units import m_from_mm

    wobj = pose_from_mm_deg(args.wobj, "--wobj") if args.wobj is not None else None
    stationary = bool(getattr(args, "workpiece_in_hand", False))
    if stationary:  # spindle fixed in the base, the part's CL frame on the flange
        X_WO, X_FT = pose_from_mm_deg(args.tool, "--tool"), wobj
    else:
        X_WO = wobj
        X_FT = pose_from_mm_deg(args.tool if args.tool is not None else [0, 0, 200, 0, 0, 0],
                                "--tool")
    io = None
    if getattr(args, "io", None) is not None:
        from drakedeburr.argcheck import input_file
        from drakedeburr.config import dataclass_from_yaml
        from drakedeburr.post.cl_post import PostIO

        input_file(args.io, "--io")
        io = dataclass_from_yaml(PostIO, args.io)  # names the file and the field
    return PostSettings(
        robot=robot_kinematics(args.robot), X_WO=X_WO, X_FT=X_FT,
        spin_mode=args.spin, zone=m_from_mm(args.zone),
        feed=None if args.feed is None else m_from_mm(args.feed), force=args.force,
        stationary_tool=stationary, io=io)


def _phase_progress():
    """One tqdm bar per phase label (read CL, spin + IK, write)."""
    from drakedeburr.cli import tqdm_progress

    bars: dict = {}

    def update(done: int, total: int, label: str = "") -> None:
        if label not in bars:
            bars[label] = tqdm_progress(label)
        bars[label](done, total, "")

    return update


def _report(summary, robot: str, io=None) -> None:
    cl = summary.cl
    for line in cl.summary():
        if not line.startswith("not applied:"):
            log.info("%s", line)
    for w in cl.read_words:  # read, and not needed for the robot's motion
        log.info("read, not needed: %s", w.describe())
    for line, unit, before in cl.mid_file_unit_changes:
        log.warning("%s:%d: UNITS switched to %s after %d moves: the following coordinates "
                    "are read in %s", Path(cl.source).name, line, unit, before, unit)
    written = io.words if io is not None else frozenset()
    words = [w for w in cl.not_applied if w.word not in written]
    for w in cl.not_applied:
        if w.word in written:
            log.info("%s x%d written to the outputs of --io", w.word, w.count)
    if words:
        log.warning("%d word(s) of the file are not in the program:", len(words))
        for w in words[:_WORDS_SHOWN]:
            log.warning("  %s", w.describe())
        if len(words) > _WORDS_SHOWN:
            log.warning("  ... %d more", len(words) - _WORDS_SHOWN)
    for w in cl.warnings:
        log.warning("%s:%d: %s: %s", Path(cl.source).name, w.line, w.word, w.message)
    extra = sum(cl.warning_counts.values()) - len(cl.warnings)
    if extra > 0:
        log.warning("... and %d more warnings of the same kinds", extra)
    if summary.unreachable_lines:
        shown = ", ".join(map(str, summary.unreachable_lines[:30]))
        more = "" if len(summary.unreachable_lines) <= 30 else " ..."
        log.error("%d CL point(s) unreachable for %s at line(s): %s%s",
                  len(summary.unreachable_lines), robot, shown, more)


def _run_post(args) -> int:
    from drakedeburr.errors import InputError
    from drakedeburr.post.cl_post import MAX_MOVES, PostOutput, post_cl_file
    from drakedeburr.post.cl_reader import ClReadOptions
    from drakedeburr.programs.writers import format_for_controller

    _check_args(args)
    from drakedeburr.argcheck import separate_outputs

    separate_outputs({"-o/--output": args.output}, inputs={"the CL file": args.cl_file})
    settings = settings_from_args(args)
    own = format_for_controller(settings.robot.controller)
    if args.fmt is not None and args.fmt != own:
        raise InputError(f"--format {args.fmt}: {args.robot} has a {settings.robot.controller} "
                         f"controller, which runs {own.upper()} (--format {own})")
    post, extra = post_cl_file, {}
    if getattr(args, "virtual_tcp", False):
        from drakedeburr.post.cl_post import pose_from_mm_deg
        from drakedeburr.post.virtual_tcp_post import post_cl_file_virtual_tcp

        post = post_cl_file_virtual_tcp
        if args.reference is not None:
            extra["X_OP"] = pose_from_mm_deg(args.reference, "--reference")
    name = program_name(args.cl_file, args.name, args.fmt or own)
    stem = Path(args.output).name.split(".")[0]
    if args.name is not None and (args.fmt or own) != "rapid" and args.name.lower() != (
            stem.lower()):
        log.warning("--name %s: a %s program takes its file's name (%s)", args.name,
                    (args.fmt or own).upper(), stem)
    if args.feed is not None:  # the arm's and the language's range, before any work
        from drakedeburr.programs.speeds import check_speed
        from drakedeburr.units import m_from_mm

        check_speed(m_from_mm(args.feed), settings.robot, args.fmt or own, "--feed",
                    settings.frames()[1])
    try:
        summary = post(
            args.cl_file,
            PostOutput(args.output, args.fmt or format_for_controller(settings.robot.controller),
                       name, args.max_moves or MAX_MOVES),
            settings,
            ClReadOptions(units=args.units,
                          cutcom="ignore" if args.ignore_cutcom else "refuse"),
            progress=_phase_progress(), **extra)
    except KeyboardInterrupt:
        log.error("interrupted: nothing new written")
        return 130
    except OSError as exc:
        if isinstance(exc, FileNotFoundError) and Path(args.cl_file).exists():
            raise InputError(f"{args.output}: cannot write: {exc}") from exc
        raise InputError(f"{exc.filename or args.output}: {exc.strerror or exc}") from exc
    _report(summary, args.robot, settings.io)
    if not summary.files:
        log.error("no program written%s", "" if args.force else " (use --force to write the "
                  "reachable part, flagged FORCED)")
        return 1
    for path in summary.files:
        log.info("wrote %s", path)
    return 1 if summary.unreachable_lines else 0
