"""Programs carry the verified motion: write -> strict read -> compare is exact in all three
formats and both modes; every edit (speed, zone, pose, configuration, move order) is named
with its line; rapidchecker accepts every RAPID; controller hygiene (names, loads, frames)."""

import re
from dataclasses import replace

import numpy as np
import pytest
from program_support import ARMS, SUFFIX, random_program

import drakedeburr.programs as mut
from drakedeburr.errors import InputError
from drakedeburr.programs.common import LS_REMARK_MAX
from drakedeburr.robots import JointLimits, RobotKinematics, get_robot, joints_from_configuration

CASES = [(fmt, arm, st) for fmt, arm in [("rapid", "irb1600"), ("krl", "kr6_r700"),
                                         ("ls", "lrmate200ic"), ("ls", "m10ia")]
         for st in (False, True)]


def rapidcheck(text: str) -> list:
    from rapidchecker.check import check_format
    from rapidchecker.whitespace_checks import check_whitespace

    return [str(e) for e in check_format(text) + check_whitespace(text)]


def _write(tmp_path, fmt, arm, stationary, **kw):
    prog = random_program(arm, stationary, **kw)
    path = tmp_path / f"deburr_test{SUFFIX[fmt]}"
    mut.write_program(prog, path)
    return prog, path


@pytest.mark.parametrize("fmt, arm, stationary", CASES)
def test_write_read_compare_is_exact(tmp_path, fmt, arm, stationary):
    prog, path = _write(tmp_path, fmt, arm, stationary)
    back = mut.read_program(path)
    assert back.format == fmt and back.stationary_tool == stationary
    assert len(back.moves) == len(prog.moves)
    assert mut.compare_programs(prog, back) == []
    # the poses + configurations read back give the planned joints (the controller's view)
    spec = get_robot(arm)
    X_BR = spec.X_BR
    for i, m in enumerate(back.moves):
        X_BF = X_BR @ back.X_RO @ m.X_OT @ np.linalg.inv(back.X_FT)
        q = joints_from_configuration(spec.kinematics, X_BF, spec.controller, m.configuration)
        assert np.abs(q - prog.moves[i].q).max() < 1e-6, (i, q, prog.moves[i].q)
    if fmt == "rapid":
        assert rapidcheck(path.read_text()) == []


@pytest.mark.parametrize("fmt, arm, stationary", CASES[::2])
def test_each_move_carries_its_own_speed_and_zone(tmp_path, fmt, arm, stationary):
    prog, path = _write(tmp_path, fmt, arm, stationary)
    back = mut.read_program(path)
    lin = [(m, r) for m, r in zip(prog.moves, back.moves, strict=True) if m.move_type == "linear"]
    speeds = {round(r.speed, 6) for _, r in lin}
    assert len(speeds) >= 6  # not collapsed onto one standard speed
    for m, r in lin:
        # LS: whole mm/sec or cm/min (1/6 mm/s), rounded down
        resolution = 1e-3 / 6 if fmt == "ls" else 1e-6
        assert m.speed - resolution - 1e-12 <= r.speed <= m.speed + 1e-6
    text = path.read_text()
    if fmt == "rapid":
        assert "CONST speeddata vdd23_457 := [23.457,500,5000,1000];" in text
        assert "MoveL p2, vdd23_457, z1," in text and "MoveL p3, v600, zdd0_300," in text
    if fmt == "krl":
        sets = [ln.strip() for ln in text.splitlines() if ln.strip().startswith("$VEL.CP")]
        # a speed is set only when it changes: no two successive identical statements
        assert all(a != b for a, b in zip(sets[:-1], sets[1:], strict=True))
        assert "$VEL.CP = 0.023457" in text and "BAS (#VEL_PTP, 33)" in text
        assert "BAS (#VEL_PTP, 12)" in text  # the last joint move at its own 12.5 %
    if fmt == "ls":
        # 23.457 mm/s: 140 cm/min = 23.333 mm/s is closer below than 23 mm/sec; CNT only where
        # speed * LS_ACCEL_TIME / 2 fits the zone (docs/post.md): the corner would round within
        # 4.5 mm of the point, more than its 1 mm zone -> FINE
        assert "L P[2] 140cm/min FINE" in text and "J P[1] 33% FINE" in text
        assert "L P[3] 600mm/sec FINE" in text


def _edit(path, pattern, repl, count=1):
    text = path.read_text()
    new, n = re.subn(pattern, repl, text, count=count, flags=re.M)
    assert n == count, pattern
    path.write_text(new)
    return next(k for k, (a, b) in enumerate(zip(text.splitlines(), new.splitlines(),
                                                  strict=False), start=1) if a != b)


def _plus(m, mm=10.0):
    return f"{float(m.group(2)) + mm:.6f}"


EDITS = {
    "rapid": {
        "speed": (r"(MoveL p4, )v\w+", r"\1v1500"),
        "zone": (r"(MoveL p2, vdd23_457, )z1", r"\1z50"),
        "pose": (r"(CONST robtarget p5 := \[\[)(-?\d+\.\d+)", lambda m: m.group(1) + _plus(m)),
        "configuration": (r"(CONST robtarget p6 := \[\[.*?\],\[.*?\],\[)(-?\d+)",
                          lambda m: m.group(1) + str(int(m.group(2)) + 1)),
        "move order": (r"MoveL p3, (\S+), (\S+),", r"MoveL p4, \1, \2,"),
    },
    "krl": {
        "speed": (r"\$VEL\.CP = 0\.023457", "$VEL.CP = 1.500000"),
        "zone": (r"\$APO\.CDIS = 5\.000", "$APO.CDIS = 50.000"),
        "pose": (r"(DECL E6POS XP5=\{X )(-?\d+\.\d+)", lambda m: m.group(1) + _plus(m)),
        "configuration": (r"(DECL E6POS XP6=\{.*?,S )(\d+)", lambda m: m.group(1) + str(
            int(m.group(2)) ^ 4)),
        "move order": (r"LIN XP3\b", "LIN XP4"),
    },
    "ls": {
        "speed": (r"(L P\[4\] )\d+(mm/sec|cm/min)", r"\g<1>1500mm/sec"),
        "zone": (r"(L P\[2\] 140cm/min )FINE", r"\1CNT100"),
        "pose": (r"(P\[5\]\{\n   GP1:\n.*\n\tX = )(-?\d+\.\d+)", lambda m: m.group(1) + _plus(m)),
        "configuration": (r"(P\[6\]\{\n   GP1:\n.*CONFIG : ')([NF])", lambda m: m.group(1) + (
            "F" if m.group(2) == "N" else "N")),
        "move order": (r"L P\[3\] (\d+)(mm/sec|cm/min)", r"L P[4] \1\2"),
    },
}


@pytest.mark.parametrize("fmt", ["rapid", "krl", "ls"])
@pytest.mark.parametrize("item", ["speed", "zone", "pose", "configuration", "move order"])
def test_an_edit_is_named_with_its_line(tmp_path, fmt, item):
    prog, path = _write(tmp_path, fmt, ARMS[fmt], False)
    pattern, repl = EDITS[fmt][item]
    edited = path.with_suffix(".dat") if fmt == "krl" and item in ("pose", "configuration") \
        else path
    line = _edit(edited, pattern, repl)
    found = mut.compare_programs(prog, mut.read_program(path))
    assert found, item
    items = {d.item for d in found}
    assert item in items, [str(d) for d in found]
    d = next(d for d in found if d.item == item)
    assert d.line == line and d.file == str(edited), (str(d), line)
    assert str(edited) in str(d) and f":{line}:" in str(d)


def test_rapid_stationary_tool_data(tmp_path):
    prog, path = _write(tmp_path, "rapid", "irb1600", True)
    text = path.read_text()
    # ABB: stationary tool = tooldata robhold FALSE, robot-held work object = wobjdata robhold
    # TRUE, ufprog TRUE, ufmec ""; the workpiece's load by GripLoad
    assert re.search(r"PERS tooldata \w+ := \[FALSE,", text)
    assert re.search(r'PERS wobjdata \w+ := \[TRUE,TRUE,"",', text)
    assert "GripLoad wobjHubLoad;" in text and "GripLoad load0;" in text
    assert "[3.050,[-18.000000,0.000000,127.000000]" in text  # the tool model's load
    back = mut.read_program(path)
    assert back.load_mass == pytest.approx(3.05 + 11.13)
    assert rapidcheck(text) == []


def test_krl_hygiene(tmp_path):
    prog, path = _write(tmp_path, "krl", "kr6_r700", True)
    src, dat = path.read_text(), path.with_suffix(".dat").read_text()
    assert "DEF deburr_test( )" in src and "DEFDAT deburr_test PUBLIC" in dat
    for key in ("$BASE = {", "$TOOL = {", "$LOAD = {M 14.180,CM {", "$IPO_MODE = #TCP"):
        assert key in src
    assert "$IPO_MODE = #BASE" in _write(tmp_path / "t", "krl", "kr6_r700", False)[1].read_text()
    for bad in ("1deburr.src", "deburr-hub.src", "a" * 25 + ".src"):
        with pytest.raises(InputError, match="not a valid KRL program name"):
            mut.write_program(prog, tmp_path / bad)
    (tmp_path / "other.src").write_text(src)
    (tmp_path / "other.dat").write_text(dat)
    with pytest.raises(mut.ProgramFormatError, match="DEF name 'deburr_test' is not the file"):
        mut.read_program(tmp_path / "other.src")
    assert len(mut.read_program(tmp_path / "other.src", check_name=False).moves) == 10


def test_ls_hygiene(tmp_path):
    prog, path = _write(tmp_path, "ls", "m10ia", True, flag="FORCED",
                        flag_reason="a long reason that must be wrapped onto several remarks")
    text = path.read_text()
    assert text.startswith("/PROG  DEBURR_TEST\n") and "FILE_NAME\t= DEBURR_TEST;" in text
    comment = re.search(r'COMMENT\t\t= "(.*)";', text).group(1)
    assert len(comment) <= 16
    remarks = re.findall(r"^\s*\d+:  !(.*) ;$", text, flags=re.M)
    assert remarks and max(len(r) for r in remarks) <= LS_REMARK_MAX
    assert "PAYLOAD[1] ;" in text and "PAYLOAD[1] M=14.180 kg" in text
    lines = [ln for ln in text.splitlines() if re.match(r"\s*\d+:  L P", ln)]
    assert lines and all(ln.endswith("RTCP ;") for ln in lines)
    n_mn = int(re.search(r"LINE_COUNT\t= (\d+);", text).group(1))
    assert n_mn == len(re.findall(r"^\s*\d+:  ", text, flags=re.M))
    with pytest.raises(InputError, match="not a valid LS program name"):
        mut.write_program(prog, tmp_path / ("x" * 37 + ".ls"))
    long_remark = path.read_text().replace("!moves: 10 ;", "!" + "m" * 33 + " ;")
    path.write_text(long_remark)
    with pytest.raises(mut.ProgramFormatError, match="remark of 33 characters"):
        mut.read_program(path)


def test_format_follows_the_controller(tmp_path):
    prog = random_program("kr6_r700")
    with pytest.raises(InputError, match="RAPID is not a program for KUKA KR 6 R700 sixx.*krl"):
        mut.write_program(prog, tmp_path / "p.mod", "rapid")
    with pytest.raises(InputError, match="LS is not a program for"):
        mut.write_program(random_program("irb1600"), tmp_path / "p.ls", "ls")
    with pytest.raises(InputError, match=r"ends in \.src"):
        mut.write_program(prog, tmp_path / "p.mod")
    paths = mut.write_program(prog, tmp_path / "p.src")  # default: the arm's format
    assert [p.suffix for p in paths] == [".src", ".dat"]


def test_deterministic_and_atomic(tmp_path):
    for fmt, arm in ARMS.items():
        a = random_program(arm, seed=3, flag="FORCED", flag_reason="3 points left out")
        b = random_program(arm, seed=3, flag="FORCED", flag_reason="3 points left out")
        assert mut.format_program(a, fmt) == mut.format_program(b, fmt)
        paths = mut.write_program(a, tmp_path / f"p{SUFFIX[fmt]}")
        assert "FORCED" in paths[0].read_text()
    assert not list(tmp_path.glob(".*.tmp"))


def test_krl_turn_ambiguity_is_flagged():
    """S/T cannot tell A6 = 390 deg from 30 deg: the header says so (an unregistered KUKA-style
    arm with wide wrist limits)."""
    spec = get_robot("irb1600")
    kin = RobotKinematics(spec.opw, JointLimits(tuple(spec.q_lower), tuple(spec.q_upper)),
                          controller="kuka", name="custom")
    prog = random_program("irb1600", seed=5)
    q = prog.moves[0].q.copy()
    q[5] = np.deg2rad(390.0)
    from drakedeburr.robots import fk_opw

    first = replace(prog.moves[0], q=q, X_WT=fk_opw(spec.opw, q) @ prog.X_FT)
    prog = replace(prog, robot=kin, moves=(first, *prog.moves[1:]))
    src, _ = mut.format_krl(prog)
    assert "WARNING: S/T cannot tell the planned turn of A4/A6 at move(s) 1" in src


def test_krl_turn_check_reads_back_only_what_s_and_t_may_not_pin_down(monkeypatch):
    """With every limit inside +-360 deg only a move on a branch boundary can be ambiguous:
    the fast path finds what reading back every move finds (KR 6 programs, and one move put
    on the A5 = 0 boundary, which is read back)."""
    from drakedeburr.programs import krl

    for seed in range(4):
        prog = random_program("kr6_r700", seed=seed)
        fast = krl._ambiguous_turns(prog)
        with monkeypatch.context() as mp:
            mp.setattr(krl, "_turn_suspects", lambda p: range(len(p.moves)))
            assert krl._ambiguous_turns(prog) == fast
    q = prog.moves[0].q.copy()
    q[4] = 0.0
    from drakedeburr.robots import fk_opw

    spec = get_robot("kr6_r700")
    first = replace(prog.moves[0], q=q, X_WT=fk_opw(spec.opw, q) @ prog.X_FT)
    prog = replace(prog, moves=(first, *prog.moves[1:]))
    assert 0 in list(krl._turn_suspects(prog))


def test_inconsistent_program_refused():
    prog = random_program("irb1600", n=3)
    bad = replace(prog, moves=(replace(prog.moves[0], q=prog.moves[1].q),))
    with pytest.raises(InputError, match="do not reach their pose"):
        mut.format_rapid(bad)
    with pytest.raises(InputError, match="program name"):
        replace(prog, name="1bad")
    with pytest.raises(InputError, match="speed must be > 0"):
        mut.RobotProgram.from_poses("p", [prog.moves[0].X_WT], [prog.moves[0].q], speed=0.0)
    with pytest.raises(InputError, match="workpiece_mass"):
        replace(prog, workpiece_mass=2.0)  # a tool-in-hand program holds no workpiece


@pytest.mark.parametrize("fmt, text, match", [
    ("rapid", "MODULE m\n  PROC main()\n    WaitTime 1;\n  ENDPROC\nENDMODULE\n",
     r":3: instruction 'WaitTime' is outside the motion subset"),
    ("rapid", "MODULE m\n  VAR num n := 1;\nENDMODULE\n", r":2: data type 'num'"),
    # a ';' alone in the routine (found by tests/test_bad_input_fuzz.py: an IndexError before)
    ("rapid", "MODULE m\n  PROC main()\n    ;\n  ENDPROC\nENDMODULE\n",
     r":3: an empty statement"),
    ("ls", "/PROG  BAD\n/ATTR\n/MN\n   1:  CALL FOO ;\n/POS\n/END\n",
     r"bad.ls:4: /MN line 1 'CALL FOO' is outside the motion subset"),
    ("krl", "DEF bad( )\n   WAIT SEC 1\nEND\n", r"bad.src:2: statement 'WAIT SEC 1'"),
])
def test_readers_name_what_they_refuse(tmp_path, fmt, text, match):
    path = tmp_path / f"bad{SUFFIX[fmt]}"
    path.write_text(text)
    with pytest.raises(mut.ProgramFormatError, match=match):
        mut.read_program(path)


def test_read_types_split_and_numbers():
    """The readers' shared parsing (drakedeburr.programs.read_types): commas inside brackets
    and quotes do not split; a number that is not finite or not a number is refused, naming
    the file and line."""
    from drakedeburr.programs.common import ProgramFormatError
    from drakedeburr.programs.read_types import parse_number, split_top_level

    text = 'a, [1,2,[3,4]], "x,y", {5,6}'
    assert split_top_level(text) == ["a", "[1,2,[3,4]]", '"x,y"', "{5,6}"]
    assert parse_number(" -1.5e3 ", "f.mod", 3, "x") == float("-1.5e3")
    for bad in ("1e999", "nan", "1,5", ""):
        with pytest.raises(ProgramFormatError, match="f.mod:3"):
            parse_number(bad, "f.mod", 3, "x")
