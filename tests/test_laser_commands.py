"""CLI: drakedeburr laser shape / tool."""

import json
import re

import numpy as np
import pytest

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


def _servo_deg(text):

    return np.array(re.findall(r"J1 =\t(-?[\d.]+)\tdeg,\tJ2 =\t(-?[\d.]+)\tdeg", text), float)


def _head(l0, l1, l2, l3, l4, q):
    """Head J5 [mm] from servo angles: intersection of the two link circles (source 004
    Fig. 3 conventions), the branch on the +x side; written here, not the package's FK."""
    j3 = np.stack([l1 * np.sin(q[:, 0]), -l1 * np.cos(q[:, 0])], 1)
    j4 = np.stack([l2 * np.sin(q[:, 1]), l0 - l2 * np.cos(q[:, 1])], 1)
    d = np.linalg.norm(j4 - j3, axis=1)
    a = (l3 ** 2 - l4 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(l3 ** 2 - a ** 2)
    u = (j4 - j3) / d[:, None]
    n = np.stack([u[:, 1], -u[:, 0]], 1)  # u turned -90 deg: +x side for u ~ +y
    return j3 + a[:, None] * u + h[:, None] * n


@pytest.mark.parametrize("how", ["links", "file"])
def test_link_lengths_from_the_cli_or_a_yaml_file(tmp_path, capsys, how):
    """A tool with other link lengths (L0 36, cranks 45, links 80 mm) cuts the same 10 mm
    circle: the servo angles written are those of that tool (its head, by circle
    intersection with those lengths, runs on the circle), not of the default one."""
    links = (36.0, 45.0, 45.0, 80.0, 80.0)
    if how == "links":
        opt = ["--links", ",".join(map(str, links))]
    else:
        f = tmp_path / "tool.yaml"
        f.write_text("".join(f"l{k}_mm: {v}\n" for k, v in enumerate(links)))
        opt = ["--tool-file", str(f)]
    out = tmp_path / "c.ls"
    assert main(["laser", "shape", "circle", "--diameter", "10", "--lead-in", "2",
                 "--mode", "tool", "-o", str(out), *opt]) == 0
    capsys.readouterr()
    q = np.deg2rad(_servo_deg(out.read_text()))
    p = _head(*links, q)
    home = np.array([65.0, links[0] / 2])  # default home_x 65 mm, centred between servos
    r = np.linalg.norm(p - home, axis=1)
    assert np.abs(r[-30:] - 5.0).max() < 0.05  # the last points: on the 10 mm circle
    default = tmp_path / "d.ls"
    assert main(["laser", "shape", "circle", "--diameter", "10", "--lead-in", "2",
                 "--mode", "tool", "-o", str(default)]) == 0
    capsys.readouterr()
    assert np.abs(np.deg2rad(_servo_deg(default.read_text()))[-1] - q[-1]).max() > 0.01
    assert main(["laser", "tool", *opt]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert [shown[f"l{k}_mm"] for k in range(5)] == pytest.approx(links)


def test_bad_tool_file_is_exit_2_naming_the_key(tmp_path, capsys):
    f = tmp_path / "tool.yaml"
    f.write_text("l0_mm: 30\nl9_mm: 4\n")
    assert main(["laser", "tool", "--tool-file", str(f)]) == 2
    err = capsys.readouterr().err
    assert "tool.yaml" in err and "'l9_mm'" in err and len(err.strip().splitlines()) == 1
    f.write_text("l1_mm: -4\n")
    assert main(["laser", "tool", "--tool-file", str(f)]) == 2
    assert "l1 must be > 0" in capsys.readouterr().err
    assert main(["laser", "tool", "--links", "30,40,40"]) == 2


def test_robot_mode_writes_the_plate_as_uframe_and_the_arms_config(tmp_path, capsys):

    out = tmp_path / "r.ls"
    assert main(["laser", "shape", "rectangle", "--width", "200", "--height", "100",
                 "--corner-radius", "10", "--plate", "750,-50,150,0,0,45", "--robot",
                 "lrmate200ic", "-o", str(out)]) == 2  # the LR Mate cannot reach 750 mm out
    assert "out of reach of FANUC LR Mate 200iC" in capsys.readouterr().err
    assert main(["laser", "shape", "rectangle", "--width", "200", "--height", "100",
                 "--corner-radius", "10", "--plate", "750,-50,150,0,0,45", "-o",
                 str(out)]) == 0
    text = out.read_text()
    from test_laser_feature import _ls_frame  # the LS frame parser written there

    assert _ls_frame(text, "UFRAME") == pytest.approx([750, -50, 150, 0, 0, 45])
    assert "!UFRAME" not in text  # set by statements, not left to remarks
    configs = set(re.findall(r"CONFIG : '([^']*)'", text))
    assert len(configs) >= 2  # J6's turn changes as the tool goes once around
    assert main(["laser", "shape", "rectangle", "--width", "200", "--height", "100",
                 "--robot", "irb1600", "-o", str(out)]) == 2
    assert "abb controller" in capsys.readouterr().err
