"""``drakedeburr post``: CL/APT file -> ABB RAPID, KUKA KRL or FANUC LS program."""

from __future__ import annotations

import argparse
import logging

__all__ = ["register"]

log = logging.getLogger(__name__)


def _six(text: str) -> list[float]:
    parts = [p for p in text.replace(";", ",").split(",") if p.strip()]
    try:
        return [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y,z,rx,ry,rz numbers, got {text!r}") from None


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "post", help="post-process a CL/APT file into a robot program",
        description="Read a CAM cutter-location file (NX CLSF, Creo, APT), solve the robot's "
                    "joints with the analytic IK and write an ABB RAPID, KUKA KRL or FANUC LS "
                    "program. CL coordinates are in the robot base frame unless --wobj is given. "
                    "Unreachable points are listed with their CL line numbers and no program "
                    "is written unless --force (then the header says FORCED).")
    p.add_argument("cl_file", help="the .cl / CLSF / APT file")
    p.add_argument("--robot", default="irb1600", choices=["irb1600"], help="robot model")
    p.add_argument("--format", dest="fmt", required=True, choices=["rapid", "krl", "ls"])
    p.add_argument("-o", "--output", required=True,
                   help="program file (.mod / .src (+ .dat beside it) / .ls)")
    p.add_argument("--wobj", type=_six, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="work object (CL frame) in the robot base: mm, deg, R = Rz Ry Rx")
    p.add_argument("--tool", type=_six, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="TCP in the flange frame: mm, deg (default 0,0,200,0,0,0)")
    p.add_argument("--units", default="mm", choices=["mm", "inch"],
                   help="CL length unit until a UNITS statement (NX CLSF files: often inch)")
    p.add_argument("--spin", default="min_travel",
                   choices=["min_travel", "greedy", "theta6_zero"],
                   help="rule for the free rotation about the tool axis")
    p.add_argument("--zone", type=float, default=1.0, help="corner zone of feed moves [mm]")
    p.add_argument("--feed", type=float, default=None,
                   help="feed-move TCP speed [mm/s] (default: the file's FEDRAT)")
    p.add_argument("--name", default=None, help="program name (default from the file name)")
    p.add_argument("--force", action="store_true",
                   help="write the program even if points are unreachable (they are left out)")
    p.set_defaults(_run=_run_post)


def _run_post(args) -> int:
    import re
    from pathlib import Path

    from drakedeburr.cli import tqdm_progress
    from drakedeburr.errors import InputError
    from drakedeburr.post.cl_post import ROBOTS, pose_from_mm_deg, program_from_cl
    from drakedeburr.post.cl_reader import read_cl
    from drakedeburr.programs.writers import write_program
    from drakedeburr.units import m_from_mm

    cl = read_cl(args.cl_file, units=args.units)
    for w in cl.warnings:
        log.warning("%s:%d: %s: %s", Path(args.cl_file).name, w.line, w.word, w.message)
    X_WO = pose_from_mm_deg(args.wobj, "--wobj") if args.wobj is not None else None
    X_FT = pose_from_mm_deg(args.tool if args.tool is not None else [0, 0, 200, 0, 0, 0], "--tool")
    name = args.name or re.sub(r"[^A-Za-z0-9_]", "_", Path(args.cl_file).name.split(".")[0])
    if not name[:1].isalpha():
        name = "p" + name
    name = name[:24]
    if args.feed is not None and not args.feed > 0:
        raise InputError(f"--feed must be > 0 mm/s, got {args.feed}")
    result = program_from_cl(
        cl, name, robot=ROBOTS[args.robot], X_WO=X_WO, X_FT=X_FT, spin_mode=args.spin,
        zone=m_from_mm(args.zone), feed=None if args.feed is None else m_from_mm(args.feed),
        force=args.force, progress=tqdm_progress("IK"))
    if result.unreachable_lines:
        shown = ", ".join(map(str, result.unreachable_lines[:30]))
        more = "" if len(result.unreachable_lines) <= 30 else " ..."
        log.error("%d CL point(s) unreachable for %s at line(s): %s%s",
                  len(result.unreachable_lines), args.robot, shown, more)
    if result.program is None:
        log.error("no program written%s", "" if args.force else " (use --force to write the "
                  "reachable part, flagged FORCED)")
        return 1
    paths = write_program(result.program, args.output, args.fmt)
    for path in paths:
        log.info("wrote %s", path)
    return 1 if result.unreachable_lines else 0
