"""Export checks what it wrote (issue 41): the program is read back from a staging folder and
re-simulated as the controller runs it (joints from the written pose + configuration); a
program the controller would run differently is refused (exit 1, nothing written); the
program items name every value the cell must hold."""

from __future__ import annotations

import pytest
import verify_support as vs

from drakedeburr.cli import main
from drakedeburr.plan.io import load_plan, save_plan
from drakedeburr.verify.html import write_report_files


@pytest.fixture(scope="module")
def verified(tmp_path_factory):
    folder = tmp_path_factory.mktemp("export") / "plan"
    plan = vs.good_plan()
    save_plan(plan, folder)
    report = vs.verify(plan, coarse=False)
    assert report.passed, report.failed
    write_report_files(report, folder, plan=plan, replay=False)
    return folder


def test_the_exported_program_passes_its_controller_check(verified, tmp_path):
    from drakedeburr.post.program_check import program_items
    from drakedeburr.programs import read_program

    out = tmp_path / "deburr.mod"
    assert main(["-q", "export", str(verified), "--format", "rapid", "-o", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deburr.mod"]  # no staging left
    items = {i.name: i for i in program_items(load_plan(verified), read_program(out))}
    for name in ("program_file", "controller_joints", "controller_motion", "controller_path",
                 "controller_zones"):
        assert items[name].passed, (name, items[name].detail)
    assert items["controller_joints"].value < 1e-6  # rad, from the file's 6 decimals
    setup = items["controller_setup"].detail
    assert "the cell must hold: tool (TCP) in the flange frame" in setup and " kg at " in setup


def test_a_program_the_controller_would_run_on_another_wrist_is_refused(verified, tmp_path,
                                                                       monkeypatch):
    """The FANUC bug of issue 41 in RAPID form: the wrist bit of cfx written wrong. No
    solution of the written pose has that confdata (the other wrist also turns axes 4/6 into
    other quadrants): the controller stops; export refuses, nothing written."""
    from drakedeburr.programs import program as program_mod

    real = program_mod.RobotProgram.configuration

    def wrong_wrist(self, i):
        cf1, cf4, cf6, cfx = real(self, i)
        return (cf1, cf4, cf6, cfx ^ 1)

    monkeypatch.setattr(program_mod.RobotProgram, "configuration", wrong_wrist)
    out = tmp_path / "deburr.mod"
    assert main(["-q", "export", str(verified), "--format", "rapid", "-o", str(out)]) == 1
    assert list(tmp_path.iterdir()) == []  # nothing written, no staging folder left
