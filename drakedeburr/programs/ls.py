"""FANUC TP (.ls): write a :class:`RobotProgram`, read one back strictly.

Written (FANUC R-30iA/R-30iB HandlingTOOL Operator's Manual: program header, motion
instructions, position data, frame instructions, PAYLOAD; Remote TCP option): /PROG = the
file's name; /MN with ``UFRAME_NUM``, ``UTOOL_NUM``, ``PAYLOAD[n]``, ``L P[n] 150mm/sec CNT10``
(whole mm/sec or whole cm/min, whichever is closer below the plan: 400 mm/min is
``40cm/min``; rounded down so the program is never faster than planned; FINE for zone 0,
``CNTn`` for a zone: see docs/post.md for what CNT means), ``J P[n] 25%``; with a stationary
tool every L move carries ``RTCP`` (the remote TCP is the user frame; the header names the
Remote TCP option); /POS with CONFIG from the planned joints. The tool and user frame are set
by the program from their values: ``PR[10]=LPOS`` (a Cartesian register), ``PR[10,1..6]=``
X, Y, Z, W, P, R, ``UTOOL[1]=PR[10]``, the same for UFRAME (RoboDK's FANUC post writes them
so); the payload schedule's values cannot be set from a TP program: ``PAYLOAD[n]`` selects it
and remarks list the values it must hold (``verify --program`` names them). The reader takes
the frames from those statements (or from ``!UTOOL[1] X=...`` remarks of older files).
Remarks are at most 32 characters.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from drakedeburr.programs.common import (
    LS_ACCEL_TIME,
    LS_COMMENT_MAX,
    LS_REMARK_MAX,
    ProgramFormatError,
    R_from_euler_zyx_deg,
    check_writable,
    euler_zyx_deg,
    fnum,
    header_lines,
    io_lines,
    joint_percent,
    ls_cnts,
    ls_speed,
    pose_from_mm,
    wrap_remarks,
    zone_from_cnt,
)
from drakedeburr.programs.names import comment_text
from drakedeburr.programs.program import JOINT, LINEAR, RobotProgram
from drakedeburr.programs.read_types import ReadMove, ReadProgram, parse_number
from drakedeburr.units import mm_from_m

__all__ = ["format_ls", "read_ls", "frame_statements", "FRAME_PR"]

_ATTR = ["OWNER\t\t= MNEDITOR;", "PROG_SIZE\t= 0;", "VERSION\t\t= 0;", "MEMORY_SIZE\t= 0;",
         "PROTECT\t\t= READ_WRITE;", "TCD:  STACK_SIZE\t= 0,", "      TASK_PRIORITY\t= 50,",
         "      TIME_SLICE\t= 0,", "      BUSY_LAMP_OFF\t= 0,", "      ABORT_REQUEST\t= 0,",
         "      PAUSE_REQUEST\t= 0;", "DEFAULT_GROUP\t= 1,*,*,*,*;",
         "CONTROL_CODE\t= 00000000 00000000;"]
_KEYS = ("X", "Y", "Z", "W", "P", "R")


#: the position register the LS program loads its tool and user frame values through
FRAME_PR = 10


def frame_statements(label: str, n: int, X: np.ndarray, pr: int) -> list[str]:
    """``PR[pr]`` set to the frame's X, Y, Z [mm], W, P, R [deg] and ``UTOOL[n]=PR[pr]`` (or
    UFRAME): the controller takes the values from the program, not from its setup screens
    (HandlingTOOL Operator's Manual, frame instructions; RoboDK's FANUC post does the same)."""
    xyz = mm_from_m(X[:3, 3])
    r, p, w = euler_zyx_deg(X[:3, :3])
    values = (*xyz, w, p, r)
    return ([f"PR[{pr}]=LPOS"] + [f"PR[{pr},{k + 1}]={fnum(v)}" for k, v in enumerate(values)]
            + [f"{label}[{n}]=PR[{pr}]"])


def _payload_remarks(p: RobotProgram, n: int) -> list[str]:
    m = p.tool_mass + p.workpiece_mass
    cog = (p.tool_mass * np.asarray(p.tool_cog, float)
           + p.workpiece_mass * np.asarray(p.workpiece_cog, float)) / m
    out = [f"PAYLOAD[{n}] M={fnum(m, 3)} kg"]
    out += [f"PAYLOAD[{n}] C{k}={fnum(v, 3)} mm" for k, v in zip("XYZ", mm_from_m(cog),
                                                                 strict=True)]
    return out


def _mn(p: RobotProgram, uframe: int, utool: int, payload: int) -> list[str]:
    extra = (f"CNT corners assume an ACC100 acceleration time <= {LS_ACCEL_TIME * 1e3:.0f} ms "
             "($PARAM_GROUP[1].$ACCEL_TIME1 + $ACCEL_TIME2)",)
    if p.stationary_tool:
        extra += ("needs the Remote TCP option (RTCP): the user frame is the stationary tool",)
    mn = [f"!{h}" for h in wrap_remarks(header_lines(p, "FANUC LS", extra), LS_REMARK_MAX)]
    X_RO = np.linalg.solve(p.X_BR, p.X_WO)
    mn += [f"!sets UTOOL[{utool}], UFRAME[{uframe}]", f"!through PR[{FRAME_PR}] (overwritten)"]
    mn += frame_statements("UTOOL", utool, p.X_FT, FRAME_PR)
    mn += frame_statements("UFRAME", uframe, X_RO, FRAME_PR)
    mn += [f"!the cell must hold PAYLOAD[{payload}]:"]
    mn += ["!" + r for r in _payload_remarks(p, payload)]
    mn += [f"UFRAME_NUM={uframe}", f"UTOOL_NUM={utool}", f"PAYLOAD[{payload}]"]
    cnts = ls_cnts(p)
    for i, m in enumerate(p.moves):
        if m.comment:
            mn += [f"!{c}" for c in wrap_remarks([comment_text(m.comment, "ls")],
                                                 LS_REMARK_MAX)]
        mn += io_lines(m.io, "ls")
        cnt = int(cnts[i])
        term = "FINE" if cnt == 0 else f"CNT{cnt}"
        if m.move_type == JOINT:
            mn.append(f"J P[{i + 1}] {joint_percent(p.joint_fraction(i))}% {term}")
        else:
            v, unit = ls_speed(m.speed)
            mn.append(f"L P[{i + 1}] {v}{unit} {term}" + (" RTCP" if p.stationary_tool else ""))
    return mn + io_lines(p.io_end, "ls")


def format_ls(program: RobotProgram, uframe: int = 1, utool: int = 1, payload: int = 1) -> str:
    """FANUC TP (.ls) text named ``program.name`` (module docstring).

    Args:
        program: the program.
        uframe, utool, payload: the frame and payload schedule numbers the program selects.
    """
    check_writable(program)
    p = program
    mn = _mn(p, uframe, utool, payload)
    comment = ("drakedeburr " + ("RTCP" if p.stationary_tool else "burr"))[:LS_COMMENT_MAX]
    out = [f"/PROG  {p.name.upper()}", "/ATTR", _ATTR[0], f"COMMENT\t\t= \"{comment}\";",
           _ATTR[1], f"FILE_NAME\t= {p.name.upper()};", _ATTR[2], f"LINE_COUNT\t= {len(mn)};",
           *_ATTR[3:], "/MN"]
    out += [f"{k + 1:4d}:  {line} ;" for k, line in enumerate(mn)]
    out.append("/POS")
    for i in range(len(p.moves)):
        X = p.X_OT(i)
        x, y, z = (fnum(v) for v in mm_from_m(X[:3, 3]))
        r, pp, w = (fnum(v) for v in euler_zyx_deg(X[:3, :3]))
        out += [f"P[{i + 1}]{{", "   GP1:",
                f"\tUF : {uframe}, UT : {utool},\t\tCONFIG : '{p.configuration(i)}',",
                f"\tX = {x} mm,\tY = {y} mm,\tZ = {z} mm,",
                f"\tW = {w} deg,\tP = {pp} deg,\tR = {r} deg", "};"]
    out += ["/END", ""]
    return "\n".join(out)


# ---------------------------------------------------------------------------------- reading
_MN = re.compile(r"\s*(\d+):\s*(.*?)\s*;\s*")
_MOTION = re.compile(r"([JL])\s+P\[(\d+)(?::[^\]]*)?\]\s+(\S+)\s+(FINE|CNT\s*\d+)((?:\s+\S+)*)",
                     re.I)
_OPTIONS = re.compile(r"RTCP|(?:Tool_)?Offset,PR\[\d+\]|ACC\d+", re.I)
_REMARK = re.compile(r"(UTOOL|UFRAME)\[(\d+)\] ([XYZWPR])=(\S+)|PAYLOAD\[(\d+)\] "
                     r"(M|CX|CY|CZ)=(\S+) (kg|mm)")


class _MnState:
    def __init__(self) -> None:
        self.frames = {"UFRAME_NUM": None, "UTOOL_NUM": None}
        self.remarks: dict = {}
        self.lines: dict = {}
        self.motions: list = []
        self.header: list = []
        self.io: list = []
        self.pr: dict = {}


def _mn_line(n: int, text: str, k: int, file: str, st: _MnState) -> None:
    if not text:
        return
    if text.startswith("!"):
        body = text[1:]
        if len(body) > LS_REMARK_MAX:
            raise ProgramFormatError(f"{file}:{k}: remark of {len(body)} characters (FANUC: at "
                                     f"most {LS_REMARK_MAX})")
        r = _REMARK.fullmatch(body)
        if r and r.group(1):
            st.remarks[(r.group(1), r.group(3))] = parse_number(r.group(4), file, k, body)
            st.lines.setdefault("tool" if r.group(1) == "UTOOL" else "work object", k)
        elif r:
            st.remarks[("PAYLOAD", r.group(6))] = parse_number(r.group(7), file, k, body)
            st.lines.setdefault("load", k)
        else:
            st.header.append(body)
        return
    m = re.fullmatch(r"(UFRAME_NUM|UTOOL_NUM)\s*=\s*(\d+)|PAYLOAD\[(\d+)\]", text)
    if m:
        if m.group(1):
            st.frames[m.group(1)] = int(m.group(2))
        return
    m = re.fullmatch(r"DO\[(\d+)\]\s*=\s*(ON|OFF)|AO\[(\d+)\]\s*=\s*(\d+)", text)
    if m:
        if m.group(1):
            st.io.append((k, "do", int(m.group(1)), 1.0 if m.group(2) == "ON" else 0.0))
        else:
            st.io.append((k, "ao", int(m.group(3)), float(m.group(4))))
        return
    m = re.fullmatch(r"PR\[(\d+)\]\s*=\s*LPOS", text)
    if m:
        st.pr[int(m.group(1))] = {}
        return
    m = re.fullmatch(r"PR\[(\d+),([1-6])\]\s*=\s*(\S+)", text)
    if m:
        st.pr.setdefault(int(m.group(1)), {})[int(m.group(2))] = parse_number(
            m.group(3), file, k, f"PR[{m.group(1)},{m.group(2)}]")
        return
    m = re.fullmatch(r"(UTOOL|UFRAME)\[(\d+)\]\s*=\s*PR\[(\d+)\]", text)
    if m:
        vals = st.pr.get(int(m.group(3)), {})
        if sorted(vals) != [1, 2, 3, 4, 5, 6]:
            raise ProgramFormatError(f"{file}:{k}: {text}: PR[{m.group(3)}] is not set (X, Y, "
                                     "Z, W, P, R) before it is used")
        for j, key in enumerate(_KEYS):
            st.remarks[(m.group(1), key)] = vals[j + 1]
        st.lines["tool" if m.group(1) == "UTOOL" else "work object"] = k
        return
    m = _MOTION.fullmatch(text)
    if not m:
        raise ProgramFormatError(f"{file}:{k}: /MN line {n} {text!r} is outside the motion "
                                 "subset this reader accepts (J/L P[n], UFRAME_NUM, UTOOL_NUM, "
                                 "PAYLOAD[n], DO[n]=ON/OFF, AO[n]=value, PR[n]=LPOS, "
                                 "PR[n,i]=value, UTOOL/UFRAME[n]=PR[m], remarks)")
    options = tuple(m.group(5).split())
    for o in options:
        if not _OPTIONS.fullmatch(o):
            raise ProgramFormatError(f"{file}:{k}: motion option {o!r} is not one this reader "
                                     "accepts (RTCP, Tool_Offset,PR[n], Offset,PR[n], ACCn)")
    st.motions.append((k, m.group(1).upper(), int(m.group(2)), m.group(3),
                       m.group(4).upper().replace(" ", ""), options,
                       (st.frames["UFRAME_NUM"], st.frames["UTOOL_NUM"])))


_NUMX = r"([-+]?(?:\d+\.?\d*|\.\d+))"
_POS = re.compile(
    r"GP1:\s*UF\s*:\s*(\d+)\s*,\s*UT\s*:\s*(\d+)\s*,\s*CONFIG\s*:\s*'([^']*)'\s*,"
    rf"\s*X\s*=\s*{_NUMX}\s*mm\s*,\s*Y\s*=\s*{_NUMX}\s*mm\s*,\s*Z\s*=\s*{_NUMX}\s*mm\s*,"
    rf"\s*W\s*=\s*{_NUMX}\s*deg\s*,\s*P\s*=\s*{_NUMX}\s*deg\s*,\s*R\s*=\s*{_NUMX}\s*deg\s*")
_CONFIG = re.compile(r"\s*([NF])\s*([UD])\s*([TB])\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*,\s*(-?\d+)\s*")


def _positions(lines: list[str], start: int, file: str) -> tuple[dict, int]:
    """/POS section from line index ``start``: {n: (X, config, line)} and the /END index."""
    out, i = {}, start
    while i < len(lines):
        s = lines[i].strip()
        if s in ("/END", "/END."):
            return out, i
        m = re.fullmatch(r"P\[(\d+)(?::[^\]]*)?\]\s*\{", s)
        if not s:
            i += 1
            continue
        if not m:
            raise ProgramFormatError(f"{file}:{i + 1}: expected 'P[n]{{' or /END in /POS, "
                                     f"got {s!r}")
        n, k0 = int(m.group(1)), i + 1
        j = i + 1
        while j < len(lines) and lines[j].strip() != "};":
            j += 1
        if j == len(lines):
            raise ProgramFormatError(f"{file}:{k0}: P[{n}] has no closing '}};'")
        body = " ".join(x.strip() for x in lines[i + 1:j])
        p = _POS.fullmatch(body)
        if not p:
            raise ProgramFormatError(f"{file}:{k0}: P[{n}] is not a Cartesian GP1 position "
                                     "(UF, UT, CONFIG, X Y Z mm, W P R deg) as this reader "
                                     "accepts (no joint positions, no other groups)")
        c = _CONFIG.fullmatch(p.group(3))
        if not c:
            raise ProgramFormatError(f"{file}:{k0}: CONFIG {p.group(3)!r} is not 'F/N U/D T/B, "
                                     "t1, t4, t6'")
        x, y, z, w, pp, r = (float(v) for v in p.groups()[3:])
        config = f"{c.group(1)} {c.group(2)} {c.group(3)}, " + ", ".join(
            str(int(c.group(k))) for k in (4, 5, 6))
        if n in out:
            raise ProgramFormatError(f"{file}:{k0}: P[{n}] defined twice")
        rows = [i + 1 + d for d, x in enumerate(lines[i + 1:j]) if x.strip()]
        found = {key: next((r for r in rows if re.match(rf"\s*{key}\s*[=:]", lines[r - 1])), k0)
                 for key in ("UF", "X", "W")}
        out[n] = (pose_from_mm([x, y, z], R_from_euler_zyx_deg(r, pp, w)), config,
                  (found["X"], found["W"], found["UF"]), (int(p.group(1)), int(p.group(2))))
        i = j + 1
    raise ProgramFormatError(f"{file}: no /END")


def _head(lines: list[str], file: str) -> tuple[str, int]:
    """/PROG name and the index of /MN; the /ATTR block is checked for form only."""
    m = re.fullmatch(r"/PROG\s+(\w+)(\s+Macro)?", lines[0].strip()) if lines else None
    if not m:
        raise ProgramFormatError(f"{file}:1: expected '/PROG <name>'")
    for i in range(1, len(lines)):
        s = lines[i].strip()
        if s == "/MN":
            return m.group(1), i
        if s in ("/ATTR", "") or re.fullmatch(r"(TCD:)?\s*\w+\s*=.*[;,]", s):
            continue
        raise ProgramFormatError(f"{file}:{i + 1}: unexpected header line {s!r} (only /ATTR "
                                 "entries before /MN)")
    raise ProgramFormatError(f"{file}: no /MN section")


def _frame_from(remarks: dict, label: str) -> np.ndarray | None:
    vals = [remarks.get((label, k)) for k in _KEYS]
    if any(v is None for v in vals):
        return None
    x, y, z, w, p, r = vals
    return pose_from_mm([x, y, z], R_from_euler_zyx_deg(r, p, w))


def read_ls(path: str | Path, check_name: bool = True) -> ReadProgram:
    """Read a FANUC .ls strictly (/PROG = file name, /MN motion subset, Cartesian /POS).

    ``check_name=False`` skips the /PROG = file name rule (for files renamed after export)."""
    path = Path(path)
    file = str(path)
    lines = path.read_text(encoding="utf-8").splitlines()
    name, i_mn = _head(lines, file)
    st = _MnState()
    i, expected = i_mn + 1, 1
    while i < len(lines) and lines[i].strip() != "/POS":
        m = _MN.fullmatch(lines[i])
        if not m or int(m.group(1)) != expected:
            raise ProgramFormatError(f"{file}:{i + 1}: expected /MN line {expected} "
                                     f"('{expected}:  <instruction> ;'), got {lines[i]!r}")
        _mn_line(expected, m.group(2), i + 1, file, st)
        expected, i = expected + 1, i + 1
    if i == len(lines):
        raise ProgramFormatError(f"{file}: no /POS section")
    pos, i_end = _positions(lines, i + 1, file)
    if any(s.strip() for s in lines[i_end + 1:]):
        raise ProgramFormatError(f"{file}:{i_end + 2}: text after /END")
    stem = path.name.split(".")[0]
    if check_name and name.lower() != stem.lower():
        raise ProgramFormatError(f"{file}:1: /PROG name {name!r} is not the file name {stem!r} "
                                 "(the controller names the program after the file)")
    return _program(name, file, st, pos)


def _move(motion: tuple, pos: dict, file: str) -> ReadMove:
    """The ReadMove of one parsed motion line ``(line, kind, position number, speed text,
    termination, options, (uframe, utool))`` with its /POS entry."""
    k, kind, n, speed_text, term, options, frames = motion
    if n not in pos:
        raise ProgramFormatError(f"{file}:{k}: P[{n}] has no position in /POS")
    X, config, (tline, oline, cline), uf_ut = pos[n]
    if uf_ut != frames:
        raise ProgramFormatError(f"{file}:{tline}: P[{n}] is taught in UF {uf_ut[0]}, UT "
                                 f"{uf_ut[1]} but line {k} moves to it with UFRAME_NUM "
                                 f"{frames[0]}, UTOOL_NUM {frames[1]}")
    if kind == "J":
        m = re.fullmatch(r"(\d+)%", speed_text)
        if not m or not 1 <= int(m.group(1)) <= 100:
            raise ProgramFormatError(f"{file}:{k}: J speed {speed_text!r} (1..100%)")
        speed, pct = None, int(m.group(1))
    else:
        m = re.fullmatch(r"(\d+)(mm/sec|cm/min)", speed_text)
        if not m:
            raise ProgramFormatError(f"{file}:{k}: L speed {speed_text!r} (whole mm/sec or "
                                     "cm/min)")
        speed = int(m.group(1)) / (1000.0 if m.group(2) == "mm/sec" else 6000.0)
        pct = None
    cnt = 0 if term == "FINE" else int(term[3:])
    if cnt > 100:
        raise ProgramFormatError(f"{file}:{k}: {term} (CNT 0..100)")
    return ReadMove(file=file, line=k, move_type=JOINT if kind == "J" else LINEAR,
                    name=f"P[{n}]", X_OT=X, configuration=config, speed=speed,
                    joint_percent=pct, zone=0.0 if term == "FINE" else zone_from_cnt(cnt),
                    target_file=file, target_line=tline, speed_line=k, zone_line=k,
                    options=options, orientation_line=oline, config_line=cline)


def _program(name: str, file: str, st: _MnState, pos: dict) -> ReadProgram:
    moves = tuple(_move(mo, pos, file) for mo in st.motions)
    rtcp = [("RTCP" in (o.upper() for o in m.options)) for m in moves if m.move_type == LINEAR]
    if rtcp and any(rtcp) and not all(rtcp):
        first = next(m for m in moves if m.move_type == LINEAR and "RTCP" not in m.options)
        raise ProgramFormatError(f"{file}:{first.line}: some linear moves are RTCP and some are "
                                 "not; this reader accepts one mode per program")
    X_FT, X_RO = _frame_from(st.remarks, "UTOOL"), _frame_from(st.remarks, "UFRAME")
    mass = st.remarks.get(("PAYLOAD", "M"))
    cog = None
    if all(("PAYLOAD", k) in st.remarks for k in ("CX", "CY", "CZ")):
        cog = np.array([st.remarks[("PAYLOAD", k)] for k in ("CX", "CY", "CZ")]) / 1000.0
    lines = {key: (file, k) for key, k in st.lines.items()}
    return ReadProgram(format="ls", files=(file,), name=name, moves=moves,
                       stationary_tool=bool(rtcp) and all(rtcp), X_FT=X_FT, X_RO=X_RO,
                       frame_lines=lines, load_mass=mass, load_cog=cog,
                       header=tuple(st.header), io=tuple(st.io))
