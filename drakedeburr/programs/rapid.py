"""ABB RAPID: write a :class:`RobotProgram` as a module, read one back strictly.

Written (RAPID reference manual: tooldata, wobjdata, loaddata, speeddata, zonedata, robtarget,
MoveL, MoveJ, GripLoad, ConfL/ConfJ):

* tool in hand: ``tooldata`` robhold TRUE, tframe = TCP in tool0, tload = the tool model's mass
  and centre of gravity; ``wobjdata`` robhold FALSE, ufprog TRUE, uframe = the work object in
  the world (= base) frame; robtargets = TCP in the work object;
* workpiece in hand (stationary tool): ``tooldata`` robhold FALSE, tframe = the stationary TCP
  in the world frame, tload = the gripper; ``wobjdata`` robhold TRUE, ufprog TRUE, ufmec "",
  uframe = the held work object in tool0 ("in the wrist coordinate system if a stationary tool
  is used"); robtargets = the stationary TCP in the held work object; the workpiece's load by
  ``GripLoad`` (loaddata cog in the held object frame).
* each move's speed: a predefined speeddata when it is one exactly (v150), else a named
  ``CONST speeddata vdd23_456 := [23.456,500,5000,1000]`` (mm/s, 0.001 mm/s): never rounded
  to a standard speed; zones: fine/z1/... or ``CONST zonedata zdd0_300`` with ABB's ratios.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.programs.common import (
    ABB_SPEEDS,
    ABB_ZONES,
    ProgramFormatError,
    R_from_quat_wxyz,
    check_writable,
    fnum,
    header_lines,
    io_lines,
    pose_from_mm,
    quat_wxyz,
    speed_written,
    zone_written,
)
from drakedeburr.programs.names import comment_text
from drakedeburr.programs.program import JOINT, LINEAR, RobotProgram
from drakedeburr.programs.read_types import ReadMove, ReadProgram, parse_number, split_top_level
from drakedeburr.units import mm_from_m

__all__ = ["format_rapid", "read_rapid", "speed_name", "zone_name"]

_IND = "  "


def speed_name(speed: float) -> str:
    """speeddata name of a TCP speed [m/s]: predefined (v150) or ``vdd<mm>_<0.001 mm>``."""
    mm = round(mm_from_m(speed_written("rapid", speed)), 3)
    if mm in ABB_SPEEDS:
        return f"v{int(mm)}"
    return "vdd" + fnum(mm, 3).replace(".", "_")


def zone_name(zone: float) -> str:
    """zonedata name of a zone radius [m]: fine, z1, ... or ``zdd<mm>_<0.001 mm>``."""
    mm = round(mm_from_m(zone_written("rapid", zone)), 3)
    if mm == 0:
        return "fine"
    if mm in ABB_ZONES:
        return f"z{int(mm)}"
    return "zdd" + fnum(mm, 3).replace(".", "_")


def _pose_text(X: np.ndarray) -> str:
    xyz = ",".join(fnum(v) for v in mm_from_m(X[:3, 3]))
    return f"[[{xyz}],[{','.join(fnum(v, 10) for v in quat_wxyz(X[:3, :3]))}]]"


def _load_text(mass: float, cog_m) -> str:
    cog = ",".join(fnum(v) for v in mm_from_m(np.asarray(cog_m, float)))
    return f"[{fnum(mass, 3)},[{cog}],[1,0,0,0],0,0,0]"


def _data(p: RobotProgram) -> list[str]:
    """tooldata, wobjdata, loaddata declarations."""
    X_RO = np.linalg.solve(p.X_BR, p.X_WO)
    if not p.stationary_tool:
        return [f"PERS tooldata {p.tool_name} := [TRUE,{_pose_text(p.X_FT)},"
                f"{_load_text(p.tool_mass, p.tool_cog)}];",
                f"PERS wobjdata {p.wobj_name} := [FALSE,TRUE,\"\",{_pose_text(X_RO)},"
                "[[0,0,0],[1,0,0,0]]];"]
    # the workpiece's cog in the held object frame (loaddata, stationary tool)
    cog_O = np.linalg.solve(p.X_FT, np.append(np.asarray(p.workpiece_cog, float), 1.0))[:3]
    return [f"PERS tooldata {p.tool_name} := [FALSE,{_pose_text(X_RO)},"
            f"{_load_text(p.tool_mass, p.tool_cog)}];",
            f"PERS wobjdata {p.wobj_name} := [TRUE,TRUE,\"\",{_pose_text(p.X_FT)},"
            "[[0,0,0],[1,0,0,0]]];",
            f"PERS loaddata {p.wobj_name}Load := {_load_text(p.workpiece_mass, cog_O)};"]


def _speed_zone_data(p: RobotProgram) -> list[str]:
    speeds, zones = {}, {}
    for m in p.moves:
        name = speed_name(m.speed)
        if name.startswith("vdd"):
            v = fnum(mm_from_m(speed_written("rapid", m.speed)), 3)
            speeds[name] = f"CONST speeddata {name} := [{v},500,5000,1000];"
        name = zone_name(m.zone)
        if name.startswith("zdd"):
            z = mm_from_m(zone_written("rapid", m.zone))
            zones[name] = (f"CONST zonedata {name} := [FALSE,{fnum(z, 3)},{fnum(1.5 * z, 3)},"
                           f"{fnum(1.5 * z, 3)},{fnum(0.15 * z, 3)},{fnum(1.5 * z, 3)},"
                           f"{fnum(0.15 * z, 3)}];")
    return [speeds[k] for k in sorted(speeds)] + [zones[k] for k in sorted(zones)]


def format_rapid(program: RobotProgram) -> str:
    """RAPID module text (module docstring); refuses inconsistent programs."""
    check_writable(program)
    p = program
    if len(p.name) > 32:
        raise InputError(f"RAPID module name {p.name!r}: at most 32 characters")
    out = [f"MODULE {p.name}"]
    out += [f"{_IND}! {h}".rstrip() for h in header_lines(p, "ABB RAPID")]
    out += [_IND + line for line in _data(p) + _speed_zone_data(p)]
    for i in range(len(p.moves)):
        X = p.X_OT(i)
        if p.stationary_tool:
            X = np.linalg.inv(X)  # the stationary TCP in the held work object
        cf = p.configuration(i)
        out.append(f"{_IND}CONST robtarget p{i + 1} := [{_pose_text(X)[1:-1]},"
                   f"[{cf[0]},{cf[1]},{cf[2]},{cf[3]}],[9E9,9E9,9E9,9E9,9E9,9E9]];")
    out += ["", f"{_IND}PROC main()", f"{_IND * 2}ConfJ \\On;", f"{_IND * 2}ConfL \\On;"]
    if p.stationary_tool:
        out.append(f"{_IND * 2}GripLoad {p.wobj_name}Load;")
    for i, m in enumerate(p.moves):
        if m.comment:
            out.append(f"{_IND * 2}! {comment_text(m.comment, 'rapid')}")
        out += [f"{_IND * 2}{x}" for x in io_lines(m.io, "rapid")]
        instr = "MoveJ" if m.move_type == JOINT else "MoveL"
        out.append(f"{_IND * 2}{instr} p{i + 1}, {speed_name(m.speed)}, {zone_name(m.zone)}, "
                   f"{p.tool_name} \\WObj:={p.wobj_name};")
    out += [f"{_IND * 2}{x}" for x in io_lines(p.io_end, "rapid")]
    if p.stationary_tool:
        out.append(f"{_IND * 2}GripLoad load0;")
    out += [f"{_IND}ENDPROC", "ENDMODULE", ""]
    return "\n".join(out)


# ---------------------------------------------------------------------------------- reading
_TYPES = ("tooldata", "wobjdata", "loaddata", "speeddata", "zonedata", "robtarget")


def _aggregate(text: str, file: str, line: int):
    """RAPID aggregate ``[a,[b,c],"s",TRUE]`` -> nested lists of float/bool/str."""
    t = text.strip()
    if t.startswith("[") and t.endswith("]"):
        return [_aggregate(x, file, line) for x in split_top_level(t[1:-1])]
    if t in ("TRUE", "FALSE"):
        return t == "TRUE"
    if t.startswith('"') and t.endswith('"'):
        return t[1:-1]
    if t[:1].isalpha():
        return ("ref", t)  # another data's name (e.g. := z10)
    return parse_number(t, file, line, "value")


def _pose(value, file: str, line: int, what: str) -> np.ndarray:
    try:
        xyz, q = value
        if len(xyz) != 3 or len(q) != 4:
            raise ValueError
        if abs(np.linalg.norm(q) - 1.0) > 1e-6:
            raise ProgramFormatError(f"{file}:{line}: {what}: quaternion not normalised "
                                     f"(|q| = {np.linalg.norm(q):.9f})")
        return pose_from_mm(xyz, R_from_quat_wxyz(q))
    except (TypeError, ValueError) as exc:
        raise ProgramFormatError(f"{file}:{line}: {what}: expected [[x,y,z],[q1,q2,q3,q4]]"
                                 ) from exc


def _confdata(value, file: str, line: int) -> tuple[int, ...]:
    """A robtarget's confdata [cf1,cf4,cf6,cfx] as integers."""
    try:
        cf = value[2]
        return tuple(int(round(float(v))) for v in cf)
    except (TypeError, ValueError, IndexError) as exc:
        raise ProgramFormatError(f"{file}:{line}: robtarget: confdata expected as "
                                 f"[cf1,cf4,cf6,cfx] numbers") from exc


def _declaration(stmt: str, file: str, line: int, data: dict) -> None:
    words = stmt.split(None, 1)
    if words and words[0] in ("LOCAL", "TASK"):
        stmt = words[1]
    head, sep, value = stmt.partition(":=")
    parts = head.split()
    if len(parts) >= 2 and parts[0] in ("PERS", "CONST", "VAR") and parts[1] not in _TYPES:
        raise ProgramFormatError(f"{file}:{line}: data type {parts[1]!r} is outside the motion "
                                 f"subset this reader accepts ({', '.join(_TYPES)})")
    if not sep or len(parts) != 3 or parts[0] not in ("PERS", "CONST", "VAR"):
        raise ProgramFormatError(f"{file}:{line}: expected '<PERS|CONST|VAR> <type> <name> := "
                                 f"<value>;', got {stmt!r}")
    _, dtype, name = parts
    if dtype not in _TYPES:
        raise ProgramFormatError(f"{file}:{line}: data type {dtype!r} is outside the motion "
                                 f"subset this reader accepts ({', '.join(_TYPES)})")
    data[name] = (dtype, _aggregate(value, file, line), line)


def _strip_comment(raw: str) -> str:
    """A line without its '!' comment (a '!' inside a string is text)."""
    quote = False
    for i, ch in enumerate(raw):
        if ch == '"':
            quote = not quote
        elif ch == "!" and not quote:
            return raw[:i].strip()
    return raw.strip()


def _statements(path: Path):
    """(module name, [(line, statement, where)]) with where in data/proc/body/endproc/
    endmodule; comments and blank lines dropped."""
    file = str(path)
    module, out, proc = None, [], False
    for k, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        s = _strip_comment(raw)
        if not s:
            continue
        word = s.split()[0]
        if module is None:
            if word != "MODULE" or len(s.split()) != 2:
                raise ProgramFormatError(f"{file}:{k}: expected 'MODULE <name>', got {s!r}")
            module = s.split()[1]
            continue
        if word in ("PROC", "ENDPROC", "ENDMODULE"):
            proc = word == "PROC"
            out.append((k, s, word.lower()))
            continue
        if not s.endswith(";"):  # refused in file order by read_rapid
            out.append((k, s, "unterminated"))
            continue
        out.append((k, s[:-1].strip(), "body" if proc else "data"))
    if module is None:
        raise ProgramFormatError(f"{file}: no MODULE")
    if not out or out[-1][2] != "endmodule":
        raise ProgramFormatError(f"{file}: no ENDMODULE at the end")
    return module, out


def _parse(stmts, file: str) -> tuple[dict, list, list, list]:
    """In file order: data declarations {name: (type, value, line)}, motion statements
    [(line, instr, target, speed, zone, tool, wobj)], GripLoads and SetDO/SetAO; the first
    line outside the subset raises."""
    data: dict = {}
    moves, grips, procs = [], [], 0
    io: list = []
    for k, s, where in stmts:
        if where == "unterminated":
            raise ProgramFormatError(f"{file}:{k}: {s!r} is a construct this reader does not "
                                     "accept (or a statement without ';')")
        if where == "data":
            _declaration(s, file, k, data)
            continue
        if where == "proc":
            procs += 1
            if s.replace(" ", "") != "PROCmain()" or procs > 1:
                raise ProgramFormatError(f"{file}:{k}: only one routine, 'PROC main()', is "
                                         f"accepted (straight-line motion programs), got {s!r}")
            continue
        if where != "body":
            continue
        if not s.strip():
            raise ProgramFormatError(f"{file}:{k}: an empty statement (a ';' alone) is "
                                     "outside the motion subset this reader accepts")
        word = s.split()[0]
        if word in ("ConfJ", "ConfL") and s[len(word):].replace(" ", "") in ("\\On", "\\Off"):
            continue
        if word == "GripLoad" and len(s.split()) == 2:
            grips.append((k, s.split()[1]))
            continue
        if word in ("SetDO", "SetAO"):
            args = split_top_level(s[len(word):])
            if len(args) != 2 or not re.fullmatch(r"[A-Za-z]\w*", args[0].strip()):
                raise ProgramFormatError(f"{file}:{k}: expected '{word} <signal>, <value>', "
                                         f"got {s!r}")
            value = parse_number(args[1].strip(), file, k, f"{word} value")
            if word == "SetDO" and value not in (0, 1):
                raise ProgramFormatError(f"{file}:{k}: SetDO value must be 0 or 1, got {s!r}")
            io.append((k, word[3:].lower(), args[0].strip(), value))
            continue
        if word in ("MoveL", "MoveJ"):
            args = split_top_level(s[len(word):])
            if len(args) != 4 or not args[3].replace(" ", "").count("\\WObj:=") == 1:
                raise ProgramFormatError(f"{file}:{k}: expected '{word} <target>, <speed>, "
                                         f"<zone>, <tool> \\WObj:=<wobj>', got {s!r}")
            tool, wobj = args[3].replace(" ", "").split("\\WObj:=")
            moves.append((k, word, args[0], args[1], args[2], tool, wobj))
            continue
        raise ProgramFormatError(f"{file}:{k}: instruction {word!r} is outside the motion "
                                 "subset this reader accepts (MoveL, MoveJ, ConfL, ConfJ, "
                                 "GripLoad, SetDO, SetAO)")
    return data, moves, grips, io


def _speed(name: str, data: dict, file: str, k: int) -> tuple[float, int]:
    if name in data and data[name][0] == "speeddata":
        value, line = data[name][1], data[name][2]
        return parse_number(str(value[0]), file, line, "speeddata v_tcp") / 1000.0, line
    if name.startswith("v") and name[1:].isdigit() and int(name[1:]) in ABB_SPEEDS:
        return int(name[1:]) / 1000.0, k
    raise ProgramFormatError(f"{file}:{k}: speed {name!r} is neither predefined nor declared")


def _zone(name: str, data: dict, file: str, k: int) -> tuple[float, int]:
    if name in data and data[name][0] == "zonedata":
        value, line = data[name][1], data[name][2]
        if isinstance(value, tuple):  # := z10
            return _zone(value[1], data, file, line)
        return (0.0 if value[0] is True else float(value[1]) / 1000.0), line
    if name == "fine":
        return 0.0, k
    if name.startswith("z") and name[1:].isdigit() and int(name[1:]) in ABB_ZONES:
        return int(name[1:]) / 1000.0, k
    raise ProgramFormatError(f"{file}:{k}: zone {name!r} is neither predefined nor declared")


def _get(data: dict, name: str, dtype: str, file: str, k: int):
    if name not in data or data[name][0] != dtype:
        raise ProgramFormatError(f"{file}:{k}: {name!r} is not a declared {dtype}")
    return data[name][1], data[name][2]


def _frames(tool, wobj, file: str):
    """(stationary, X_FT, X_RO, tool load (mass, cog_F)) from tooldata and wobjdata values."""
    (tv, tl), (wv, wl) = tool, wobj
    try:
        robhold, tframe, tload = tv
        w_robhold, _ufprog, _ufmec, uframe, oframe = wv
    except (TypeError, ValueError) as exc:
        raise ProgramFormatError(f"{file}:{tl}: tooldata/wobjdata with the wrong number of "
                                 "components") from exc
    X_t = _pose(tframe, file, tl, "tooldata tframe")
    X_w = _pose(uframe, file, wl, "wobjdata uframe") @ _pose(oframe, file, wl, "wobjdata oframe")
    if robhold is w_robhold:
        raise ProgramFormatError(f"{file}:{tl}: tooldata robhold {robhold} with wobjdata robhold "
                                 f"{w_robhold}: one of tool and work object must be held")
    mass = parse_number(str(tload[0]), file, tl, "tload mass")
    cog = np.asarray(tload[1], float) / 1000.0
    if robhold:
        return False, X_t, X_w, (mass, cog)
    return True, X_w, X_t, (mass, cog)


def read_rapid(path: str | Path) -> ReadProgram:
    """Read a RAPID module strictly (see :mod:`drakedeburr.programs.read_types`)."""
    path = Path(path)
    file = str(path)
    name, stmts = _statements(path)
    data, moves_raw, grips, io_raw = _parse(stmts, file)
    io = tuple(io_raw)
    if not moves_raw:
        raise ProgramFormatError(f"{file}: no MoveL/MoveJ in PROC main()")
    tools = {(t, w) for *_, t, w in moves_raw}
    if len(tools) != 1:
        raise ProgramFormatError(f"{file}:{moves_raw[0][0]}: the moves use several tools/work "
                                 f"objects {sorted(tools)}; the subset uses one of each")
    tool_name, wobj_name = tools.pop()
    k0 = moves_raw[0][0]
    stationary, X_FT, X_RO, (mass, cog) = _frames(
        _get(data, tool_name, "tooldata", file, k0), _get(data, wobj_name, "wobjdata", file, k0),
        file)
    for k, gname in grips:
        if gname == "load0":
            continue
        (gm, gcog_O, *_), _ = _get(data, gname, "loaddata", file, k)
        g_cog = (X_FT @ np.append(np.asarray(gcog_O, float) / 1000.0, 1.0))[:3]
        cog = (mass * cog + gm * g_cog) / (mass + gm)
        mass += gm
    moves = []
    for k, instr, target, speed, zone, _, _ in moves_raw:
        value, tline = _get(data, target, "robtarget", file, k)
        X = _pose(value[:2], file, tline, "robtarget")
        cf = _confdata(value, file, tline)
        v, vline = _speed(speed, data, file, k)
        z, zline = _zone(zone, data, file, k)
        moves.append(ReadMove(
            file=file, line=k, move_type=JOINT if instr == "MoveJ" else LINEAR, name=target,
            X_OT=np.linalg.inv(X) if stationary else X, configuration=cf, speed=v,
            joint_percent=None, zone=z, target_file=file, target_line=tline, speed_line=vline,
            zone_line=zline))
    lines = {"tool": (file, data[tool_name][2]), "work object": (file, data[wobj_name][2]),
             "load": (file, data[tool_name][2])}
    return ReadProgram(format="rapid", files=(file,), name=name, moves=tuple(moves),
                       stationary_tool=stationary, X_FT=X_FT, X_RO=X_RO, frame_lines=lines,
                       load_mass=mass, load_cog=cog,
                       declarations={n: d[0] for n, d in data.items()}, io=io)
