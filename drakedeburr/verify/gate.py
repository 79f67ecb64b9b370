"""The export gate: a robot program is written from a plan folder only when the verification
report inside it passed, was made for this very plan (its content hash) in this very cell (the
cell's content hash, :func:`drakedeburr.cell.fingerprint.cell_fingerprint`) by this verifier
version. ``--force`` writes anyway, and the program's header says why."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

__all__ = ["REPORT_FILE", "REPORT_HTML", "GateResult", "gate", "plan_identity"]

REPORT_FILE = "report.json"
REPORT_HTML = "report.html"


@dataclass(frozen=True)
class GateResult:
    """Whether a plan folder may be exported: ``ok``, the flag a forced program carries
    ("" when ok, else "FORCED" for a failed verification or "UNVERIFIED"), and why."""

    ok: bool
    flag: str
    reason: str


def plan_identity(plan) -> dict:
    """What a report ties itself to: the plan's content hash, the cell's and the verifier's
    version."""
    import drakedeburr
    from drakedeburr.cell.fingerprint import cell_fingerprint
    from drakedeburr.plan.io import plan_digest

    robot = (plan.meta or {}).get("robot")
    return {"plan_digest": plan_digest(plan),
            "cell_digest": cell_fingerprint(plan.scenario, plan.hub, robot),
            "verifier_version": getattr(drakedeburr, "__version__", "")}


def _certifying(tolerances: dict) -> bool:
    """Were these (a report's) the verifier's own tolerances and sampling?"""
    from dataclasses import asdict

    from drakedeburr.config import default_tolerances

    own = asdict(default_tolerances())
    return set(tolerances) == set(own) and all(
        abs(float(tolerances[k]) - v) <= 1e-9 * max(1.0, abs(v)) for k, v in own.items())


def gate(folder: str | Path, plan) -> GateResult:
    """Check the report in plan folder ``folder`` against ``plan`` (loaded from it)."""
    folder = Path(folder)
    path = folder / REPORT_FILE
    if not path.is_file():
        return GateResult(False, "UNVERIFIED", f"no verification report in {folder} (run "
                                               f"drakedeburr verify {folder})")
    try:
        report = json.loads(path.read_text())
        identity = report["plan"]["identity"]
        passed = bool(report["passed"])
    except (OSError, ValueError, KeyError, TypeError):
        return GateResult(False, "UNVERIFIED", f"{path}: not a readable verification report")
    try:
        now = plan_identity(plan)
    except FileNotFoundError as exc:
        return GateResult(False, "UNVERIFIED", f"the plan's cell cannot be loaded: {exc}")
    for key, what in (("plan_digest", "another plan (the plan changed since it was verified)"),
                      ("cell_digest", "another cell (scenario, arm, tool or hub models changed "
                                      "since verification)"),
                      ("verifier_version", "another drakedeburr version")):
        if identity.get(key) != now[key]:
            return GateResult(False, "UNVERIFIED", f"{path} is for {what}; run drakedeburr "
                                                   f"verify {folder} again")
    if not _certifying(report.get("settings", {}).get("tolerances", {})):
        return GateResult(False, "UNVERIFIED", f"{path} was made with other tolerances or "
                                               "sampling than the verifier's own (--quick?); run "
                                               f"drakedeburr verify {folder} again")
    if not passed:
        failed = ", ".join(report.get("summary", {}).get("failed", [])) or "?"
        return GateResult(False, "FORCED", f"verification FAILED ({failed}): {path}")
    return GateResult(True, "", f"verified: {path}")
