"""drakedeburr.orientation: tool-axis optimisation along window edges (source §2.3) -> ToolPath."""

from drakedeburr.orientation.exact import ExactOptions, SolveReport, solve_exact
from drakedeburr.orientation.models import OrientationProblem, make_problem
from drakedeburr.orientation.orient import (
    OrientOptions,
    orient_window,
    problem_for,
    solve_problem,
    tool_path_summary,
)
from drakedeburr.orientation.pso import PsoOptions, pso_minimize
from drakedeburr.orientation.smoothing import gaussian_smooth_mirror
from drakedeburr.orientation.stats import angle_statistics, axis_turning
from drakedeburr.orientation.types import ToolPath

__all__ = [
    "ToolPath",
    "orient_window",
    "OrientOptions",
    "OrientationProblem",
    "make_problem",
    "problem_for",
    "solve_problem",
    "solve_exact",
    "ExactOptions",
    "SolveReport",
    "PsoOptions",
    "pso_minimize",
    "gaussian_smooth_mirror",
    "angle_statistics",
    "axis_turning",
    "tool_path_summary",
]
