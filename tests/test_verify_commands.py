"""drakedeburr verify: exit codes 0 pass / 1 fail / 2 bad input, JSON written."""

from __future__ import annotations

import json

from drakedeburr.cli import main

COMMON = ["--planner", "reference", "--windows", "0", "--quick", "--no-replay"]


def test_verify_reference_plan_passes_and_writes_reports(tmp_path):
    out = tmp_path / "out"
    code = main(["-q", "verify", "tool_in_hand/h5_straight", *COMMON, "--grinding-speed", "75",
                 "-o", str(out)])
    doc = json.loads((out / "report.json").read_text())
    assert code == 0
    assert doc["passed"] is True and doc["schema"] == "drakedeburr.verify/1"
    assert doc["plan"]["windows"] == [0]
    assert (out / "report.html").read_text().startswith("<!DOCTYPE html>")


def test_verify_failing_plan_exits_1(tmp_path):
    # at 150 mm/s the reference plan's fillets need J3 accelerations above the model's limit
    f = tmp_path / "r.json"
    code = main(["-q", "verify", "tool_in_hand/h5_straight", *COMMON, "--json", str(f)])
    doc = json.loads(f.read_text())
    assert code == 1
    assert doc["passed"] is False and "joint_acceleration" in doc["summary"]["failed"]


def test_verify_bad_input_exits_2(tmp_path):
    assert main(["-q", "verify", "no_such_cell/no_such_hub"]) == 2
    assert main(["-q", "verify", str(tmp_path / "missing.stl")]) == 2
    mesh = tmp_path / "hub.stl"
    mesh.write_text("solid x\nendsolid x\n")
    assert main(["-q", "verify", str(mesh)]) == 2  # a mesh without triangles
    assert main(["-q", "verify", "tool_in_hand/h5_straight", "--windows", "zero"]) == 2


def test_verify_all_bad_input_exits_2(tmp_path):
    assert main(["-q", "verify-all", str(tmp_path / "no_catalogue")]) == 2
    assert main(["-q", "verify-all", str(tmp_path)]) == 2  # a folder without hubs
