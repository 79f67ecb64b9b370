"""drakedeburr.path stage: window edge -> EdgeCurve (closed NURBS fit) -> CL points (ClPath)."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "cl_planning": ("METHODS", "PlannerParams", "plan_all", "plan_cl"),
    "edge_curve": ("EdgeCurve", "fit_edge_curve"),
    "metrics": ("cl_metrics", "coefficient_of_variation", "segment_figures"),
    "table": ("cl_table", "format_table", "windows_from_source"),
    "types": ("ClPath",),
    "window_fit": ("fit_window_edge",),
})
