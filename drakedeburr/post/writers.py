"""Program writers: ABB RAPID module, KUKA KRL .src/.dat, FANUC TP .ls.

Deterministic: the same :class:`~drakedeburr.post.program.RobotProgram` always gives the same
bytes (no dates, fixed number formats, names numbered in move order). Millimetres and degrees
only here, converted with :mod:`drakedeburr.units`. Poses are written with 6 decimals (mm, deg)
and quaternions with 10, so a reader recomputes the planned joints to better than 1e-6 rad away
from singularities. Syntax follows the vendor samples in extdata/robot_programs/.
"""

from __future__ import annotations

import logging
import textwrap
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drakedeburr._io import atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.post.configuration import (
    abb_confdata,
    fanuc_config,
    joints_from_configuration,
    kuka_status_turn,
)
from drakedeburr.post.program import JOINT, RobotProgram
from drakedeburr.units import mm_from_m

__all__ = [
    "FORMATS",
    "format_rapid",
    "format_krl",
    "format_ls",
    "write_program",
    "abb_speed_name",
    "abb_zone_name",
    "quat_wxyz",
    "euler_zyx_deg",
]

log = logging.getLogger(__name__)

FORMATS = ("rapid", "krl", "ls")
_CONSISTENCY_TOL = 1e-6  # [m]+[rad] FK(q) X_FT vs X_WT
# ABB predefined speeddata [mm/s] and zonedata radii [mm]
_ABB_SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000,
               1500, 2000, 2500, 3000, 4000, 5000, 6000, 7000)
_ABB_ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)


def _f(x: float, nd: int = 6) -> str:
    s = f"{x:.{nd}f}"
    return "0." + "0" * nd if s.startswith("-") and float(s) == 0.0 else s


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """(4,) unit quaternion [w, x, y, z] of a rotation matrix, w >= 0 (ABB order)."""
    q = Rotation.from_matrix(R).as_quat(scalar_first=True)
    return -q if q[0] < 0 else q


def euler_zyx_deg(R: np.ndarray) -> np.ndarray:
    """(3,) [a, b, c] deg with R = Rz(a) Ry(b) Rx(c): KUKA A, B, C; FANUC R, P, W."""
    return np.asarray(Rotation.from_matrix(R).as_euler("ZYX", degrees=True))


def abb_speed_name(speed: float) -> str | None:
    """Predefined ABB speeddata name for a TCP speed [m/s] (e.g. v150), None if none fits."""
    mm_s = mm_from_m(speed)
    for v in _ABB_SPEEDS:
        if abs(mm_s - v) < 1e-6:
            return f"v{v}"
    return None


def abb_zone_name(zone: float) -> str | None:
    """Predefined ABB zonedata name for a zone radius [m] (fine, z1, ...), None if none."""
    mm = mm_from_m(zone)
    for z in _ABB_ZONES:
        if abs(mm - z) < 1e-6:
            return "fine" if z == 0 else f"z{z}"
    return None


def _check(program: RobotProgram) -> None:
    err = program.consistency_error()
    bad = np.flatnonzero(err > _CONSISTENCY_TOL)
    if bad.size:
        moves = ", ".join(str(i + 1) for i in bad[:10])
        raise InputError(f"program {program.name}: move(s) {moves}"
                         f" have joints that do not reach their TCP pose (error "
                         f"{err[bad].max():.3g}); the writers need consistent q and X_WT")
    inside = program.robot.limits.contains(np.array([m.q for m in program.moves]))
    if not np.all(inside):
        i = int(np.flatnonzero(~inside)[0])
        raise InputError(f"program {program.name}: move {i + 1} joints outside the limits")


def _header(program: RobotProgram, c: str, fmt: str, extra: tuple[str, ...] = ()) -> list[str]:
    lines = [f"{c} drakedeburr post-processor, {fmt} program {program.name}",
             f"{c} robot: {program.robot.opw.name or program.robot.name}",
             f"{c} tool: {program.tool_name}  work object: {program.wobj_name}"]
    if program.source:
        lines.append(f"{c} source: {program.source}")
    lines.append(f"{c} moves: {len(program.moves)}")
    if program.flag:
        bar = f"{c} " + "!" * 60
        lines += [bar, f"{c} {program.flag.upper()}: {program.flag_reason}".rstrip(": "),
                  f"{c} {program.flag.upper()}: check this program before running it", bar]
    lines += [f"{c} {n}" for n in (*program.notes, *extra)]
    return lines


def _xyz_mm(X: np.ndarray) -> list[str]:
    return [_f(v) for v in mm_from_m(X[:3, 3])]


# ----------------------------------------------------------------------------------- RAPID
def format_rapid(program: RobotProgram) -> str:
    """ABB RAPID module text: tooldata, wobjdata, robtargets (confdata from the joints),
    MoveL/MoveJ with predefined or custom speeddata/zonedata, ConfL/ConfJ on."""
    _check(program)
    p = program
    out = [f"MODULE {p.name}"]
    out += _header(p, "!", "ABB RAPID")
    tq = quat_wxyz(p.X_FT[:3, :3])
    cog = [_f(v) for v in mm_from_m(np.asarray(p.tool_cog, float))]
    out.append(f"PERS tooldata {p.tool_name} := [TRUE,[[{','.join(_xyz_mm(p.X_FT))}],"
               f"[{','.join(_f(v, 10) for v in tq)}]],"
               f"[{_f(p.tool_mass, 3)},[{','.join(cog)}],[1,0,0,0],0,0,0]];")
    wq = quat_wxyz(p.X_WO[:3, :3])
    out.append(f"PERS wobjdata {p.wobj_name} := [FALSE,TRUE,\"\",[[{','.join(_xyz_mm(p.X_WO))}],"
               f"[{','.join(_f(v, 10) for v in wq)}]],[[0,0,0],[1,0,0,0]]];")
    speeds: dict[str, str] = {}
    zones: dict[str, str] = {}
    for m in p.moves:
        if abb_speed_name(m.speed) is None:
            mm_s = mm_from_m(m.speed)
            name = "vDD_" + _f(mm_s, 1).replace(".", "_")
            speeds[name] = (f"CONST speeddata {name} := [{_f(mm_s, 3)},500,5000,1000];")
        if abb_zone_name(m.zone) is None:
            z = mm_from_m(m.zone)
            name = "zDD_" + _f(z, 2).replace(".", "_")
            zones[name] = (f"CONST zonedata {name} := [FALSE,{_f(z, 3)},{_f(1.5 * z, 3)},"
                           f"{_f(1.5 * z, 3)},{_f(0.15 * z, 3)},{_f(1.5 * z, 3)},"
                           f"{_f(0.15 * z, 3)}];")
    out += [speeds[k] for k in sorted(speeds)] + [zones[k] for k in sorted(zones)]
    for i, m in enumerate(p.moves):
        X = p.X_OT(i)
        cf = abb_confdata(p.robot, m.q)
        out.append(f"CONST robtarget p{i + 1} := [[{','.join(_xyz_mm(X))}],"
                   f"[{','.join(_f(v, 10) for v in quat_wxyz(X[:3, :3]))}],"
                   f"[{cf[0]},{cf[1]},{cf[2]},{cf[3]}],[9E9,9E9,9E9,9E9,9E9,9E9]];")
    out += ["", "PROC main()", "    ConfJ \\On;", "    ConfL \\On;"]
    for i, m in enumerate(p.moves):
        if m.comment:
            out.append(f"    ! {m.comment}")
        v = abb_speed_name(m.speed) or "vDD_" + _f(mm_from_m(m.speed), 1).replace(".", "_")
        z = abb_zone_name(m.zone) or "zDD_" + _f(mm_from_m(m.zone), 2).replace(".", "_")
        instr = "MoveJ" if m.move_type == JOINT else "MoveL"
        out.append(f"    {instr} p{i + 1}, {v}, {z}, {p.tool_name} \\WObj:={p.wobj_name};")
    out += ["ENDPROC", "ENDMODULE", ""]
    return "\n".join(out)


# ------------------------------------------------------------------------------------- KRL
def _frame(X: np.ndarray) -> str:
    x, y, z = _xyz_mm(X)
    a, b, c = (_f(v) for v in euler_zyx_deg(X[:3, :3]))
    return f"{{X {x},Y {y},Z {z},A {a},B {b},C {c}}}"


def format_krl(program: RobotProgram) -> tuple[str, str]:
    """KUKA KRL (.src, .dat) texts: $BASE/$TOOL frames, E6POS points with S and T from the
    joints, LIN with $VEL.CP [m/s] and $APO.CDIS [mm], PTP for joint moves.

    KUKA S/T identify a solution only for joints within +-360 deg; moves whose planned joints
    are not the ones S/T select are listed in a header warning (the program is still written).
    """
    _check(program)
    p = program
    ambiguous = []
    for i, m in enumerate(p.moves):
        X_WF = m.X_WT @ np.linalg.inv(p.X_FT)
        q_back = joints_from_configuration(p.robot, X_WF, "kuka", kuka_status_turn(p.robot, m.q))
        if np.abs(q_back - m.q).max() > 1e-6:
            ambiguous.append(i + 1)
    extra = ()
    if ambiguous:
        extra = ("WARNING: S/T cannot tell the planned turn of A4/A6 at move(s) "
                 + ", ".join(map(str, ambiguous[:20])),)
    hdr = _header(p, ";", "KUKA KRL", extra)
    src = ["&ACCESS RVP", "&REL 1", f"DEF {p.name}( )"] + ["   " + h for h in hdr]
    src += [";FOLD INI", "  ;FOLD BASISTECH INI", "    BAS (#INITMOV,0 )", "  ;ENDFOLD",
            ";ENDFOLD (INI)", "",
            f"   ; work object {p.wobj_name}", f"   $BASE = {_frame(p.X_WO)}",
            f"   ; tool {p.tool_name}", f"   $TOOL = {_frame(p.X_FT)}",
            "   $ADVANCE = 3", "   BAS (#VEL_PTP, 100)"]
    v_prev, z_prev = None, None
    for i, m in enumerate(p.moves):
        if m.comment:
            src.append(f"   ; {m.comment}")
        if m.move_type == JOINT:
            src.append(f"   PTP XP{i + 1}" + (" C_PTP" if m.zone > 0 else ""))
            continue
        if m.speed != v_prev:
            src.append(f"   $VEL.CP = {_f(m.speed, 6)}")
            v_prev = m.speed
        if m.zone > 0 and m.zone != z_prev:
            src.append(f"   $APO.CDIS = {_f(mm_from_m(m.zone), 3)}")
            z_prev = m.zone
        src.append(f"   LIN XP{i + 1}" + (" C_DIS" if m.zone > 0 else ""))
    src += ["END", ""]
    dat = ["&ACCESS RVP", "&REL 1", f"DEFDAT {p.name} PUBLIC"] + ["   " + h for h in hdr]
    for i, m in enumerate(p.moves):
        X = p.X_OT(i)
        x, y, z = _xyz_mm(X)
        a, b, c = (_f(v) for v in euler_zyx_deg(X[:3, :3]))
        s, t = kuka_status_turn(p.robot, m.q)
        dat.append(f"DECL E6POS XP{i + 1}={{X {x},Y {y},Z {z},A {a},B {b},C {c},S {s},T {t},"
                   "E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}")
    dat += ["ENDDAT", ""]
    return "\n".join(src), "\n".join(dat)


# -------------------------------------------------------------------------------------- LS
def format_ls(program: RobotProgram, uframe: int = 1, utool: int = 1,
              cnt_per_mm: float = 10.0) -> str:
    """FANUC TP (.ls) text: /MN with ``L P[n] 150mm/sec CNTxx`` (FINE for zone 0), /POS with
    CONFIG strings from the joints. The tool and user frame values are written as remarks:
    enter them as UTOOL ``utool`` / UFRAME ``uframe`` on the controller.

    Args:
        program: the program.
        uframe, utool: frame numbers the program selects.
        cnt_per_mm: CNT value per mm of zone radius (FANUC CNT is not a distance; capped
            to 1..100).
    """
    _check(program)
    p = program
    mn: list[str] = []
    for h in _header(p, "", "FANUC LS"):
        # TP remarks are short: wrap at 30 characters
        mn += [f"!{part} ;" for part in textwrap.wrap(h.strip(), 30)]
    for label, X, num in (("UTOOL", p.X_FT, utool), ("UFRAME", p.X_WO, uframe)):
        x, y, z = _xyz_mm(X)
        r, pp, w = (_f(v) for v in euler_zyx_deg(X[:3, :3]))
        mn.append(f"!{label}[{num}] X {x} Y {y} Z {z} ;")
        mn.append(f"!{label}[{num}] W {w} P {pp} R {r} ;")
    mn += [f"UFRAME_NUM={uframe} ;", f"UTOOL_NUM={utool} ;"]
    rounded = []
    for i, m in enumerate(p.moves):
        if m.comment:
            mn.append(f"!{m.comment[:30]} ;")
        if m.zone == 0:
            term = "FINE"
        else:
            term = f"CNT{min(100, max(1, int(round(mm_from_m(m.zone) * cnt_per_mm))))}"
        if m.move_type == JOINT:
            mn.append(f"J P[{i + 1}] 100% {term} ;")
        else:
            mm_s = mm_from_m(m.speed)
            v = max(1, int(round(mm_s)))
            if abs(v - mm_s) > 1e-6:
                rounded.append(i + 1)
            mn.append(f"L P[{i + 1}] {v}mm/sec {term} ;")
    if rounded:
        mn.insert(0, f"!speeds rounded to mm/sec at {len(rounded)} move(s) ;")
    out = [f"/PROG  {p.name.upper()}", "/ATTR", "OWNER\t\t= MNEDITOR;",
           f"COMMENT\t\t= \"{p.source[-16:] if p.source else 'drakedeburr'}\";",
           "PROG_SIZE\t= 0;", f"FILE_NAME\t= {p.name.upper()};", "VERSION\t\t= 0;",
           f"LINE_COUNT\t= {len(mn)};", "MEMORY_SIZE\t= 0;", "PROTECT\t\t= READ_WRITE;",
           "TCD:  STACK_SIZE\t= 0,", "      TASK_PRIORITY\t= 50,", "      TIME_SLICE\t= 0,",
           "      BUSY_LAMP_OFF\t= 0,", "      ABORT_REQUEST\t= 0,", "      PAUSE_REQUEST\t= 0;",
           "DEFAULT_GROUP\t= 1,*,*,*,*;", "CONTROL_CODE\t= 00000000 00000000;", "/MN"]
    out += [f"{k + 1:4d}:  {line}" for k, line in enumerate(mn)]
    out.append("/POS")
    for i, m in enumerate(p.moves):
        X = p.X_OT(i)
        x, y, z = _xyz_mm(X)
        r, pp, w = (_f(v) for v in euler_zyx_deg(X[:3, :3]))
        out += [f"P[{i + 1}]{{", "   GP1:",
                f"\tUF : {uframe}, UT : {utool},\t\tCONFIG : '{fanuc_config(p.robot, m.q)}',",
                f"\tX = {x} mm,\tY = {y} mm,\tZ = {z} mm,",
                f"\tW = {w} deg,\tP = {pp} deg,\tR = {r} deg", "};"]
    out += ["/END", ""]
    return "\n".join(out)


def write_program(program: RobotProgram, path: str | Path, fmt: str) -> list[Path]:
    """Write a program atomically in format ``fmt`` ('rapid', 'krl', 'ls').

    For KRL, ``path`` names the .src file; the .dat is written beside it.

    Returns:
        the written paths.
    """
    path = Path(path)
    if fmt == "rapid":
        return [atomic_write_text(path, format_rapid(program))]
    if fmt == "krl":
        src, dat = format_krl(program)
        src_path = path if path.suffix.lower() == ".src" else path.with_suffix(".src")
        return [atomic_write_text(src_path, src),
                atomic_write_text(src_path.with_suffix(".dat"), dat)]
    if fmt == "ls":
        return [atomic_write_text(path, format_ls(program))]
    raise InputError(f"unknown program format {fmt!r}: use one of {', '.join(FORMATS)}")


