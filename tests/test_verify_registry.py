"""The verifier's registry: the docs table lists every check in report order with its
purpose, and a check is added by one function and one registry line (the docs' example)."""

from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from drakedeburr.config import default_tolerances
from drakedeburr.verify.registry import CHECKS, Check, run_checks
from drakedeburr.verify.report import CheckItem

DOCS = Path(__file__).resolve().parents[1] / "docs" / "verify.md"


def _docs_table() -> list[tuple[str, str]]:
    text = DOCS.read_text()
    table = text[text.index("| name | purpose | what | limit |"):]
    rows = []
    for line in table.splitlines()[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        for name in re.split(r"\s*/\s*", cells[0]):
            rows.append((name, cells[1]))
    return rows


def test_the_docs_table_is_the_registry():
    assert _docs_table() == [(c.name, c.purpose) for c in CHECKS]


def test_a_check_is_one_function_and_one_registry_line():
    def tool_height(sp, cfg) -> CheckItem:  # the docs' example
        z = sp.samples.p_HT[:, 2]
        i = int(np.argmin(z))
        return CheckItem("tool_height", bool(z[i] >= -0.05), float(z[i]), -0.05, "m", ">=",
                         **sp.where(i), detail="tool point never 50 mm below the hub face")

    checks = (Check("tool_height", tool_height, "required", "tool point above the hub's back"),)
    for z, passed in ((0.01, True), (-0.06, False)):
        sp = SimpleNamespace(samples=SimpleNamespace(p_HT=np.array([[0, 0, 0.02], [0, 0, z]])),
                             where=lambda i: {"window": 0, "time": float(i)})
        (item,) = run_checks(sp, SimpleNamespace(tolerances=default_tolerances()), checks)
        assert item.required and item.passed is passed and item.value == z
        assert item.time == 1.0
