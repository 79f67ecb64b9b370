"""The main job (``drakedeburr demo``) in test mode: every output written, program only if
the plan passed its independent verification."""

import json

import drakedeburr.demo as mut
from drakedeburr.cli import main


def test_demo_writes_outputs_and_gates_the_program_on_verification(tmp_path):
    summary = mut.run_demo(tmp_path, test_mode=True)
    out = summary["outputs"]
    for name in ("cl_table", "plan", "report_json", "report_html", "summary"):
        assert name in out, name
    folder = tmp_path / "plan"  # one layout: the plan folder holds its report
    for name in ("plan.json", "arrays.npz", "joints.csv", "run.json", "report.json",
                 "report.html"):
        assert (folder / name).is_file(), name
    report = json.loads((folder / "report.json").read_text())
    assert report["passed"] is summary["passed"]
    assert summary["windows_planned"] == [0]
    table = json.loads((tmp_path / "cl_table.json").read_text())
    assert len(table["windows"]) == 5  # the default hub has five windows
    html = (folder / "report.html").read_text()
    assert "<iframe" in html and "srcdoc" in html  # the Meshcat replay is embedded
    program = tmp_path / f"deburr_{summary['hub']}.mod"
    # never a robot program from a plan that failed verification (no --force here)
    assert program.exists() is report["passed"]
    assert report["passed"], report["summary"]["failed"]
    text = program.read_text()
    assert "MODULE" in text and "FORCED" not in text and "UNVERIFIED" not in text
    # its cutting moves carry the plan's own speeds, several of them (not a flat v150)
    from drakedeburr.plan.io import load_plan
    from drakedeburr.programs import read_program

    plan = load_plan(folder)
    from drakedeburr.post.program_check import _target_moves, plan_program

    moves = read_program(program).moves
    # one move per target, home included, plus via points where a joint move bends
    move_of = _target_moves(plan, plan_program(plan, "x"))
    assert len(move_of) == len(plan.targets) and len(moves) >= len(plan.targets)
    cut = [(moves[move_of[k]], t) for k, t in enumerate(plan.targets) if t.segment == "cut"]
    assert all(abs(m.speed - t.speed) <= 1e-6 for m, t in cut)
    assert len({round(t.speed, 4) for _, t in cut}) > 10
    assert min(t.speed for _, t in cut) < 0.5 * summary_speed(plan)


def summary_speed(plan) -> float:
    return plan.meta["config"]["process"]["grinding_speed"]


def test_demo_cli_rejects_unknown_hub(tmp_path, capsys):
    rc = main(["demo", "--hub", "no_such_hub", "--out", str(tmp_path), "--test-mode"])
    assert rc == 2
    assert "no_such_hub" in capsys.readouterr().err
