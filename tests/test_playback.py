"""Meshcat replay of a plan: the static HTML is self-contained and animates the cell."""

import base64
import re

import verify_support as vs

import drakedeburr.viz.playback as mut


def test_static_html_replay_of_a_plan(tmp_path):
    plan = vs.good_plan()
    path = mut.save_plan_html(plan, tmp_path / "replay.html", dt=0.5)
    html = path.read_text()
    assert html.lstrip().lower().startswith("<!doctype html") or "<html" in html[:500].lower()
    # no external scripts or stylesheets: the file must open offline
    assert not re.search(r"<script[^>]+src=\"https?://", html)
    assert not re.search(r"<link[^>]+href=\"https?://", html)
    # the scene commands are embedded as base64 msgpack: they carry the animation of the
    # recording and the planned tool path
    blobs = re.findall(r'"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html)
    decoded = b"".join(base64.b64decode(b) for b in blobs)
    assert b"/plan/tool_path" in decoded or b"tool_path" in decoded
    assert b"animation" in decoded.lower()
