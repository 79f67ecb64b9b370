"""The main job (``drakedeburr demo``) in test mode: every output written, program only if
the plan passed its independent verification."""

import json

import drakedeburr.demo as mut
from drakedeburr.cli import main


def test_demo_writes_outputs_and_gates_the_program_on_verification(tmp_path):
    summary = mut.run_demo(tmp_path, test_mode=True)
    out = summary["outputs"]
    for name in ("cl_table", "plan", "joints_csv", "report_json", "report_html", "summary"):
        assert name in out, name
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["passed"] is summary["passed"]
    assert summary["windows_planned"] == [0]
    table = json.loads((tmp_path / "cl_table.json").read_text())
    assert len(table["windows"]) == 5  # the default hub has five windows
    html = (tmp_path / "report.html").read_text()
    assert "<iframe" in html and "srcdoc" in html  # the Meshcat replay is embedded
    program = tmp_path / f"deburr_{summary['hub']}.mod"
    # never a robot program from a plan that failed verification (no --force here)
    assert program.exists() is report["passed"]
    if program.exists():
        text = program.read_text()
        assert "MODULE" in text and "FORCED" not in text


def test_demo_cli_rejects_unknown_hub(tmp_path, capsys):
    rc = main(["demo", "--hub", "no_such_hub", "--out", str(tmp_path), "--test-mode"])
    assert rc == 2
    assert "no_such_hub" in capsys.readouterr().err
