"""``drakedeburr calibrate``: touch points -> the cell's frames (source 002).

Reads a touch file (:mod:`drakedeburr.post.calibration_io`), fits the calibration tool's TCP
(pivot) and the table / tool-holder frames, reports residuals and the predicted error at the
part (warning when it lies outside the touched region), and writes what was asked: a report
(YAML), a scenario with the fitted frames, a check program visiting the nominal features
through the fitted work object and tool.

Exit codes: 0 fitted and written; 1 fitted, but a residual RMS exceeds ``--max-rms`` or the
predicted error at the part exceeds ``--max-error`` (the report is written, the scenario and
program are not); 2 bad input (one line naming the file and item); 130 interrupted.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

__all__ = ["register"]

log = logging.getLogger(__name__)


def register(subparsers) -> None:
    from drakedeburr.argcheck import six_numbers
    from drakedeburr.robots import robot_names

    p = subparsers.add_parser(
        "calibrate", help="fit the cell's frames (TCP, table, tool holder) from touch points",
        description="Read measured touch points (YAML or CSV: robot-reported TCP poses and "
                    "the nominal feature each touches; mm, deg), fit the calibration tool's "
                    "TCP (pivot method), the work table and the tool holder frames, report "
                    "the residuals and the predicted error at the part (a warning when it "
                    "lies outside the touched region), and write a scenario with the fitted "
                    "frames and a check program. Exit codes: 0 ok, 1 residual or predicted "
                    "error over the limit (report written), 2 bad input, 130 interrupted.")
    p.add_argument("touches", help="touch file (.yaml / .csv, see docs/post.md)")
    p.add_argument("--robot", default=None, metavar="NAME|FILE",
                   help=f"the arm that reported the poses: a registered arm "
                        f"({', '.join(robot_names())}) or an arm file (*.yaml, "
                        "docs/robots.md); default: the touch file's, else irb1600")
    p.add_argument("--tool", type=six_numbers, default=None, metavar="X,Y,Z,RX,RY,RZ",
                   help="the tool set on the controller when the poses were reported (mm, "
                        "deg; default: the file's 'tool')")
    p.add_argument("--report", default=None, help="write the fitted frames and residuals "
                                                  "(YAML, mm / deg)")
    p.add_argument("--scenario", default=None,
                   help="scenario to copy with the fitted frames (bundled name or file)")
    p.add_argument("--scenario-out", default=None, help="the calibrated scenario file")
    p.add_argument("--table-weld", default="fixture::chuck_top",
                   help="the scenario weld (child frame) of the table; the table features "
                        "are in this frame")
    p.add_argument("--holder-weld", default="stand::stand",
                   help="the scenario weld (child frame) of the tool holder")
    p.add_argument("--program", default=None,
                   help="write a check program visiting the nominal features (.mod/.src/.ls)")
    p.add_argument("--program-target", default=None, choices=["table", "holder"],
                   help="whose features the check program visits (default: table if touched)")
    p.add_argument("--max-rms", type=float, default=0.1,
                   help="largest acceptable residual RMS of a fit [mm] (default 0.1)")
    p.add_argument("--max-error", type=float, default=0.1,
                   help="largest acceptable predicted error at the part [mm] (default 0.1)")
    p.set_defaults(_run=_run)


def _mm_deg(X: np.ndarray) -> list[float]:
    from scipy.spatial.transform import Rotation

    rz, ry, rx = Rotation.from_matrix(X[:3, :3]).as_euler("ZYX", degrees=True)
    return [round(float(v), 4) for v in (*(X[:3, 3] * 1e3), rx, ry, rz)]


def _check_args(args) -> None:
    from drakedeburr.errors import InputError

    if (args.scenario is None) != (args.scenario_out is None):
        raise InputError("--scenario and --scenario-out go together (the scenario to copy, the "
                         "file to write)")
    for opt in ("max_rms", "max_error"):
        if not getattr(args, opt) > 0:
            raise InputError(f"--{opt.replace('_', '-')} must be > 0 mm")
    for out in (args.report, args.scenario_out, args.program):
        if out is not None:
            parent = Path(out).parent
            if Path(out).is_dir() or not (parent if str(parent) else Path(".")).is_dir():
                raise InputError(f"{out}: not a file in an existing folder")


def _report(cal, robot: str) -> dict:
    """The report mapping (logged as it is built)."""
    rep: dict = {"robot": robot, "tcp": {"tool_mm_deg": _mm_deg(cal.X_FT)}}
    if cal.pivot is not None:
        rep["tcp"]["pivot_rms_mm"] = round(cal.pivot.rms * 1e3, 4)
        rep["tcp"]["pivot_max_mm"] = round(float(cal.pivot.residuals.max()) * 1e3, 4)
        log.info("TCP (pivot, %d poses): --tool %s; residual RMS %.3f mm",
                 len(cal.pivot.residuals), ",".join(map(str, _mm_deg(cal.X_FT))),
                 cal.pivot.rms * 1e3)
    for t in cal.targets:
        entry = {"frame_mm_deg": _mm_deg(t.fit.X_WT), "touches": t.fit.n_points,
                 "rms_mm": round(t.fit.rms_rigid * 1e3, 4),
                 "max_mm": round(float(t.fit.residuals_rigid.max()) * 1e3, 4),
                 "scale": round(t.scaled.scale, 7)}
        log.info("%s: frame %s (--wobj) from %d touches; residual RMS %.3f mm, max %.3f mm; "
                 "scale of the touches %.6f", t.name, ",".join(map(str, entry["frame_mm_deg"])),
                 t.fit.n_points, entry["rms_mm"], entry["max_mm"], t.scaled.scale)
        if len(t.part_error):
            k = int(np.argmax(t.part_error))
            entry["part_predicted_error_mm"] = round(float(t.part_error.max()) * 1e3, 4)
            entry["part_outside_mm"] = round(float(t.part_outside.max()) * 1e3, 2)
            if t.part_outside.max() > 0:
                log.warning("%s: the part lies up to %.0f mm outside the touched region: "
                            "predicted error %.3f mm at part point %d (grows with the "
                            "distance: touch points around the part)", t.name,
                            t.part_outside.max() * 1e3, t.part_error[k] * 1e3, k + 1)
        rep[t.name] = entry
    return rep


def _run(args) -> int:
    from drakedeburr._io import atomic_write_text
    from drakedeburr.post.calibration_io import (
        calibrate,
        check_program,
        read_touches,
        write_calibrated_scenario,
    )
    from drakedeburr.post.cl_post import pose_from_mm_deg
    from drakedeburr.robots import get_robot

    _check_args(args)
    data = read_touches(args.touches)
    robot = get_robot(args.robot or data.robot or "irb1600")
    tool = pose_from_mm_deg(args.tool, "--tool") if args.tool is not None else None
    cal = calibrate(data, np.asarray(robot.X_BR), tool)
    rep = _report(cal, robot.name)
    fails = []
    rms = [("TCP pivot", cal.pivot.rms)] if cal.pivot is not None else []
    rms += [(t.name, t.fit.rms_rigid) for t in cal.targets]
    fails += [f"{n} residual RMS {v * 1e3:.3f} mm > --max-rms {args.max_rms} mm"
              for n, v in rms if v * 1e3 > args.max_rms]
    fails += [f"{t.name}: predicted error at the part {t.part_error.max() * 1e3:.3f} mm > "
              f"--max-error {args.max_error} mm" for t in cal.targets
              if len(t.part_error) and t.part_error.max() * 1e3 > args.max_error]
    rep["ok"], rep["failures"] = not fails, fails
    if args.report:
        import yaml

        log.info("wrote %s", atomic_write_text(args.report, yaml.safe_dump(rep, sort_keys=False)))
    if fails:
        for f in fails:
            log.error("%s", f)
        log.error("calibration not accepted: no scenario or program written")
        return 1
    if args.scenario_out:
        welds = {t.name: (args.table_weld if t.name == "table" else args.holder_weld)
                 for t in cal.targets}
        log.info("wrote %s", write_calibrated_scenario(args.scenario, args.scenario_out, cal,
                                                       welds, note=Path(args.touches).name,
                                                       robot=robot))
    if args.program:
        from drakedeburr.programs.writers import format_for_controller, write_program

        target = args.program_target or ("table" if any(t.name == "table" for t in cal.targets)
                                         else "holder")
        stem = "".join(c if c.isalnum() else "_" for c in Path(args.program).stem)
        name = ("c" + stem if not stem[:1].isalpha() else stem)[:24]
        prog = check_program(cal, data, target, robot, name)
        for path in write_program(prog, args.program, format_for_controller(robot.controller)):
            log.info("wrote %s", path)
    return 0
