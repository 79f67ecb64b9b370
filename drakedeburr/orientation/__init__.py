"""drakedeburr.orientation: tool-axis optimisation along window edges (source §2.3) -> ToolPath."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "exact": ("ExactOptions", "SolveReport", "solve_exact"),
    "models": ("OrientationProblem", "make_problem"),
    "orient": (
        "OrientOptions", "orient_window", "problem_for", "solve_problem", "tool_path_summary",
    ),
    "pso": ("PsoOptions", "pso_minimize"),
    "smoothing": ("gaussian_smooth_mirror",),
    "stats": ("angle_statistics", "axis_turning"),
    "types": ("ToolPath",),
})
