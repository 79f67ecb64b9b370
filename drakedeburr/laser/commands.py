"""CLI: ``drakedeburr laser shape KIND ... -o prog.ls`` and ``drakedeburr laser tool``.

Sizes on the command line are millimetres and degrees (converted with drakedeburr.units).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from drakedeburr.argcheck import number

_POS = number(0, lo_open=True)
_NONNEG = number(0)
#: shape sizes and offsets [mm]: up to 5 m (beyond any robot's reach; 1e300 would overflow)
_SIZE = number(0.01, 5000, unit="mm")  # from 10 um (1e-300 mm broke the timing)
_NONNEG_SIZE = number(0, 5000, unit="mm")
#: the most contour points a program is planned with (a 100 mm hole at 0.2 mm: 1571)
MAX_POINTS = 200_000

_SIZES = {
    "circle": [("diameter", "hole diameter [mm]")],
    "semicircle": [("diameter", "diameter [mm]")],
    "rectangle": [("width", "width along x [mm]"), ("height", "height along y [mm]"),
                  ("corner-radius", "corner radius [mm] (default 0)")],
    "slot": [("length", "overall length [mm]"), ("width", "width [mm]")],
    "keyhole": [("head-diameter", "head diameter [mm]"), ("slot-width", "slot width [mm]"),
                ("slot-length", "head centre to slot-end centre [mm]")],
    "hexagon": [("across-flats", "size across flats [mm]")],
    "polyline": [],
}


def register(subparsers) -> None:
    laser = subparsers.add_parser("laser", help="laser cutting with the five-bar Cutting Tool")
    sub = laser.add_subparsers(dest="laser_command", metavar="ACTION")
    sub.required = True

    shape = sub.add_parser("shape", help="generate a hole/contour program (FANUC .ls)")
    kinds = shape.add_subparsers(dest="kind", metavar="KIND")
    kinds.required = True
    for kind, sizes in _SIZES.items():
        p = kinds.add_parser(kind, help=f"{kind} contour")
        for name, text in sizes:
            p.add_argument(f"--{name}", type=_NONNEG_SIZE if name == "corner-radius" else _SIZE,
                           required=name != "corner-radius",
                           default=0.0 if name == "corner-radius" else None, help=text)
        if kind == "polyline":
            p.add_argument("--points", required=True,
                           help="vertices 'x1,y1 x2,y2 ...' [mm] or a CSV file of x,y rows")
        _common(p)
        p.set_defaults(_run=_run_shape)

    tool = sub.add_parser("tool", help="show the Cutting Tool geometry and workspace figures")
    tool.add_argument("--sdf", type=Path, help="also write the tool's SDF model here")
    tool.set_defaults(_run=_run_tool)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--center", type=number(-5000, 5000, unit="mm"), nargs=2,
                   default=(0.0, 0.0), metavar=("X", "Y"),
                   help="shape origin [mm] (tool mode: offset from the tool's home point)")
    p.add_argument("--rotation", type=number(), default=0.0, help="rotation [deg]")
    p.add_argument("--lead-in", type=_NONNEG_SIZE, default=0.0, help="lead-in length [mm], >= 0")
    p.add_argument("--clockwise", action="store_true", help="cut clockwise")
    p.add_argument("--spacing", type=number(1e-3, 1000, unit="mm"), default=None,
                   help="point spacing [mm], 0.001 to 1000 (default 0.2 tool / 2 robot); at "
                        f"most {MAX_POINTS} points along the contour")
    p.add_argument("--mode", choices=("auto", "tool", "robot"), default="auto",
                   help="tool: Cutting Tool alone; robot: robot contour; auto: tool if it fits")
    p.add_argument("--feed", type=number(0, 600, lo_open=True, unit="m/min"), default=10.0,
                   help="cutting speed [m/min], > 0 and <= 600 (10 m/s)")
    p.add_argument("--servo-velocity", type=number(0, 1e4, lo_open=True, unit="rad/s"),
                   default=10.0, help="servo limit [rad/s], > 0")
    p.add_argument("--servo-acceleration", type=number(0, 1e6, lo_open=True, unit="rad/s^2"),
                   default=300.0, help="servo limit [rad/s^2], > 0")
    p.add_argument("--travel-angle", type=number(-90, 90, lo_open=True, hi_open=True),
                   default=0.0, help="robot mode [deg], between -90 and 90")
    p.add_argument("--work-angle", type=number(-90, 90, lo_open=True, hi_open=True),
                   default=0.0, help="robot mode [deg], between -90 and 90")
    p.add_argument("--robot-acceleration", type=number(0, 100, lo_open=True, unit="m/s^2"),
                   default=3.0,
                   help="robot mode TCP acceleration [m/s^2], > 0")
    p.add_argument("--min-command", type=number(0, 100, unit="V"), default=0.5,
                   help="laser command floor [V], >= 0")
    p.add_argument("--max-command", type=number(0, 100, lo_open=True, unit="V"), default=10.0,
                   help="laser command ceiling [V], > the floor")
    p.add_argument("--ao", type=number(1, integer=True), default=1,
                   help="analogue output port, >= 1")
    p.add_argument("--name", default=None, help="FANUC program name (default: from -o)")
    p.add_argument("-o", "--output", type=Path, required=True, help="output .ls file")
    p.add_argument("--summary", type=Path, help="also write a JSON summary here")


def _make_shape(args):
    from drakedeburr.errors import InputError
    from drakedeburr.laser import shapes
    from drakedeburr.units import m_from_mm, rad_from_deg

    common = dict(center=tuple(m_from_mm(c) for c in args.center),
                  rotation=rad_from_deg(args.rotation), lead_in=m_from_mm(args.lead_in),
                  clockwise=args.clockwise)
    if args.kind == "polyline":
        src = Path(args.points)
        if src.suffix.lower() in (".csv", ".txt") or src.is_dir():
            from drakedeburr.argcheck import input_file

            input_file(src, "polyline --points file")
        try:
            text = src.read_text() if src.is_file() else args.points.replace(" ", "\n")
            rows = [ln.replace(";", ",").split(",") for ln in text.splitlines() if ln.strip()]
            pts = tuple((m_from_mm(float(x)), m_from_mm(float(y))) for x, y in rows)
            bad = [v for p in pts for v in p if not (math.isfinite(v) and abs(v) <= 5.0)]
            if bad:
                raise ValueError(f"a coordinate of {bad[0] * 1e3:g} mm: each must be finite, "
                                 "|x|, |y| <= 5000 mm")
        except ValueError as exc:
            raise InputError(f"polyline --points {args.points!r}: expected x,y pairs in mm "
                             f"({exc})") from exc
        return shapes.Polyline(points=pts, **common)
    sizes = {name.replace("-", "_"): m_from_mm(getattr(args, name.replace("-", "_")))
             for name, _ in _SIZES[args.kind]}
    return shapes.SHAPE_KINDS[args.kind](**sizes, **common)


def _check_point_count(shape, args) -> None:
    """Refuse a --spacing that would give more than :data:`MAX_POINTS` contour points (the
    contour measured at 1 mm: at most ~31 000 points for the largest shape allowed)."""
    from drakedeburr.errors import InputError
    from drakedeburr.laser.shapes import build_contour
    from drakedeburr.units import m_from_mm

    spacing = 2.0 if args.spacing is None else args.spacing  # the larger default (robot)
    if args.spacing is None and args.mode != "robot":
        spacing = 0.2
    perimeter_mm = build_contour(shape, m_from_mm(1.0)).perimeter * 1e3
    if perimeter_mm / spacing > MAX_POINTS:
        raise InputError(f"--spacing {spacing:g} mm: the {shape.kind}'s {perimeter_mm:.4g} mm "
                         f"contour would have {perimeter_mm / spacing:.3g} points, more than "
                         f"the limit of {MAX_POINTS}; give a larger --spacing")


def _run_shape(args) -> int:
    from drakedeburr._io import atomic_write_json
    from drakedeburr.argcheck import output_file
    from drakedeburr.errors import InputError
    from drakedeburr.laser import fanuc_ls
    from drakedeburr.laser.feature import FeatureSettings, plan_contour
    from drakedeburr.laser.hole import ServoLimits, plan_hole
    from drakedeburr.laser.kinematics import FiveBarGeometry, check_reach
    from drakedeburr.laser.power import PowerMap
    from drakedeburr.laser.shapes import build_contour
    from drakedeburr.units import m_from_mm, rad_from_deg

    output_file(args.output, "-o/--output")
    output_file(args.summary, "--summary")
    from drakedeburr.argcheck import separate_outputs

    points = Path(args.points) if getattr(args, "points", None) else None
    separate_outputs({"-o/--output": args.output, "--summary": args.summary},
                     inputs={"the --points file": points if points and points.is_file() else
                             None})
    if args.output.suffix.lower() != ".ls":
        raise InputError(f"{args.output}: -o/--output is a FANUC program: a .ls file")
    if not args.max_command > args.min_command:
        raise InputError(f"--max-command {args.max_command:g} V must be above --min-command "
                         f"{args.min_command:g} V")
    fanuc_ls._check_name(args.name or args.output.stem)
    shape = _make_shape(args)
    _check_point_count(shape, args)
    feed = args.feed / 60.0
    power = PowerMap(nominal_speed=feed, min_command=args.min_command,
                     max_command=args.max_command, channel=args.ao)
    name = args.name or args.output.stem
    g = FiveBarGeometry()
    mode = args.mode
    if mode == "auto":
        probe = build_contour(shape, m_from_mm(0.5 if args.spacing is None else args.spacing))
        mode = "tool" if check_reach(g, g.p_CHome + probe.p_P).reachable.all() else "robot"
    if mode == "tool":
        limits = ServoLimits(velocity=args.servo_velocity,
                             acceleration=args.servo_acceleration, feed=feed)
        prog = plan_hole(shape, m_from_mm(0.2 if args.spacing is None else args.spacing), g,
                         limits, power)
        text = fanuc_ls.hole_program_ls(prog, name)
        summary = {"mode": "tool", "shape": shape.kind, "points": len(prog.q),
                   "perimeter_mm": prog.contour.perimeter * 1e3,
                   "area_mm2": prog.contour.area * 1e6, "cycle_time_s": prog.duration,
                   "max_speed_m_min": float(prog.v_tcp.max() * 60)}
    else:
        if args.feed <= 0:
            raise InputError(f"--feed must be > 0, got {args.feed}")
        settings = FeatureSettings(travel_angle=rad_from_deg(args.travel_angle),
                                   work_angle=rad_from_deg(args.work_angle),
                                   point_spacing=m_from_mm(2.0 if args.spacing is None
                                                           else args.spacing), speed=feed,
                                   acceleration=args.robot_acceleration)
        tg = plan_contour(shape, None, settings, power)
        text = fanuc_ls.contour_program_ls(tg, name)
        summary = {"mode": "robot", "shape": shape.kind, "points": len(tg),
                   "perimeter_mm": tg.contour.perimeter * 1e3,
                   "area_mm2": tg.contour.area * 1e6, "cycle_time_s": float(tg.t[-1]),
                   "max_speed_m_min": float(tg.speed.max() * 60)}
    fanuc_ls.write_ls(args.output, text)
    if args.summary:
        atomic_write_json(args.summary, summary, indent=2)
    sys.stdout.write(json.dumps(summary) + "\n")
    return 0


def _run_tool(args) -> int:
    import numpy as np

    from drakedeburr._io import atomic_write_text
    from drakedeburr.argcheck import output_file
    from drakedeburr.laser.kinematics import FiveBarGeometry, inverse_kinematics
    from drakedeburr.laser.kinematics import singularity_measures as sm
    from drakedeburr.laser.model import five_bar_sdf

    output_file(args.sdf, "--sdf")
    g = FiveBarGeometry()
    a = np.linspace(0, 2 * np.pi, 181)
    rr = np.linspace(0, g.work_radius, 11)
    p = np.array([g.p_CHome + r * np.array([np.cos(x), np.sin(x)]) for r in rr for x in a])
    q, ok = inverse_kinematics(g, p)
    m = sm(g, q)
    out = {"l0_mm": g.l0 * 1e3, "l1_mm": g.l1 * 1e3, "l2_mm": g.l2 * 1e3, "l3_mm": g.l3 * 1e3,
           "l4_mm": g.l4 * 1e3, "home_mm": (g.p_CHome * 1e3).tolist(),
           "working_disc_mm": 2e3 * g.work_radius, "reachable": bool(ok.all()),
           "max_condition": float(m["condition"].max()),
           "min_serial_sine": float(min(m["serial_1"].min(), m["serial_2"].min())),
           "min_parallel_sine": float(m["parallel"].min())}
    if args.sdf:
        atomic_write_text(args.sdf, five_bar_sdf(g))
    sys.stdout.write(json.dumps(out, indent=2) + "\n")
    return 0
