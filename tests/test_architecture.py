"""The house rules of issue 20, read from the source: no function over 100 lines, no module
over 600, stage packages importing only earlier stages (no cycles), the tolerances constructed
in one place, and every verification check registered once with its purpose."""

from __future__ import annotations

import ast
from pathlib import Path

import drakedeburr

ROOT = Path(drakedeburr.__file__).parent
#: stage packages in pipeline order (a package may import only the ones before it); the
#: CLI layer (``*/commands.py``, cli.py, demo.py) may import anything
ORDER = ("hub", "path", "frames", "orientation", "robots", "programs", "cell", "viz", "plan",
         "verify", "post", "laser")
#: modules shared by every stage (configuration, units, errors, I/O, model lookup, lazy
#: re-exports)
BASE = {"config", "units", "errors", "_io", "resources", "_lazy"}


def _modules():
    for f in sorted(ROOT.rglob("*.py")):
        yield f, ast.parse(f.read_text(), filename=str(f))


def test_no_function_over_100_lines_and_no_module_over_600():
    long_fns, long_mods = [], []
    for f, tree in _modules():
        n = len(f.read_text().splitlines())
        if n > 600:
            long_mods.append(f"{f.relative_to(ROOT)}: {n}")
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                if length > 100:
                    long_fns.append(f"{f.relative_to(ROOT)}:{node.lineno} {node.name} {length}")
    assert not long_mods, long_mods
    assert not long_fns, long_fns


def _package_of(f: Path) -> str | None:
    parts = f.relative_to(ROOT).parts
    return parts[0] if len(parts) > 1 else None


def test_stages_import_only_earlier_stages():
    wrong = []
    for f, tree in _modules():
        pkg = _package_of(f)
        if pkg is None or f.name == "commands.py" or pkg not in ORDER:
            continue
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            for name in names:
                parts = name.split(".")
                if parts[0] != "drakedeburr" or len(parts) < 2 or parts[1] in BASE:
                    continue
                target = parts[1]
                if target == pkg:
                    continue
                if target not in ORDER or ORDER.index(target) > ORDER.index(pkg):
                    wrong.append(f"{f.relative_to(ROOT)}:{node.lineno} imports {name}")
    assert not wrong, wrong


def test_tolerances_are_constructed_in_one_place():
    places = []
    for f, tree in _modules():
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id == "Tolerances"):
                places.append(f"{f.relative_to(ROOT)}:{node.lineno}")
    assert places == ["config.py:" + places[0].split(":")[1]] and len(places) == 1, places


def test_every_check_is_registered_once_with_a_purpose():
    from drakedeburr.verify.registry import CHECKS

    names = [c.name for c in CHECKS]
    assert len(names) == len(set(names))
    assert all(c.purpose in ("required", "process", "info") and c.doc for c in CHECKS)
