"""Small, self-contained FANUC .ls (TP source) writer for the laser cell.

Syntax follows the FANUC ASCII programs in extdata (``/PROG``, ``/ATTR``, ``/MN``, ``/POS``).
Two program kinds:

* hole by the Cutting Tool: the tool is motion group 2 (two extended axes J1, J2 in deg);
  the robot (group 1) holds still. Each target is a joint move of one interpolation period
  (``J P[i] 8msec CNT100``: :mod:`drakedeburr.laser.itp`), preceded by ``AO[n]=counts``
  with the segment's command (planned energy / period).
* contour by the robot: group 1 Cartesian targets in the plate frame (UFRAME; X, Y, Z [mm],
  W, P, R [deg], fixed-axis x-y-z angles as on FANUC) with the CONFIG of the arm's IK
  joints, linear moves at the planned speed (whole mm/sec or cm/min) and ``AO[n]`` per
  point;
* a job: the robot's program positions the tool over each hole and CALLs the hole's
  group-2 program, then cuts the contour (:func:`job_programs_ls`).

The general RAPID/KRL/LS writers live in ``drakedeburr.post``; this module stays small so the
laser stage does not depend on them (see docs/laser.md).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.laser.feature import LaserTargets
from drakedeburr.laser.hole import HoleProgram
from drakedeburr.laser.robot_job import LaserJob
from drakedeburr.programs.ls import FRAME_PR, frame_statements

__all__ = ["hole_program_ls", "contour_program_ls", "job_programs_ls", "write_ls",
           "wpr_deg_from_R", "check_name"]

_TCD = """TCD:  STACK_SIZE		= 0,
      TASK_PRIORITY		= 50,
      TIME_SLICE		= 0,
      BUSY_LAMP_OFF		= 0,
      ABORT_REQUEST		= 0,
      PAUSE_REQUEST		= 0;"""


def _header(name: str, comment: str, n_lines: int, groups: str) -> list[str]:
    return ["/PROG " + name, "/ATTR", "OWNER\t\t\t= MNEDITOR;", f'COMMENT\t\t\t= "{comment[:16]}";',
            "PROG_SIZE\t\t= 0;", f"FILE_NAME\t\t= {name};", "VERSION\t\t\t= 0;",
            f"LINE_COUNT\t\t= {n_lines};", "MEMORY_SIZE\t\t= 0;", "PROTECT\t\t\t= READ_WRITE;",
            _TCD, f"DEFAULT_GROUP\t= {groups};", "CONTROL_CODE\t= 00000000 00000000;", "/MN"]


def check_name(name: str) -> str:
    """The /PROG name: an LS identifier (:mod:`drakedeburr.programs.names`), upper case."""
    from drakedeburr.programs.names import check_identifier

    return check_identifier(str(name), "ls", "FANUC program name", "program name").upper()


def wpr_deg_from_R(R: np.ndarray) -> tuple[float, float, float]:
    """FANUC W, P, R [deg] (R = Rz(r) Ry(p) Rx(w)) of a rotation matrix (3, 3)."""
    from pydrake.math import RollPitchYaw, RotationMatrix

    rpy = RollPitchYaw(RotationMatrix(np.asarray(R, dtype=float)))
    w, p, r = np.rad2deg(rpy.vector())
    return float(w), float(p), float(r)


def hole_program_ls(prog: HoleProgram, name: str, laser_do: int = 1, uframe: int = 0,
                    utool: int = 1) -> str:
    """FANUC .ls text of a hole cut by the Cutting Tool (group 2), as the controller runs it.

    One joint move per interpolation period (``J P[i] 8msec CNT100``; FINE at the stops), each
    preceded by ``AO[n]=counts`` with the segment's re-planned command, so command x time per
    segment is the planned energy (:mod:`drakedeburr.laser.itp`). Timed motion in msec:
    1-32000 msec (FANUC HandlingTool Operator's Manual, motion instruction feed rate).
    """
    from drakedeburr.errors import InputError
    from drakedeburr.laser.itp import TP_MSEC_MAX, ControllerTiming, quantise

    name = check_name(name)
    seg = prog.segments
    if seg is None:
        seg = quantise(prog.timed, prog.geometry, prog.power, ControllerTiming())
    ms = seg.ticks * seg.timing.period_ms
    if ms.max() > TP_MSEC_MAX:
        raise InputError(f"{name}: a segment of {int(ms.max())} msec exceeds the TP limit "
                         f"{TP_MSEC_MAX} msec")
    q_deg = np.rad2deg(seg.q)
    counts = prog.power.counts(seg.command)
    ch = prog.power.channel
    mn = [f"UFRAME_NUM={uframe} ;", f"UTOOL_NUM={utool} ;",
          f"!{prog.contour.name} {prog.contour.perimeter * 1e3:.3f}mm "
          f"{seg.duration:.3f}s ;",
          f"!ITP {seg.timing.period_ms}ms feed {prog.limits.feed * 60:.3f}m/min ;",
          "J P[1] 100% FINE ;", f"AO[{ch}]={counts[0]} ;", f"DO[{laser_do}]=ON ;"]
    for i in range(1, len(q_deg)):
        term = "FINE" if seg.stop[i] else "CNT100"
        mn.append(f"AO[{ch}]={counts[i - 1]} ;")
        mn.append(f"J P[{i + 1}] {int(ms[i - 1])}msec {term} ;")
    mn += [f"DO[{laser_do}]=OFF ;", f"AO[{ch}]=0 ;"]
    pos = []
    for i, (a, b) in enumerate(q_deg):
        pos.append(f"P[{i + 1}]{{\n   GP2:\n\tUF : {uframe}, UT : {utool},\n"
                   f"\tJ1 =\t{a:.6f}\tdeg,\tJ2 =\t{b:.6f}\tdeg\n}};")
    return _assemble(name, prog.contour.name, mn, pos, "*,1,*,*,*")


def _gp1(i: int, uframe: int, utool: int, config: str, X: np.ndarray) -> str:
    x, y, z = X[:3, 3] * 1e3
    w, p, r = wpr_deg_from_R(X[:3, :3])
    return (f"P[{i}]{{\n   GP1:\n\tUF : {uframe}, UT : {utool},\t\tCONFIG : '{config}',\n"
            f"\tX =\t{x:.6f}\tmm,\tY =\t{y:.6f}\tmm,\tZ =\t{z:.6f}\tmm,\n"
            f"\tW =\t{w:.6f}\tdeg,\tP =\t{p:.6f}\tdeg,\tR =\t{r:.6f}\tdeg\n}};")


def _speed_text(v: float) -> str:
    from drakedeburr.programs.common import ls_speed

    value, unit = ls_speed(v)
    return f"{value}{unit}"


def _contour_lines(targets: LaserTargets, first: int, laser_do: int) -> list[str]:
    counts = targets.power.counts(targets.command)
    ch = targets.power.channel
    n = len(targets)
    mn = [f"!contour {targets.name} ;", f"J P[{first}] 20% FINE ;", f"AO[{ch}]={counts[0]} ;",
          f"DO[{laser_do}]=ON ;"]
    for i in range(1, n):
        v = max(0.5 * (targets.speed[i - 1] + targets.speed[i]), 1e-3)
        term = "FINE" if (targets.contour.corner[i] or i == n - 1) else "CNT100"
        mn.append(f"AO[{ch}]={counts[i]} ;")
        mn.append(f"L P[{first + i}] {_speed_text(v)} {term} ;")
    return mn + [f"DO[{laser_do}]=OFF ;", f"AO[{ch}]=0 ;"]


def job_programs_ls(job: LaserJob, name: str, laser_do: int = 1) -> dict[str, str]:
    """FANUC .ls texts of a laser job, {program name: text}: the robot's program ``name``
    (group 1: UFRAME / UTOOL set from their values through ``PR[10]``
    (:func:`drakedeburr.programs.ls.frame_statements`), ``UFRAME_NUM``/``UTOOL_NUM``, a FINE
    joint move over each hole and ``CALL <name>_Hnn``, then the contour with the laser on)
    and one Cutting Tool program per hole (group 2, :func:`hole_program_ls`). Every robot
    point carries the CONFIG of its joints (:mod:`drakedeburr.laser.robot_job`).
    """
    from drakedeburr.laser.robot_job import X_FT_of

    name = check_name(name)
    cell = job.cell
    out: dict[str, str] = {}
    mn = [f"!sets UFRAME[{cell.uframe}], UTOOL[{cell.utool}] ;",
          f"!through PR[{FRAME_PR}] (overwritten) ;"]
    mn += [f"{s} ;" for s in frame_statements("UFRAME", cell.uframe, cell.X_RP, FRAME_PR)]
    mn += [f"{s} ;" for s in frame_statements("UTOOL", cell.utool, X_FT_of(cell, job.geometry),
                                              FRAME_PR)]
    mn += [f"UFRAME_NUM={cell.uframe} ;", f"UTOOL_NUM={cell.utool} ;"]
    pos: list[str] = []
    k = 0
    for h, prog in enumerate(job.holes):
        sub = check_name(f"{name[:32]}_H{h + 1:02d}")
        out[sub] = hole_program_ls(prog, sub)
        k += 1
        mn += [f"!hole {h + 1} {prog.contour.name} ;", f"J P[{k}] 20% FINE ;", f"CALL {sub} ;"]
        pos.append(_gp1(k, cell.uframe, cell.utool, job.hole_motion.config[h],
                        job.hole_motion.X_PT[h]))
    if job.contour is not None:
        mn += _contour_lines(job.contour, k + 1, laser_do)
        for i in range(len(job.contour)):
            pos.append(_gp1(k + 1 + i, cell.uframe, cell.utool, job.contour_motion.config[i],
                            job.contour_motion.X_PT[i]))
    out = {name: _assemble(name, "laser job", mn, pos, "1,*,*,*,*"), **out}
    return out


def contour_program_ls(targets: LaserTargets, name: str, cell=None, geometry=None,
                       laser_do: int = 1) -> str:
    """FANUC .ls text of a contour cut by the robot (group 1) with TCP-speed AO: the targets
    are in the plate frame P (the UFRAME ``cell.X_RP``); CONFIG per point from the arm's IK.
    """
    from drakedeburr.laser.kinematics import FiveBarGeometry
    from drakedeburr.laser.robot_job import LaserCell, LaserJob, solve_robot

    cell = cell or LaserCell()
    g = geometry or FiveBarGeometry()
    X_PT = np.tile(np.eye(4), (len(targets), 1, 1))
    X_PT[:, :3, :3] = targets.R_WT
    X_PT[:, :3, 3] = targets.p_WT
    motion = solve_robot(cell, X_PT, g, f"contour {targets.name}")
    job = LaserJob(cell=cell, geometry=g, holes=(), hole_centers=np.zeros((0, 2)),
                   hole_motion=None, contour=targets, contour_motion=motion)
    return job_programs_ls(job, name, laser_do)[check_name(name)]


def _assemble(name: str, comment: str, mn: list[str], pos: list[str], groups: str) -> str:
    lines = _header(name, comment, len(mn), groups)
    lines += [f"\t{k + 1}:  {line}" if not line.startswith(("J ", "L ")) else f"\t{k + 1}:{line}"
              for k, line in enumerate(mn)]
    lines.append("/POS")
    lines += pos
    lines.append("/END")
    return "\n".join(lines) + "\n"


def write_ls(path: str | Path, text: str) -> Path:
    """Write a .ls program atomically."""
    return atomic_write_text(path, text)
