"""``python -m drakedeburr.cell`` (cell/__main__.py) regenerates the tool models."""

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def test_module_entry_point_writes_the_tool_models(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.run([sys.executable, "-m", "drakedeburr.cell", str(tmp_path)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    written = [Path(line) for line in proc.stdout.split()]
    assert written and all(p.is_file() and p.stat().st_size > 0 for p in written)
    # identical to the committed models (the generator is deterministic)
    for p in written:
        committed = REPO / "models" / "tools" / p.name
        if committed.is_file():
            assert p.read_bytes() == committed.read_bytes(), p.name
