"""Issue 41 items 6 and 7: nothing from the inputs becomes program code, speeds stay in range.

Names are checked against the vendors' rules (cited in drakedeburr/programs/names.py) and
against rapidchecker's own RAPID grammar (an independent parser); hostile hub, file, tool path,
tool and program names are fed through ``post`` (RAPID, KRL, LS), ``export`` and the writers,
and every written file is parsed line by line with a grammar written here: each line is one of
the statements the format's program consists of, and the motion lines are exactly the planned
moves, in order.
"""

from __future__ import annotations

import json
import re
import shutil
import unicodedata
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from program_support import random_program

import drakedeburr.programs.names as mut
from drakedeburr.cli import main
from drakedeburr.errors import InputError
from drakedeburr.programs import write_program
from drakedeburr.programs.speeds import LANGUAGE_SPEED_RANGE, speed_range, tcp_speed_bound
from drakedeburr.robots import ROBOTS, fk_opw

REPO = Path(__file__).resolve().parent.parent
INJECT = "PTP {A1 45,A2 0,A3 0,A4 0,A5 0,A6 0}"
HOSTILE = [
    f"hub\n{INJECT}",                      # a new line, then a motion
    f"hub\r\n{INJECT}\r\n",                 # CR LF
    f"hub\u2028{INJECT}",                  # a Unicode line separator (str.splitlines splits)
    f"hub\x0b{INJECT}\x0c",                # vertical tab, form feed
    f"hub; {INJECT}",                      # KRL comment / LS statement end
    "hub ! MoveL p1, v7000, fine, tool0;",  # RAPID comment marker and an instruction
    'hub" ; 1:  J P[1] 100% FINE ;',       # an LS /MN line
    "hub ;FOLD PTP P1 ;ENDFOLD",           # a KRL fold
    "ENDFOLD x",
    "Nabe Ölwanne 轮毂 \x00\x1b[2J",       # non-ASCII, NUL, an escape sequence
    "x" * 400,                             # overlong
]


# ------------------------------------------------------------------ identifier rules (cited)
# (language, name, accepted, source of the rule)
RULE_CASES = [
    ("rapid", "a" * 32, True, "RAPID kernel 3HAC050946-001: identifiers of up to 32 characters"),
    ("rapid", "a" * 33, False, "RAPID kernel: at most 32 characters"),
    ("rapid", "Deburr_h5_straight", True, "letters, digits, '_'"),
    ("rapid", "1deburr", False, "RAPID kernel: the first character must be a letter"),
    ("rapid", "_deburr", False, "RAPID kernel: the first character must be a letter"),
    ("rapid", "de-burr", False, "RAPID kernel: letters, digits, underscores"),
    ("rapid", "Ölwanne", False, "RAPID kernel: letters a-z"),
    ("rapid", "MODULE", False, "RAPID kernel: reserved words (issue 41: --name MODULE)"),
    ("rapid", "endproc", False, "RAPID: identifiers ignore case, ENDPROC is reserved"),
    ("rapid", "Proc", False, "RAPID: PROC is reserved, case ignored"),
    ("rapid", "main", False, "the module's own PROC main()"),
    ("rapid", "p12", False, "the module's own robtarget p12"),
    ("krl", "a" * 24, True, "KUKA KSS 8.x Quickguide KRL-Syntax: at most 24 characters"),
    ("krl", "a" * 25, False, "KUKA Quickguide: at most 24 characters"),
    ("krl", "9deburr", False, "KUKA Quickguide: must not begin with a number"),
    ("krl", "DEF", False, "KUKA Quickguide: must not be a keyword"),
    ("krl", "lin", False, "KRL ignores case; LIN is a motion keyword"),
    ("krl", "MODULE", True, "MODULE is RAPID's keyword, not KRL's"),
    ("krl", "XP3", False, "the .dat's own point XP3"),
    ("ls", "A" * 36, True, "FANUC R-30iA and later: program names up to 36 characters"),
    ("ls", "A" * 37, False, "at most 36 characters"),
    ("ls", "deburr hub", False, "letters, digits, '_' only"),
]


@pytest.mark.parametrize("language, name, ok, source", RULE_CASES)
def test_identifier_rules_from_the_vendor_documents(language, name, ok, source):
    assert (mut.identifier_problem(name, language) is None) == ok, source
    if ok:
        assert mut.check_identifier(name, language, "--name") == name
    else:
        with pytest.raises(mut.ProgramNameError, match=rf"--name: '{re.escape(name)}' is not"):
            mut.check_identifier(name, language, "--name")


def _rapidchecker_keywords() -> list[str]:
    from rapidchecker.parser import tokens

    return sorted(t.match for t in vars(tokens).values()
                  if isinstance(t, tokens.RapidKeyword))


def test_rapid_reserved_words_agree_with_rapidchecker():
    """rapidchecker's grammar (written by others) refuses each of its keywords as a module
    name; every one of them is reserved here too, and a module we accept parses there."""
    from rapidchecker.check import check_format

    words = _rapidchecker_keywords()
    assert len(words) > 30
    for w in words:
        assert mut.identifier_problem(w, "rapid") is not None, w
    refused = [w for w in words if check_format(f"MODULE {w}\nENDMODULE\n")]
    assert len(refused) > 30  # rapidchecker refuses these as names; all reserved here
    for name in ("Deburr", "Deburr_h5_straight", mut.clean_identifier("MODULE", "rapid")):
        assert check_format(f"MODULE {name}\nENDMODULE\n") == [], name


@pytest.mark.parametrize("language", mut.LANGUAGES)
@pytest.mark.parametrize("text", HOSTILE + ["MODULE", "DEF", "17-B", "", "___", "main", "XP1"])
def test_clean_identifier_is_a_valid_deterministic_name(language, text):
    name = mut.clean_identifier(text, language)
    assert mut.identifier_problem(name, language) is None
    assert re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name)
    assert name == mut.clean_identifier(text, language)  # deterministic
    assert len(name) <= mut.RULES[language].max_length


def test_clean_identifier_keeps_a_clean_name_and_repairs_a_bad_one():
    assert mut.clean_identifier("CreoPost__profilfraesen_2", "rapid") == "CreoPost__profilfraesen_2"
    assert mut.clean_identifier("Hub 17-B", "krl") == "Hub_17_B"
    assert mut.clean_identifier("17B", "ls") == "P_17B"
    assert mut.clean_identifier("MODULE", "rapid") == "MODULE_1"
    assert mut.clean_identifier("Deburr_" + "x" * 40, "krl") == ("Deburr_" + "x" * 40)[:24]


@pytest.mark.parametrize("language", mut.LANGUAGES)
@pytest.mark.parametrize("text", HOSTILE)
def test_comment_text_is_one_inert_line(language, text):
    s = mut.comment_text(text, language)
    assert s.splitlines() == ([s] if s else [])  # no line break of any kind
    assert s.isascii() and s.isprintable()
    assert not any(unicodedata.category(c)[0] == "C" for c in s)
    assert not set(s) & set("!;\"'`\\{}")
    assert not re.match(r"(?i)(END)?FOLD\b", s)
    assert mut.comment_text(s, language) == s  # idempotent


# ------------------------------------------------------------- a grammar written by the test
_NUM = r"-?\d+(?:\.\d+)?(?:E[+-]?\d+)?"
_RAPID = [r"MODULE [A-Za-z]\w*", r"  ! [ -~]*|  !", r"    ! [ -~]*",
          r"  (PERS|CONST) (tooldata|wobjdata|loaddata|speeddata|zonedata|robtarget) "
          r"[A-Za-z]\w* := \[[-\w.,\[\]\"+E]*\];",
          "", r"  PROC main\(\)", r"    Conf[JL] \\On;", r"    GripLoad [A-Za-z]\w*;",
          r"    Move[LJ] p(?P<n>\d+), \w+, \w+, [A-Za-z]\w* \\WObj:=[A-Za-z]\w*;", "  ENDPROC",
          "ENDMODULE"]
_KRL_SRC = ["&ACCESS RVP", "&REL 1", r"DEF [A-Za-z]\w*\( \)", r"(   |  |    )?;[ -~]*",
            r"    BAS \(#INITMOV,0 \)", "", r"   \$(BASE|TOOL) = \{[-\w ,.]*\}",
            r"   \$LOAD = \{M [\d.]+,CM \{[-\w ,.]*\},J \{[-\w ,.]*\}\}",
            r"   \$IPO_MODE = #(BASE|TCP)", r"   \$ADVANCE = 3", rf"   \$APO\.CDIS = {_NUM}",
            rf"   \$VEL\.CP = {_NUM}", r"   BAS \(#VEL_PTP, \d+\)",
            r"   (PTP|LIN) XP(?P<n>\d+)( C_DIS)?", "END"]
_KRL_DAT = ["&ACCESS RVP", "&REL 1", r"DEFDAT [A-Za-z]\w* PUBLIC", r"   ;[ -~]*", "",
            r"DECL E6POS XP\d+=\{[-\w ,.]*\}", "ENDDAT"]
_LS_MN = [r"![ -:<-~]{0,32}", r"UFRAME_NUM=\d+", r"UTOOL_NUM=\d+", r"PAYLOAD\[\d+\]",
          r"J P\[(?P<n>\d+)\] \d+% (FINE|CNT\d+)",
          r"L P\[(?P<n>\d+)\] \d+(mm/sec|cm/min) (FINE|CNT\d+)( RTCP)?",
          r"PR\[\d+\]=LPOS", rf"PR\[\d+,[1-6]\]={_NUM}", r"(UTOOL|UFRAME)\[\d+\]=PR\[\d+\]"]


def _motions(lines: list[str], grammar: list[str], where: str) -> list[int]:
    """The move numbers of the motion lines; every line must match one pattern."""
    out = []
    for k, line in enumerate(lines, start=1):
        m = next((m for g in grammar if (m := re.fullmatch(g, line))), None)
        assert m is not None, f"{where}:{k}: {line!r} is outside the grammar"
        if "n" in m.groupdict() and m["n"] is not None:
            out.append(int(m["n"]))
    return out


def parse_written(path: Path) -> list[int]:
    """Move numbers of every motion line of a written program (KRL: .src and .dat)."""
    raw = path.read_bytes()
    assert raw.isascii() and b"\r" not in raw and b"\x00" not in raw
    text = raw.decode()
    assert len(text.split("\n")) == len(text.splitlines()) + 1  # no other line breaks
    lines = text.split("\n")[:-1]
    if path.suffix == ".mod":
        from rapidchecker.check import check_format

        assert check_format(text) == [], "rapidchecker refuses the module"
        return _motions(lines, _RAPID, str(path))
    if path.suffix == ".src":
        dat = path.with_suffix(".dat").read_text().split("\n")[:-1]
        assert _motions(dat, _KRL_DAT, str(path.with_suffix(".dat"))) == []
        return _motions(lines, _KRL_SRC, str(path))
    i_mn, i_pos = lines.index("/MN"), lines.index("/POS")
    assert re.fullmatch(r"/PROG  [A-Z][A-Z0-9_]*", lines[0]) and lines[-1] == "/END"
    for line in lines[1:i_mn]:
        assert re.fullmatch(r"/ATTR|[ A-Z_:]+\t+= [^;]*[;,]", line), line
    body = []
    for k, line in enumerate(lines[i_mn + 1:i_pos], start=1):
        m = re.fullmatch(rf"\s*{k}:  (.*) ;", line)
        assert m and ";" not in m[1], f"/MN line {k}: {line!r}"
        body.append(m[1])
    for line in lines[i_pos + 1:-1]:
        assert re.fullmatch(r"P\[\d+\]\{|   GP1:|\t.*,|\t[WPR] = .*|\};", line), line
    return _motions(body, _LS_MN, str(path))


# ------------------------------------------------------------------------ the writers
ARMS = {"rapid": ("irb1600", ".mod"), "krl": ("kr6_r700", ".src"), "ls": ("m10ia", ".ls")}


@pytest.mark.parametrize("fmt", ARMS)
@pytest.mark.parametrize("stationary", [False, True])
def test_hostile_texts_in_a_program_add_no_instruction(fmt, stationary, tmp_path):
    """Every text field of a program carries hostile text: hub and scenario names in the
    notes, a CL file name as source, a flag reason, a load source, move comments."""
    arm, suffix = ARMS[fmt]
    n = 10
    prog = random_program(arm, stationary, n=n, name="deburr_test",
                          source=HOSTILE[0], load_source=HOSTILE[5], flag="FORCED",
                          flag_reason=HOSTILE[6], notes=tuple(HOSTILE))
    moves = tuple(replace(m, comment=HOSTILE[i % len(HOSTILE)]) for i, m in
                  enumerate(prog.moves))
    prog = replace(prog, moves=moves)
    path = tmp_path / f"deburr_test{suffix}"
    write_program(prog, path)
    assert parse_written(path) == list(range(1, n + 1))
    text = path.read_text() + (path.with_suffix(".dat").read_text() if fmt == "krl" else "")
    assert "PTP {A1" not in text  # the braces of an aggregate never reach a comment
    assert not re.search(r"^\s*(MoveL p1, v7000|\d+:  J P\[1\] 100%)", text, re.M)
    from drakedeburr.programs import read_program

    assert len(read_program(path).moves) == n  # our strict reader agrees


@pytest.mark.parametrize("fmt, file, bad", [
    ("rapid", "x.mod", "MODULE"), ("rapid", "x.mod", "main"), ("rapid", "x.mod", "wobjHub"),
    ("krl", "DEF.src", None), ("krl", "XP1.src", None), ("krl", "a-b.src", None),
    ("ls", "x;y.ls", None), ("ls", ("A" * 37) + ".ls", None)])
def test_program_names_that_are_no_identifiers_are_refused(fmt, file, bad, tmp_path):
    arm, _ = ARMS[fmt]
    prog = random_program(arm, name=bad or "deburr_test")
    with pytest.raises(InputError, match="is not a valid|clashes"):
        write_program(prog, tmp_path / file)
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- post (CLI)
# 6 GOTOs, tool down (tip -> spindle +z), 10 mm squares in the work object
_CL = ["UNITS/MM", "TOOL PATH/{path},TOOL,T1", "FEDRAT/MMPM,3000", "{word}/1",
       "GOTO/0,0,20,0,0,1", "GOTO/0,0,0", "GOTO/10,0,0", "GOTO/10,10,0", "GOTO/0,10,0",
       "GOTO/0,0,20", "END-OF-PATH"]
WOBJ = {"rapid": "600,0,300,0,0,0", "krl": "450,0,250,0,0,0", "ls": "700,0,300,0,0,0"}


def _cl_file(folder: Path, name: str, path_name: str = "OP1", word: str = "PAINT") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    f = folder / name
    f.write_text("\n".join(_CL).format(path=path_name, word=word) + "\n", newline="\n")
    return f


def _post(cl: Path, fmt: str, out: Path, *extra: str) -> int:
    arm, _ = ARMS[fmt]
    return main(["post", str(cl), "--robot", arm, "-o", str(out), "--wobj", WOBJ[fmt],
                 "--spin", "greedy", *extra])


@pytest.mark.parametrize("fmt", ARMS)
def test_post_hostile_cl_file_and_path_names_are_cleaned(fmt, tmp_path, capsys):
    """A CL file named with a line break and a motion, a tool path name and an unknown word
    with ';', '!' and a Unicode line separator: the program is written (derived names are
    cleaned), it holds the six GOTOs and nothing else."""
    _, suffix = ARMS[fmt]
    cl = _cl_file(tmp_path / "in", f"evil\n{INJECT}\n;.cl",
                  path_name=f"OP1; {INJECT} ! x\u2028{INJECT}", word=f"FOO\x0b{INJECT}")
    n_goto = sum(1 for line in cl.read_text().splitlines() if line.startswith("GOTO/"))
    out = tmp_path / f"prog{suffix}"
    assert _post(cl, fmt, out) == 0, capsys.readouterr().err
    assert parse_written(out) == list(range(1, n_goto + 1))
    text = out.read_text()
    assert "PTP {A1" not in text
    if fmt == "rapid":  # RAPID takes the (derived, cleaned) name; KRL and LS their file's
        module = mut.clean_identifier(cl.name.split(".")[0], fmt, max_length=24)
        assert text.startswith(f"MODULE {module}\n") and module.startswith("evil_PTP_A1_45")


@pytest.mark.parametrize("fmt, extra, says", [
    ("rapid", ["--name", f"x\n{INJECT}"], "--name"), ("rapid", ["--name", "MODULE"], "MODULE"),
    ("rapid", ["--name", "ENDPROC"], "reserved"), ("krl", ["--name", "DEF"], "DEF"),
    ("ls", ["--name", "a;b"], "--name")])
def test_post_hostile_name_option_is_refused(fmt, extra, says, tmp_path, capsys):
    cl = _cl_file(tmp_path, "part.cl")
    out = tmp_path / f"prog{ARMS[fmt][1]}"
    assert _post(cl, fmt, out, *extra) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("fmt, out", [("krl", "DEF.src"), ("krl", "END.src"),
                                       ("krl", "XP2.src"), ("ls", "a b.ls")])
def test_post_output_file_that_names_no_program_is_refused(fmt, out, tmp_path, capsys):
    cl = _cl_file(tmp_path, "part.cl")
    assert _post(cl, fmt, tmp_path / out) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "is not a valid" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.cl"]


# ---------------------------------------------------------------------- export (CLI)
@pytest.fixture(scope="module")
def hostile_plan(tmp_path_factory):
    """The reference plan of the verify tests, made on a hub folder whose name carries a
    line break and a KRL motion, with a hostile tool title in plan.json."""
    import verify_support as vs

    from drakedeburr.plan.io import save_plan

    root = tmp_path_factory.mktemp("hostile_export")
    hub = root / f"h5 evil\n{INJECT}; ! x"
    hub.mkdir()
    for f in (REPO / "models" / "hubs" / vs.HUB).iterdir():
        (hub / f.name).symlink_to(f)
    plan = vs.good_plan()
    meta = dict(plan.meta, tool="standard", tool_title=f"burr\r\n{INJECT}\u2028END")
    folder = save_plan(replace(plan, hub=str(hub), meta=meta), root / "plan")
    return folder, _moves_of(plan)


def _moves_of(plan) -> int:
    """Motion lines the plan's program carries under a clean name: the targets plus the via
    points of bent joint moves (programs.plan_program); a hostile name must add none."""
    from drakedeburr.programs.plan_program import program_from_plan

    return len(program_from_plan(plan, "Clean").moves)


def test_export_hostile_hub_and_tool_title_add_no_instruction(hostile_plan, tmp_path, capsys):
    folder, n = hostile_plan
    out = tmp_path / "deburr.mod"
    assert main(["export", str(folder), "-o", str(out), "--force"]) == 0, capsys.readouterr()
    assert parse_written(out) == list(range(1, n + 1))
    text = out.read_text()
    assert "PTP {A1" not in text and "UNVERIFIED" in text
    assert re.search(r"^  ! burr: burr PTP A1 45,A2 0,A3 0,A4 0,A5 0,A6 0 END: mount it", text,
                     re.M)


@pytest.mark.parametrize("name", ["MODULE", "PROC", f"x\n{INJECT}", "main", "a" * 33])
def test_export_hostile_name_is_refused(hostile_plan, tmp_path, capsys, name):
    folder, _ = hostile_plan
    out = tmp_path / "deburr.mod"
    assert main(["export", str(folder), "-o", str(out), "--force", "--name", name]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--name" in err and "Traceback" not in err
    assert not out.exists()


def test_export_refuses_a_plan_speed_the_arm_cannot_run(hostile_plan, tmp_path, capsys):
    """A plan.json edited to a 1e9 m/s target: bad input (exit 2) naming the move."""
    folder, _ = hostile_plan
    bad = tmp_path / "plan"
    shutil.copytree(folder, bad)
    doc = json.loads((bad / "plan.json").read_text())
    k = next(i for i, t in enumerate(doc["targets"]) if t.get("motion", "linear") != "joint")
    doc["targets"][k]["speed"] = 1e9
    (bad / "plan.json").write_text(json.dumps(doc))
    out = tmp_path / "x.mod"
    assert main(["export", str(bad), "-o", str(out), "--force"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "out of range" in err and "7000 mm/s" in err
    assert not out.exists()


def test_demo_names_the_program_after_a_cleaned_hub_name(tmp_path):
    from drakedeburr.demo import demo_program_path

    for fmt, suffix in (("rapid", ".mod"), ("krl", ".src"), ("ls", ".ls")):
        name, path = demo_program_path(tmp_path, str(tmp_path / f"h5 evil\n{INJECT}"), fmt)
        assert mut.identifier_problem(name, fmt) is None and name.startswith("Deburr_h5_evil")
        assert path.parent == tmp_path and path.suffix == suffix
        assert mut.identifier_problem(path.stem, fmt) is None  # KRL/LS: the file names it
    assert demo_program_path(tmp_path, "h5_straight", "rapid") == (
        "Deburr_h5_straight", tmp_path / "deburr_h5_straight.mod")


# ----------------------------------------------------------------------------- speeds
@pytest.mark.parametrize("arm", sorted(ROBOTS))
def test_tcp_speed_bound_holds_at_sampled_poses(arm):
    """At random poses, every joint at +-its speed limit (all sign patterns): the TCP speed,
    by finite differences of the forward kinematics, never exceeds the bound."""
    spec = ROBOTS[arm]
    X_FT = np.eye(4)
    X_FT[:3, 3] = [0.03, -0.02, 0.2]
    bound = tcp_speed_bound(spec, X_FT)
    rng = np.random.default_rng(0)
    signs = np.array(np.meshgrid(*[[-1, 1]] * 6)).reshape(6, -1).T
    h, fastest = 1e-6, 0.0
    for _ in range(40):
        q = rng.uniform(spec.q_lower, spec.q_upper)
        p0 = (fk_opw(spec.opw, q) @ X_FT)[:3, 3]
        for s in signs:
            p1 = (fk_opw(spec.opw, q + h * s * spec.v_max) @ X_FT)[:3, 3]
            fastest = max(fastest, float(np.linalg.norm(p1 - p0) / h))
    assert fastest <= bound
    assert bound < 3 * fastest  # a bound, but not a meaningless one
    lo, hi = speed_range(spec, spec.program_format, X_FT)
    assert hi == min(bound, LANGUAGE_SPEED_RANGE[spec.program_format][1]) and lo > 0


@pytest.mark.parametrize("feed", ["1e9", "1e300", "-5", "0", "nan", "inf", "-inf"])
@pytest.mark.parametrize("fmt", ARMS)
def test_post_feed_out_of_range_is_refused_naming_the_range(feed, fmt, tmp_path, capsys):
    cl = _cl_file(tmp_path, "part.cl")
    out = tmp_path / f"prog{ARMS[fmt][1]}"
    assert _post(cl, fmt, out, f"--feed={feed}") == 2
    err = capsys.readouterr().err.strip()
    top = {"rapid": "7000", "krl": "2000", "ls": "2000"}[fmt]
    assert len(err.splitlines()) == 1 and "--feed" in err and f"to {top} mm/s" in err
    assert not out.exists()


@pytest.mark.parametrize("fmt", ARMS)
def test_post_feed_at_the_top_of_the_range_is_written(fmt, tmp_path, capsys):
    cl = _cl_file(tmp_path, "part.cl")
    out = tmp_path / f"prog{ARMS[fmt][1]}"
    top = mm = 1000 * LANGUAGE_SPEED_RANGE[fmt][1]
    assert _post(cl, fmt, out, "--feed", f"{top:g}") == 0, capsys.readouterr().err
    assert parse_written(out) == list(range(1, 7))
    speed = {"rapid": r"MoveL p2, v7000, ", "krl": rf"\$VEL\.CP = {mm / 1000:.6f}",
             "ls": rf"L P\[\d+\] {mm:.0f}mm/sec"}[fmt]
    assert re.search(speed, out.read_text())


def test_post_cl_feed_beyond_the_range_is_refused_naming_the_move(tmp_path, capsys):
    """FEDRAT in the file (no --feed) faster than RAPID holds: the writer refuses it."""
    cl = _cl_file(tmp_path, "part.cl")
    cl.write_text(cl.read_text().replace("FEDRAT/MMPM,3000", "FEDRAT/MMPM,1E9"))
    out = tmp_path / "prog.mod"
    assert _post(cl, "rapid", out) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "out of range" in err and "source line" in err
    assert not out.exists()


def test_demo_on_a_hostile_hub_folder_writes_a_clean_program(tmp_path, monkeypatch):
    """``demo --hub <folder>`` where the folder's name carries a line break and a KRL motion:
    the program (named after the cleaned hub name) holds the plan's moves and nothing else.
    The CL table and the planning are replaced by the verify tests' reference plan (the
    naming, verification and export are the demo's own)."""
    import verify_support as vs

    import drakedeburr.path
    import drakedeburr.plan
    from drakedeburr.demo import run_demo

    hub = tmp_path / f"h5 evil\n{INJECT}; ! x"
    hub.mkdir()
    for f in (REPO / "models" / "hubs" / vs.HUB).iterdir():
        (hub / f.name).symlink_to(f)
    plan = replace(vs.good_plan(), hub=str(hub))
    monkeypatch.setattr(drakedeburr.path, "cl_table", lambda h: {"windows": []})
    monkeypatch.setattr(drakedeburr.plan, "plan_hub", lambda *a, **k: plan)
    summary = run_demo(tmp_path / "out", hub=str(hub), test_mode=True, force=True)
    program = Path(summary["outputs"]["program"])
    assert program.parent == tmp_path / "out" and program.name.startswith("deburr_h5_evil_PTP")
    assert parse_written(program) == list(range(1, _moves_of(plan) + 1))
    assert "PTP {A1" not in program.read_text()


def test_post_name_of_a_krl_program_is_its_file_name_and_said_so(tmp_path, caplog):
    cl = _cl_file(tmp_path, "part.cl")
    out = tmp_path / "prog.src"
    assert _post(cl, "krl", out, "--name", "Other") == 0
    assert "DEF prog( )" in out.read_text()
    assert any("takes its file's name (prog)" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize("language", mut.LANGUAGES)
def test_any_text_becomes_an_inert_remark_and_a_valid_name(language):
    """Property: for any Unicode text (hypothesis, 400 cases per language) the remark is one
    printable ASCII line without markers, and the cleaned name an identifier."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=400, deadline=None, derandomize=True)
    @given(st.text(max_size=80))
    def check(text):
        s = mut.comment_text(text, language)
        assert s.isascii() and s.isprintable() and s.splitlines() == ([s] if s else [])
        assert not set(s) & set("!;\"'`\\{}") and mut.comment_text(s, language) == s
        assert mut.identifier_problem(mut.clean_identifier(text, language), language) is None

    check()
