"""drakedeburr.verify stage: dense, independent re-check of a plan -> VerificationReport."""

from drakedeburr.verify.batch import BatchJob, verify_all
from drakedeburr.verify.checks import verify_plan
from drakedeburr.verify.html import report_html, write_report_html
from drakedeburr.verify.report import (
    SCHEMA,
    CheckItem,
    VerificationReport,
    report_json,
    write_report_json,
)
from drakedeburr.verify.synthetic import reference_plan

__all__ = [
    "verify_plan", "VerificationReport", "CheckItem", "SCHEMA", "report_json",
    "write_report_json", "report_html", "write_report_html", "verify_all", "BatchJob",
    "reference_plan",
]
