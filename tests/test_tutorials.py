"""Tutorials are code: each ``tutorials/NN_name/tutorial.py`` runs here in test mode."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
TUTORIALS = sorted((REPO / "tutorials").glob("*/tutorial.py"))


@pytest.mark.parametrize("script", TUTORIALS, ids=[p.parent.name for p in TUTORIALS])
def test_tutorial_runs(script, tmp_path):
    # the tutorial imports this checkout's drakedeburr, installed or not
    pythonpath = os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)
    env = dict(os.environ, DRAKEDEBURR_TEST_MODE="1", MPLBACKEND="Agg", PYTHONPATH=pythonpath)
    proc = subprocess.run(
        [sys.executable, str(script), "--test-mode", "--out", str(tmp_path)],
        cwd=script.parent, env=env, capture_output=True, text=True, timeout=900,
    )
    assert proc.returncode == 0, f"{script} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
