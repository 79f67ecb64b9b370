"""drakedeburr.verify stage: dense, independent re-check of a plan -> VerificationReport."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "batch": ("BatchJob", "JobSettings", "verify_all"),
    "checks": ("verify_plan",),
    "html": ("report_html", "write_report_html"),
    "report": ("SCHEMA", "CheckItem", "VerificationReport", "report_json", "write_report_json"),
    "synthetic": ("reference_plan",),
})
