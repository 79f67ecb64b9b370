"""The verification report: per-check items, dense series for plots, and its JSON form.

JSON schema ``drakedeburr.verify/1`` (``report.json``)::

    {
      "schema": "drakedeburr.verify/1",
      "passed": bool,                 # every required item passed
      "plan": {scenario, hub, mode, windows, targets, knots, duration_s, planner},
      "summary": {"items": n, "failed": [names], "advisory_failed": [names]},
      "items": [ {name, passed, required, value, limit, unit, comparison,
                  where: {window, time_s, target_index, pair}, detail, per_window}, ... ],
      "settings": {tolerances and sampling used},
      "run": {"timestamp": ISO-8601 UTC, "elapsed_s": float, "versions": {...}}
    }

Everything except ``run`` is a pure function of the plan and the settings: floats are rounded
to 10 significant digits and keys are sorted, so identical input gives byte-identical files
once ``run`` is set aside (``report_json(report, include_run=False)``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drakedeburr._io import atomic_write_text

__all__ = ["SCHEMA", "CheckItem", "VerificationReport", "report_json", "write_report_json",
           "is_report_folder"]

SCHEMA = "drakedeburr.verify/1"


@dataclass(frozen=True, eq=False)
class CheckItem:
    """One check of the verification.

    Attributes:
        name: check name (stable identifier, e.g. ``"clearance"``).
        passed: the check's verdict.
        value: the measured worst value (SI unit ``unit``), None if not measurable.
        limit: the limit it is compared with, None for information items.
        unit: unit of ``value`` and ``limit`` ("m", "rad", "rad/s", "m/s", "s", "-", ...).
        comparison: "<=" (value must not exceed limit), ">=" (must reach it), "==" or "info".
        required: False for advisory items (targets from the source, reported, not gating).
        window: window of the worst location (-1 for home/transition moves), or None.
        time: trajectory time of the worst location [s], or None.
        target_index: index into ``Plan.targets`` nearest the worst location, or None.
        pair: (name_a, name_b) of the closest geometry pair for distance checks, or None.
        detail: one line for a human.
        per_window: {window: {figure: value}} breakdown (JSON keys are strings).
    """

    name: str
    passed: bool
    value: float | None
    limit: float | None
    unit: str
    comparison: str = "<="
    required: bool = True
    window: int | None = None
    time: float | None = None
    target_index: int | None = None
    pair: tuple[str, str] | None = None
    detail: str = ""
    per_window: dict = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class VerificationReport:
    """Outcome of :func:`drakedeburr.verify.verify_plan`.

    Attributes:
        passed: True when every required item passed.
        items: the checks, in a fixed order.
        plan_info: scenario, hub, mode, windows, counts, duration.
        settings: tolerances and sampling used.
        series: dense per-sample arrays for plots (not in the JSON): ``t`` (N,) [s],
            ``q`` (N, 6) [rad], ``speed`` (N,) [m/s], ``clearance`` (N,) [m], ``burr`` (N,) [m],
            ``kind`` (N,) segment kind, ``window`` (N,), ``path_dev`` (N,) [m] (NaN off linear
            moves), ``edge_dev`` (N,) [m], ``theta_A``/``theta_B`` (N,) [rad] (NaN off cuts),
            ``s_cut`` (N,) tool travel along the window [m].
        run: timestamp, elapsed seconds, versions (the only non-deterministic part).
    """

    passed: bool
    items: tuple[CheckItem, ...]
    plan_info: dict
    settings: dict
    series: dict = field(default_factory=dict)
    run: dict = field(default_factory=dict)

    def item(self, name: str) -> CheckItem:
        """The item called ``name`` (KeyError if absent)."""
        for it in self.items:
            if it.name == name:
                return it
        raise KeyError(f"no check item {name!r}; have {[i.name for i in self.items]}")

    @property
    def failed(self) -> list[str]:
        """Names of the required items that failed."""
        return [i.name for i in self.items if i.required and not i.passed]

    @property
    def advisory_failed(self) -> list[str]:
        return [i.name for i in self.items if not i.required and not i.passed]


def _clean(x: Any) -> Any:
    """JSON-ready value: numpy -> Python, floats rounded to 10 significant digits, NaN/inf ->
    None, dict keys as strings."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return [_clean(v) for v in x.tolist()]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        v = float(x)
        if not math.isfinite(v):
            return None
        return float(f"{v:.10g}")
    if isinstance(x, Path):
        return str(x)
    return x


def _item_dict(it: CheckItem) -> dict:
    return {
        "name": it.name, "passed": it.passed, "required": it.required, "value": it.value,
        "limit": it.limit, "unit": it.unit, "comparison": it.comparison,
        "where": {"window": it.window, "time_s": it.time, "target_index": it.target_index,
                  "pair": list(it.pair) if it.pair else None},
        "detail": it.detail, "per_window": it.per_window,
    }


def report_dict(report: VerificationReport, include_run: bool = True) -> dict:
    """The JSON document as a dict (see module docstring)."""
    out = {
        "schema": SCHEMA,
        "passed": report.passed,
        "plan": report.plan_info,
        "summary": {"items": len(report.items), "failed": report.failed,
                    "advisory_failed": report.advisory_failed},
        "items": [_item_dict(i) for i in report.items],
        "settings": report.settings,
    }
    if include_run:
        out["run"] = report.run
    return _clean(out)


def report_json(report: VerificationReport, include_run: bool = True) -> str:
    """Deterministic JSON text (sorted keys, rounded floats; ``run`` optional)."""
    return json.dumps(report_dict(report, include_run), indent=2, sort_keys=True) + "\n"


def write_report_json(report: VerificationReport, path: str | Path) -> Path:
    """Write ``report.json`` atomically."""
    return atomic_write_text(Path(path), report_json(report))


def is_report_folder(folder: str | Path) -> bool:
    """Does ``folder`` hold only a report of ours (``report.json`` of this schema, no plan)?
    ``verify MESH -o DIR`` writes one when no window of the mesh can be cut."""
    import json

    from drakedeburr.verify.gate import REPORT_FILE

    try:
        doc = json.loads((Path(folder) / REPORT_FILE).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(doc, dict) and doc.get("schema") == SCHEMA
