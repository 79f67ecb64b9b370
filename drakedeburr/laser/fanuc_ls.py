"""Small, self-contained FANUC .ls (TP source) writer for the laser cell.

Syntax follows the FANUC ASCII programs in extdata (``/PROG``, ``/ATTR``, ``/MN``, ``/POS``).
Two program kinds:

* hole by the Cutting Tool: the tool is motion group 2 (two extended axes J1, J2 in deg);
  the robot (group 1) holds still. Each target is a joint move of one interpolation period
  (``J P[i] 8msec CNT100``: :mod:`drakedeburr.laser.itp`), preceded by ``AO[n]=counts``
  with the segment's command (planned energy / period).
* contour by the robot: group 1 Cartesian targets (X, Y, Z [mm], W, P, R [deg], fixed-axis
  x-y-z angles as on FANUC) with linear moves at the planned speed and ``AO[n]`` per point.

The general RAPID/KRL/LS writers live in ``drakedeburr.post``; this module stays small so the
laser stage does not depend on them (see docs/laser.md).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.laser.feature import LaserTargets
from drakedeburr.laser.hole import HoleProgram

__all__ = ["hole_program_ls", "contour_program_ls", "write_ls", "wpr_deg_from_R"]

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


def _check_name(name: str) -> str:
    from drakedeburr.errors import InputError

    clean = name.upper()
    if not clean or not clean[0].isalpha() or not all(c.isalnum() or c == "_" for c in clean) \
            or len(clean) > 36:
        raise InputError(f"FANUC program name {name!r}: letters, digits and _ only, starting "
                         f"with a letter, at most 36 characters")
    return clean


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
    from drakedeburr.laser.itp import ControllerTiming, TP_MSEC_MAX, quantise

    name = _check_name(name)
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


def contour_program_ls(targets: LaserTargets, name: str, laser_do: int = 1, uframe: int = 0,
                       utool: int = 1, config: str = "N U T, 0, 0, 0") -> str:
    """FANUC .ls text of a contour cut by the robot (group 1) with TCP-speed AO."""
    name = _check_name(name)
    counts = targets.power.counts(targets.command)
    ch = targets.power.channel
    mn = [f"UFRAME_NUM={uframe} ;", f"UTOOL_NUM={utool} ;", "J P[1] 100% FINE ;",
          f"AO[{ch}]={counts[0]} ;", f"DO[{laser_do}]=ON ;"]
    n = len(targets)
    for i in range(1, n):
        v = max(0.5 * (targets.speed[i - 1] + targets.speed[i]), 1e-3) * 1e3
        term = "FINE" if (targets.contour.corner[i] or i == n - 1) else "CNT100"
        mn.append(f"AO[{ch}]={counts[i]} ;")
        mn.append(f"L P[{i + 1}] {max(1, round(v))}mm/sec {term} ;")
    mn += [f"DO[{laser_do}]=OFF ;", f"AO[{ch}]=0 ;"]
    pos = []
    for i in range(n):
        x, y, z = targets.p_WT[i] * 1e3
        w, p, r = wpr_deg_from_R(targets.R_WT[i])
        pos.append(f"P[{i + 1}]{{\n   GP1:\n"
                   f"\tUF : {uframe}, UT : {utool},\t\tCONFIG : '{config}',\n"
                   f"\tX =\t{x:.6f}\tmm,\tY =\t{y:.6f}\tmm,\tZ =\t{z:.6f}\tmm,\n"
                   f"\tW =\t{w:.6f}\tdeg,\tP =\t{p:.6f}\tdeg,\tR =\t{r:.6f}\tdeg\n}};")
    return _assemble(name, targets.name, mn, pos, "1,*,*,*,*")


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
