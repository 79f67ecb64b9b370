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


def test_a_readable_rim_with_nothing_to_cut_is_a_report_and_exit_1(tmp_path, capsys):
    """A disc whose six slots are 8 mm wide: no burr of the tool library fits (the 6 mm burr
    needs 10 mm, the 12 mm one 16 mm). A readable mesh with nothing to cut is a result: exit 1
    with a report naming every opening, its width and each burr's need, not bad input (issue
    16, 42); the report-only folder is ours to replace on the next run."""
    from hub_meshes import narrow_slot_disc_stl

    rim = narrow_slot_disc_stl(tmp_path / "slots.stl")
    out, js = tmp_path / "out", tmp_path / "r.json"
    args = ["-q", "verify", str(rim), "-o", str(out), "--hub-cache", str(tmp_path / "hubs"),
            "--front", "+z"]
    assert main([*args, "--json", str(js)]) == 1
    doc = json.loads((out / "report.json").read_text())
    assert doc == json.loads(js.read_text())
    assert doc["passed"] is False and doc["summary"]["failed"] == ["windows"]
    (item,) = doc["items"]
    assert item["name"] == "windows" and item["value"] == 0 and item["required"]
    assert item["detail"].count("vent slot 8.") == 6
    assert item["detail"].count("the 6 mm burr needs 10.0 mm") == 6
    openings = doc["plan"]["openings"]
    assert len(openings) == 7 and sum(7.5 < o["width_mm"] < 8.5 for o in openings) == 6
    assert doc["plan"]["rejected_outlines"] == []
    assert (out / "report.html").read_text().startswith("<!DOCTYPE html>")
    assert "no window can be cut" in capsys.readouterr().out
    assert main(args) == 1  # the same folder again: replaced, not refused
    assert not (out / "plan.json").exists()


def test_a_wheel_with_its_tyre_and_a_cad_solid(tmp_path, extdata, capsys):
    """``verify wheel.dae`` (COLLADA, tyre + rim): a report (exit 0 or 1) on the rim, which
    says the tyre was dropped; ``verify hub.step`` of a broken STEP file: exit 2 in one line
    naming the file and what is wrong (not read as a plan folder)."""
    dae = extdata / "wheel_models" / "audibot__wheel.dae"
    out = tmp_path / "out"
    assert main(["-q", "verify", str(dae), "-o", str(out), "--hub-cache",
                 str(tmp_path / "hubs"), "--windows", "0"]) in (0, 1)  # one window: a test
    doc = json.loads((out / "report.json").read_text())
    (note,) = doc["plan"]["import_notes"]
    assert note.startswith("tyre dropped")
    step = tmp_path / "hub.step"
    step.write_text("ISO-10303-21;")
    capsys.readouterr()
    assert main(["-q", "verify", str(step), "-o", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    # read as STEP (drakedeburr.hub.cad): the parser's complaint, in one line
    assert len(err) == 1 and "hub.step: not a readable STEP file" in err[0], err
