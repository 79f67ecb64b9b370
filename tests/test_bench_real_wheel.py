"""benchmarks/bench_real_wheel.py: its run_all arguments and the meshes it reads (the run itself
is the benchmark's, in RESULTS.md)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from drakedeburr.resources import extdata_dir

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_real_wheel.py"


def _constants() -> dict:
    tree = ast.parse(SCRIPT.read_text())
    return {t.id: ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
            for t in n.targets if isinstance(t, ast.Name) and t.id.isupper()
            and isinstance(n.value, ast.Tuple)}


def test_quick_run_is_the_first_mesh_and_writes_outside_the_repository():
    c = _constants()
    assert c["QUICK_ARGS"][0] == "--quick" and "{tmp}" in c["QUICK_ARGS"]
    assert "{tmp}" in c["FULL_ARGS"]
    assert c["MESHES"][0].startswith("audibot")


def test_the_meshes_it_reads_are_in_the_shared_data():
    root = extdata_dir()
    if root is None:
        pytest.skip("no ../shared/extdata next to this checkout")
    for name in _constants()["MESHES"]:
        assert (root / "wheel_models" / name).stat().st_size > 0, name
