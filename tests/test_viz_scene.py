"""Meshcat scene publishing and the self-contained static HTML."""

import base64
import re
from pathlib import Path

import numpy as np
import pytest

import drakedeburr.viz.scene as mut
from drakedeburr.cell import load_cell

STAND_IN_HUB = Path(__file__).resolve().parent / "data" / "stand_in_hub" / "hub.sdf"


@pytest.fixture(scope="module")
def meshcat():
    return mut.get_meshcat()


def _decoded_commands(html: str) -> bytes:
    """All embedded Meshcat commands (base64 msgpack data URIs) of a static HTML page."""
    chunks = re.findall(r"data:application/octet-(?:stream|binary);base64,([A-Za-z0-9+/=]+)", html)
    return b"".join(base64.b64decode(c) for c in chunks)


def test_static_html_is_self_contained_and_holds_the_scene(meshcat, tmp_path):
    cell = load_cell("tool_in_hand", hub=STAND_IN_HUB)
    mut.publish_cell(meshcat, cell)
    square = np.array([[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [-0.1, 0.0, 0.0], [0.0, -0.1, 0.0]])
    mut.publish_edge_loops(meshcat, [square, 0.5 * square], cell.X_WH(cell.q_home))
    mut.publish_points(meshcat, f"{mut.ROOT}/points", square)
    mut.publish_arrows(meshcat, f"{mut.ROOT}/normals", square, np.tile([0, 0, 1.0], (4, 1)))
    mut.publish_frame(meshcat, f"{mut.ROOT}/frames/T", cell.X_WT(cell.q_home))
    out = mut.write_static_html(meshcat, tmp_path / "cell.html")
    html = out.read_text()
    # nothing has to be fetched from the network to load the page
    assert not re.search(r"<script[^>]*\ssrc=", html)
    assert not re.search(r"<link[^>]*\shref=[\"']https?:", html)
    assert "meshcat" in html.lower()
    commands = _decoded_commands(html)
    for name in (b"/drakedeburr/cell/robot/link_3", b"/drakedeburr/cell/spindle/burr",
                 b"/drakedeburr/cell/hub/hub", b"/drakedeburr/edges/window_01",
                 b"/drakedeburr/points", b"/drakedeburr/normals", b"/drakedeburr/frames/T"):
        assert name in commands, name


def test_moving_the_robot_changes_body_transforms(meshcat, tmp_path):
    cell = load_cell("tool_in_hand", hub=STAND_IN_HUB)
    mut.publish_cell(meshcat, cell, path=f"{mut.ROOT}/moved")
    before = _decoded_commands(meshcat.StaticHtml())
    q = np.array(cell.q_home)
    q[0] += 0.5
    mut.set_cell_configuration(meshcat, cell, q, path=f"{mut.ROOT}/moved")
    after = _decoded_commands(meshcat.StaticHtml())
    assert before != after
    mut.animate_cell(meshcat, cell, np.array([0.0, 1.0]), np.vstack([cell.q_home, q]),
                     path=f"{mut.ROOT}/moved")
    assert b"set_animation" in _decoded_commands(meshcat.StaticHtml())
    meshcat.Delete(f"{mut.ROOT}/moved")


def test_bad_arrays_are_named(meshcat):
    with pytest.raises(ValueError, match=r"p_W must have shape \(N, 3\)"):
        mut.publish_polyline(meshcat, "/x", np.zeros((4, 2)))
    with pytest.raises(ValueError, match="differ in length"):
        mut.publish_arrows(meshcat, "/x", np.zeros((4, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="role must be one of"):
        cell = load_cell("workpiece_in_hand", hub=STAND_IN_HUB)
        mut.publish_cell(meshcat, cell, role="perception")


def test_show_command_writes_html(tmp_path):
    from drakedeburr.cli import main

    out = tmp_path / "show.html"
    assert main(["show", "workpiece_in_hand", "--hub", str(STAND_IN_HUB), "--html", str(out),
                 "--q", "0", "10", "20", "0", "60", "0"]) == 0
    commands = _decoded_commands(out.read_text())
    assert b"/drakedeburr/cell/gripper/gripper" in commands
    assert main(["show", "tool_in_hand", "--hub", str(STAND_IN_HUB), "--html", str(out),
                 "--q", "0", "10"]) == 2
    assert main(["show", str(STAND_IN_HUB), "--html", str(out)]) == 0
    assert b"/drakedeburr/hub/hub/hub" in _decoded_commands(out.read_text())


def test_show_bundled_hub_with_its_window_edges(tmp_path):
    from drakedeburr.cli import main
    from drakedeburr.hub import load_hub

    n = len(load_hub("h5_split").windows)
    out = tmp_path / "hub.html"
    assert main(["show", "h5_split", "--html", str(out)]) == 0
    commands = _decoded_commands(out.read_text())
    assert b"/drakedeburr/hub/hub/hub" in commands
    for i in range(n):
        assert f"/drakedeburr/edges/window_{i:02d}".encode() in commands
    assert f"/drakedeburr/edges/window_{n:02d}".encode() not in commands
    out2 = tmp_path / "cell.html"
    assert main(["show", "tool_in_hand", "--hub", "h5_split", "--html", str(out2)]) == 0
    commands = _decoded_commands(out2.read_text())
    assert b"/drakedeburr/cell/hub/hub" in commands and b"/drakedeburr/edges/window_09" in commands
