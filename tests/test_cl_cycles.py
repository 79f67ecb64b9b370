"""Drilling cycles expanded into moves: the real Creo CYCLE/DEEP file, NX and positional forms,
the geometry of every hole re-checked (on the hole axis, depths, pecks, return level)."""

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drakedeburr.post.cl_cycles as mut
from drakedeburr.post.cl_reader import ClParseError, parse_cl_text, read_cl
from drakedeburr.units import INCH_M

BOHREN = "CreoPost__bohren_1.ncl.8"


def _axis_coords(p: np.ndarray, top: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, float]:
    """Height of each point along a above top, and the largest distance off the axis line."""
    h = (p - top) @ a
    off = np.linalg.norm(p - top - h[:, None] * a, axis=1)
    return h, float(off.max())


def test_creo_deep_cycle_expanded(extdata):
    path = extdata / "cl_files" / BOHREN
    text = path.read_text()
    # the cycle's numbers, read here with a plain regex (independent of the reader)
    stmt = re.search(r"CYCLE / DEEP,(.*?)\n GOTO|CYCLE / DEEP,([^G]*)", text, re.S).group(0)
    nums = dict(re.findall(r"(DEPTH|STEP|MMPM|CLEAR),\s*\$?\s*([\d.]+)", stmt.replace("\n", "")))
    depth, step, feed, clear = (float(nums[k]) * 1e-3 for k in ("DEPTH", "STEP", "MMPM", "CLEAR"))
    lines = text.splitlines()
    holes = [(n, np.array([float(v) for v in ln.split("/")[1].split(",")]) * 1e-3)
             for n, ln in enumerate(lines, 1)
             if ln.startswith("GOTO") and 16 < n < lines.index("CYCLE / OFF") + 1]
    assert len(holes) == 2

    prog = read_cl(path)
    assert prog.paths[0].n_holes == 2 and prog.warnings == ()
    a = np.array([0.0, 0.0, 1.0])
    n_pecks = math.ceil(depth / step - 1e-9)
    for line, top in holes:
        sel = prog.lines == line
        p, rapid = prog.p_C[sel], prog.rapid[sel]
        assert prog.cycle[sel].all()
        h, off = _axis_coords(p, top, a)
        assert off < 1e-12  # every move on the hole axis
        feeds = h[~rapid]
        expect = -np.minimum(step * np.arange(1, n_pecks + 1), depth)
        assert np.allclose(feeds, expect, atol=1e-12) and feeds.min() == pytest.approx(-depth)
        assert np.allclose(prog.feed[sel][~rapid], feed / 60)
        # first and last: the R level (clearance above the hole top); out to R after each peck
        assert h[0] == pytest.approx(clear) and rapid[0]
        assert h[-1] == pytest.approx(clear) and rapid[-1]
        k_feed = np.flatnonzero(~rapid)
        for k in k_feed[:-1]:
            assert h[k + 1] == pytest.approx(clear) and rapid[k + 1]
            # back in, rapid, to the peck gap above the last depth
            assert h[k + 2] == pytest.approx(h[k] + mut.PECK_GAP_M) and rapid[k + 2]
        assert len(k_feed) == n_pecks
    # before the cycle the tool was 2 mm up over hole 1, after it goes back up to 2 mm
    before = np.flatnonzero(prog.lines == holes[0][0])[0] - 1
    assert prog.p_C[before][2] == pytest.approx(2e-3) and not prog.cycle[before]
    assert prog.p_C[-1][2] == pytest.approx(2e-3) and prog.rapid[-1] and not prog.cycle[-1]


def test_nx_keyword_drill_with_auto_retract():
    text = "\n".join([
        "UNITS/MM", "RAPID", "GOTO/20,100,50,0,0,1",
        "CYCLE/DRILL,RAPTO,3.0000,FEDTO,-10.0000,RTRCTO,AUTO,MMPM,250.0000",
        "GOTO/20,100,10", "GOTO/80,100,12", "CYCLE/OFF", "GOTO/80,100,60", "FINI"])
    prog = parse_cl_text(text)
    p = prog.p_C * 1e3
    first = p[prog.lines == 5]
    # R at 13, bottom at 0, back to the level the cycle started from (50)
    assert np.allclose(first, [[20, 100, 13], [20, 100, 0], [20, 100, 50]])
    assert prog.rapid[prog.lines == 5].tolist() == [True, False, True]
    second = p[prog.lines == 6]
    # over hole 2 at the retract level, down to R (15), feed to 2, back up to 50
    assert np.allclose(second, [[80, 100, 50], [80, 100, 15], [80, 100, 2], [80, 100, 50]])
    assert prog.feed[prog.lines == 6][2] == pytest.approx(0.25 / 60)


def test_positional_drill_is_read_and_reported():
    text = "UNITS/INCHES\nGOTO/0,0,1\nCYCLE/DRILL,0.5,IPM,10,0.1\nGOTO/0,0,0\nCYCLE/OFF\nFINI"
    prog = parse_cl_text(text)
    z = prog.p_C[prog.cycle][:, 2] / INCH_M
    assert np.allclose(z, [0.1, -0.5, 0.1])
    assert prog.feed[prog.cycle][1] == pytest.approx(10 * INCH_M / 60)
    assert any("positional" in w.message for w in prog.warnings)
    # value-then-unit, as in early APT: CYCLE/DRILL, depth, feed, IPM, clearance
    prog2 = parse_cl_text(text.replace("0.5,IPM,10,0.1", ".5,10.,IPM,.1"))
    assert np.allclose(prog2.p_C, prog.p_C) and np.allclose(prog2.feed, prog.feed, equal_nan=True)


def test_chip_break_bore_and_tilted_axis():
    a = np.array([0.0, 0.6, 0.8])
    text = "\n".join([
        "UNITS/MM", "GOTO/0,6,8,0,0.6,0.8", "CYCLE/BRKCHP,DEPTH,5,STEP,2,MMPM,100,CLEAR,2",
        "GOTO/0,0,0", "CYCLE/BORE,DEPTH,4,MMPM,60,CLEAR,1,RTRCTO,3", "GOTO/10,0,0",
        "CYCLE/OFF", "FINI"])
    prog = parse_cl_text(text)
    sel = prog.lines == 4
    h, off = _axis_coords(prog.p_C[sel] * 1e3, np.zeros(3), a)
    assert off < 1e-9
    # already over the hole on its axis: straight to R, then pecks with short back-offs
    assert np.allclose(h, [2, -2, -2 + 0.5, -4, -4 + 0.5, -5, 2])
    assert prog.rapid[sel].tolist() == [True, False, True, False, True, False, True]
    sel = prog.lines == 6
    h, off = _axis_coords(prog.p_C[sel] * 1e3, np.array([10.0, 0, 0]), a)
    assert off < 1e-9
    # over hole 2 at the level the tool left hole 1 (2 mm), R; bore: fed in and fed back out
    # to R, then up to the retract level
    assert np.allclose(h, [2, 1, -4, 1, 3])
    assert prog.rapid[sel].tolist() == [True, True, False, False, True]


@pytest.mark.parametrize("cycle, token, message", [
    ("CYCLE/TAP,DEPTH,5,MMPR,1", "TAP", "not supported"),
    ("CYCLE/CSINK,6,90,MMPM,50", "CSINK", "not supported"),
    ("CYCLE/DEEP,DEPTH,5,MMPM,50", "DEEP", "STEP"),
    ("CYCLE/DRILL,MMPM,50", "DRILL", "without a depth"),
    ("CYCLE/DRILL,DEPTH,5,SPEED,3", "SPEED", "unknown CYCLE parameter"),
    ("CYCLE/DRILL,1,2,3,4", "3", "left over"),
    ("CYCLE/DRILL,DEPTH,-2", "-2", "must be > 0"),
    ("CYCLE/DEEP,DEPTH,1e8,STEP,1e-3", "0.001", "more than 10000 pecks"),
    ("CYCLE/ON", "ON", "before any cycle"),
    ("CYCLE/FOO,1", "FOO", "unknown drilling cycle"),
    ("CYCLE83(10,0,2,-5)", "CYCLE83", "NC drilling cycle"),
])
def test_unsupported_cycles_refused_with_the_line(cycle, token, message):
    text = f"GOTO/0,0,5\n{cycle}\nGOTO/0,0,0\nCYCLE/OFF\nFINI"
    with pytest.raises(ClParseError, match=message) as info:
        parse_cl_text(text, source="<t>")
    assert info.value.line == 2 and token in info.value.token


def test_cycle_on_reuses_the_last_cycle():
    text = "\n".join(["GOTO/0,0,5", "CYCLE/DRILL,DEPTH,2,MMPM,50,CLEAR,1", "GOTO/0,0,0",
                      "CYCLE/OFF", "GOTO/5,0,5", "CYCLE/ON", "GOTO/5,0,0", "CYCLE/OFF", "FINI"])
    prog = parse_cl_text(text)
    assert prog.paths[0].n_holes == 2
    assert np.allclose(prog.p_C[prog.lines == 7][-2:] * 1e3, [[5, 0, -2], [5, 0, 1]])


@settings(max_examples=300, deadline=None)
@given(depth=st.floats(0.1, 50), step=st.floats(0.05, 20), clear=st.floats(0, 10),
       start=st.floats(0, 40), kind=st.sampled_from(["DEEP", "BRKCHP", "DRILL", "BORE"]),
       tilt=st.floats(0, 1.2), turn=st.floats(-math.pi, math.pi))
def test_hole_geometry_property(depth, step, clear, start, kind, tilt, turn):
    a = np.array([math.sin(tilt) * math.cos(turn), math.sin(tilt) * math.sin(turn),
                  math.cos(tilt)])
    cyc = mut.DrillCycle(kind, depth, step if kind in ("DEEP", "BRKCHP") else 0.0, clear,
                         None, 0.01, 0.0, 1, "")
    top = np.array([0.1, -0.2, 0.3])
    prev = top + (clear + start) * a + np.array([0.01, 0.02, 0.0])
    moves = mut.hole_moves(cyc, top, a, prev, prev)
    p = np.array([m[0] for m in moves])
    rapid = np.array([m[1] for m in moves])
    h, off = _axis_coords(p[1:], top, a)  # the first move may come from off the axis
    assert off < 1e-9
    feeds = h[~rapid[1:]]
    assert feeds.min() == pytest.approx(-depth) and np.all(feeds >= -depth - 1e-12)
    assert np.all(h <= max(clear, (prev - top) @ a) + 1e-9)  # never above where it started
    assert h[-1] >= clear - 1e-12  # ends out of the hole
    if kind in ("DEEP", "BRKCHP"):
        assert len(feeds) == math.ceil(depth / step - 1e-9)
        assert np.all(np.diff(feeds) < 0)  # every peck deeper
    # a rapid never enters uncut material: it stays the peck gap above the deepest feed
    deepest = 0.0
    for hk, rk in zip(h, rapid[1:], strict=True):
        if rk:
            assert hk >= min(clear, deepest + mut.PECK_GAP_M) - 1e-12
        else:
            deepest = min(deepest, hk)
