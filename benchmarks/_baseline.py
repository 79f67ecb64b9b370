"""A module as it was at a previous commit, for the benchmarks' same-run baselines."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def module_at(ref: str, path: str, name: str):
    """The module ``path`` (relative to the repository) at git ``ref``, imported as ``name``
    (its own imports resolve against this tree). Raises ``CalledProcessError`` /
    ``FileNotFoundError`` when git or the ref is not there."""
    src = subprocess.run(["git", "show", f"{ref}:{path}"], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout
    file = Path(tempfile.mkdtemp()) / f"{name}.py"
    file.write_text(src)
    spec = importlib.util.spec_from_file_location(name, file)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


def tree_at(ref: str, prefix: str = "bench_tree_") -> Path:
    """This repository's files at git ``ref`` in a new temporary folder (``git archive``); run
    code from there with that folder as the working directory (``python -m`` and ``-c`` put
    the working folder first on the path)."""
    out = Path(tempfile.mkdtemp(prefix=prefix))
    data = subprocess.run(["git", "-C", str(ROOT), "archive", ref], check=True,
                          capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(out)], input=data, check=True)
    return out
