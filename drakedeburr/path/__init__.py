"""drakedeburr.path stage: window edge -> EdgeCurve (closed NURBS fit) -> CL points (ClPath)."""

from drakedeburr.path.cl_planning import METHODS, PlannerParams, plan_all, plan_cl
from drakedeburr.path.edge_curve import EdgeCurve, fit_edge_curve
from drakedeburr.path.metrics import cl_metrics, coefficient_of_variation, segment_figures
from drakedeburr.path.table import cl_table, format_table, windows_from_source
from drakedeburr.path.types import ClPath

__all__ = [
    "ClPath", "EdgeCurve", "fit_edge_curve", "METHODS", "PlannerParams", "plan_cl", "plan_all",
    "cl_metrics", "coefficient_of_variation", "segment_figures", "cl_table", "format_table",
    "windows_from_source",
]
