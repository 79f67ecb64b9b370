"""Exact solvers of the orientation models.

``axis`` model: a smooth box-constrained problem (see :mod:`drakedeburr.orientation.models`).
Solved by sequential convex programming (a box-constrained Newton method): at the current x,
solve the convex QP

    min_dx  grad^T dx + 1/2 dx^T Q dx   s.t.  lower - x <= dx <= upper - x

with Q the Gauss-Newton Hessian 2 J^T J plus the positive semidefinite part of the exact
Hessian's second-order term, which is block diagonal and cheap (the curvature of each axis in
its own two angles): the exact Newton step where those blocks are PSD, a convex model always.
The QP is one Drake ``MathematicalProgram`` built once and updated in place, solved by Clarabel
(an interior-point conic solver; OSQP as a fallback); then a backtracking (Armijo) line search
on the true objective. The box is convex, so every iterate stays feasible. The iteration stops
at a KKT point of the original problem (projected-gradient norm below ``kkt_tolerance``
relative to the gradient at the box centre), which is reported. The default start is the box
centre; a caller may pass a warm start (e.g. a previous solve of a nearby problem).

``paper`` model: its global minimum is known in closed form - any constant pair inside the box
has objective 0 (the degeneracy documented in models.py) - so the exact solver returns the
constant box centre.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.orientation.models import OrientationProblem, block_diag_2

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


class _BoxQp:
    """min 0.5 dx^T Q dx + c^T dx  s.t.  lo <= dx <= hi, built once and updated in place
    (Drake MathematicalProgram; Clarabel, OSQP as a fallback)."""

    def __init__(self, n: int):
        from pydrake.solvers import ClarabelSolver, MathematicalProgram, OsqpSolver

        self.prog = MathematicalProgram()
        self.dx = self.prog.NewContinuousVariables(n, "dx")
        self.cost = self.prog.AddQuadraticCost(np.eye(n), np.zeros(n), self.dx, is_convex=True)
        self.box = self.prog.AddBoundingBoxConstraint(-np.ones(n), np.ones(n), self.dx)
        self.solvers = [ClarabelSolver(), OsqpSolver()]

    def solve(self, Q, c, lo, hi) -> np.ndarray | None:
        self.cost.evaluator().UpdateCoefficients(Q, c, 0.0, is_convex=True)
        self.box.evaluator().set_bounds(lo, hi)
        for solver in self.solvers:
            result = solver.Solve(self.prog)
            if result.is_success():
                return np.clip(result.GetSolution(self.dx), lo, hi)
        return None


def _psd_part(blocks: np.ndarray) -> tuple[np.ndarray, bool]:
    """Project each symmetric 2x2 block onto the PSD cone; also say whether all were PSD."""
    w, v = np.linalg.eigh(blocks)
    exact = bool((w >= 0).all())
    return np.einsum("mij,mj,mkj->mik", v, np.maximum(w, 0.0), v), exact


def _pg_norm(x, g, lo, hi) -> float:
    return float(np.abs(x - np.clip(x - g, lo, hi)).max())


def projected_gradient_norm(prob: OrientationProblem, x: np.ndarray) -> float:
    """|x - clip(x - grad f(x))|_inf: 0 exactly at a KKT point of the box problem."""
    return _pg_norm(x, prob.gradient(x), prob.lower, prob.upper)


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
    g_ref = max(float(np.abs(prob.gradient(centre)).max()), 1e-12)
    qp = _BoxQp(prob.n_vars)
    f, grad, H_gn, blocks = prob.derivatives(x)
    it = 0
    message = "iteration limit"
    newton_steps = 0
    for it in range(1, options.max_iterations + 1):
        scale = float(np.trace(H_gn)) / len(x) + 1e-300
        # Gauss-Newton + the PSD part of the exact curvature blocks: the exact Newton step
        # wherever those blocks are PSD (near the optimum), a convex model always
        if _pg_norm(x, grad, lo, hi) <= options.kkt_tolerance * g_ref:
            message = "converged (KKT)"
            break
        psd, exact_newton = _psd_part(blocks)
        newton_steps += exact_newton
        Q = H_gn + block_diag_2(psd) + options.damping * scale * np.eye(len(x))
        dx = qp.solve(Q, grad, lo - x, hi - x)
        if dx is None:
            message = f"QP subproblem failed at iteration {it}"
            break
        slope = float(grad @ dx)
        step = 1.0
        while True:
            x_new = np.clip(x + step * dx, lo, hi)
            f_new = float(prob.objective(x_new))
            if f_new <= f + 1e-4 * step * min(slope, 0.0) or step < 1e-6:
                break
            step *= 0.5
        small_step = np.abs(step * dx).max() < options.step_tolerance
        decrease = f - f_new
        f_prev = f
        if f_new <= f:
            x = x_new
            f, grad, H_gn, blocks = prob.derivatives(x)
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
                       {"kkt_residual": kkt, "gradient_scale": g_ref,
                        "newton_steps": newton_steps})
