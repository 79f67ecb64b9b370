"""Configuration data against public references (tests/data/vendor_config_reference.yaml):
the rule (robots/configuration.py), every writer (the text in the file), every reader (what it
returns), and the controller's resolution of a written pose + configuration back to joints.

The expected values are the table's, written by hand from the cited sources; the code under
test never produces them. "In front of / behind axis 1" is also recomputed here from forward
kinematics alone (the wrist centre's x in the axis-1 frame, the KUKA/SINUMERIK definition)."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from drakedeburr.programs import RobotProgram, read_program, write_program
from drakedeburr.robots import configuration_of, fk_opw, get_robot, joints_from_configuration

_TABLE = yaml.safe_load((Path(__file__).parent / "data" / "vendor_config_reference.yaml")
                        .read_text())
_FMT = {"fanuc": ("ls", ".ls"), "abb": ("rapid", ".mod"), "kuka": ("krl", ".src")}
_CASES = [(vendor, c) for vendor in ("fanuc", "abb", "kuka") for c in _TABLE[vendor]]


def _expected(vendor, case):
    e = case["expected"]
    return e if vendor == "fanuc" else tuple(int(v) for v in e)


def _model_joints(case):
    spec = get_robot(case["arm"])
    return spec, spec.model_joints(np.radians(case["joints_deg"]))


def test_every_case_cites_a_source_and_every_branch_is_covered():
    for _, c in _CASES:
        assert c["source"] in _TABLE["sources"], c["id"]
    fanuc = {c["expected"] for c in _TABLE["fanuc"]}
    letters = {(s[0], s[2], s[4]) for s in fanuc}
    assert {x[0] for x in letters} == {"F", "N"}
    assert {x[1] for x in letters} == {"U", "D"}
    assert {x[2] for x in letters} == {"T", "B"}
    turns = {tuple(int(t) for t in s.split(",")[1:]) for s in fanuc}
    assert {t[1] for t in turns} >= {-1, 0, 1} and {t[2] for t in turns} >= {-1, 0, 1}
    abb = [tuple(c["expected"]) for c in _TABLE["abb"]]
    assert {cf[3] & b for cf in abb for b in (1, 2, 4)} >= {1, 2, 4}
    assert {cf[0] for cf in abb} >= {-2, -1, 0, 1} and len({cf[1] for cf in abb}) >= 3
    assert len({cf[2] for cf in abb}) >= 3
    kuka = [tuple(c["expected"]) for c in _TABLE["kuka"]]
    assert {s & b for s, _ in kuka for b in (1, 2, 4)} >= {1, 2, 4}
    assert {t & (1 << i) for _, t in kuka for i in range(6)} >= {1, 2, 4, 8, 16, 32}


@pytest.mark.parametrize("vendor, case", _CASES, ids=[c["id"] for _, c in _CASES])
def test_configuration_rule_matches_the_reference(vendor, case):
    spec, q = _model_joints(case)
    assert spec.controller == vendor
    assert spec.within_limits(q), "reference case outside the arm's limits"
    assert configuration_of(spec.kinematics, q, vendor) == _expected(vendor, case)


@pytest.mark.parametrize("vendor, case", _CASES, ids=[c["id"] for _, c in _CASES])
def test_front_or_back_of_axis_1_from_forward_kinematics(vendor, case):
    spec, q = _model_joints(case)
    X = fk_opw(spec.opw, q)
    wrist = X[:3, 3] - spec.opw.c4 * X[:3, 2]
    # the axis-1 frame's x: where the wrist centre is with the same J1 and the arm stretched
    # out forward (every vendor's zero posture has the wrist in front)
    q0 = spec.model_joints(np.radians([case["joints_deg"][0], 0, 0, 0, 0, 0]))
    if vendor == "kuka":  # KUKA zero: A2 = 0 is the lower arm horizontal, forward
        q0 = spec.model_joints(np.radians([case["joints_deg"][0], -90, 90, 0, 0, 0]))
    X0 = fk_opw(spec.opw, q0)
    x_dir = (X0[:3, 3] - spec.opw.c4 * X0[:3, 2])[:2]
    x_a1 = wrist[:2] @ x_dir / np.linalg.norm(x_dir)
    assert abs(x_a1) > 0.05, "a reference case sits on the axis-1 boundary"
    e = _expected(vendor, case)
    behind = {"fanuc": lambda: e[4] == "B", "abb": lambda: bool(e[3] & 4),
              "kuka": lambda: bool(e[0] & 1)}[vendor]()
    assert (x_a1 < 0) == behind


def test_the_worked_fanuc_pair_is_one_pose_two_wrists():
    cases = {c["id"]: c for c in _TABLE["fanuc"]}
    spec, q_n = _model_joints(cases["onerobotics_nut"])
    _, q_f = _model_joints(cases["onerobotics_fut"])
    X_n, X_f = fk_opw(spec.opw, q_n), fk_opw(spec.opw, q_f)
    assert np.abs(X_n - X_f).max() < 1e-9
    # and the controller resolves that pose with each string to its own wrist
    for q, c in ((q_n, "onerobotics_nut"), (q_f, "onerobotics_fut")):
        got = joints_from_configuration(spec.kinematics, X_n, "fanuc", cases[c]["expected"])
        assert np.abs(got - q).max() < 1e-9


@pytest.mark.parametrize("vendor, case", _CASES, ids=[c["id"] for _, c in _CASES])
def test_pose_plus_reference_configuration_resolves_to_the_case_joints(vendor, case):
    spec, q = _model_joints(case)
    X = fk_opw(spec.opw, q)
    got = joints_from_configuration(spec.kinematics, X, vendor, _expected(vendor, case))
    assert np.abs(got - q).max() < 1e-7


@pytest.mark.parametrize("vendor, case", _CASES, ids=[c["id"] for _, c in _CASES])
def test_writer_writes_and_reader_reads_the_reference_configuration(vendor, case, tmp_path):
    spec, q = _model_joints(case)
    fmt, suffix = _FMT[vendor]
    X_FT = np.eye(4)
    X_FT[2, 3] = 0.1
    X_WT = fk_opw(spec.opw, q) @ X_FT
    prog = RobotProgram.from_poses("ref_case", [X_WT], [q], X_FT=X_FT, robot=spec)
    path = tmp_path / f"ref_case{suffix}"
    written = write_program(prog, path)
    text = "".join(p.read_text() for p in written)
    e = _expected(vendor, case)
    if vendor == "fanuc":
        assert f"CONFIG : '{e}'" in text
    elif vendor == "abb":
        assert "[" + ",".join(str(v) for v in e) + "]" in text.replace(" ", "")
    else:
        assert f"S {e[0]},T {e[1]}" in text.replace(", ", ",")
    back = read_program(path)
    assert back.moves[0].configuration == e


# ------------------------------------------------------------------ zones the controller keeps
def _line_program(robot, zone, speed, n=6, step=0.002, stationary=False):
    """n linear moves ``step`` apart along the base's y axis, all with ``zone`` and ``speed``."""
    spec = get_robot(robot)
    q0 = {"irb1600": [0.3, 0.3, 0.2, 0.4, 0.8, 0.5], "kr6_r700": [0.3, -1.4, 1.6, 0.4, 0.9, 0.5],
          "m10ia": [0.3, 0.2, -0.3, 0.4, -0.8, 0.5]}[robot]
    X0 = fk_opw(spec.opw, np.array(q0))
    X, q = [], []
    for k in range(n):
        Xk = X0.copy()
        Xk[1, 3] += step * k
        X.append(Xk)
        q.append(joints_from_configuration(spec.kinematics, Xk, spec.controller,
                                           configuration_of(spec.kinematics, np.array(q0),
                                                            spec.controller)))
    return RobotProgram.from_poses("zones", X, q, speed=speed, zone=zone, robot=spec,
                                   stationary_tool=stationary)


def test_a_zone_over_half_a_move_is_refused_and_the_builder_cuts_it():
    from drakedeburr.errors import InputError
    from drakedeburr.programs import zones_within_half_moves
    from drakedeburr.programs.common import check_writable

    prog = _line_program("irb1600", zone=0.005, speed=0.05)
    with pytest.raises(InputError, match="more than half an adjacent move"):
        check_writable(prog)
    cut = zones_within_half_moves(prog)
    check_writable(cut)
    assert [m.zone for m in cut.moves] == [0.001] * 6  # half of the 2 mm steps


@pytest.mark.parametrize("robot, suffix", [("irb1600", ".mod"), ("kr6_r700", ".src")])
def test_no_written_zone_exceeds_half_an_adjacent_move_as_read_back(robot, suffix, tmp_path):
    from drakedeburr.programs import zones_within_half_moves

    prog = zones_within_half_moves(_line_program(robot, zone=0.005, speed=0.05, step=0.003))
    path = write_program(prog, tmp_path / f"zones{suffix}")[0]
    back = read_program(path)
    p = np.array([m.X_OT[:3, 3] for m in back.moves])  # the file's own positions
    d = np.linalg.norm(np.diff(p, axis=0), axis=1)
    z = np.array([m.zone for m in back.moves])
    assert z.max() == pytest.approx(0.0015)
    assert np.all(z[1:-1] <= 0.5 * np.minimum(d[:-1], d[1:]) + 1e-9)
    assert z[0] <= 0.5 * d[0] + 1e-9 and z[-1] <= 0.5 * d[-1] + 1e-9


def test_fanuc_cnt_only_where_the_acceleration_bound_fits_the_zone(tmp_path):
    from drakedeburr.programs.common import LS_ACCEL_TIME

    # 10 mm/s: a CNT corner stays within 10 * 0.384 / 2 = 1.92 mm of its point
    assert LS_ACCEL_TIME == pytest.approx(0.384)
    slow = _line_program("m10ia", zone=0.002, speed=0.010, step=0.005)
    text = write_program(slow, tmp_path / "slow.ls")[0].read_text()
    assert text.count("mm/sec CNT20") == 5 and text.count("mm/sec FINE") == 1  # last: FINE
    fast = _line_program("m10ia", zone=0.002, speed=0.050, step=0.005)  # 9.6 mm > 2 mm zone
    text = write_program(fast, tmp_path / "fast.ls")[0].read_text()
    assert text.count("mm/sec CNT") == 0 and text.count("mm/sec FINE") == 6
    assert "acceleration time <= 384 ms" in text.replace("!", "").replace(" ;\n", "")
    from drakedeburr.programs import zones_within_half_moves

    short = zones_within_half_moves(  # zones cut to 1.5 mm < 1.92 mm
        _line_program("m10ia", zone=0.002, speed=0.010, step=0.003))
    assert write_program(short, tmp_path / "short.ls")[0].read_text().count("mm/sec FINE") == 6


# ------------------------------------------------------------------ programs set up their frames
def test_ls_sets_its_tool_and_user_frame_from_values_and_reads_them_back(tmp_path):
    import re
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from program_support import random_program

    from drakedeburr.programs import compare_programs

    prog = random_program("m10ia", stationary=True, n=4, name="frames")
    path = write_program(prog, tmp_path / "frames.ls")[0]
    text = path.read_text()
    assert "UTOOL[1]=PR[10] ;" in text and "UFRAME[1]=PR[10] ;" in text
    assert "!UTOOL[1] X=" not in text  # values are statements, not remarks
    assert "Remote TCP option" in text.replace("!", "").replace(" ;\n", " ")
    back = read_program(path)
    X_RO = np.linalg.solve(prog.X_BR, prog.X_WO)
    assert np.abs(back.X_FT - prog.X_FT).max() < 1e-8 and np.abs(back.X_RO - X_RO).max() < 1e-8
    assert compare_programs(prog, back) == []
    # the tool's X changed in the program: named at the UTOOL statement's line
    lines = text.splitlines()
    k = next(i for i, s in enumerate(lines) if "PR[10,1]=" in s)
    lines[k] = re.sub(r"=(-?[\d.]+)", lambda m: f"={float(m[1]) + 1.0:.6f}", lines[k])
    path.write_text("\n".join(lines) + "\n")
    found = compare_programs(prog, read_program(path))
    utool = next(i for i, s in enumerate(lines) if "UTOOL[1]=PR[10]" in s) + 1
    assert [(d.item, d.line) for d in found] == [("tool", utool)]


def test_krl_comments_name_the_stationary_tool_and_the_held_work_object(tmp_path):
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from program_support import random_program

    prog = random_program("kr6_r700", stationary=True, n=4, name="wp", tool_name="tSpindle",
                          wobj_name="wobjHub")
    src = write_program(prog, tmp_path / "wp.src")[0].read_text()
    assert "; $BASE: stationary tool tSpindle (external TCP)" in src
    assert "; $TOOL: work object wobjHub held on the flange" in src
    tool = random_program("kr6_r700", n=4, name="t", tool_name="tBurr", wobj_name="wobjHub")
    src = write_program(tool, tmp_path / "t.src")[0].read_text()
    assert "; $BASE: work object wobjHub" in src and "; $TOOL: tool tBurr" in src
