"""RAPID / KRL / LS writers: read each program back, recompute the joints from pose +
configuration with the analytic IK, compare with the planned joints."""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drakedeburr.post.writers as mut
from drakedeburr.errors import InputError
from drakedeburr.post.configuration import joints_from_configuration
from drakedeburr.post.opw import fk_opw
from drakedeburr.post.opw_ik import IRB1600_10_120_ROBOT as ROBOT
from drakedeburr.post.program import JOINT, LINEAR, RobotProgram

NUM = r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"


def _pose(xyz_mm, R):
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = np.asarray(xyz_mm, float) / 1000.0
    return X


def _zyx(a, b, c):
    return Rotation.from_euler("ZYX", [a, b, c], degrees=True).as_matrix()


def _program(rng, n=12, j6_beyond=False, **kw):
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    q = []
    while len(q) < n:
        v = rng.uniform(lo, hi)
        v[3] = rng.uniform(-2.9, 2.9)
        v[5] = rng.uniform(-2.9, 2.9)
        # away from the wrist (J5 = 0) and stretched-elbow (J3 = +-90 deg) singularities
        if abs(np.sin(v[4])) > 0.1 and abs(np.cos(v[2])) > 0.05:
            q.append(v)
    q = np.array(q)
    if j6_beyond:
        q[0, 5] = np.deg2rad(390.0)
    X_FT = _pose([10.0, -5.0, 180.0], _zyx(0, 30, 0))
    X_WO = _pose([700.0, -100.0, 250.0], _zyx(15, 0, 5))
    X_WT = fk_opw(ROBOT.opw, q) @ X_FT
    speeds = [0.150, 0.450, 0.600, 0.1234] * (n // 4) + [0.15] * (n % 4)
    zones = [0.0, 0.001, 0.0003, 0.005] * (n // 4) + [0.0] * (n % 4)
    types = [JOINT] + [LINEAR] * (n - 1)
    return RobotProgram.from_poses("deburr_test", X_WT, q, speed=speeds, zone=zones,
                                   move_type=types, X_FT=X_FT, X_WO=X_WO,
                                   comments=["window 1"] + [""] * (n - 1), **kw)


# ----------------------------------------------------------------------------- readers
def read_rapid(text):
    def nums(s):
        return [float(v) for v in re.findall(NUM, s)]

    tool = re.search(r"PERS tooldata \w+ := \[TRUE,\[\[(.*?)\],\[(.*?)\]\]", text)
    wobj = re.search(r"PERS wobjdata \w+ := \[FALSE,TRUE,\"\",\[\[(.*?)\],\[(.*?)\]\]", text)

    def pose(g):
        w, x, y, z = nums(g.group(2))
        return _pose(nums(g.group(1)), Rotation.from_quat([x, y, z, w]).as_matrix())

    X_FT, X_WO = pose(tool), pose(wobj)
    targets = {}
    for m in re.finditer(r"CONST robtarget (\w+) := \[\[(.*?)\],\[(.*?)\],\[(.*?)\],", text):
        w, x, y, z = nums(m.group(3))
        targets[m.group(1)] = (_pose(nums(m.group(2)), Rotation.from_quat([x, y, z, w])
                                     .as_matrix()), tuple(int(v) for v in nums(m.group(4))))
    moves = re.findall(r"(MoveL|MoveJ) (\w+), (\w+), (\w+), \w+ \\WObj:=\w+;", text)
    return X_FT, X_WO, targets, moves


def read_krl(src, dat):
    def frame(s):
        v = dict(re.findall(r"([XYZABC]) (" + NUM + ")", s))
        return _pose([float(v["X"]), float(v["Y"]), float(v["Z"])],
                     _zyx(float(v["A"]), float(v["B"]), float(v["C"])))

    X_WO = frame(re.search(r"\$BASE = \{(.*?)\}", src).group(1))
    X_FT = frame(re.search(r"\$TOOL = \{(.*?)\}", src).group(1))
    points = {}
    for m in re.finditer(r"DECL E6POS (\w+)=\{(.*?)\}", dat):
        s = dict(re.findall(r"([ST]) (\d+)", m.group(2)))
        points[m.group(1)] = (frame(m.group(2)), (int(s["S"]), int(s["T"])))
    motions = re.findall(r"^\s*(LIN|PTP) (\w+)", src, re.M)
    return X_FT, X_WO, points, motions


def read_ls(text):
    def remark(label):
        xyz = re.search(label + r"\[\d\] X (" + NUM + ") Y (" + NUM + ") Z (" + NUM + ")", text)
        wpr = re.search(label + r"\[\d\] W (" + NUM + ") P (" + NUM + ") R (" + NUM + ")", text)
        w, p, r = (float(v) for v in wpr.groups())
        return _pose([float(v) for v in xyz.groups()], _zyx(r, p, w))

    X_FT, X_WO = remark("UTOOL"), remark("UFRAME")
    points = {}
    for m in re.finditer(r"P\[(\d+)\]\{.*?CONFIG : '(.*?)',\s*X = (" + NUM + r") mm,\s*Y = ("
                         + NUM + r") mm,\s*Z = (" + NUM + r") mm,\s*W = (" + NUM + r") deg,\s*"
                         r"P = (" + NUM + r") deg,\s*R = (" + NUM + r") deg", text, re.S):
        x, y, z, w, p, r = (float(v) for v in m.groups()[2:])
        points[int(m.group(1))] = (_pose([x, y, z], _zyx(r, p, w)), m.group(2))
    motions = re.findall(r"^\s*\d+:\s*([LJ]) P\[(\d+)\] (\S+) (\S+) ;", text, re.M)
    return X_FT, X_WO, points, motions


def _recompute(X_FT, X_WO, X_OT, vendor, conf):
    X_WF = X_WO @ X_OT @ np.linalg.inv(X_FT)
    return joints_from_configuration(ROBOT, X_WF, vendor, conf)


# ------------------------------------------------------------------------------- tests
def test_rapid_round_trip():
    prog = _program(np.random.default_rng(0))
    text = mut.format_rapid(prog)
    X_FT, X_WO, targets, moves = read_rapid(text)
    assert np.abs(X_FT - prog.X_FT).max() < 1e-8 and np.abs(X_WO - prog.X_WO).max() < 1e-8
    assert len(targets) == len(moves) == len(prog.moves)
    for i, (instr, name, _speed, _zone) in enumerate(moves):
        X_OT, conf = targets[name]
        q = _recompute(X_FT, X_WO, X_OT, "abb", conf)
        assert np.abs(q - prog.moves[i].q).max() <= 1e-6, i
        assert instr == ("MoveJ" if i == 0 else "MoveL")
    names = [(s, z) for _, _, s, z in moves]
    assert names[:4] == [("v150", "fine"), ("vDD_450_0", "z1"), ("v600", "zDD_0_30"),
                         ("vDD_123_4", "z5")]
    assert "CONST speeddata vDD_450_0 := [450.000," in text  # ABB has no v450
    assert "CONST zonedata zDD_0_30 := [FALSE,0.300," in text
    assert "! window 1" in text and "ConfL \\On;" in text


def test_krl_round_trip_and_turn_ambiguity():
    prog = _program(np.random.default_rng(1))
    src, dat = mut.format_krl(prog)
    X_FT, X_WO, points, motions = read_krl(src, dat)
    assert np.abs(X_FT - prog.X_FT).max() < 1e-8 and np.abs(X_WO - prog.X_WO).max() < 1e-8
    assert [m[0] for m in motions] == ["PTP"] + ["LIN"] * (len(prog.moves) - 1)
    for i, (_, name) in enumerate(motions):
        X_OT, st = points[name]
        q = _recompute(X_FT, X_WO, X_OT, "kuka", st)
        assert np.abs(q - prog.moves[i].q).max() <= 1e-6, i
    assert "$VEL.CP = 0.450000" in src and "$APO.CDIS = 1.000" in src
    assert "WARNING" not in src
    # J6 = 390 deg: S/T cannot express it; the header says so (and ABB/LS still can)
    prog2 = _program(np.random.default_rng(1), j6_beyond=True)
    src2, _ = mut.format_krl(prog2)
    assert "WARNING: S/T cannot tell the planned turn of A4/A6 at move(s) 1" in src2


def test_ls_round_trip():
    prog = _program(np.random.default_rng(2), j6_beyond=True)
    text = mut.format_ls(prog)
    X_FT, X_WO, points, motions = read_ls(text)
    assert np.abs(X_FT - prog.X_FT).max() < 1e-8 and np.abs(X_WO - prog.X_WO).max() < 1e-8
    for i, (kind, n, _speed, _term) in enumerate(motions):
        X_OT, conf = points[int(n)]
        # UTOOL / UFRAME come from the program's remarks (set them on the controller)
        q = _recompute(X_FT, X_WO, X_OT, "fanuc", conf)
        assert np.abs(q - prog.moves[i].q).max() <= 1e-6, i
        assert kind == ("J" if i == 0 else "L")
    assert motions[1][2:] == ("450mm/sec", "CNT10") and motions[0][3] == "FINE"
    assert "CONFIG : 'N" in text or "CONFIG : 'F" in text
    assert re.search(r"CONFIG : '[NF] [UD] [TB], -?\d, -?\d, 1'", text)  # J6 = 390 deg: turn 1


def test_deterministic_and_atomic(tmp_path):
    a = _program(np.random.default_rng(3), flag="FORCED", flag_reason="3 points left out")
    b = _program(np.random.default_rng(3), flag="FORCED", flag_reason="3 points left out")
    assert mut.format_rapid(a) == mut.format_rapid(b)
    assert mut.format_krl(a) == mut.format_krl(b)
    assert mut.format_ls(a) == mut.format_ls(b)
    for fmt, name in (("rapid", "p.mod"), ("krl", "p.src"), ("ls", "p.ls")):
        paths = mut.write_program(a, tmp_path / name, fmt)
        text = paths[0].read_text()
        assert "FORCED" in text and "3 points left out" in text
    assert (tmp_path / "p.dat").exists()
    assert not list(tmp_path.glob(".*.tmp"))


def test_inconsistent_program_refused():
    prog = _program(np.random.default_rng(4), n=2)
    bad = RobotProgram(name="bad", moves=(prog.moves[0].__class__(
        X_WT=prog.moves[0].X_WT, q=prog.moves[1].q),), X_FT=prog.X_FT)
    with pytest.raises(InputError, match="do not reach their TCP pose"):
        mut.format_rapid(bad)
    with pytest.raises(InputError, match="program name"):
        RobotProgram(name="1bad", moves=prog.moves)
    with pytest.raises(InputError, match="speed must be > 0"):
        RobotProgram.from_poses("p", [prog.moves[0].X_WT], [prog.moves[0].q], speed=0.0)
