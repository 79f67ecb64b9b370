"""What the three program formats share: number formats, rotations, names, header lines, and
the values a format can hold (speeds, zones, joint speeds as written).

The ``*_written`` functions are the one definition of each format's resolution; the writers
write these values and :mod:`drakedeburr.programs.compare` compares a program read back with
them, so "as planned" and "as written" never drift apart.

Vendor limits enforced here (sources in docs/post.md):

* RAPID identifiers: a letter, then letters, digits, '_'; at most 32 characters.
* KRL names (DEF/DEFDAT = file name): a letter, then letters, digits, '_'; at most 24
  characters; the .src/.dat file name must equal the DEF/DEFDAT name.
* FANUC TP: program name = file name: a letter, then letters, digits, '_'; at most 36
  characters (R-30iA and later; R-J3iB: 8); remark (``!``) text at most 32 characters;
  /ATTR COMMENT at most 16 characters; linear speeds are whole numbers of mm/sec (1..2000)
  or of cm/min (1..12000) (FANUC HandlingTool Operator's Manual, motion instruction speed:
  mm/sec 1-2000, cm/min 1-12000, sec 0.1-3200, msec 1-32000, as quoted in docs/post.md);
  CNT 0..100; J speed 1..100 %.
"""

from __future__ import annotations

import math
import re
import textwrap
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drakedeburr.errors import InputError
from drakedeburr.units import mm_from_m

__all__ = [
    "FORMATS", "SUFFIXES", "ProgramFormatError", "fnum", "quat_wxyz", "euler_zyx_deg",
    "R_from_quat_wxyz", "R_from_euler_zyx_deg", "pose_from_mm", "program_name_for",
    "speed_written", "zone_written", "joint_percent", "cnt_from_zone", "zone_from_cnt",
    "header_lines", "ABB_SPEEDS", "ABB_ZONES", "LS_REMARK_MAX", "LS_COMMENT_MAX",
    "CNT_PER_MM", "wrap_remarks", "check_writable", "ls_speed", "LS_MM_SEC_MAX",
    "LS_CM_MIN_MAX", "io_lines", "LS_ACCEL_TIME", "ls_cnts",
]

FORMATS = ("rapid", "krl", "ls")
SUFFIXES = {"rapid": (".mod", ".modx", ".prg"), "krl": (".src",), "ls": (".ls",)}
#: ABB predefined speeddata [mm/s] and zonedata radii [mm] (RAPID reference, speeddata/zonedata)
ABB_SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000,
              1500, 2000, 2500, 3000, 4000, 5000, 6000, 7000)
ABB_ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)
LS_REMARK_MAX = 32
LS_MM_SEC_MAX = 2000  # FANUC TP linear speed limits (module docstring)
LS_CM_MIN_MAX = 12000
LS_COMMENT_MAX = 16
#: FANUC CNT per mm of zone radius (CNT is a rounding degree, not a distance: docs/post.md)
CNT_PER_MM = 10.0
#: FANUC: the longest acceleration/deceleration time [s] the LS writer assumes for a linear
#: move at ACC100 (the sum of the controller's two acceleration filters); a CNT corner stays
#: within speed * LS_ACCEL_TIME / 2 of its point. The header names it as a value the cell must
#: hold (docs/post.md "FANUC CNT").
LS_ACCEL_TIME = 0.384
_NAMES = {
    "rapid": (re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}"), "a letter, then letters, digits, '_', "
              "at most 32 characters"),
    "krl": (re.compile(r"[A-Za-z][A-Za-z0-9_]{0,23}"), "a letter, then letters, digits, '_', at "
            "most 24 characters"),
    "ls": (re.compile(r"[A-Za-z][A-Za-z0-9_]{0,35}"), "a letter, then letters, digits, '_', at "
           "most 36 characters"),
}


class ProgramFormatError(InputError):
    """A program file breaks the format (or the subset the readers accept); the message
    names file, line and what was wrong."""


def fnum(x: float, nd: int = 6) -> str:
    """Fixed-point text of ``x`` with ``nd`` decimals (no "-0.000")."""
    s = f"{x:.{nd}f}"
    return s[1:] if s.startswith("-") and float(s) == 0.0 else s


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """(4,) unit quaternion [w, x, y, z] of a rotation matrix, w >= 0 (ABB order)."""
    q = Rotation.from_matrix(R).as_quat(scalar_first=True)
    return -q if q[0] < 0 else q


def R_from_quat_wxyz(q: np.ndarray) -> np.ndarray:
    """(3, 3) rotation of a quaternion [w, x, y, z] (normalised first)."""
    return Rotation.from_quat(np.asarray(q, float), scalar_first=True).as_matrix()


def euler_zyx_deg(R: np.ndarray) -> np.ndarray:
    """(3,) [a, b, c] deg with R = Rz(a) Ry(b) Rx(c): KUKA A, B, C; FANUC R, P, W."""
    import warnings

    with warnings.catch_warnings():  # gimbal lock: still an exact representation
        warnings.simplefilter("ignore", UserWarning)
        return np.asarray(Rotation.from_matrix(R).as_euler("ZYX", degrees=True))


def R_from_euler_zyx_deg(a: float, b: float, c: float) -> np.ndarray:
    """Rz(a) Ry(b) Rx(c) from degrees."""
    return Rotation.from_euler("ZYX", [a, b, c], degrees=True).as_matrix()


def pose_from_mm(xyz_mm, R: np.ndarray) -> np.ndarray:
    """(4, 4) pose [m] from a position in mm and a rotation matrix."""
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = np.asarray(xyz_mm, float) / 1000.0
    return X


def program_name_for(path: str | Path, fmt: str) -> str:
    """The program name a file must carry (KRL DEF/DEFDAT, LS /PROG = the file's stem).

    Raises:
        InputError: the stem breaks the format's naming rules.
    """
    from drakedeburr.programs.names import check_identifier

    stem = Path(path).name.split(".")[0]
    return check_identifier(stem, fmt, f"{path} (the program takes its file's name)",
                            "program name")


def ls_speed(speed: float) -> tuple[int, str]:
    """FANUC TP linear speed (value, unit) of a TCP speed [m/s]: whole mm/sec or whole cm/min,
    whichever comes closest without exceeding the plan (rounded *down*, never faster; mm/sec
    on a tie). 400 mm/min is ``40cm/min`` (exact) where mm/sec could only hold 6 (-10 %); the
    resolution is 1/6 mm/s. At least 1 cm/min; at most 2000 mm/sec."""
    mm_s = mm_from_m(float(speed))
    v_mm = int(min(LS_MM_SEC_MAX, math.floor(mm_s + 1e-9)))
    v_cm = int(min(LS_CM_MIN_MAX, math.floor(6.0 * mm_s + 1e-9)))
    if v_mm >= 1 and v_mm * 6 >= v_cm:
        return v_mm, "mm/sec"
    return max(1, v_cm), "cm/min"


def speed_written(fmt: str, speed: float) -> float:
    """TCP speed [m/s] as the format holds it: RAPID 0.001 mm/s, KRL $VEL.CP 1e-6 m/s, LS whole
    mm/sec or whole cm/min rounded *down* (never faster than planned: :func:`ls_speed`)."""
    if fmt == "rapid":
        return round(mm_from_m(speed), 3) / 1000.0
    if fmt == "krl":
        return round(float(speed), 6)
    v, unit = ls_speed(speed)
    return v / 1000.0 if unit == "mm/sec" else v / 6000.0


def io_lines(actions, fmt: str) -> list[str]:
    """Instructions (without indent or terminator where the writer adds them) setting the
    outputs of :class:`~drakedeburr.programs.program.IoAction` s: RAPID ``SetDO name, 1;``
    / ``SetAO name, value;`` (RAPID reference: SetDO, SetAO); KRL ``$OUT[n] = TRUE`` /
    ``$ANOUT[n] = value`` after ``WAIT SEC 0`` (writing $OUT does not stop the advance run,
    the WAIT does: the output switches when the robot is at the previous point; KSS
    programming manual); LS ``DO[n]=ON`` / ``AO[n]=value`` (HandlingTool manual, I/O
    instructions)."""
    out: list[str] = []
    if not actions:
        return out
    if fmt == "krl":
        out.append("WAIT SEC 0")
    for a in actions:
        if fmt == "rapid":
            v = int(a.value) if a.kind == "do" else fnum(a.written("rapid"), 4)
            out.append(f"Set{a.kind.upper()} {a.name}, {v};")
        elif fmt == "krl":
            if a.kind == "do":
                out.append(f"$OUT[{a.port}] = {'TRUE' if a.value else 'FALSE'}")
            else:
                out.append(f"$ANOUT[{a.port}] = {fnum(a.written('krl'), 6)}")
        else:
            if a.kind == "do":
                out.append(f"DO[{a.port}]={'ON' if a.value else 'OFF'}")
            else:
                out.append(f"AO[{a.port}]={int(a.written('ls'))}")
    return out


def cnt_from_zone(zone: float) -> int:
    """FANUC CNT value of a zone radius [m]; 0 means FINE (see docs/post.md)."""
    if zone <= 0.0:
        return 0
    return int(min(100, max(1, round(mm_from_m(zone) * CNT_PER_MM))))


def zone_from_cnt(cnt: int) -> float:
    """The nominal zone radius [m] a CNT value stands for (inverse of :func:`cnt_from_zone`)."""
    return cnt / CNT_PER_MM / 1000.0


def ls_cnts(program) -> np.ndarray:
    """(N,) the CNT value the LS writer gives each move; 0 = FINE.

    CNT n is a degree of rounding, not a distance (FANUC's corner depends on speed, the
    acceleration profile and the load). A bound holds for a linear move into a linear move:
    the blend starts no earlier than the deceleration, so the corner stays within
    ``d = max(v_in, v_out) * LS_ACCEL_TIME / 2`` of the point, for any n. CNT (n =
    :func:`cnt_from_zone`) is written only where ``d`` is within the planned zone and within
    half of both adjacent moves (the blend stays inside them); everywhere else FINE.
    """
    moves = program.moves
    n = len(moves)
    out = np.zeros(n, dtype=int)
    limits = program.zone_limits()
    for i in range(n - 1):
        m, nxt = moves[i], moves[i + 1]
        if m.zone <= 0 or m.move_type != "linear" or nxt.move_type != "linear":
            continue
        d = max(speed_written("ls", m.speed), speed_written("ls", nxt.speed)) * LS_ACCEL_TIME / 2
        if d <= m.zone + 1e-12 and d <= limits[i] + 1e-12:
            out[i] = cnt_from_zone(m.zone)
    return out


def zone_written(fmt: str, zone: float) -> float:
    """Zone radius [m] as the format holds it: RAPID/KRL 0.001 mm (0 = fine / exact stop), LS
    the nominal radius of its CNT value."""
    if fmt == "ls":
        return zone_from_cnt(cnt_from_zone(zone))
    return round(mm_from_m(zone), 3) / 1000.0


def joint_percent(fraction: float) -> int:
    """Joint-move speed in % of the axes' top speed (KRL BAS #VEL_PTP, LS J %): rounded down,
    at least 1."""
    return int(max(1, min(100, math.floor(100.0 * fraction + 1e-9))))


_LANGUAGE_OF = {"ABB RAPID": "rapid", "KUKA KRL": "krl", "FANUC LS": "ls"}


def header_lines(program, fmt: str, extra: tuple[str, ...] = ()) -> list[str]:
    """Header comment lines (text only, without the comment marker), each one cleaned by
    :func:`~drakedeburr.programs.names.comment_text` (hub, file and tool names are inputs)."""
    from drakedeburr.programs.names import comment_text

    p = program
    spec = p.spec
    arm = f"{spec.title} ({spec.controller_model})" if spec else (p.kinematics.name or "robot")
    lines = [f"drakedeburr, {fmt} program {p.name}", f"robot: {arm}",
             ("workpiece in hand: stationary tool " if p.stationary_tool else "tool: ")
             + f"{p.tool_name}, work object {p.wobj_name}",
             f"loads: {p.load_source}"]
    if p.source:
        lines.append(f"source: {p.source}")
    lines.append(f"moves: {len(p.moves)}")
    if p.flag:
        lines += ["*" * 30, f"{p.flag.upper()}: {p.flag_reason}".rstrip(": "),
                  f"{p.flag.upper()}: check this program before running it", "*" * 30]
    language = _LANGUAGE_OF.get(fmt, "ls")  # unknown label: the strictest remark rules
    return [comment_text(h, language) for h in lines + list(p.notes) + list(extra)]


def wrap_remarks(lines: list[str], width: int = LS_REMARK_MAX) -> list[str]:
    """Lines wrapped to ``width`` characters (FANUC remarks)."""
    out = []
    for line in lines:
        out += textwrap.wrap(line, width, break_long_words=True) or [""]
    return out


def check_writable(program, tol: float = 1e-6) -> None:
    """Refuse a program whose joints do not reach their poses (FK(q) X_FT vs X_WT, ``tol`` in
    m + rad), whose zones the controller would shrink (more than half an adjacent move), or
    whose joints leave the joint limits.

    Raises:
        InputError: naming the first moves and the error.
    """
    err = program.consistency_error()
    bad = np.flatnonzero(err > tol)
    if bad.size:
        moves = ", ".join(str(i + 1) for i in bad[:10])
        raise InputError(f"program {program.name}: move(s) {moves} have joints that do not "
                         f"reach their pose (error {err[bad].max():.3g}); the writers need "
                         "consistent q and X_WT")
    zones = np.array([m.zone for m in program.moves])
    over = np.flatnonzero(zones > program.zone_limits() + 1e-9)
    if over.size:
        i = int(over[0])
        raise InputError(f"program {program.name}: move {i + 1} zone {zones[i] * 1e3:.3f} mm is "
                         f"more than half an adjacent move ({program.zone_limits()[i] * 1e3:.3f} "
                         f"mm, {over.size} move(s)): the controller would shrink it; build the "
                         "program with programs.zones_within_half_moves")
    inside = program.kinematics.limits.contains(np.array([m.q for m in program.moves]))
    if not np.all(inside):
        i = int(np.flatnonzero(~inside)[0])
        raise InputError(f"program {program.name}: move {i + 1} joints outside the limits")
