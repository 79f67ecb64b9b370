"""CL/APT reader on the real NX and Creo files, error cases, and a property-based fuzz."""

import math

import numpy as np
import pytest
from cl_support import msys_point_inch, nx_multipath, scan_nx_paths
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import drakedeburr.post.cl_reader as mut
from drakedeburr.errors import InputError
from drakedeburr.units import INCH_M

CL = "cl_files"


def _count_goto(path):
    return sum(1 for line in path.read_text().splitlines() if line.lstrip().startswith("GOTO"))


def test_nx_contour_chamfer_inch(extdata):
    path = extdata / CL / "MECH491_NX_CLSF__APT_code.txt"
    prog = mut.read_cl(path, units="inch")
    assert len(prog.moves) == _count_goto(path) == 325
    first, last = prog.moves[0], prog.moves[-1]
    # GOTO/0.0776,1.6841,3.4760,0.7196045,0.2803955,0.6352541 on line 10, inches
    assert first.line == 10 and first.rapid
    assert np.allclose(first.p_C, np.array([0.0776, 1.6841, 3.4760]) * INCH_M, atol=1e-12)
    assert np.allclose(first.axis_C, [0.7196045, 0.2803955, 0.6352541], atol=1e-6)
    assert last.line == 347 and not last.rapid
    assert np.allclose(last.p_C, np.array([0.7417, 0.4924, 3.4959]) * INCH_M, atol=1e-12)
    # 4 RAPID statements, each for one move
    assert prog.rapid.sum() == 4
    # FEDRAT/IPM,10 -> 10 in/min
    feed = prog.feed[~np.isnan(prog.feed)]
    assert np.allclose(feed, 10 * INCH_M / 60)
    assert np.allclose(np.linalg.norm(prog.axis_C, axis=1), 1.0, atol=1e-12)
    assert prog.end_line == 350 and prog.warnings == ()  # END-OF-PATH; nothing unknown
    assert prog.moves[0].tool == 1  # LOAD/TOOL,1
    # a 3-number GOTO keeps the previous axis
    assert prog.moves[2].axis_C == prog.moves[1].axis_C


def test_nx_variable_axis_inch(extdata):
    path = extdata / CL / "MECH491_NX_CLSF__APT_Variable_Axis.txt"
    prog = mut.read_cl(path, units="inch")
    assert len(prog.moves) == _count_goto(path) == 348
    ax = prog.axis_C
    assert np.allclose(np.linalg.norm(ax, axis=1), 1.0, atol=1e-12)
    assert np.allclose(ax[0], [-0.3778015, -0.0069217, 0.9258607], atol=1e-6)
    # variable axis: the tool axis really varies (> 20 deg spread)
    ang = np.degrees(np.arccos(np.clip(ax @ ax[0], -1, 1)))
    assert ang.max() > 20
    # MSYS/3,3,0,... : the MCS is shifted 3 inch in x and y from the absolute frame
    assert np.allclose(prog.moves[-1].p_C, (np.array([3.6648, 3.0081, 3.0]) + [3, 3, 0]) * INCH_M)
    assert [p.name for p in prog.paths] == ["NORM_PART"] and prog.paths[0].tool_name == (
        "BALL_MILL_1.00")


def test_creo_profile_circles_mm(extdata):
    path = extdata / CL / "CreoPost__profilfraesen_2.ncl.2"
    prog = mut.read_cl(path, arc_tolerance=1e-5)
    gotos = _count_goto(path)
    circ = [m for m in prog.moves if m.from_circle]
    assert len(prog.moves) == gotos + len(circ)
    assert prog.units == "mm" and prog.end_line == 112 and prog.warnings == ()
    assert [p.name for p in prog.paths] == ["FEATNO 638"]
    assert [(w.word, w.count, w.lines) for w in prog.not_applied] == [("SPINDL", 2, (13, 110))]
    assert prog.moves[0].p_C == pytest.approx((0.0, 1.5e-3, 2e-3))
    assert prog.moves[0].spindle_rpm == pytest.approx(15915.507752)
    assert np.allclose(prog.feed[2:], 400e-3 / 60)  # FEDRAT / 400, MMPM
    # every CIRCLE point lies on its circle (radius 1.5 mm about its centre, in its plane)
    text = path.read_text().splitlines()
    by_line: dict[int, list] = {}
    for m in circ:
        by_line.setdefault(m.line, []).append(np.array(m.p_C))
    assert len(by_line) == 20
    for line, pts in by_line.items():
        nums = [float(v) for v in (text[line - 1].split("/")[1] + text[line]).replace("$", "")
                .split(",")]
        c = np.array(nums[:3]) * 1e-3
        pts = np.array(pts)
        assert np.allclose(np.linalg.norm(pts[:, :2] - c[:2], axis=1), 1.5e-3, atol=1e-12)
        assert np.allclose(pts[:, 2], c[2])
        # chord-height error within tolerance: chord between neighbours
        chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        sagitta = 1.5e-3 - np.sqrt(1.5e-3 ** 2 - (chords / 2) ** 2)
        assert sagitta.max() <= 1e-5 + 1e-12
    # first arc: from (0, 1.5) to (1.5, 0) right-handed about -z (clockwise seen from +z)
    first = np.array(by_line[min(by_line)])
    ang = np.unwrap(np.arctan2(first[:, 1], first[:, 0]))
    assert np.all(np.diff(ang) < 0) and ang[0] < math.pi / 2 and ang[-1] > 0


def test_statements_and_units():
    text = "\n".join([
        "UNITS/INCHES", "LOADTL/3", "SPINDL/RPM,1200,CCLW", "TLAXIS/0,0,2",
        "PPRINT/HELLO", "FEDRAT/20,IPM", "GOTO/1,2,$", "  3", "MULTAX/ON",
        "GOTO/1,2,3,0,1,0", "UNITS/MM", "FEDRAT/MMPR,0.1", "GOTO/10,0,0", "FOO/1",
        "FINI", "GOTO/oops"])
    prog = mut.parse_cl_text(text)
    m0, m1, m2 = prog.moves
    assert m0.p_C == pytest.approx((INCH_M, 2 * INCH_M, 3 * INCH_M)) and m0.line == 7
    assert m0.axis_C == pytest.approx((0, 0, 1)) and m0.tool == 3
    assert m0.spindle_rpm == -1200 and m0.feed == pytest.approx(20 * INCH_M / 60)
    assert m1.axis_C == pytest.approx((0, 1, 0))
    assert m2.p_C == pytest.approx((0.01, 0, 0))
    assert m2.feed == pytest.approx(0.1e-3 * 1200 / 60)
    # the mid-file switch to mm after two inch moves is honoured and reported
    assert prog.unit_changes == ((1, "inch", 0), (11, "mm", 2))
    assert prog.mid_file_unit_changes == ((11, "mm", 2),)
    assert [(w.line, w.word) for w in prog.warnings] == [(4, "TLAXIS"), (11, "UNITS")]
    assert "after 2 moves" in prog.warnings[1].message
    assert any("UNITS switched to mm at line 11" in ln for ln in prog.summary())
    words = {w.word: (w.count, w.lines) for w in prog.not_applied}
    assert words == {"SPINDL": (1, (3,)), "FOO": (1, (14,)), "(after FINI)": (1, (16,))}
    assert prog.comments == ((5, "HELLO"),)  # data after FINI are not read


def test_unknown_words_listed_once_with_counts_and_lines():
    text = "\n".join(["GOTO/0,0,0"] + [f"FOO/{k}" if k % 2 else f"BAR/{k}" for k in range(50)]
                     + ["COOLNT/ON", "GOTO/1,0,0", "COOLNT/OFF", "FINI"])
    prog = mut.parse_cl_text(text)
    words = {w.word: w for w in prog.not_applied}
    assert set(words) == {"FOO", "BAR", "COOLNT"}
    assert words["FOO"].count == 25 and words["BAR"].count == 25
    assert words["BAR"].lines == tuple(range(2, 2 + 40, 2))  # the first 20 lines
    assert words["COOLNT"].count == 2 and words["COOLNT"].lines == (52, 54)
    assert "FOO x25 (lines 3, 5," in words["FOO"].describe()
    assert len(prog.moves) == 2


def test_nx_banner_and_footer_are_not_words(extdata, tmp_path):
    path = nx_multipath(extdata, tmp_path / "two.cls", n_paths=2)
    prog = mut.read_cl(path, units="inch")
    assert prog.not_applied == () and prog.warnings == ()


def test_fifteen_tool_paths_all_read_in_order(extdata, tmp_path):
    """Every GOTO of every path (counted by a plain scan) becomes a move at its MCS point."""
    path = nx_multipath(extdata, tmp_path / "fifteen.cls", n_paths=15)
    scan = scan_nx_paths(path)
    prog = mut.read_cl(path, units="inch")
    assert len(scan) == 15 == len(prog.paths)
    assert [p.name for p in prog.paths] == [s["name"] for s in scan]
    assert [p.n_goto for p in prog.paths] == [len(s["gotos"]) for s in scan]
    assert [(p.start_line, p.end_line) for p in prog.paths] == [
        (s["start"], s["end"]) for s in scan]
    n_goto = sum(len(s["gotos"]) for s in scan)
    assert len(prog) == n_goto > 5000
    lines = prog.lines
    assert np.all(np.diff(lines) > 0)  # file order
    expected = np.array([msys_point_inch(m, v) for s in scan for _, v, m in s["gotos"]])
    # the MSYS axes are printed with 7 digits and orthonormalised by the reader: 1e-9 m
    assert np.abs(prog.p_C - expected).max() < 1e-9
    assert lines.tolist() == [n for s in scan for n, _, _ in s["gotos"]]
    # the path index of every move matches the path its line lies in
    for k, s in enumerate(scan):
        inside = (lines >= s["start"]) & (lines <= s["end"])
        assert np.all(prog.path[inside] == k)


def test_msys_rotates_axes_and_circles():
    # MCS turned 90 deg about z, origin (10, 20, 30) mm
    text = "\n".join(["UNITS/MM", "MSYS/10,20,30,0,1,0,-1,0,0", "GOTO/1,0,0,1,0,0",
                      "CIRCLE/0,0,0,0,0,1,1", "GOTO/0,1,0", "TLAXIS/0,1,0", "GOTO/0,0,5",
                      "MSYS/0,0,0,1,0,0,0,1,0", "GOTO/1,2,3", "FINI"])
    prog = mut.parse_cl_text(text, arc_tolerance=1e-6)
    p = prog.p_C * 1e3
    assert np.allclose(p[0], [10, 21, 30]) and np.allclose(prog.axis_C[0], [0, 1, 0])
    arc = p[prog.from_circle]
    # the arc runs about the MCS origin, counter-clockwise about z (z is unchanged by the turn)
    assert np.allclose(np.hypot(arc[:, 0] - 10, arc[:, 1] - 20), 1.0)
    ang = np.unwrap(np.arctan2(arc[:, 1] - 20, arc[:, 0] - 10))
    assert np.all(np.diff(ang) > 0)
    assert np.allclose(p[prog.lines == 5][-1], [9, 20, 30])
    assert np.allclose(prog.axis_C[prog.lines == 7][0], [-1, 0, 0])
    assert np.allclose(p[-1], [1, 2, 3])  # identity MSYS: as written


@pytest.mark.parametrize("text, line, token, message", [
    ("MSYS/0,0,0,1,0,0,0.5,1,0\nFINI", 1, "1,0,0,0.5,1,0", "not orthonormal"),
    ("MSYS/0,0,0,1,0,0\nFINI", 1, "0,0,0,1,0,0", "9 numbers"),
    ("GOTO/0,0,0\nCUTCOM/LEFT,1\nGOTO/1,0,0\nFINI", 2, "CUTCOM/LEFT,1", "cutter compensation"),
    ("GOTO/0,0,0\nTLCOMP/ON\nFINI", 2, "TLCOMP/ON", "cutter compensation"),
    ("GOTO/0,0,0\nTLON,GOFWD/(CIRCLE/0,0,0,5),ON,(LINE/0,0,0,1,1,1)\nFINI", 2, "TLON,GOFWD",
     "not supported"),
    ("GODLTA/1,0,0\nFINI", 1, "GODLTA", "before any position"),
    ("GOHOME\nFINI", 1, "GOHOME", "without a FROM"),
])
def test_refused_statements_name_the_line(text, line, token, message):
    with pytest.raises(mut.ClParseError, match=message) as info:
        mut.parse_cl_text(text, source="<t>")
    assert info.value.line == line and token in info.value.token


def test_cutcom_ignored_on_request_and_listed():
    text = "GOTO/0,0,0\nCUTCOM/LEFT\nGOTO/1,0,0\nCUTCOM/OFF\nFINI"
    prog = mut.parse_cl_text(text, cutcom="ignore")
    assert len(prog) == 2
    assert [(w.word, w.count, w.lines) for w in prog.not_applied] == [("CUTCOM", 1, (2,))]


def test_godlta_from_gohome():
    text = "\n".join(["UNITS/MM", "FROM/0,0,100", "GOTO/10,0,0,0,0,1", "GODLTA/0,5,0",
                      "GODLTA/2", "MSYS/0,0,0,0,1,0,-1,0,0", "GODLTA/1,0,0", "GOHOME", "FINI"])
    prog = mut.parse_cl_text(text)
    p = prog.p_C * 1e3
    assert np.allclose(p, [[0, 0, 100], [10, 0, 0], [10, 5, 0], [10, 5, 2], [10, 6, 2],
                           [0, 0, 100]])
    assert prog.rapid.tolist() == [True, False, False, False, False, True]
    assert prog.paths[0].n_goto == 6


def test_end_of_path_continues_and_truncation_is_caught():
    two = "TOOL PATH/A\nGOTO/0,0,0\nEND-OF-PATH\nTOOL PATH/B\nGOTO/1,0,0\nEND-OF-PATH\n"
    prog = mut.parse_cl_text(two)
    assert [(p.name, p.n_goto, p.start_line, p.end_line) for p in prog.paths] == [
        ("A", 1, 1, 3), ("B", 1, 4, 6)]
    assert prog.path.tolist() == [0, 1] and prog.end_line == 6
    # the second path cut before its END-OF-PATH: a truncated file
    with pytest.raises(mut.ClParseError, match="without FINI or END-OF-PATH") as info:
        mut.parse_cl_text(two.rsplit("END-OF-PATH", 1)[0], source="<t>")
    assert info.value.line == 5


def test_missing_file_is_named(tmp_path):
    with pytest.raises(InputError, match=r"missing\.cl: CL file not found"):
        mut.read_cl(tmp_path / "missing.cl")
    with pytest.raises(InputError, match="CL file is a folder, a file is needed"):
        mut.read_cl(tmp_path)
    (tmp_path / "zero.cl").symlink_to("/dev/zero")  # issue 43: never read to the end
    with pytest.raises(InputError, match="zero.cl: CL file is a character device"):
        mut.read_cl(tmp_path / "zero.cl")


@pytest.mark.parametrize("text, line, token", [
    ("GOTO/1,2,nan\nFINI", 1, "nan"),
    ("GOTO/1,2,3\nGOTO/1,2,inf\nFINI", 2, "inf"),
    ("GOTO/1,2,3\nGOTO/1,2\nFINI", 2, "1,2"),
    ("GOTO/1,2,3\nGOTO/1,2,x3\nFINI", 2, "x3"),
    ("GOTO/1,2,3\nGOTO/1,2,$", 2, "$"),
    ("GOTO/1,2,3\nGOTO/4,5,6", 2, "EOF"),
    ("GOTO/1,2,3\nCIRCLE/0,0,0,0,0,1,5\nFINI", 3, "CIRCLE"),
    ("GOTO/1,0,0\nCIRCLE/0,0,0,0,0,1,1\nGOTO/0,3,0\nFINI", 2, "1"),
    ("GOTO/1,0,0,0,0,0\nFINI", 1, "0,0,0"),
    ("UNITS/FURLONG\nFINI", 1, "FURLONG"),
    ("GOTO/1,2,1e300\nFINI", 1, "1e300"),
    ("LOADTL\nFINI", 1, "LOADTL"),
])
def test_errors_name_file_line_token(text, line, token):
    with pytest.raises(mut.ClParseError, match=r"<t>:\d+:") as info:
        mut.parse_cl_text(text, source="<t>")
    assert info.value.line == line and token in info.value.token
    assert isinstance(info.value, InputError)


def test_truncated_real_file_fails_with_line(extdata, tmp_path):
    lines = (extdata / CL / "CreoPost__profilfraesen_2.ncl.2").read_text().splitlines()
    cut = tmp_path / "cut.ncl"
    cut.write_text("\n".join(lines[:35]) + "\n")  # ends after "CIRCLE / ... $"
    with pytest.raises(mut.ClParseError, match=r"cut.ncl:35: .*truncated"):
        mut.read_cl(cut)
    cut.write_text("\n".join(lines[:60]) + "\n")
    with pytest.raises(mut.ClParseError, match=r"cut.ncl:60: .*without FINI"):
        mut.read_cl(cut)
    nan = tmp_path / "nan.ncl"
    nan.write_text("\n".join(lines[:20] + ["GOTO / NaN, 1.0, 2.0"] + lines[20:]) + "\n")
    with pytest.raises(mut.ClParseError, match=r"nan.ncl:21: not a finite number"):
        mut.read_cl(nan)


def test_circle_full_and_helix():
    text = "GOTO/1,0,0\nCIRCLE/0,0,0,0,0,1,1\nGOTO/1,0,0.5\nFINI"
    prog = mut.parse_cl_text(text, units="mm", arc_tolerance=1e-7)
    p = prog.p_C * 1e3
    ang = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
    assert ang[-2] > 1.9 * np.pi  # a full turn, counter-clockwise about +z
    assert np.allclose(np.hypot(p[:, 0], p[:, 1]), 1.0)
    assert np.all(np.diff(p[:, 2]) > 0) and p[-1, 2] == pytest.approx(0.5)


_WORDS = ["GOTO", "FEDRAT", "SPINDL", "RAPID", "CIRCLE", "TLAXIS", "MULTAX", "UNITS", "LOADTL",
          "PPRINT", "FINI", "END-OF-PATH", "PAINT", "CYCLE", "$$", "LOAD", "XYZ", "INCHES",
          "MSYS", "CUTCOM", "GODLTA", "FROM", "GOHOME", "TOOL PATH", "CYCLE", "CYCLE", "GOFWD"]
_TOKENS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.floats(-1e9, 1e9).map(repr),
    st.sampled_from(["IPM", "MMPM", "IPR", "MMPR", "RPM", "CLW", "CCLW", "OFF", "ON", "MM",
                     "INCHES", "TOOL", "", "$", "nan", "1e999", "-0", " ", "DRILL", "DEEP",
                     "BRKCHP", "BORE", "TAP", "DEPTH", "STEP", "CLEAR", "RAPTO", "FEDTO",
                     "RTRCTO", "AUTO", "DWELL", "LEFT"]),
    st.text(max_size=6),
)
_LINE = st.one_of(
    st.builds(lambda w, args, sep: w + (sep + ",".join(args) if args is not None else ""),
              st.sampled_from(_WORDS), st.one_of(st.none(), st.lists(_TOKENS, max_size=8)),
              st.sampled_from(["/", " / "])),
    st.text(max_size=30),
)


@settings(max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(lines=st.lists(_LINE, max_size=12), units=st.sampled_from(["mm", "inch"]),
       require_end=st.booleans())
def test_fuzz_only_typed_errors(lines, units, require_end):
    try:
        prog = mut.parse_cl_text("\n".join(lines), units=units, require_end=require_end)
    except mut.ClParseError as exc:
        assert exc.line >= 1
        return
    for m in prog.moves:
        assert all(math.isfinite(v) for v in m.p_C)
        assert abs(math.hypot(*m.axis_C) - 1.0) < 1e-9


def test_reader_streams():
    """Moves come out while the file is still being read (nothing is loaded whole)."""
    read = []

    def lines():
        for text in ("GOTO/1,2,3", "GOTO/4,5,6", "GOTO/7,8,9"):
            read.append(text)
            yield text
        raise AssertionError("the consumer stopped early: never reached")

    it = mut.iter_cl_moves(lines(), options=mut.ClReadOptions(units="mm"))
    first = next(it)
    assert first.p_C == pytest.approx((1e-3, 2e-3, 3e-3)) and len(read) <= 2


def test_dollar_dollar_starts_a_comment_also_after_a_statement():
    """APT: '$$' starts a comment that runs to the end of the line, wherever it stands (issue
    41: NX wrote ``GOTO/1.9949,0.1148,1.4399 $$ 1.9949,0.0707,1.3611`` and the reader took the
    comment for coordinates); '$' at the end of the statement part still continues it; the
    text of PPRINT is literal."""
    text = "\n".join([
        "UNITS/INCHES", "GOTO/1.9949,0.1148,1.4399 $$ 1.9949,0.0707,1.3611",
        "GOTO/1,2,$ $$ continued", "$$ a comment line inside the continuation",
        "3,0,0,1 $$ tool axis up", "PAINT/COLOR,31 $$ display only", "$$ alone",
        "PPRINT/ COST $$ 5", "GOTO/4,5,6$$no space", "FINI $$ the end"])
    prog = mut.parse_cl_text(text)
    assert np.allclose(prog.p_C / INCH_M, [[1.9949, 0.1148, 1.4399], [1, 2, 3], [4, 5, 6]],
                       atol=1e-12)
    assert prog.lines.tolist() == [2, 3, 9] and np.allclose(prog.axis_C[1], [0, 0, 1])
    assert prog.comments == (
        (2, "1.9949,0.0707,1.3611"), (3, "continued"),
        (4, "a comment line inside the continuation"), (5, "tool axis up"),
        (6, "display only"), (7, "alone"), (8, "COST $$ 5"), (9, "no space"), (10, "the end"))
    assert prog.not_applied == () and prog.warnings == () and prog.end_line == 10


@pytest.mark.parametrize("name, counts", [
    ("MECH491_NX_CLSF__APT_code.txt", {"TLDATA": 1, "PAINT": 14}),
    ("MECH491_NX_CLSF__APT_Variable_Axis.txt", {"TLDATA": 1, "PAINT": 31})])
def test_nx_statements_other_than_motion_are_read_and_accounted_for(extdata, name, counts):
    """Every statement of the real NX files is either a move, a setting the reader applies
    (TOOL PATH, MSYS, LOAD/TOOL, FEDRAT, RAPID, END-OF-PATH), a comment, or a word read and
    not needed with its reason (TLDATA, PAINT: counted here by a plain scan of the file)."""
    path = extdata / CL / name
    lines = path.read_text().splitlines()
    words = {}
    for ln in lines:
        w = ln.split("/")[0].strip()
        if w and not w.startswith("$$") and not w.startswith("Tool Path Listing"):
            words[w] = words.get(w, 0) + 1
    applied = {"GOTO", "TOOL PATH", "MSYS", "LOAD", "FEDRAT", "RAPID", "END-OF-PATH"}
    assert set(words) - applied == set(counts)
    prog = mut.read_cl(path, units="inch")
    read = {w.word: w for w in prog.read_words}
    assert {w: r.count for w, r in read.items()} == counts == {w: words[w] for w in counts}
    assert "TCP comes from --tool" in read["TLDATA"].reason
    assert read["TLDATA"].lines == (2,) and prog.not_applied == () and prog.warnings == ()
