"""Exact solvers of the orientation models.

``axis`` model: a box-constrained nonlinear least-squares problem (see
:mod:`drakedeburr.orientation.models`). Solved by sequential convex programming: at the current
x, linearise the residuals (Gauss-Newton) and solve the convex QP

    min_dx |r + J dx|^2 + mu |dx|^2   s.t.  lower - x <= dx <= upper - x

with Drake's ``MathematicalProgram`` (Clarabel, an interior-point conic solver; OSQP as a
fallback), then a backtracking (Armijo) line search on the true objective. The box is convex,
so every iterate stays feasible. A fixed point (dx = 0) satisfies the KKT conditions of the
original problem (the Gauss-Newton gradient J^T r is the exact gradient), which is checked and
reported as the projected-gradient norm. The first step from the box centre is the
minimiser of the linearised (convex) problem: a warm start close to the optimum, because the
box is small (<= 0.18 rad wide); a caller may pass its own warm start (e.g. a previous solve).

``paper`` model: its global minimum is known in closed form - any constant pair inside the box
has objective 0 (the degeneracy documented in models.py) - so the exact solver returns the
constant box centre.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.orientation.models import OrientationProblem

__all__ = ["ExactOptions", "SolveReport", "solve_exact"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ExactOptions:
    """Sequential-convex (Gauss-Newton) settings."""

    max_iterations: int = 50
    step_tolerance: float = 1e-10  # [rad] stop when |dx|_inf is below
    relative_decrease: float = 1e-13  # stop when the objective decreases less than this share
    damping: float = 1e-9  # mu, relative to the mean diagonal of J^T J
    kkt_tolerance: float = 1e-6  # projected-gradient norm relative to |gradient at centre|


@dataclass(frozen=True)
class SolveReport:
    """Outcome of one solve (exact or PSO)."""

    x: np.ndarray  # (2M,) [theta_A_0, theta_B_0, ...] [rad]
    objective: float
    solver: str
    success: bool
    solve_seconds: float
    iterations: int
    message: str = ""
    info: dict = field(default_factory=dict)


def _solve_qp(Q: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    from pydrake.solvers import ClarabelSolver, MathematicalProgram, OsqpSolver

    prog = MathematicalProgram()
    dx = prog.NewContinuousVariables(len(c), "dx")
    prog.AddQuadraticCost(Q, c, dx, is_convex=True)
    prog.AddBoundingBoxConstraint(lo, hi, dx)
    for solver in (ClarabelSolver(), OsqpSolver()):
        result = solver.Solve(prog)
        if result.is_success():
            return np.clip(result.GetSolution(dx), lo, hi)
    return None


def projected_gradient_norm(prob: OrientationProblem, x: np.ndarray) -> float:
    """|x - clip(x - grad f(x))|_inf: 0 exactly at a KKT point of the box problem."""
    g = prob.gradient(x)
    return float(np.abs(x - np.clip(x - g, prob.lower, prob.upper)).max())


def solve_exact(
    prob: OrientationProblem, x0: np.ndarray | None = None, options: ExactOptions = ExactOptions()
) -> SolveReport:
    """Solve ``prob`` to (local, KKT-checked) optimality; see the module docstring."""
    t0 = time.perf_counter()
    lo, hi = prob.lower, prob.upper
    centre = 0.5 * (lo + hi)
    if prob.model == "paper":
        x = centre.copy()
        return SolveReport(x, float(prob.objective(x)), "exact", True, time.perf_counter() - t0, 0,
                           "paper model: a constant pair is a global minimum (objective 0)")
    x = centre.copy() if x0 is None else np.clip(np.asarray(x0, float), lo, hi)
    f = float(prob.objective(x))
    g_ref = max(float(np.abs(prob.gradient(centre)).max()), 1e-12)
    it = 0
    message = "iteration limit"
    for it in range(1, options.max_iterations + 1):
        r = prob.residuals(x).reshape(-1)
        J = prob.residual_jacobian(x)
        JtJ = J.T @ J
        mu = options.damping * max(float(np.trace(JtJ)) / len(x), 1e-300)
        Q = 2.0 * (JtJ + mu * np.eye(len(x)))
        c = 2.0 * J.T @ r
        dx = _solve_qp(Q, c, lo - x, hi - x)
        if dx is None:
            message = f"QP subproblem failed at iteration {it}"
            break
        slope = float(c @ dx)
        step = 1.0
        while True:
            x_new = np.clip(x + step * dx, lo, hi)
            f_new = float(prob.objective(x_new))
            if f_new <= f + 1e-4 * step * min(slope, 0.0) or step < 1e-6:
                break
            step *= 0.5
        small_step = np.abs(step * dx).max() < options.step_tolerance
        decrease = f - f_new
        if f_new <= f:
            x, f_prev, f = x_new, f, f_new
        else:
            f_prev = f
        if small_step or decrease <= options.relative_decrease * max(f_prev, 1e-300):
            message = "converged"
            break
    kkt = projected_gradient_norm(prob, x)
    success = kkt <= options.kkt_tolerance * g_ref and bool(prob.in_bounds(x).all())
    if not success:
        message += f"; KKT residual {kkt:.3g} (gradient scale {g_ref:.3g})"
    elapsed = time.perf_counter() - t0
    log.debug("%s: exact axis solve %d it, J=%.6g, kkt=%.2g, %.1f ms", prob.name, it, f, kkt,
              1e3 * elapsed)
    return SolveReport(x, f, "exact", success, elapsed, it, message,
                       {"kkt_residual": kkt, "gradient_scale": g_ref})
