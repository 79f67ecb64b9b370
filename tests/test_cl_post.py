"""CL file -> program pipeline and the ``drakedeburr post`` command."""

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
    res = mut.program_from_cl(cl, "creo", X_WO=X_WO)
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
    res = mut.program_from_cl(cl, "p", X_WO=X_WO)
    assert res.program is None and res.unreachable_lines == (4,)
    forced = mut.program_from_cl(cl, "p", X_WO=X_WO, force=True)
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
    # KRL is not a program for the ABB arm: a clear input error, nothing written
    assert main(["post", cl, "--format", "krl", "-o", str(tmp_path / "c.src"),
                 "--wobj", wobj]) == 2
    assert not (tmp_path / "c.src").exists() and not (tmp_path / "c.dat").exists()
    # in the robot base (no work object) the part sits inside the robot: nothing written
    bad = tmp_path / "bad.mod"
    assert main(["post", cl, "--format", "rapid", "-o", str(bad), *fast]) == 1
    assert not bad.exists()
    # a bad work object is an input error (exit 2)
    assert main(["post", cl, "--format", "rapid", "-o", str(bad), "--wobj", "1,2,3"]) == 2
    assert main(["post", str(tmp_path / "missing.cl"), "--format", "rapid", "-o",
                 str(bad)]) == 2


def test_cli_force(tmp_path):
    cl = tmp_path / "far.apt"
    cl.write_text("UNITS/MM\nFEDRAT/9000,MMPM\nGOTO/0,0,0\nGOTO/2500,0,0\nGOTO/10,0,0\nFINI\n")
    out = tmp_path / "far.mod"
    args = ["post", str(cl), "--format", "rapid", "-o", str(out), "--wobj", "700,0,300,0,0,0"]
    assert main(args) == 1 and not out.exists()
    assert main(args + ["--force"]) == 1
    text = out.read_text()
    assert "FORCED" in text and "MoveL p2, v150, fine," in text
