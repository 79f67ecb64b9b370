"""The export gate and the plan folder as one transaction (issue 17): a program only from a
plan whose report passed for this very plan and cell; programs carry the verified speeds and
are checked line by line against the plan; a killed run leaves the previous plan whole; the
same inputs give the same plan content whatever the thread settings."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import verify_support as vs

from drakedeburr.cli import main
from drakedeburr.plan.io import load_plan, plan_digest, save_plan
from drakedeburr.verify.gate import gate
from drakedeburr.verify.html import write_report_files


@pytest.fixture(scope="module")
def verified(tmp_path_factory):
    """The verify tests' good plan saved as a plan folder with its passing report."""
    folder = tmp_path_factory.mktemp("gate") / "plan"
    plan = vs.good_plan()
    save_plan(plan, folder)
    report = vs.verify(plan, coarse=False)
    assert report.passed, report.failed
    write_report_files(report, folder, plan=plan, replay=False)
    return folder


def _export(folder, out, *extra):
    return main(["-q", "export", str(folder), "--format", "rapid", "-o", str(out), *extra])


def test_gate_passes_the_verified_plan_and_its_program_carries_the_plan(verified, tmp_path):
    assert gate(verified, load_plan(verified)).ok
    out = tmp_path / "p.mod"
    assert _export(verified, out) == 0
    text = out.read_text()
    assert "FORCED" not in text and "UNVERIFIED" not in text
    # the program read back is the plan's, move by move (speeds, zones, poses, configuration)
    copy = tmp_path / "copy"
    shutil.copytree(verified, copy)
    page = tmp_path / "page.html"  # --html: the page written into the plan folder, copied
    main(["-q", "verify", str(copy), "--quick", "--no-replay", "--program", str(out),
          "--html", str(page)])
    assert page.read_bytes() == (copy / "report.html").read_bytes()
    report = json.loads((copy / "report.json").read_text())
    item = next(i for i in report["items"] if i["name"] == "program_file")
    assert item["passed"] and item["required"], item["detail"]
    # a --quick report is a smoke test: the gate does not take it
    assert not gate(copy, load_plan(copy)).ok
    assert _export(copy, tmp_path / "q.mod") == 1


def _edit(text: str, item: str) -> tuple[str, int]:
    """Change one cutting move's speed, zone or target position; returns (text, its line)."""
    import re

    lines = text.splitlines()
    # the second linear move (the program numbers via points of bent joint moves too)
    k = [i for i, s in enumerate(lines) if s.strip().startswith("MoveL p")][1]
    name = lines[k].split()[1].rstrip(",")
    if item == "pose":
        k = next(i for i, s in enumerate(lines) if re.search(rf"robtarget {name}\b", s))
        lines[k] = re.sub(r"\[\[(-?[\d.]+)", lambda m: f"[[{float(m[1]) + 1.0:.3f}",
                          lines[k], count=1)
    elif item == "speed":
        lines[k] = re.sub(r", v\w+,", ", v1500,", lines[k], count=1)
    else:
        lines[k] = re.sub(r", (fine|z\w+),", ", z50,", lines[k], count=1)
    return "\n".join(lines) + "\n", k + 1


@pytest.mark.parametrize("item", ["speed", "zone", "pose"])
def test_an_edited_program_fails_naming_the_line(verified, tmp_path, item):
    out = tmp_path / "p.mod"
    assert _export(verified, out) == 0
    edited, line = _edit(out.read_text(), item)
    assert edited != out.read_text()
    bad = tmp_path / "bad.mod"
    bad.write_text(edited)
    from drakedeburr.verify.commands import _program_item

    found = _program_item(load_plan(verified), str(bad))
    assert not found.passed and found.required
    assert f"bad.mod:{line}: {item}" in found.detail, found.detail


def test_a_report_for_another_plan_or_an_old_one_is_refused(verified, tmp_path):
    other = tmp_path / "other"
    plan = load_plan(verified)
    from dataclasses import replace

    moved = replace(plan, targets=plan.targets[:-1] + (replace(plan.targets[-1], speed=0.5),))
    save_plan(moved, other)
    shutil.copy(verified / "report.json", other / "report.json")  # a report copied over
    out = tmp_path / "p.mod"
    assert _export(other, out) == 1 and not out.exists()
    assert "another plan" in gate(other, moved).reason
    assert _export(other, out, "--force") == 0
    assert "UNVERIFIED" in out.read_text()
    # re-planning into the folder replaces it whole: the old report goes with the old plan
    copy = tmp_path / "copy"
    shutil.copytree(verified, copy)
    save_plan(moved, copy)
    assert not (copy / "report.json").exists()
    assert _export(copy, tmp_path / "q.mod") == 1


def test_a_failed_save_leaves_the_previous_plan_whole(verified, tmp_path, monkeypatch):
    folder = tmp_path / "plan"
    shutil.copytree(verified, folder)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    import drakedeburr.plan.io as io_mut

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(io_mut, "write_joint_csv", broken)
    with pytest.raises(OSError):
        save_plan(vs.good_plan(), folder)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["plan"]  # no temporary folder left
    with pytest.raises(Exception, match="did not write"):
        save_plan(vs.good_plan(), tmp_path)  # a folder that is not a plan is never replaced


def _plan_cmd(out: Path, env: dict | None = None) -> list[str]:
    return [sys.executable, "-m", "drakedeburr", "-q", "plan", "tool_in_hand", "--hub",
            vs.HUB, "--windows", "0", "--source", "edges", "-o", str(out)]


@pytest.mark.slow
def test_kill_during_plan_leaves_the_old_plan_which_still_verifies(verified, tmp_path):
    folder = tmp_path / "plan"
    shutil.copytree(verified, folder)
    digest = plan_digest(load_plan(folder))
    proc = subprocess.Popen(_plan_cmd(folder), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 600
    # kill -9 once the new plan is being written beside the old one
    while not list(tmp_path.glob(".plan.tmp-*")) and proc.poll() is None:
        assert time.monotonic() < deadline
        time.sleep(0.002)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert plan_digest(load_plan(folder)) == digest
    assert gate(folder, load_plan(folder)).ok  # its report still holds
    save_plan(load_plan(folder), folder)  # the next run removes what the kill left
    assert not list(tmp_path.glob(".plan.*"))


@pytest.mark.slow
def test_plan_content_is_the_same_whatever_the_thread_settings(tmp_path):
    digests = []
    for threads in ("1", "2"):
        env = {**os.environ, "OMP_NUM_THREADS": threads, "OPENBLAS_NUM_THREADS": threads,
               "MKL_NUM_THREADS": threads}
        out = tmp_path / f"t{threads}"
        subprocess.run(_plan_cmd(out), env=env, check=True, timeout=900)
        digests.append(plan_digest(load_plan(out)))
        doc = json.loads((out / "plan.json").read_text())
        windows = json.dumps(doc["meta"]["windows"])
        assert "timings" not in doc["meta"]
        assert not any(k in windows for k in ("ik_seconds", "dense_seconds", "per_point"))
    assert digests[0] == digests[1]
    a, b = (np.load(tmp_path / f"t{t}" / "arrays.npz") for t in ("1", "2"))
    assert all(np.array_equal(a[k], b[k], equal_nan=True) for k in a.files)
