"""KUKA KRL: write a :class:`RobotProgram` as .src + .dat, read one back strictly.

Written (KUKA System Software 8.x, Operating and Programming Instructions for System
Integrators; Expert Programming): DEF/DEFDAT named as the file; the standard INI fold
(``BAS (#INITMOV,0 )``); ``$BASE`` (the fixed frame in $WORLD = $ROBROOT), ``$TOOL`` (the frame
on the flange), ``$LOAD`` (mass and centre of gravity of everything on the flange, in FLANGE
coordinates), ``$IPO_MODE`` (#BASE; #TCP for an external TCP: the stationary tool is $BASE,
the robot-guided workpiece is $TOOL); E6POS points with S and T from the planned joints in
the .dat; ``LIN`` with ``$VEL.CP`` [m/s] and ``$APO.CDIS`` [mm] + ``C_DIS``; ``PTP`` at
``BAS (#VEL_PTP, n)`` percent of the axes' top speed. Speeds and zones are written only when
they change.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from drakedeburr.programs.common import (
    ProgramFormatError,
    R_from_euler_zyx_deg,
    check_writable,
    euler_zyx_deg,
    fnum,
    header_lines,
    io_lines,
    joint_percent,
    pose_from_mm,
    speed_written,
    zone_written,
)
from drakedeburr.programs.names import comment_text
from drakedeburr.programs.program import JOINT, LINEAR, RobotProgram
from drakedeburr.programs.read_types import ReadMove, ReadProgram, parse_number, split_top_level
from drakedeburr.robots import joints_from_configuration, kuka_status_turn
from drakedeburr.robots.opw_ik import arm_branches
from drakedeburr.units import mm_from_m

__all__ = ["format_krl", "read_krl", "read_krl_dat", "frame_text"]

_IND = "   "
_INI = [";FOLD INI", "  ;FOLD BASISTECH INI", "    BAS (#INITMOV,0 )", "  ;ENDFOLD (BASISTECH INI)",
        ";ENDFOLD (INI)"]


def frame_text(X: np.ndarray) -> str:
    """KRL FRAME aggregate ``{X ..,Y ..,Z ..,A ..,B ..,C ..}`` of a pose [m] (mm, deg)."""
    x, y, z = (fnum(v) for v in mm_from_m(X[:3, 3]))
    a, b, c = (fnum(v) for v in euler_zyx_deg(X[:3, :3]))
    return f"{{X {x},Y {y},Z {z},A {a},B {b},C {c}}}"


def _load(p: RobotProgram) -> str:
    m = p.tool_mass + p.workpiece_mass
    cog = (p.tool_mass * np.asarray(p.tool_cog, float)
           + p.workpiece_mass * np.asarray(p.workpiece_cog, float)) / m
    x, y, z = (fnum(v) for v in mm_from_m(cog))
    return (f"{{M {fnum(m, 3)},CM {{X {x},Y {y},Z {z},A 0.0,B 0.0,C 0.0}},"
            "J {X 0.0,Y 0.0,Z 0.0}}")


def _ambiguous_turns(p: RobotProgram) -> list[int]:
    """Moves whose planned joints are not the ones S/T select (turns beyond +-360 deg)."""
    out = []
    for i in _turn_suspects(p):
        m = p.moves[i]
        X_BF = m.X_WT @ np.linalg.inv(p.X_FT)
        q_back = joints_from_configuration(p.kinematics, X_BF, "kuka",
                                           kuka_status_turn(p.kinematics, m.q))
        if np.abs(q_back - m.q).max() > 1e-6:
            out.append(i + 1)
    return out


def _turn_suspects(p: RobotProgram):
    """The moves S/T might not pin down. T holds every joint's sign and a 2*pi turn flips it,
    so with every limit inside +-360 deg no other turn has the same T; S holds the branch
    signs (shoulder, elbow, A5), so only a move exactly on a branch boundary can have a second
    IK solution with the same S. Anything else is read back in full (IK for every move: ~5 s
    for 7 500 moves, most of a KRL post)."""
    kin = p.kinematics
    if not p.moves:
        return []
    lower, upper = np.asarray(kin.limits.lower), np.asarray(kin.limits.upper)
    if np.any(lower <= -2 * np.pi) or np.any(upper >= 2 * np.pi):
        return range(len(p.moves))
    Q = np.array([m.q for m in p.moves], float)
    on_boundary = (arm_branches(kin.opw, Q) == 0).any(axis=1) | (np.abs(Q[:, 4]) < 1e-9)
    return np.flatnonzero(on_boundary)


def _motion_lines(p: RobotProgram) -> list[str]:
    out = []
    v_prev = z_prev = pct_prev = None
    for i, m in enumerate(p.moves):
        if m.comment:
            out.append(f"{_IND}; {comment_text(m.comment, 'krl')}")
        out += [f"{_IND}{x}" for x in io_lines(m.io, "krl")]
        if m.zone > 0 and zone_written("krl", m.zone) != z_prev:
            z_prev = zone_written("krl", m.zone)
            out.append(f"{_IND}$APO.CDIS = {fnum(mm_from_m(z_prev), 3)}")
        approx = " C_DIS" if m.zone > 0 else ""
        if m.move_type == JOINT:
            pct = joint_percent(p.joint_fraction(i))
            if pct != pct_prev:
                out.append(f"{_IND}BAS (#VEL_PTP, {pct})")
                pct_prev = pct
            out.append(f"{_IND}PTP XP{i + 1}{approx}")
            continue
        if speed_written("krl", m.speed) != v_prev:
            v_prev = speed_written("krl", m.speed)
            out.append(f"{_IND}$VEL.CP = {fnum(v_prev, 6)}")
        out.append(f"{_IND}LIN XP{i + 1}{approx}")
    out += [f"{_IND}{x}" for x in io_lines(p.io_end, "krl")]
    return out


def format_krl(program: RobotProgram) -> tuple[str, str]:
    """KRL (.src, .dat) texts named ``program.name`` (module docstring).

    KUKA S/T identify a solution only for joints within +-360 deg; moves whose planned joints
    are not the ones S/T select are listed in a header warning (the program is still written).
    """
    check_writable(program)
    p = program
    ambiguous = _ambiguous_turns(p)
    extra = ()
    if ambiguous:
        extra = ("WARNING: S/T cannot tell the planned turn of A4/A6 at move(s) "
                 + ", ".join(map(str, ambiguous[:20])),)
    hdr = [f"{_IND}; {h}".rstrip() for h in header_lines(p, "KUKA KRL", extra)]
    X_RO = np.linalg.solve(p.X_BR, p.X_WO)
    src = ["&ACCESS RVP", "&REL 1", f"DEF {p.name}( )", *hdr, *_INI, "",
           (f"{_IND}; $BASE: stationary tool {p.tool_name} (external TCP)" if p.stationary_tool
            else f"{_IND}; $BASE: work object {p.wobj_name}"),
           f"{_IND}$BASE = {frame_text(X_RO)}",
           (f"{_IND}; $TOOL: work object {p.wobj_name} held on the flange" if p.stationary_tool
            else f"{_IND}; $TOOL: tool {p.tool_name}"),
           f"{_IND}$TOOL = {frame_text(p.X_FT)}",
           f"{_IND}$LOAD = {_load(p)}",
           f"{_IND}$IPO_MODE = {'#TCP' if p.stationary_tool else '#BASE'}",
           f"{_IND}$ADVANCE = 3", *_motion_lines(p), "END", ""]
    dat = ["&ACCESS RVP", "&REL 1", f"DEFDAT {p.name} PUBLIC", *hdr]
    for i, m in enumerate(p.moves):
        X = p.X_OT(i)
        body = frame_text(X)[1:-1]
        s, t = kuka_status_turn(p.kinematics, m.q)
        dat.append(f"DECL E6POS XP{i + 1}={{{body},S {s},T {t},"
                   "E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}")
    dat += ["ENDDAT", ""]
    return "\n".join(src), "\n".join(dat)


# ---------------------------------------------------------------------------------- reading
_DAT_TYPES = ("INT", "REAL", "BOOL", "CHAR", "E6POS", "E6AXIS", "POS", "AXIS", "FRAME", "PDAT",
              "LDAT", "FDAT", "LOAD")
_STANDARD_INI = ("BAS(#INITMOV,0)", "GLOBALINTERRUPTDECL3WHEN$STOPMESS==TRUEDOIR_STOPM()",
                 "INTERRUPTON3")
_NAME = r"[A-Za-z_$][A-Za-z0-9_$]*"


def _struct(text: str, file: str, line: int) -> dict:
    """``{X 1.0,Y 2,...}`` -> {"X": 1.0, ...} (nested structures as dicts, enums as str)."""
    t = text.strip()
    if not (t.startswith("{") and t.endswith("}")):
        raise ProgramFormatError(f"{file}:{line}: expected a {{...}} structure, got {t[:40]!r}")
    out = {}
    for part in split_top_level(t[1:-1]):
        key, _, value = part.strip().partition(" ")
        value = value.strip()
        if not re.fullmatch(_NAME, key) or not value:
            raise ProgramFormatError(f"{file}:{line}: bad structure component {part!r}")
        if value.startswith("{"):
            out[key.upper()] = _struct(value, file, line)
        elif value.startswith("#") or value.upper() in ("TRUE", "FALSE"):
            out[key.upper()] = value
        else:
            out[key.upper()] = parse_number(value, file, line, key)
    return out


def _frame(d: dict, file: str, line: int) -> np.ndarray:
    try:
        return pose_from_mm([d["X"], d["Y"], d["Z"]], R_from_euler_zyx_deg(d["A"], d["B"], d["C"]))
    except KeyError as exc:
        raise ProgramFormatError(f"{file}:{line}: frame lacks component {exc}") from exc


def _lines(path: Path):
    """(line, text) without comments and blank lines; '&' directives only before DEF."""
    out = []
    for k, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        s = raw.split(";", 1)[0].strip()
        if s:
            out.append((k, s))
    return out


def read_krl_dat(path: str | Path, expect_name: str | None = None) -> tuple[str, dict]:
    """Read a .dat strictly: DEFDAT, typed declarations, ENDDAT.

    Returns:
        (DEFDAT name, {name: (type, value, line)}) with E6POS/POS/FRAME/E6AXIS as dicts.
    """
    path = Path(path)
    file = str(path)
    name, decls, ended = None, {}, False
    for k, s in _lines(path):
        words = s.split()
        if s.startswith("&") and name is None:
            continue
        if name is None:
            if words[0].upper() != "DEFDAT" or len(words) not in (2, 3) or (
                    len(words) == 3 and words[2].upper() != "PUBLIC"):
                raise ProgramFormatError(f"{file}:{k}: expected 'DEFDAT <name> [PUBLIC]', "
                                         f"got {s!r}")
            name = words[1]
            continue
        if words[0].upper() == "ENDDAT":
            ended = True
            continue
        if ended:
            raise ProgramFormatError(f"{file}:{k}: text after ENDDAT: {s!r}")
        m = re.fullmatch(rf"(?:DECL\s+)?(?:GLOBAL\s+)?(\w+)\s+({_NAME})\s*=\s*(.+)", s, re.I)
        if not m or m.group(1).upper() not in _DAT_TYPES:
            raise ProgramFormatError(f"{file}:{k}: expected '[DECL] <type> <name>=<value>' with a "
                                     f"type in {', '.join(_DAT_TYPES)}, got {s!r}")
        dtype, vname, value = m.group(1).upper(), m.group(2), m.group(3).strip()
        parsed = (_struct(value, file, k) if value.startswith("{")
                  else value if dtype in ("BOOL", "CHAR") else parse_number(value, file, k, vname))
        decls[vname.upper()] = (dtype, parsed, k)
    if name is None or not ended:
        raise ProgramFormatError(f"{file}: expected DEFDAT ... ENDDAT")
    if expect_name is not None and name.lower() != expect_name.lower():
        raise ProgramFormatError(f"{file}: DEFDAT name {name!r} is not the file name "
                                 f"{expect_name!r} (KRL requires them equal)")
    return name, decls


class _SrcState:
    """Settings in force while reading a .src (value, line)."""

    def __init__(self) -> None:
        self.vel_cp: tuple[float, int] | None = None
        self.cdis: tuple[float, int] | None = None
        self.vel_ptp: tuple[int, int] | None = None
        self.frames: dict[str, tuple[object, int]] = {}
        self.io: list[tuple[int, str, int, float]] = []


def _assignment(s: str, k: int, file: str, st: _SrcState) -> None:
    target, _, value = (x.strip() for x in s.partition("="))
    key = target.upper().replace(" ", "")
    if key in ("$BASE", "$TOOL"):
        st.frames[key] = (_frame(_struct(value, file, k), file, k), k)
    elif key == "$LOAD":
        st.frames[key] = (_struct(value, file, k), k)
    elif key == "$IPO_MODE":
        if value.upper() not in ("#BASE", "#TCP"):
            raise ProgramFormatError(f"{file}:{k}: $IPO_MODE must be #BASE or #TCP, got {value!r}")
        st.frames[key] = (value.upper(), k)
    elif key == "$ADVANCE":
        parse_number(value, file, k, "$ADVANCE")
    elif key == "$VEL.CP":
        st.vel_cp = (parse_number(value, file, k, "$VEL.CP"), k)
    elif key == "$APO.CDIS":
        st.cdis = (parse_number(value, file, k, "$APO.CDIS") / 1000.0, k)
    elif re.fullmatch(r"\$(OUT|ANOUT)\[\d+\]", key):
        port = int(key[key.index("[") + 1:-1])
        if key.startswith("$OUT"):
            if value.upper() not in ("TRUE", "FALSE"):
                raise ProgramFormatError(f"{file}:{k}: {target} must be TRUE or FALSE, got "
                                         f"{value!r}")
            st.io.append((k, "do", port, 1.0 if value.upper() == "TRUE" else 0.0))
        else:
            v = parse_number(value, file, k, target)
            if not -1.0 <= v <= 1.0:
                raise ProgramFormatError(f"{file}:{k}: {target} must be -1.0 .. 1.0, got "
                                         f"{value!r}")
            st.io.append((k, "ao", port, v))
    else:
        raise ProgramFormatError(f"{file}:{k}: assignment to {target!r} is outside the motion "
                                 "subset this reader accepts ($BASE, $TOOL, $LOAD, $IPO_MODE, "
                                 "$ADVANCE, $VEL.CP, $APO.CDIS, $OUT[n], $ANOUT[n])")


def _motion(s: str, k: int, file: str, st: _SrcState, decls: dict, dat_file: str) -> ReadMove:
    words = s.split()
    kind = words[0].upper()
    approx = words[2].upper() if len(words) == 3 else None
    if len(words) not in (2, 3) or approx not in (None, "C_DIS"):
        raise ProgramFormatError(f"{file}:{k}: expected '{kind} <point> [C_DIS]', got {s!r}")
    name = words[1].upper()
    if name not in decls or decls[name][0] != "E6POS":
        raise ProgramFormatError(f"{file}:{k}: {words[1]!r} is not an E6POS declared in "
                                 f"{dat_file} (this reader takes points from the .dat)")
    _, d, tline = decls[name]
    if approx and st.cdis is None:
        raise ProgramFormatError(f"{file}:{k}: C_DIS before any $APO.CDIS")
    zone, zline = (st.cdis if approx else (0.0, k))
    if kind == "PTP":
        if st.vel_ptp is None:
            raise ProgramFormatError(f"{file}:{k}: PTP before any BAS (#VEL_PTP, n)")
        speed, pct, vline = None, st.vel_ptp[0], st.vel_ptp[1]
    else:
        if st.vel_cp is None:
            raise ProgramFormatError(f"{file}:{k}: LIN before any $VEL.CP")
        speed, pct, vline = st.vel_cp[0], None, st.vel_cp[1]
    for key in ("S", "T"):
        if key not in d:
            raise ProgramFormatError(f"{dat_file}:{tline}: {words[1]} lacks {key}")
    return ReadMove(file=file, line=k, move_type=JOINT if kind == "PTP" else LINEAR,
                    name=words[1], X_OT=_frame(d, dat_file, tline),
                    configuration=(int(d["S"]), int(d["T"])), speed=speed, joint_percent=pct,
                    zone=zone, target_file=dat_file, target_line=tline, speed_line=vline,
                    zone_line=zline)


def _src_statement(s: str, k: int, file: str, st: _SrcState, decls: dict, dat_file: str,
                   moves: list) -> None:
    compact = s.upper().replace(" ", "")
    if compact in _STANDARD_INI or compact == "WAITSEC0":
        return
    m = re.fullmatch(r"BAS\(#VEL_PTP,(\d+)\)", compact)
    if m:
        st.vel_ptp = (int(m.group(1)), k)
        return
    if s.split()[0].upper() in ("PTP", "LIN"):
        moves.append(_motion(s, k, file, st, decls, dat_file))
        return
    if "=" in s and not re.search(r"[<>!]=|==", s):
        _assignment(s, k, file, st)
        return
    raise ProgramFormatError(f"{file}:{k}: statement {s!r} is outside the motion subset this "
                             "reader accepts (PTP, LIN, BAS #INITMOV/#VEL_PTP, the settings "
                             "$BASE, $TOOL, $LOAD, $IPO_MODE, $ADVANCE, $VEL.CP, $APO.CDIS)")


def read_krl(path: str | Path, check_name: bool = True) -> ReadProgram:
    """Read a KRL .src and the .dat beside it (if any) strictly.

    ``check_name=False`` skips the DEF/DEFDAT = file name rule (for files renamed after
    export)."""
    path = Path(path)
    src = path.with_suffix(".src")
    dat = path.with_suffix(".dat")
    file, dat_file = str(src), str(dat)
    dat_name, decls = read_krl_dat(dat) if dat.is_file() else (None, {})
    name, ended, moves, st = None, False, [], _SrcState()
    for k, s in _lines(src):
        if name is None:
            if s.startswith("&"):
                continue
            m = re.fullmatch(rf"(?:GLOBAL\s+)?DEF\s+({_NAME})\s*\(\s*\)", s, re.I)
            if not m:
                raise ProgramFormatError(f"{file}:{k}: expected 'DEF <name>( )', got {s!r}")
            name = m.group(1)
            continue
        if s.upper() == "END":
            ended = True
            continue
        if ended:
            raise ProgramFormatError(f"{file}:{k}: text after END: {s!r}")
        _src_statement(s, k, file, st, decls, dat_file, moves)
    if name is None or not ended:
        raise ProgramFormatError(f"{file}: expected DEF ... END")
    stem = src.name.split(".")[0]
    for what, n, f in (("DEF", name, file), ("DEFDAT", dat_name, dat_file)):
        if check_name and n is not None and n.lower() != stem.lower():
            raise ProgramFormatError(f"{f}: {what} name {n!r} is not the file name {stem!r} "
                                     "(KRL requires them equal)")
    return _program(name, (file, dat_file) if dat_name else (file,), moves, st)


def _program(name: str, files: tuple[str, str], moves: list, st: _SrcState) -> ReadProgram:
    file = files[0]
    load = st.frames.get("$LOAD")
    mass = cog = None
    if load is not None:
        d, k = load
        mass = float(d.get("M", np.nan))
        cm = d.get("CM", {})
        cog = np.array([cm.get("X", np.nan), cm.get("Y", np.nan), cm.get("Z", np.nan)]) / 1000.0
    lines = {"tool": (file, st.frames.get("$TOOL", (None, 0))[1]),
             "work object": (file, st.frames.get("$BASE", (None, 0))[1]),
             "load": (file, load[1] if load else 0)}
    ipo = st.frames.get("$IPO_MODE", ("#BASE", 0))[0]
    return ReadProgram(format="krl", files=files, name=name, moves=tuple(moves),
                       stationary_tool=ipo == "#TCP",
                       X_FT=st.frames.get("$TOOL", (None, 0))[0],
                       X_RO=st.frames.get("$BASE", (None, 0))[0], frame_lines=lines,
                       load_mass=mass, load_cog=cog, io=tuple(st.io))
