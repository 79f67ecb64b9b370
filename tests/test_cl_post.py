"""CL file -> program pipeline and the ``drakedeburr post`` command."""

import re

import numpy as np
import pytest

import drakedeburr.post.cl_post as mut
from drakedeburr.cli import main
from drakedeburr.errors import InputError
from drakedeburr.post.cl_reader import parse_cl_text, read_cl
from drakedeburr.robots.opw import fk_opw

CREO = "CreoPost__profilfraesen_2.ncl.2"
WOBJ = [700.0, 0.0, 300.0, 0.0, 0.0, 30.0]


def test_pose_from_mm_deg():
    X = mut.pose_from_mm_deg([100, 200, 300, 90, 0, 0])
    assert np.allclose(X[:3, 3], [0.1, 0.2, 0.3])
    assert np.allclose(X[:3, :3] @ [0, 1, 0], [0, 0, 1])  # rx = 90 deg: y -> z
    X = mut.pose_from_mm_deg([0, 0, 0, 0, 0, 90])
    assert np.allclose(X[:3, :3] @ [1, 0, 0], [0, 1, 0])
    with pytest.raises(InputError, match="6 finite numbers"):
        mut.pose_from_mm_deg([1, 2, 3])


def test_creo_program_in_work_object(extdata):
    cl = read_cl(extdata / "cl_files" / CREO)
    X_WO = mut.pose_from_mm_deg(WOBJ)
    res = mut.program_from_cl(cl, "creo", mut.PostSettings(X_WO=X_WO))
    assert res.ok and res.program is not None
    prog = res.program
    assert len(prog.moves) == len(cl.moves) and prog.flag == "UNVERIFIED"
    for i, m in enumerate(prog.moves):
        X_OT = prog.X_OT(i)
        assert np.allclose(X_OT[:3, 3], cl.moves[i].p_C, atol=1e-12)  # tip on the CL point
        assert np.allclose(X_OT[:3, 2], -np.array(cl.moves[i].axis_C), atol=1e-12)
        X = fk_opw(prog.robot.opw, m.q) @ prog.X_FT
        assert np.abs(X - m.X_WT).max() < 1e-9
        assert m.move_type == ("joint" if cl.moves[i].rapid else "linear")
        assert m.source_line == cl.moves[i].line
    assert prog.moves[-1].zone == 0.0
    assert prog.moves[2].speed == pytest.approx(400e-3 / 60)  # FEDRAT 400 mm/min


def test_unreachable_reported_with_lines_and_forced():
    text = "\n".join(["UNITS/MM", "GOTO/0,0,0", "GOTO/10,0,0", "GOTO/3000,0,0", "GOTO/20,0,0",
                      "FINI"])
    cl = parse_cl_text(text)
    X_WO = mut.pose_from_mm_deg(WOBJ)
    res = mut.program_from_cl(cl, "p", mut.PostSettings(X_WO=X_WO))
    assert res.program is None and res.unreachable_lines == (4,)
    forced = mut.program_from_cl(cl, "p", mut.PostSettings(X_WO=X_WO, force=True))
    assert forced.program is not None and len(forced.program.moves) == 3
    assert forced.program.flag == "FORCED" and "lines 4" in forced.program.flag_reason


def test_cli_post(extdata, tmp_path):
    cl = str(extdata / "cl_files" / CREO)
    out = tmp_path / "creo.mod"
    wobj = ",".join(str(v) for v in WOBJ)
    fast = ["--spin", "greedy"]
    assert main(["post", cl, "--format", "rapid", "-o", str(out), "--wobj", wobj, *fast]) == 0
    text = out.read_text()
    assert text.startswith("MODULE CreoPost__profilfraesen") and "UNVERIFIED" in text
    assert text.count("MoveL") + text.count("MoveJ") == len(read_cl(cl).moves)
    # the same command twice gives the same bytes
    out2 = tmp_path / "creo2.mod"
    assert main(["post", cl, "--format", "rapid", "-o", str(out2), "--wobj", wobj, *fast]) == 0
    assert out2.read_text() == text
    # KRL (for a KUKA arm, the part within its 0.7 m reach) writes .src + .dat
    near = "450,0,100,0,0,30"
    assert main(["post", cl, "--robot", "kr6_r700", "-o", str(tmp_path / "c.src"),
                 "--wobj", near]) == 0
    # KRL is not for the ABB arm: refused before any work (exit 2)
    assert main(["post", cl, "--format", "krl", "-o", str(tmp_path / "d.src"),
                 "--wobj", near]) == 2
    assert (tmp_path / "c.dat").read_text().count("DECL E6POS") == len(read_cl(cl).moves)
    # in the robot base (no work object) the part sits inside the robot: nothing written
    bad = tmp_path / "bad.ls"
    fanuc = ["--robot", "m10ia"]
    bad_mod = tmp_path / "bad.mod"
    assert main(["post", cl, "-o", str(bad_mod), *fast]) == 1
    assert not bad_mod.exists()
    # a bad work object is an input error (exit 2)
    assert main(["post", cl, *fanuc, "-o", str(bad), "--wobj", "1,2,3"]) == 2
    assert main(["post", str(tmp_path / "missing.cl"), *fanuc, "-o", str(bad)]) == 2


def test_cli_force(tmp_path):
    cl = tmp_path / "far.apt"
    cl.write_text("UNITS/MM\nFEDRAT/9000,MMPM\nGOTO/0,0,0\nGOTO/2500,0,0\nGOTO/10,0,0\nFINI\n")
    out = tmp_path / "far.ls"
    args = ["post", str(cl), "--robot", "m10ia", "-o", str(out), "--wobj", "700,0,300,0,0,0"]
    assert main(args) == 1 and not out.exists()
    assert main(args + ["--force"]) == 1
    text = out.read_text()
    assert "FORCED" in text and "L P[2] 150mm/sec FINE ;" in text


NX_WOBJ = [800.0, 0.0, 100.0, 0.0, 0.0, -90.0]


@pytest.fixture(scope="module")
def fifteen(extdata, tmp_path_factory):
    from cl_support import nx_multipath

    return nx_multipath(extdata, tmp_path_factory.mktemp("nx") / "fifteen.cls", n_paths=15)


def test_fifteen_paths_every_goto_in_the_program(fifteen):
    """At least one move per GOTO of all 15 paths, in file order, each path named, every
    GOTO's move on its MCS point (plain scan of the file, independent of the reader)."""
    from cl_support import msys_point_inch, scan_nx_paths

    scan = scan_nx_paths(fifteen)
    cl = read_cl(fifteen, units="inch")
    X_WO = mut.pose_from_mm_deg(NX_WOBJ)
    res = mut.program_from_cl(cl, "fifteen", mut.PostSettings(X_WO=X_WO))
    assert res.ok, res.unreachable_lines[:5]
    prog = res.program
    lines = [m.source_line for m in prog.moves]
    assert lines == sorted(lines)
    by_line = {}
    for i, m in enumerate(prog.moves):
        by_line.setdefault(m.source_line, []).append(i)
    for k, path in enumerate(scan):
        for n, values, msys in path["gotos"]:
            assert n in by_line, f"GOTO on line {n} of path {k + 1} missing"
            i = by_line[n][-1]
            assert np.abs(prog.X_OT(i)[:3, 3] - msys_point_inch(msys, values)).max() < 1e-9
        first = prog.moves[by_line[path["gotos"][0][0]][0]]
        assert first.comment.startswith(f"path {k + 1}/15 {path['name']}")
    assert sum(len(p["gotos"]) for p in scan) == len(prog.moves)
    # FK of the planned joints puts the tool on every point
    X = np.array([fk_opw(prog.robot.opw, m.q) for m in prog.moves]) @ prog.X_FT
    assert np.abs(X - np.array([m.X_WT for m in prog.moves])).max() < 1e-9
    assert any(n.startswith("path 15 'OP15'") for n in prog.notes)


@pytest.mark.parametrize("fmt, suffix, robot, wobj", [
    ("rapid", ".mod", "irb1600", NX_WOBJ), ("krl", ".src", "kr6_r700", [450.0, 0, 0, 0, 0, -90]),
    ("ls", ".ls", "m10ia", NX_WOBJ)])
def test_cli_fifteen_paths_named_in_each_format(fifteen, tmp_path, fmt, suffix, robot, wobj):
    from cl_support import scan_nx_paths

    out = tmp_path / f"fifteen{suffix}"
    wobj = ",".join(str(v) for v in wobj)
    args = ["post", str(fifteen), "--robot", robot, "-o", str(out), "--units", "inch",
            "--wobj", wobj]
    if robot == "kr6_r700":
        # the 15 paths spread wider than the KR 6's 0.7 m reach: written with --force (exit 1,
        # the result failed), every path still there and the header saying so
        assert main([*args, "--force"]) == 1 and "FORCED" in out.read_text()
    else:
        assert main(args) == 0
    text = out.read_text()
    names = [p["name"] for p in scan_nx_paths(fifteen)]
    at = [text.find(f"path {k + 1}/15 {name}") for k, name in enumerate(names)]
    assert all(a > 0 for a in at) and at == sorted(at)  # named, in file order
    n_goto = sum(len(p["gotos"]) for p in scan_nx_paths(fifteen))
    move = {"rapid": r"^\s*Move[LJ] ", "krl": r"^\s*(LIN|PTP) ", "ls": r"^\s*\d+:\s+[LJ] P\["}
    left_out = re.search(r"FORCED: (\d+) unreachable CL point", text)
    left_out = int(left_out[1]) if left_out else 0
    assert (robot == "kr6_r700") == (left_out > 0)
    assert len(re.findall(move[fmt], text, re.M)) == n_goto - left_out


def test_fifteen_paths_with_trailing_comments_post_every_goto(fifteen, tmp_path):
    """The 15-path NX listing with a '$$' comment after every GOTO (3-number GOTOs followed by
    the next point's coordinates, as in issue 41's NX file) and after other statements: the
    program holds one move per GOTO, counted by a plain scan of the file, each at the
    position written before the '$$'."""
    lines = fifteen.read_text().splitlines()
    gotos = [k for k, ln in enumerate(lines) if ln.startswith("GOTO/")]
    for a, b in zip(gotos, gotos[1:] + gotos[:1], strict=True):
        lines[a] += " $$ " + ",".join(lines[b][5:].split(",")[:3])
    lines = [ln + " $$ shown in NX" if ln.startswith("PAINT/") else ln for ln in lines]
    commented = tmp_path / "fifteen_commented.cls"
    commented.write_text("\r\n".join(lines) + "\r\n")
    scan = [(n, [float(v) for v in raw.split("$$")[0].strip()[5:].split(",")])
            for n, raw in enumerate(commented.read_text().splitlines(), start=1)
            if raw.startswith("GOTO/")]
    assert len(scan) > 5000 and all(len(v) in (3, 6) for _, v in scan)
    cl = read_cl(commented, units="inch")
    assert cl.lines.tolist() == [n for n, _ in scan] and len(cl.paths) == 15
    plain = read_cl(fifteen, units="inch")  # the same file without the comments
    assert np.array_equal(cl.p_C, plain.p_C) and np.array_equal(cl.axis_C, plain.axis_C)
    out = tmp_path / "fifteen.mod"
    assert main(["post", str(commented), "-o", str(out), "--units", "inch", "--wobj",
                 ",".join(str(v) for v in NX_WOBJ)]) == 0
    assert len(re.findall(r"^\s*Move[LJ] ", out.read_text(), re.M)) == len(scan)


def test_creo_drilling_program(extdata):
    """The cycle's moves reach the program: straight (linear) rapids in and out of the holes,
    feed moves at the cycle feed down to the depth written in the file."""
    cl = read_cl(extdata / "cl_files" / "CreoPost__bohren_1.ncl.8")
    X_WO = mut.pose_from_mm_deg(WOBJ)
    res = mut.program_from_cl(cl, "bohren", mut.PostSettings(X_WO=X_WO))
    prog = res.program
    assert res.ok and len(prog.moves) == len(cl) == 26
    for i, m in enumerate(prog.moves):
        if cl.cycle[i]:
            assert m.move_type == "linear" and m.zone == 0.0  # every depth reached exactly
            assert m.speed == pytest.approx(50e-3 / 60 if not cl.rapid[i] else prog.moves[0].speed)
        else:
            assert m.move_type == ("joint" if cl.rapid[i] else "linear")
    z = np.array([prog.X_OT(i)[2, 3] for i in range(len(prog.moves))])
    assert z.min() == pytest.approx(0.5e-3 - 3.5e-3)  # GOTO z 0.5 - DEPTH 3.5 (mm)
    assert any("2 holes drilled" in n for n in prog.notes)


def test_cli_reports_unit_switch_and_unknown_words(tmp_path, caplog):
    cl = tmp_path / "mixed.apt"
    cl.write_text("UNITS/MM\nGOTO/0,0,0\nFOO/1\nGOTO/10,0,0\nUNITS/INCHES\nGOTO/1,0,0\n"
                  "FOO/2\nBAR\nFINI\n")
    out = tmp_path / "mixed.mod"
    assert main(["post", str(cl), "--format", "rapid", "-o", str(out), "--wobj",
                 "700,0,300,0,0,0", "--spin", "greedy"]) == 0
    log = caplog.text
    assert "UNITS switched to inch after 2 moves" in log
    assert log.count("FOO x2 (lines 3, 7)") == 1 and "BAR x1 (line 8)" in log
    text = out.read_text()
    assert "UNITS switched to inch at line 5 after 2 moves" in text
    assert "not applied: FOO x2 (lines 3, 7)" in text
    prog = read_cl(cl)
    assert prog.p_C[-1] == pytest.approx([0.0254, 0, 0])  # 1 inch after the switch


@pytest.mark.parametrize("content, expected", [
    (None, "missing.cl: CL file not found"),
    ("GOTO/1,2,3\nGOTO/1,x,3\nFINI\n", "bad.cl:2: expected a number (token 'x')"),
    ("GOTO/1,2,3\nCUTCOM/LEFT\nFINI\n", "bad.cl:2: cutter compensation"),
    ("GOTO/1,2,3\nCYCLE/TAP,DEPTH,5,MMPR,1\nGOTO/0,0,0\nFINI\n", "bad.cl:2: drilling cycle"),
])
def test_cli_bad_input_exit_2_one_line(tmp_path, capsys, content, expected):
    cl = tmp_path / ("missing.cl" if content is None else "bad.cl")
    if content is not None:
        cl.write_text(content)
    out = tmp_path / "p.mod"
    assert main(["post", str(cl), "--format", "rapid", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err
    assert not out.exists()


def test_cli_output_checked_before_reading(tmp_path, capsys, extdata):
    cl = str(extdata / "cl_files" / CREO)
    assert main(["post", cl, "--format", "rapid", "-o", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err
    assert main(["post", cl, "--format", "rapid", "-o", str(tmp_path / "no" / "p.mod")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_cli_ignore_cutcom(tmp_path):
    cl = tmp_path / "comp.apt"
    cl.write_text("UNITS/MM\nCUTCOM/LEFT\nGOTO/0,0,0\nGOTO/10,0,0\nCUTCOM/OFF\nFINI\n")
    out = tmp_path / "comp.mod"
    args = ["post", str(cl), "--format", "rapid", "-o", str(out), "--wobj", "700,0,300,0,0,0"]
    assert main(args) == 2 and not out.exists()
    assert main(args + ["--ignore-cutcom"]) == 0
    assert "not applied: CUTCOM x1 (line 2)" in out.read_text()


def test_cli_parts_continue_each_other(extdata, tmp_path):
    cl_path = extdata / "cl_files" / CREO
    out = tmp_path / "creo.mod"
    wobj = ",".join(str(v) for v in WOBJ)
    assert main(["post", str(cl_path), "--format", "rapid", "-o", str(out), "--wobj", wobj,
                 "--max-moves", "100"]) == 0
    parts = [tmp_path / "creo_001.mod", tmp_path / "creo_002.mod"]
    assert all(p.exists() for p in parts) and not out.exists()
    texts = [p.read_text() for p in parts]
    counts = [t.count("MoveL") + t.count("MoveJ") for t in texts]
    assert counts == [100, len(read_cl(cl_path)) - 100]
    assert "part 1 of 2" in texts[0] and "part 2 of 2" in texts[1]
    assert texts[0].splitlines()[0].endswith("_001") and texts[1].splitlines()[0].endswith("_002")
    # part 1 runs on into part 2 (no stop point); the whole program stops at its very end
    last = [[ln for ln in t.splitlines() if ln.lstrip().startswith("Move")][-1] for t in texts]
    # (its zone is the 1 mm asked for, cut to half of the 0.33 mm arc steps around it: the
    # controller would shrink a larger one)
    assert ", zdd0_167," in last[0] and ", fine," in last[1]


def test_cli_interrupt_exit_130(extdata, tmp_path, monkeypatch):
    import drakedeburr.post.cl_post as cl_post

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cl_post, "post_cl_file", interrupted)
    out = tmp_path / "p.mod"
    out.write_text("previous")
    assert main(["post", str(extdata / "cl_files" / CREO), "--format", "rapid",
                 "-o", str(out)]) == 130
    assert out.read_text() == "previous"


def test_post_cl_file_reports_progress_and_never_prints(extdata, tmp_path, capsys):
    calls = []
    summary = mut.post_cl_file(
        extdata / "cl_files" / CREO, mut.PostOutput(tmp_path / "p.ls", "ls", "p", max_moves=60),
        mut.PostSettings(robot=mut.robot_kinematics("m10ia"), X_WO=mut.pose_from_mm_deg(WOBJ)),
        progress=lambda done, total, label: calls.append((label, done, total)))
    assert [f.name for f in summary.files] == ["p_001.ls", "p_002.ls", "p_003.ls"]
    assert summary.n_moves == len(summary.cl) == 172
    labels = [c[0] for c in calls]
    assert labels.index("read CL") < labels.index("spin + IK") < labels.index("write")
    for label in ("read CL", "spin + IK", "write"):
        last = [c for c in calls if c[0] == label][-1]
        assert last[1] == last[2]  # each phase reports its end
    assert [c[1:] for c in calls if c[0] == "write"] == [(1, 3), (2, 3), (3, 3)]
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""


@pytest.mark.parametrize("robot, suffix, spindle", [
    ("irb1600", ".mod", [700.0, 0, 500, 0, -90, 0]), ("kr6_r700", ".src", [450.0, 0, 300, 0, 0, 0]),
    ("lrmate200ic", ".ls", [400.0, 0, 400, 0, -90, 0]), ("m10ia", ".ls", [450.0, 0, 300, 0, 0, 0])])
def test_cli_workpiece_in_hand(extdata, tmp_path, robot, suffix, spindle):
    """post --workpiece-in-hand: a stationary-tool program (ABB robhold FALSE, KUKA external
    TCP, FANUC RTCP) whose every pose, read back from the file and put through the arm's own
    configuration -> joints, brings the CL point onto the spindle tip with the CL axis along
    the spindle."""
    from drakedeburr.programs import read_program
    from drakedeburr.robots import get_robot, joints_from_configuration

    cl_path = extdata / "cl_files" / CREO
    out = tmp_path / f"wih{suffix}"
    part = [0.0, 0, 100, 0, 0, 0]
    args = ["post", str(cl_path), "--robot", robot, "--workpiece-in-hand", "-o", str(out),
            "--tool", ",".join(map(str, spindle)), "--wobj", ",".join(map(str, part))]
    assert main(args) == 0
    back = read_program(out)
    cl = read_cl(cl_path)
    assert back.stationary_tool and len(back.moves) == len(cl.moves)
    text = out.read_text()
    if suffix == ".mod":
        from test_programs_formats import rapidcheck

        assert rapidcheck(text) == [] and "PERS tooldata tSpindle := [FALSE," in text
    elif suffix == ".src":
        assert "$IPO_MODE = #TCP" in text
    else:
        assert all(" RTCP" in ln for ln in text.splitlines() if re.match(r"\s*\d+:\s+L P", ln))
    spec = get_robot(robot)
    X_BS, X_FO = mut.pose_from_mm_deg(spindle), mut.pose_from_mm_deg(part)
    assert np.abs(spec.X_BR @ back.X_RO - X_BS).max() < 1e-6  # the fixed frame is the spindle
    assert np.abs(back.X_FT - X_FO).max() < 1e-6  # the flange carries the part's CL frame
    for m, cm in zip(back.moves, cl.moves, strict=True):
        X_SO = m.X_OT  # the part in the spindle's frame, as the controller stores it
        X_OS = np.linalg.inv(X_SO)  # the spindle tip in the part
        assert np.allclose(X_OS[:3, 3], cm.p_C, atol=1e-6)  # [m]: written to 1e-3 mm
        assert np.allclose(X_OS[:3, 2], -np.asarray(cm.axis_C), atol=1e-6)
        X_BF = spec.X_BR @ back.X_RO @ X_SO @ np.linalg.inv(back.X_FT)
        q = joints_from_configuration(spec.kinematics, X_BF, spec.controller, m.configuration)
        X = fk_opw(spec.kinematics.opw, q) @ X_FO @ X_OS  # the spindle, by forward kinematics
        assert np.abs(X - X_BS).max() < 1e-6


def test_workpiece_in_hand_needs_the_spindle(extdata, tmp_path, capsys):
    out = tmp_path / "wih.mod"
    assert main(["post", str(extdata / "cl_files" / CREO), "--workpiece-in-hand",
                 "-o", str(out)]) == 2
    assert "--tool" in capsys.readouterr().err and not out.exists()


def _written_feeds_mm_s(text: str, fmt: str) -> list[float]:
    """TCP speeds [mm/s] of the linear moves, read from the program text with plain regexes
    (not the project's readers): LS ``L P[n] 40cm/min``, RAPID ``MoveL p, vdd..`` resolved by
    its ``speeddata`` declaration or the predefined ``vNNN``, KRL ``$VEL.CP`` [m/s] before
    ``LIN``."""
    if fmt == "ls":
        per = {"mm/sec": 1.0, "cm/min": 10.0 / 60.0}
        return [int(v) * per[u] for v, u in
                re.findall(r"^\s*\d+:\s+L P\[\d+\] (\d+)(mm/sec|cm/min) ", text, re.M)]
    if fmt == "rapid":
        declared = dict(re.findall(r"CONST speeddata (\w+) := \[([\d.]+),", text))
        names = re.findall(r"^\s*MoveL \w+, (\w+),", text, re.M)
        return [float(declared[n]) if n in declared else float(n[1:]) for n in names]
    feeds, v = [], None
    for line in text.splitlines():
        m = re.match(r"\s*\$VEL\.CP = ([\d.]+)", line)
        if m:
            v = float(m[1]) * 1000.0
        elif re.match(r"\s*LIN ", line):
            feeds.append(v)
    return feeds


@pytest.mark.parametrize("fmt, suffix, robot, wobj", [
    ("rapid", ".mod", "irb1600", WOBJ), ("krl", ".src", "kr6_r700", [450.0, 0, 100, 0, 0, 30]),
    ("ls", ".ls", "m10ia", WOBJ)])
def test_written_feeds_are_the_files_fedrat(extdata, tmp_path, fmt, suffix, robot, wobj):
    """Creo's ``FEDRAT / 400.000000, MMPM`` (a real CAM file) comes out of every writer at
    400 mm/min: LS as ``40cm/min`` (FANUC TP takes whole cm/min, 1-12000; whole mm/sec
    could only say 6 = -10 %), RAPID to 0.001 mm/s, KRL to 1e-6 m/s. The feed is read from
    the CL file by a plain scan and the written feeds by regexes on the program text."""
    src = extdata / "cl_files" / CREO
    fedrat = {float(v) for v in re.findall(r"FEDRAT / ([\d.]+),\s*MMPM", src.read_text())}
    assert fedrat == {400.0}
    out = tmp_path / f"creo{suffix}"
    assert main(["post", str(src), "--robot", robot, "-o", str(out), "--wobj",
                 ",".join(map(str, wobj)), "--spin", "greedy"]) == 0
    text = out.read_text()
    feeds = np.array(_written_feeds_mm_s(text, fmt))
    n_feed = sum(1 for m in read_cl(src).moves if not m.rapid)
    assert feeds.size == n_feed
    want = 400.0 / 60.0
    tol = {"ls": 1e-12, "rapid": 1e-3 / 2 + 1e-12, "krl": 1e-3 / 2 + 1e-12}[fmt]
    assert np.abs(feeds - want).max() <= tol
    if fmt == "ls":
        assert "mm/sec" not in text and "40cm/min" in text


def test_ls_feed_never_faster_and_within_a_sixth_mm_s():
    """Over 1 mm/min .. 120 m/min the LS speed written is at most the plan and at most
    1/6 mm/s (one cm/min) below it; exact mm/sec and cm/min values are written as such."""
    from drakedeburr.programs.common import ls_speed

    per = {"mm/sec": 1.0, "cm/min": 1.0 / 6.0}
    for mm_min in np.r_[np.linspace(10.0, 120000.0, 4001), 254.0, 400.0, 9000.0]:
        v_plan = mm_min / 60.0
        value, unit = ls_speed(v_plan / 1000.0)
        v = value * per[unit]
        assert isinstance(value, int) and v <= v_plan + 1e-9
        assert v_plan - v < 1.0 / 6.0 + 1e-9, mm_min
        if unit == "mm/sec":
            assert 1 <= value <= 2000
        else:
            assert 1 <= value <= 12000
    assert ls_speed(0.15) == (150, "mm/sec") and ls_speed(0.4 / 60.0) == (40, "cm/min")


IO_YAML = ("spindle_do: 1\nspindle_ao: 2\nspindle_rpm_full_scale: 24000\ncoolant_do: 3\n"
           "spindle_ccw_do: 4\n")
FULL = {"rapid": 10.0, "krl": 1.0, "ls": 4095.0}  # the PostIO defaults
_IO_RE = {  # (regex, kind, port group, value group) on the written text
    "rapid": [(r"^\s*SetDO (\w+), ([01]);", "do"), (r"^\s*SetAO (\w+), ([\d.]+);", "ao")],
    "krl": [(r"^\s*\$OUT\[(\d+)\] = (TRUE|FALSE)", "do"), (r"^\s*\$ANOUT\[(\d+)\] = ([\d.]+)",
                                                           "ao")],
    "ls": [(r"^\s*\d+:\s+DO\[(\d+)\]=(ON|OFF) ;", "do"), (r"^\s*\d+:\s+AO\[(\d+)\]=(\d+) ;",
                                                           "ao")],
}
_MOVE_RE = {"rapid": r"^\s*Move[LJ] ", "krl": r"^\s*(LIN|PTP) ", "ls": r"^\s*\d+:\s+[LJ] P\["}
_PORT = {"doSpindle": 1, "aoSpindle": 2, "doCoolant": 3, "doSpindleCcw": 4}


def _io_sequence(text, fmt):
    """[(moves written before, kind, port, value)] read with regexes from the program text."""
    out, n_moves = [], 0
    for line in text.splitlines():
        if re.match(_MOVE_RE[fmt], line):
            n_moves += 1
            continue
        for pattern, kind in _IO_RE[fmt]:
            m = re.match(pattern, line)
            if m:
                port = _PORT[m[1]] if fmt == "rapid" else int(m[1])
                v = m[2]
                value = {"TRUE": 1.0, "ON": 1.0, "FALSE": 0.0, "OFF": 0.0}.get(v)
                out.append((n_moves, kind, port, float(v) if value is None else value))
    return out, n_moves


@pytest.mark.parametrize("fmt, suffix, robot, wobj", [
    ("rapid", ".mod", "irb1600", WOBJ), ("krl", ".src", "kr6_r700", [450.0, 0, 100, 0, 0, 30]),
    ("ls", ".ls", "m10ia", WOBJ)])
def test_spindle_of_the_creo_file_on_the_configured_outputs(extdata, tmp_path, fmt, suffix,
                                                            robot, wobj):
    """Creo's ``SPINDL / RPM, 15915.507752, CLW`` (before the first GOTO) and ``SPINDL / OFF``
    (after the last) become: speed AO then spindle DO on before the first move, DO off then
    AO 0 after the last one, in RAPID SetAO/SetDO, KRL $ANOUT/$OUT and LS AO[]/DO[]. The AO
    read back from the text gives the file's rpm within one step of the output."""
    src = extdata / "cl_files" / CREO
    rpm = [float(v) for v in re.findall(r"SPINDL / RPM, ([\d.]+)", src.read_text())]
    assert rpm == [15915.507752] and "SPINDL / OFF" in src.read_text()
    io = tmp_path / "io.yaml"
    io.write_text(IO_YAML)
    out = tmp_path / f"creo{suffix}"
    assert main(["post", str(src), "--robot", robot, "-o", str(out), "--wobj",
                 ",".join(map(str, wobj)), "--spin", "greedy", "--io", str(io)]) == 0
    seq, n = _io_sequence(out.read_text(), fmt)
    ccw = (0, "do", 4, 0.0)  # CLW: the direction output off
    assert seq[:3] == [ccw, (0, "ao", 2, pytest.approx(seq[1][3])), (0, "do", 1, 1.0)]
    step = FULL[fmt] * (1e-4 if fmt == "rapid" else 1e-6 if fmt == "krl" else 1.0)
    assert abs(seq[1][3] / FULL[fmt] * 24000 - rpm[0]) <= 24000 * step / FULL[fmt] / 2 + 1e-9
    assert seq[3:] == [(n, "do", 1, 0.0), (n, "ao", 2, 0.0)]
    # the project's reader reads the same outputs back
    from drakedeburr.programs.reading import read_program

    back = read_program(out)
    assert [(k, p if fmt != "rapid" else _PORT[p], v) for _, k, p, v in back.io] == \
        [(k, p, v) for _, k, p, v in seq]
    if fmt == "rapid":  # a third-party RAPID grammar accepts SetDO / SetAO as written
        from rapidchecker.check import check_format

        assert list(check_format(out.read_text())) == []


def test_coolant_and_counter_clockwise_spindle(tmp_path):
    """COOLNT/FLOOD .. COOLNT/OFF and SPINDL/.., CCLW in an APT file (the real CAM files here
    have no COOLNT): the coolant DO is on for exactly the moves between the two statements,
    the direction DO is on for CCLW; without --io nothing is written and the words are
    listed as not applied."""
    cl = tmp_path / "cool.apt"
    cl.write_text("UNITS/MM\nSPINDL/RPM,12000,CCLW\nRAPID\nGOTO/0,0,20\nCOOLNT/FLOOD\n"
                  "FEDRAT/600,MMPM\nGOTO/0,0,0\nGOTO/30,0,0\nGOTO/30,30,0\nCOOLNT/OFF\n"
                  "RAPID\nGOTO/30,30,20\nSPINDL/OFF\nFINI\n")
    io = tmp_path / "io.yaml"
    io.write_text(IO_YAML)
    out = tmp_path / "cool.ls"
    base = ["post", str(cl), "--robot", "m10ia", "-o", str(out), "--wobj",
            ",".join(map(str, WOBJ)), "--spin", "greedy"]
    assert main([*base, "--io", str(io)]) == 0
    text = out.read_text()
    seq, n = _io_sequence(text, "ls")
    assert n == 5
    assert (0, "do", 4, 1.0) in seq and (0, "do", 1, 1.0) in seq  # CCLW, on
    assert (0, "ao", 2, float(round(12000 / 24000 * 4095))) in seq
    assert (1, "do", 3, 1.0) in seq and (4, "do", 3, 0.0) in seq  # coolant moves 2..4
    assert (5, "do", 1, 0.0) in seq
    # the move before an output switches is a stop point (FINE), so the output switches there
    mn = [ln for ln in text.splitlines() if re.match(_MOVE_RE["ls"], ln)]
    assert mn[3].endswith("FINE ;") and mn[0].endswith("FINE ;")
    assert main(base) == 0
    assert _io_sequence(out.read_text(), "ls")[0] == []
    assert "COOLNT" in out.read_text() and "not applied" in out.read_text()


@pytest.mark.parametrize("yaml_text, expected", [
    ("spindle_do: 0\n", "spindle_do must be an output number >= 1"),
    ("spindel_do: 1\n", "unknown PostIO field 'spindel_do'"),
    ("spindle_do: 1\ncoolant_do: 1\n", "must differ"),
    ("spindle_ao: 1\nao_full_scale_krl: 10\n", "ao_full_scale_krl must be in (0, 1]"),
])
def test_bad_io_settings_exit_2_naming_the_file(extdata, tmp_path, capsys, yaml_text,
                                                expected):
    io = tmp_path / "io.yaml"
    io.write_text(yaml_text)
    rc = main(["post", str(extdata / "cl_files" / CREO), "-o", str(tmp_path / "c.mod"),
               "--wobj", ",".join(map(str, WOBJ)), "--io", str(io)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "io.yaml" in err and expected in err and len(err.splitlines()) == 1


def test_spindle_above_the_ao_full_scale_is_refused_with_its_line(extdata, tmp_path, capsys):
    io = tmp_path / "io.yaml"
    io.write_text("spindle_ao: 1\nspindle_rpm_full_scale: 12000\n")
    rc = main(["post", str(extdata / "cl_files" / CREO), "-o", str(tmp_path / "c.mod"),
               "--wobj", ",".join(map(str, WOBJ)), "--io", str(io)])
    err = capsys.readouterr().err
    assert rc == 2 and ":13: SPINDL 15915.5 rpm is above" in err


def test_spindle_on_without_a_speed(tmp_path, capsys):
    """``SPINDL/ON`` before any speed switches the spindle DO on; with a speed AO configured
    it is refused (the AO value is unknown) naming the CL line."""
    cl = tmp_path / "on.apt"
    cl.write_text("UNITS/MM\nSPINDL/ON\nFEDRAT/600,MMPM\nGOTO/0,0,0\nGOTO/10,0,0\nFINI\n")
    io = tmp_path / "io.yaml"
    io.write_text("spindle_do: 5\n")
    out = tmp_path / "on.ls"
    base = ["post", str(cl), "--robot", "m10ia", "-o", str(out), "--wobj",
            ",".join(map(str, WOBJ)), "--spin", "greedy", "--io", str(io)]
    assert main(base) == 0
    assert _io_sequence(out.read_text(), "ls")[0] == [(0, "do", 5, 1.0)]
    io.write_text("spindle_do: 5\nspindle_ao: 1\n")
    assert main(base) == 2
    assert "on.apt:2: SPINDL/ON without a speed" in capsys.readouterr().err
