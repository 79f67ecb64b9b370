"""CLI: ``drakedeburr laser shape KIND ... -o prog.ls`` and ``drakedeburr laser tool``.

Sizes on the command line are millimetres and degrees (converted with drakedeburr.units).
The Cutting Tool's link lengths come from ``--links L0,L1,L2,L3,L4`` [mm] or a YAML file
(``--tool-file``: the keys ``laser tool`` prints, :data:`TOOL_KEYS`).
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


#: --tool-file keys [mm] -> FiveBarGeometry fields [m]; working/assembly modes are signs
TOOL_KEYS = {"l0_mm": "l0", "l1_mm": "l1", "l2_mm": "l2", "l3_mm": "l3", "l4_mm": "l4",
             "home_x_mm": "home_x", "work_radius_mm": "work_radius"}
_MODE_KEYS = ("working_mode", "assembly_mode")


def _links(text: str) -> tuple[float, ...]:
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected L0,L1,L2,L3,L4 in mm, got {text!r}") from None
    if len(v) != 5 or not all(x > 0 and x < 1e4 for x in v):
        raise argparse.ArgumentTypeError(f"expected 5 lengths L0,L1,L2,L3,L4 > 0 mm, got {text!r}")
    return v


def _six_mm_deg(text: str) -> tuple[float, ...]:
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z,W,P,R (mm, deg), got {text!r}") from None
    if len(v) != 6 or not all(abs(x) < 1e6 for x in v):
        raise argparse.ArgumentTypeError(f"expected 6 numbers X,Y,Z,W,P,R, got {text!r}")
    return v


def _geometry_fields(data, where: str) -> dict:
    from drakedeburr.errors import InputError
    from drakedeburr.units import m_from_mm

    if not isinstance(data, dict):
        raise InputError(f"{where}: expected a mapping of {sorted(TOOL_KEYS)}")
    fields: dict = {}
    for key, value in data.items():
        if key in TOOL_KEYS:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"{where}: {key}: expected a length in mm, got {value!r}")
            fields[TOOL_KEYS[key]] = m_from_mm(float(value))
        elif key in _MODE_KEYS:
            fields[key] = tuple(value) if key == "working_mode" else value
        else:
            raise InputError(f"{where}: unknown key {key!r}; known: "
                             f"{sorted([*TOOL_KEYS, *_MODE_KEYS])}")
    return fields


def geometry_from_args(args, mapping=None, where: str = "tool"):
    """The Cutting Tool of ``mapping`` (a job's ``tool:``), then ``--tool-file``, then
    ``--links`` (each overriding the one before; the defaults otherwise)."""
    from drakedeburr.errors import InputError
    from drakedeburr.laser.kinematics import FiveBarGeometry
    from drakedeburr.units import m_from_mm

    fields: dict = {} if mapping is None else _geometry_fields(mapping, where)
    path = getattr(args, "tool_file", None)
    if path is not None:
        from drakedeburr._io import load_yaml
        from drakedeburr.argcheck import input_file

        input_file(path, "--tool-file")
        where = str(path)
        data = load_yaml(path, "Cutting Tool file") or {}  # bounded, no duplicate keys
        fields.update(_geometry_fields(data, str(path)))
    if getattr(args, "links", None) is not None:
        where = "--links"
        fields.update(zip(("l0", "l1", "l2", "l3", "l4"),
                          (m_from_mm(x) for x in args.links), strict=True))
    try:
        return FiveBarGeometry(**fields)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: {exc}") from exc


def _tool_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--links", type=_links, default=None, metavar="L0,L1,L2,L3,L4",
                   help="Cutting Tool link lengths [mm]: servo spacing, cranks 1/2, links 1/2")
    p.add_argument("--tool-file", type=Path, default=None,
                   help="Cutting Tool YAML (keys as 'laser tool' prints: l0_mm .. l4_mm, "
                        "home_x_mm, work_radius_mm; working_mode, assembly_mode)")

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

    job = sub.add_parser("job", help="one part: holes by the Cutting Tool, contour by the "
                                     "robot, in the plate frame (FANUC .ls programs)")
    job.add_argument("job_file", type=Path, help="job YAML (docs/laser.md: robot, plate, "
                                                 "contour, holes, feeds)")
    job.add_argument("-o", "--output", type=Path, required=True,
                     help="folder for NAME.ls (robot) and NAME_Hnn.ls (holes)")
    job.add_argument("--name", default=None, help="program name (default: the job file's)")
    _tool_options(job)
    job.set_defaults(_run=_run_job)

    tool = sub.add_parser("tool", help="show the Cutting Tool geometry and workspace figures")
    tool.add_argument("--sdf", type=Path, help="also write the tool's SDF model here")
    _tool_options(tool)
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
    p.add_argument("--itp", type=number(1, 100, integer=True), default=8,
                   help="controller interpolation period [ms] (FANUC 8; 16 if selected at "
                        "Controlled Start): every hole move lasts one period")
    p.add_argument("--chord-tolerance", type=_POS, default=0.01,
                   help="largest chord error of one period's step [mm] (caps the hole feed)")
    _tool_options(p)
    p.add_argument("--robot", default="m10ia",
                   help="robot mode: the FANUC arm (drakedeburr robots) whose IK gives joints "
                        "and CONFIG")
    p.add_argument("--plate", type=_six_mm_deg, default=(800.0, 0.0, 0.0, 0.0, 0.0, 0.0),
                   metavar="X,Y,Z,W,P,R",
                   help="robot mode: the plate frame (UFRAME) in the robot's world frame "
                        "[mm, deg]; the contour lies in its x-y plane")
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
    from drakedeburr.laser.itp import ControllerTiming
    from drakedeburr.laser.kinematics import check_reach
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
    fanuc_ls.check_name(args.name or args.output.stem)
    shape = _make_shape(args)
    _check_point_count(shape, args)
    feed = args.feed / 60.0
    power = PowerMap(nominal_speed=feed, min_command=args.min_command,
                     max_command=args.max_command, channel=args.ao)
    name = args.name or args.output.stem
    g = geometry_from_args(args)
    mode = args.mode
    if mode == "auto":
        probe = build_contour(shape, m_from_mm(0.5 if args.spacing is None else args.spacing))
        mode = "tool" if check_reach(g, g.p_CHome + probe.p_P).reachable.all() else "robot"
    if mode == "tool":
        limits = ServoLimits(velocity=args.servo_velocity,
                             acceleration=args.servo_acceleration, feed=feed)
        timing = ControllerTiming(period=args.itp * 1e-3,
                                  chord_tolerance=m_from_mm(args.chord_tolerance))
        prog = plan_hole(shape, m_from_mm(0.2 if args.spacing is None else args.spacing), g,
                         limits, power, timing)
        text = fanuc_ls.hole_program_ls(prog, name)
        summary = {"mode": "tool", "shape": shape.kind, "points": len(prog.segments.q),
                   "perimeter_mm": prog.contour.perimeter * 1e3,
                   "area_mm2": prog.contour.area * 1e6, "cycle_time_s": prog.duration,
                   "itp_ms": args.itp, "feed_m_min": prog.limits.feed * 60,
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
        from drakedeburr.laser.robot_job import LaserCell
        from drakedeburr.post.cl_post import pose_from_mm_deg

        cell = LaserCell(args.robot, pose_from_mm_deg(args.plate, "--plate"))
        text = fanuc_ls.contour_program_ls(tg, name, cell, g)
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
    from drakedeburr.laser.kinematics import inverse_kinematics
    from drakedeburr.laser.kinematics import singularity_measures as sm
    from drakedeburr.laser.model import five_bar_sdf

    output_file(args.sdf, "--sdf")
    g = geometry_from_args(args)
    a = np.linspace(0, 2 * np.pi, 181)
    rr = np.linspace(0, g.work_radius, 11)
    p = np.array([g.p_CHome + r * np.array([np.cos(x), np.sin(x)]) for r in rr for x in a])
    q, ok = inverse_kinematics(g, p)
    m = sm(g, q)
    out = {"l0_mm": g.l0 * 1e3, "l1_mm": g.l1 * 1e3, "l2_mm": g.l2 * 1e3, "l3_mm": g.l3 * 1e3,
           "l4_mm": g.l4 * 1e3, "home_x_mm": g.home_x * 1e3,
           "work_radius_mm": g.work_radius * 1e3, "home_mm": (g.p_CHome * 1e3).tolist(),
           "working_disc_mm": 2e3 * g.work_radius, "reachable": bool(ok.all()),
           "max_condition": float(m["condition"].max()),
           "min_serial_sine": float(min(m["serial_1"].min(), m["serial_2"].min())),
           "min_parallel_sine": float(m["parallel"].min())}
    if args.sdf:
        atomic_write_text(args.sdf, five_bar_sdf(g))
    sys.stdout.write(json.dumps(out, indent=2) + "\n")
    return 0


#: job YAML: shape sizes [mm] per kind (as the ``laser shape`` options)
_JOB_KEYS = {"robot", "plate", "mount", "tool", "feed_m_min", "hole_feed_m_min", "itp_ms",
             "chord_tolerance_mm", "travel_angle", "work_angle", "robot_acceleration",
             "min_command", "max_command", "ao", "contour", "holes"}


def _shape_from(d, where: str):
    """A shape from a job mapping: kind, sizes [mm], rotation [deg], lead_in [mm],
    clockwise, polyline points [mm]; ``at`` (the hole centre) is taken out by the caller."""
    from drakedeburr.errors import InputError
    from drakedeburr.laser import shapes
    from drakedeburr.units import m_from_mm, rad_from_deg

    if not isinstance(d, dict) or d.get("kind") not in _SIZES:
        raise InputError(f"{where}: expected a mapping with kind one of {sorted(_SIZES)}")
    sizes = [n.replace("-", "_") for n, _ in _SIZES[d["kind"]]]
    known = {"kind", "rotation", "lead_in", "clockwise", "at", "points", *sizes}
    extra = set(d) - known
    if extra:
        raise InputError(f"{where}: unknown key(s) {sorted(extra)} for a {d['kind']}; known: "
                         f"{sorted(known)}")
    try:
        kw = {k: m_from_mm(float(d[k])) for k in sizes if k in d}
        common = dict(rotation=rad_from_deg(float(d.get("rotation", 0.0))),
                      lead_in=m_from_mm(float(d.get("lead_in", 0.0))),
                      clockwise=bool(d.get("clockwise", False)))
        if d["kind"] == "polyline":
            kw["points"] = tuple((m_from_mm(float(x)), m_from_mm(float(y)))
                                 for x, y in d.get("points", ()))
        return shapes.SHAPE_KINDS[d["kind"]](**kw, **common)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: {exc}") from exc


def _run_job(args) -> int:
    import yaml

    from drakedeburr._io import atomic_write_json
    from drakedeburr.argcheck import input_file, output_folder
    from drakedeburr.errors import InputError
    from drakedeburr.laser import fanuc_ls
    from drakedeburr.laser.feature import FeatureSettings
    from drakedeburr.laser.hole import ServoLimits
    from drakedeburr.laser.itp import ControllerTiming
    from drakedeburr.laser.power import PowerMap
    from drakedeburr.laser.robot_job import LaserCell, LaserProcess, plan_job
    from drakedeburr.post.cl_post import pose_from_mm_deg
    from drakedeburr.units import m_from_mm, rad_from_deg

    src = input_file(args.job_file, "job file")
    output_folder(args.output, "-o/--output")
    try:
        job = yaml.safe_load(src.read_text()) or {}
    except yaml.YAMLError as exc:
        raise InputError(f"{src}: not valid YAML ({str(exc).splitlines()[0]})") from exc
    if not isinstance(job, dict) or set(job) - _JOB_KEYS:
        raise InputError(f"{src}: unknown key(s) {sorted(set(job) - _JOB_KEYS)}; known: "
                         f"{sorted(_JOB_KEYS)}" if isinstance(job, dict)
                         else f"{src}: expected a mapping")
    name = fanuc_ls.check_name(args.name or src.stem)
    g = geometry_from_args(args, job.get("tool"), f"{src}: tool")
    mount = pose_from_mm_deg(job.get("mount", (0, 0, 60, 0, 0, 0)), f"{src}: mount")
    cell = LaserCell(str(job.get("robot", "m10ia")),
                     pose_from_mm_deg(job.get("plate", (800, 0, 0, 0, 0, 0)), f"{src}: plate"),
                     mount)
    feed = float(job.get("feed_m_min", 6.0)) / 60.0
    hole_feed = float(job.get("hole_feed_m_min", 10.0)) / 60.0
    lo, hi = float(job.get("min_command", 0.5)), float(job.get("max_command", 10.0))
    channel = int(job.get("ao", 1))
    holes = []
    for k, h in enumerate(job.get("holes", ()) or ()):
        at = h.get("at") if isinstance(h, dict) else None
        if not (isinstance(at, (list, tuple)) and len(at) == 2):
            raise InputError(f"{src}: holes[{k}]: 'at: [x, y]' (mm, plate frame) is required")
        holes.append(((m_from_mm(float(at[0])), m_from_mm(float(at[1]))),
                      _shape_from(h, f"{src}: holes[{k}]")))
    contour = job.get("contour")
    process = LaserProcess(
        settings=FeatureSettings(travel_angle=rad_from_deg(float(job.get("travel_angle", 0))),
                                 work_angle=rad_from_deg(float(job.get("work_angle", 0))),
                                 speed=feed,
                                 acceleration=float(job.get("robot_acceleration", 3.0))),
        # one energy per length for the part: full command at the faster of the two feeds
        power=PowerMap(nominal_speed=max(feed, hole_feed), min_command=lo, max_command=hi,
                       channel=channel),
        limits=ServoLimits(feed=hole_feed),
        timing=ControllerTiming(period=float(job.get("itp_ms", 8)) * 1e-3,
                                chord_tolerance=m_from_mm(float(job.get("chord_tolerance_mm",
                                                                        0.01)))))
    plan = plan_job(
        cell, None if contour is None else _shape_from(contour, f"{src}: contour"), holes, g,
        process)
    texts = fanuc_ls.job_programs_ls(plan, name)
    args.output.mkdir(parents=True, exist_ok=True)
    files = [str(fanuc_ls.write_ls(args.output / f"{n.lower()}.ls", t)) for n, t in texts.items()]
    summary = {"programs": files, "holes": len(plan.holes),
               "hole_cycle_times_s": [p.duration for p in plan.holes],
               "contour_points": 0 if plan.contour is None else len(plan.contour),
               "configurations": sorted(set(plan.contour_motion.config)) if plan.contour
               is not None else []}
    atomic_write_json(args.output / f"{name.lower()}_summary.json", summary, indent=2)
    sys.stdout.write(json.dumps(summary) + "\n")
    return 0
