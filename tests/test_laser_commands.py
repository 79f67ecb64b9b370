"""CLI: drakedeburr laser shape / tool."""

import json

import numpy as np

from drakedeburr.cli import main


def test_shape_circle_tool_mode(tmp_path, capsys):
    out = tmp_path / "c10.ls"
    rc = main(["laser", "shape", "circle", "--diameter", "10", "--lead-in", "2",
               "--summary", str(tmp_path / "s.json"), "-o", str(out)])
    assert rc == 0
    text = out.read_text()
    assert text.startswith("/PROG C10\n") and "GP2:" in text
    s = json.loads((tmp_path / "s.json").read_text())
    assert s["mode"] == "tool" and s["shape"] == "circle"
    assert np.isclose(s["area_mm2"], np.pi * 25)
    assert json.loads(capsys.readouterr().out) == s


def test_shape_large_rectangle_goes_to_robot(tmp_path):
    out = tmp_path / "r.ls"
    rc = main(["laser", "shape", "rectangle", "--width", "200", "--height", "100",
               "--corner-radius", "10", "--travel-angle", "5", "-o", str(out)])
    assert rc == 0
    assert "GP1:" in out.read_text() and "L P[2]" in out.read_text()


def test_unreachable_in_tool_mode_is_exit_2(tmp_path, capsys):
    rc = main(["laser", "shape", "slot", "--length", "60", "--width", "10", "--mode", "tool",
               "-o", str(tmp_path / "s.ls")])
    assert rc == 2
    assert "slot: point 0" in capsys.readouterr().err
    assert not (tmp_path / "s.ls").exists()


def test_polyline_points_and_tool_summary(tmp_path, capsys):
    rc = main(["laser", "shape", "polyline", "--points", "0,0 10,0 5,8", "-o",
               str(tmp_path / "p.ls")])
    assert rc == 0
    assert np.isclose(json.loads(capsys.readouterr().out)["area_mm2"], 40.0)
    assert main(["laser", "shape", "polyline", "--points", "0,0 x", "-o",
                 str(tmp_path / "q.ls")]) == 2
    capsys.readouterr()
    assert main(["laser", "tool", "--sdf", str(tmp_path / "t.sdf")]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["reachable"] and info["max_condition"] < 2
    assert "<drake:ball_constraint>" in (tmp_path / "t.sdf").read_text()
