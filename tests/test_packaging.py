"""The wheel ships models/ inside the package and resources.py finds them there."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def test_wheel_contains_models_and_resources_finds_them(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(tmp_path / "dist"), str(REPO)],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    (wheel,) = (tmp_path / "dist").glob("drakedeburr-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        names = set(zf.namelist())
        assert "drakedeburr/models/package.xml" in names
        assert "drakedeburr/py.typed" in names
        tracked = subprocess.run(["git", "ls-files", "models"], cwd=REPO, capture_output=True,
                                 text=True).stdout.split()
        missing = [f for f in tracked if f"drakedeburr/{f}" not in names]
        assert not missing, f"models missing from the wheel: {missing[:10]}"
        zf.extractall(tmp_path / "site")
    # Import from the unpacked wheel only (not the source tree): models resolve inside it.
    code = ("import drakedeburr.resources as r; p = r.models_dir(); "
            "print(p); assert 'site' in str(p), p")
    env = dict(os.environ, PYTHONPATH=str(tmp_path / "site"))
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert str(tmp_path / "site" / "drakedeburr" / "models") in out.stdout
