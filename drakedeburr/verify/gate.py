"""The export gate: a robot program is written from a plan folder only when the verification
report inside it passed, was made for this very plan (its content hash) in this very cell (the
cell's content hash, :func:`drakedeburr.cell.fingerprint.cell_fingerprint`) by this verifier
version. ``--force`` writes anyway, and the program's header says why."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

__all__ = ["REPORT_FILE", "REPORT_HTML", "GateResult", "gate", "plan_identity",
           "read_report"]

REPORT_FILE = "report.json"
REPORT_HTML = "report.html"


@dataclass(frozen=True)
class GateResult:
    """Whether a plan folder may be exported: ``ok``, the flag a forced program carries
    ("" when ok, else "FORCED" for a failed verification or "UNVERIFIED"), and why."""

    ok: bool
    flag: str
    reason: str
    #: a verification that failed only on ``uncut_edge`` (partial windows, every other
    #: required check passed on the motion planned): the uncut stretches, else ""
    partial: str = ""


def plan_identity(plan) -> dict:
    """What a report ties itself to: the plan's content hash, the cell's and the verifier's
    version."""
    import drakedeburr
    from drakedeburr.cell.fingerprint import cell_fingerprint
    from drakedeburr.plan.io import plan_digest

    meta = plan.meta or {}
    return {"plan_digest": plan_digest(plan),
            "cell_digest": cell_fingerprint(plan.scenario, plan.hub, meta.get("robot"),
                                            meta.get("tool")),
            "verifier_version": getattr(drakedeburr, "__version__", "")}


def _certifying(tolerances: dict) -> bool:
    """Were these (a report's) the verifier's own tolerances and sampling?"""
    from dataclasses import asdict

    from drakedeburr.config import default_tolerances

    own = asdict(default_tolerances())
    return set(tolerances) == set(own) and all(
        abs(float(tolerances[k]) - v) <= 1e-9 * max(1.0, abs(v)) for k, v in own.items())


def _item(doc, path: str, kind, where: Path):
    """``doc[a][b]...`` for ``path`` "a.b" of type ``kind``; InputError naming the item."""
    from drakedeburr.errors import InputError

    value = doc
    for key in path.split("."):
        if not isinstance(value, dict) or key not in value:
            raise InputError(f"{where}: item {path!r} missing: not a verification report")
        value = value[key]
    if not isinstance(value, kind) or (kind is not bool and isinstance(value, bool)):
        raise InputError(f"{where}: item {path!r} is a {type(value).__name__}, not a "
                         f"{getattr(kind, '__name__', kind)}")
    return value


def read_report(path: str | Path) -> dict:
    """A verification report (``report.json``) with the items the gate needs checked: ``passed``
    (bool), ``plan.identity`` (the three digests, strings), ``settings.tolerances`` (numbers)
    and ``summary.failed`` (names).

    Raises:
        InputError: not readable, not JSON, or an item missing or of the wrong type (names
            the file and the item). FileNotFoundError: no file.
    """
    from drakedeburr.errors import InputError

    path = Path(path)
    try:
        report = json.loads(path.read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise InputError(f"{path}: not valid JSON ({type(exc).__name__}: {str(exc)[:100]})"
                         ) from None
    except IsADirectoryError:
        raise InputError(f"{path}: a folder, not a report file") from None
    if not isinstance(report, dict):
        raise InputError(f"{path}: a JSON {type(report).__name__}, not a verification report")
    _item(report, "passed", bool, path)
    _item(report, "plan.identity", dict, path)
    for key in ("plan_digest", "cell_digest", "verifier_version"):
        _item(report, f"plan.identity.{key}", str, path)
    tolerances = _item(report, "settings.tolerances", dict, path)
    for key, value in tolerances.items():
        try:
            ok = not isinstance(value, bool) and math.isfinite(float(value))
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise InputError(f"{path}: item 'settings.tolerances.{key}' is not a finite number")
    failed = _item(report, "summary.failed", list, path)
    if not all(isinstance(f, str) for f in failed):
        raise InputError(f"{path}: item 'summary.failed' is not a list of check names")
    return report


def gate(folder: str | Path, plan) -> GateResult:
    """Check the report in plan folder ``folder`` against ``plan`` (loaded from it)."""
    folder = Path(folder)
    path = folder / REPORT_FILE
    if not path.is_file():
        return GateResult(False, "UNVERIFIED", f"no verification report in {folder} (run "
                                               f"drakedeburr verify {folder})")
    from drakedeburr.errors import InputError

    try:
        report = read_report(path)
    except (OSError, InputError) as exc:
        return GateResult(False, "UNVERIFIED", f"no readable verification report ({exc})")
    identity, passed = report["plan"]["identity"], report["passed"]
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
    if not _certifying(report["settings"]["tolerances"]):
        return GateResult(False, "UNVERIFIED", f"{path} was made with other tolerances or "
                                               "sampling than the verifier's own (--quick?); run "
                                               f"drakedeburr verify {folder} again")
    if not passed:
        failed = ", ".join(report["summary"]["failed"]) or "?"
        uncut = next((i["detail"] for i in report["items"] if i["name"] == "uncut_edge"), "")
        only_uncut = report["summary"]["failed"] == ["uncut_edge"]
        return GateResult(False, "FORCED", f"verification FAILED ({failed}): {path}",
                          partial=uncut if only_uncut else "")
    return GateResult(True, "", f"verified: {path}")
