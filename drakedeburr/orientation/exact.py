"""Exact solvers of the orientation models.

``axis`` model: a smooth box-constrained problem (see :mod:`drakedeburr.orientation.models`).
Solved by a projected (semismooth) Newton method with Levenberg-Marquardt damping and banded
Cholesky factorisations:

1. At x, estimate the active set from the diagonally scaled projected-gradient step
   z = x - g / diag(H): variables with z below (above) the box are fixed at their bound.
2. Newton step on the free variables with the exact Hessian (Gauss-Newton part 2 J^T G J plus
   the curvature of each axis in its own two angles), the active ones moved onto their bounds:
   (H_FF + mu h I) d_F = -(g + H d_A)_F, h the mean diagonal. If the exact Hessian is not
   positive definite there (Cholesky fails), its 2x2 curvature blocks are replaced by their
   PSD part (a convex model). The active set is then refined on this quadratic model (up to
   ``max_active_set_updates`` re-solves, a primal-dual active-set step): the rule of 1. is
   re-applied at the predicted point x + d with the predicted gradient g + H d. Without it a
   run of angles on a bound is released one angle per Newton step (its neighbour has to move
   first): 40-60 steps from a start on the bounds, up to 23 from the centre; with two
   re-solves at most 23 / 12.
3. Backtracking (Armijo) along the projected path x(a) = clip(x + a d); mu shrinks by 10 after
   a full step and grows otherwise (it keeps the first steps from the box centre from slamming
   hundreds of variables onto the bounds, which the active set would then release slowly).
   If the refined Newton step does not descend (a wrong active-set guess on badly scaled
   loops: the planner's CL points have chords from 0.01 to 10 mm), the unrefined step and then
   the scaled projected-gradient path clip(x - a g / diag(H)) are searched instead; the latter
   always descends from a non-KKT point (``info["safeguard_steps"]`` counts these iterations).

The objective couples neighbouring CL points only, so the Hessian is block-banded - cyclic for
the closed loop. Numbering the points 0, M-1, 1, M-2, 2, ... makes the cyclic band an ordinary
band (lower bandwidth 5 for first differences, 9 with second differences), so each step is one
banded Cholesky solve (LAPACK ``dpbsv`` from scipy, O(M)); fixed variables become identity
rows, which keeps the band. The model (:mod:`drakedeburr.orientation.banded`) and the whole
iteration work in that numbering: x is permuted once on entry and once on exit. The box is
convex and every trial point is projected, so every iterate is feasible. The iteration stops at
a KKT point of the original problem (projected-gradient norm below ``kkt_tolerance`` relative
to the gradient at the box centre), which is reported. Safeguards: if the Newton iteration ends
short of a KKT point (iteration limit, no descent, no positive definite model), it continues
from there with scipy's L-BFGS-B on the same objective (``ExactOptions.fallback``, reported in
``info["fallback"]``); and the final objective is re-evaluated with the problem's own
``objective`` - a disagreement with the fast model is reported as a failure. Measured on the
synthetic test windows and every window of the four bundled hubs (CL points every 2 / 3 mm,
with and without second differences, and the planner's "proposed" CL points), started from the
box centre, both bound corners and random points, 654 solves: all end at a KKT point, 6-25
Newton steps; the projected-gradient safeguard was used in 9 solves (all on the planner's CL
points), the L-BFGS-B fallback in none.

Why hand-written rather than a library (measured on h5_split windows 0 / 1, M = 204 / 76
CL points, CPU time, 2 shared cores): the target is >= 100x faster than the source's PSO,
whose 50 x 200 evaluations take ~300 / ~120 ms, i.e. an exact solve of ~1-3 ms. The Newton
sub-problems as box QPs in a Drake ``MathematicalProgram`` (Clarabel): ~5 ms fixed cost per
QP, 25-186 ms per window. One Drake solve of the whole
problem with the analytic gradient and a bounding box: SNOPT 1330 / 130 ms, IPOPT (quasi-
Newton Hessian) hits its iteration limit after 100 / 38 s. scipy L-BFGS-B with the exact
gradient: 324 / 116 evaluations, 540 / 115 ms (the problem is ill-conditioned: a discrete
Laplacian along the loop, condition ~M^2; 276 / 111 evaluations with the current sign of
theta_A, the same optimum within 3e-11). This method: 6-8 Newton steps (11-17 banded solves),
~2.0 / ~1.3 ms CPU for a first solve of a fresh problem (``benchmarks/bench_orientation.py``).

Cost per call (the ratio to PSO must hold on a busy machine too): the solve is ~600
small numpy / LAPACK calls, so it is written for a low fixed cost per call - no threaded BLAS
anywhere (a dense G = C^T C product and OpenBLAS thread hand-offs made a first solve take
5-20 ms on a loaded machine, the "22x under load"), G's bands in O(M), band layout tables
built in few calls and cached per size, the model and the whole iteration in band numbering,
LAPACK / BLAS on Fortran-ordered band arrays in place (no copies), ``ndarray.take`` and
``count_nonzero`` instead of numpy's Python-level wrappers. The iterates are pinned by
tests/test_orientation_reference.py (the stored optima of 13 solves reproduced to 1e-12).

``paper`` model: its global minimum is known in closed form - any constant pair inside the box
has objective 0 (the degeneracy documented in models.py) - so the exact solver returns the
constant box centre.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dpbsv
from scipy.optimize import minimize

from drakedeburr.orientation.banded import BandedAxisModel
from drakedeburr.orientation.models import OrientationProblem

__all__ = ["ExactOptions", "SolveReport", "solve_exact", "projected_gradient_norm"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ExactOptions:
    """Projected-Newton settings."""

    max_iterations: int = 60
    step_tolerance: float = 1e-12  # [rad] stop when the accepted |step|_inf is below
    relative_decrease: float = 1e-15  # stop when the objective decreases less than this share
    damping: float = 1e-9  # added to a non-PD model's diagonal, relative to its mean diagonal
    kkt_tolerance: float = 1e-6  # projected-gradient norm relative to |gradient at centre|
    initial_damping: float = 0.3  # Levenberg-Marquardt mu at the start, relative to mean diagonal
    damping_decrease: float = 0.1  # mu factor after a full Newton step
    max_active_set_updates: int = 2  # re-solves per Newton step refining the active set
    fallback: bool = True  # L-BFGS-B from the Newton iterate if it ends short of a KKT point


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


def _psd_curvature(curv: np.ndarray) -> np.ndarray:
    """PSD part of each 2x2 curvature block, (3: aa, ab, bb, M)."""
    B = np.stack([curv[:2].T, curv[1:].T], 1)  # (M, 2, 2)
    w, v = np.linalg.eigh(B)
    B = np.einsum("mij,mj,mkj->mik", v, np.maximum(w, 0.0), v)
    return np.stack([B[:, 0, 0], B[:, 0, 1], B[:, 1, 1]])


def _clip(v: np.ndarray, lo: float, hi: float) -> np.ndarray:
    # np.minimum / np.maximum: same values as np.clip, a third of its call overhead
    return np.minimum(np.maximum(v, lo), hi)


def _pg_norm(x, g, lo, hi) -> float:
    return float(np.abs(x - np.minimum(np.maximum(x - g, lo), hi)).max())


def projected_gradient_norm(prob: OrientationProblem, x: np.ndarray) -> float:
    """|x - clip(x - grad f(x))|_inf: 0 exactly at a KKT point of the box problem."""
    return _pg_norm(x, prob.gradient(x), prob.lower, prob.upper)


class _Newton:
    """State of one projected-Newton solve, in band numbering (see the module docstring)."""

    def __init__(self, mdl: BandedAxisModel, xb: np.ndarray, lo: float, hi: float,
                 options: ExactOptions):
        self.mdl, self.lo, self.hi, self.opt = mdl, lo, hi, options
        self.x = xb
        self.f, self.g, self.hv, self.curv = mdl.derivatives(xb)
        self.mu = options.initial_damping
        self.ab = np.zeros((mdl.bandwidth + 1, mdl.n), order="F")  # LAPACK's order: no copy
        self.convex_models = self.solves = self.safeguard_steps = 0

    def direction(self, h_diag: np.ndarray):
        """(refined step d, first step d_first) on the free variables, or (None, None) when no
        positive definite model was found.

        The active set is estimated from the diagonally scaled projected-gradient step, then
        refined on the quadratic model (primal-dual active set / semismooth Newton on the box
        QP): the same rule re-applied at the model's predicted point y = x + d with its
        predicted gradient q = g + H d, re-solving until the set repeats. Without this, a run
        of variables on a bound is released one end variable per outer iteration (its
        neighbour must move first): 40-60 iterations from a start on the bounds, where the
        refined set needs 1-3 extra banded solves.
        """
        mdl, x, g, lo, hi = self.mdl, self.x, self.g, self.lo, self.hi
        h_mean = float(h_diag.sum()) / mdl.n
        z = _clip(x - g / h_diag, lo, hi)
        fixed = (z == lo) | (z == hi)
        abH = mdl.hessian_band(self.hv, self.curv)  # exact model Hessian, band storage
        d = d_first = None
        extra = 0.0
        for _ in range(self.opt.max_active_set_updates + 1):
            any_fixed = np.count_nonzero(fixed) > 0
            mask = mdl.free_mask(fixed) if any_fixed else None
            d_fix = (z - x) * fixed  # active variables move onto their bound
            moves = any_fixed and np.count_nonzero(d_fix) > 0
            d = None
            while d is None:
                # -(g + H d_fix) (one BLAS call)
                rhs = mdl.hess_vec(abH, d_fix, -1.0, -1.0, g) if moves else -g
                if any_fixed:
                    np.copyto(rhs, d_fix, where=fixed)
                damp = (self.mu + extra) * h_mean
                mdl.system(abH, mask, damp, fixed, self.ab)  # banded Cholesky (LAPACK) next:
                _, d, info = dpbsv(self.ab, rhs, lower=1, overwrite_ab=1, overwrite_b=1)
                if info == 0:
                    break
                d = None
                if extra != 0.0:
                    break
                # exact Hessian not PD on the free set: convex model
                extra = self.opt.damping
                abH = mdl.hessian_band(self.hv, _psd_curvature(self.curv))
                self.convex_models += 1
            if d is None:
                return None, None
            self.solves += 1
            if d_first is None:
                d_first = d
            q = mdl.hess_vec(abH, d, 1.0, 1.0, g + damp * d)  # g + H d + damp d
            z = _clip(x + d - q / h_diag, lo, hi)
            new_fixed = (z == lo) | (z == hi)
            if np.count_nonzero(new_fixed ^ fixed) == 0:
                break
            fixed = new_fixed
        return d, d_first

    def line_search(self, d, d_first, h_diag):
        """Armijo search along the projected path x(a) = clip(x + a d), first with the refined
        Newton step, then (safeguard) with the unrefined one, then along the scaled
        projected-gradient path clip(x - a g / diag(H)), which always descends from a non-KKT
        point: a wrong active-set guess (badly scaled loops, e.g. CL chords from 0.01 to
        10 mm) can make the projected Newton step ascend.

        Returns (accepted path index or -1, step, x_new, f_new, derivatives at x_new or None).
        """
        x, f, g, lo, hi = self.x, self.f, self.g, self.lo, self.hi
        paths = [(d, 1e-6)]
        if d_first is not d:
            paths.append((d_first, 1e-6))
        paths.append((None, 1e-12))  # -g / diag(H), computed only if reached
        for k, (dk, min_step) in enumerate(paths):
            if dk is None:
                dk = -g / h_diag
            step = 1.0
            while step >= min_step:
                x_new = _clip(x + step * dk if step != 1.0 else x + dk, lo, hi)
                slope = float(g @ (x_new - x))
                if slope < 0.0:
                    # the full Newton step is nearly always accepted: evaluate all there
                    new = self.mdl.derivatives(x_new) if step == 1.0 and k == 0 else None
                    f_new = new[0] if new is not None else self.mdl.objective(x_new)
                    if f_new <= f + 1e-4 * slope:
                        return k, step, x_new, f_new, new
                step *= 0.5
        return -1, 0.0, x, f, None

    def iterate(self, kkt_abs: float) -> tuple[int, str]:
        """Newton iterations until a KKT point, a stall or the limit: (iterations, message)."""
        opt, mdl, it = self.opt, self.mdl, 0
        for it in range(1, opt.max_iterations + 1):
            if np.abs(self.x - _clip(self.x - self.g, self.lo, self.hi)).max() <= kkt_abs:
                return it, "converged (KKT)"
            # diagonally scaled projected-gradient step -> active set estimate (the
            # Gauss-Newton diagonal 2 G_mm |d axis / d theta|^2 is > 0)
            h_diag = mdl.gauss_newton_diagonal(self.hv) + np.maximum(
                self.curv[::2], 0.0).T.reshape(-1)
            d, d_first = self.direction(h_diag)
            if d is None:
                return it, f"Newton system not positive definite at iteration {it}"
            accepted, step, x_new, f_new, new = self.line_search(d, d_first, h_diag)
            if accepted < 0:
                return it, f"no descent at iteration {it}"
            if accepted > 0:
                self.safeguard_steps += 1
            full = accepted == 0 and step == 1.0
            mu = self.mu * opt.damping_decrease if full else max(self.mu * 10.0, 1e-3)
            self.mu = 0.0 if mu < 1e-8 else mu
            moved = float(np.abs(x_new - self.x).max())
            decrease, f_prev = self.f - f_new, self.f
            self.x = x_new
            self.f, self.g, self.hv, self.curv = new if new is not None else mdl.derivatives(
                x_new)
            if moved < opt.step_tolerance or decrease <= opt.relative_decrease * f_prev:
                return it, "converged (step)"
        return it, "iteration limit"

    def fallback(self, kkt_abs: float) -> str:
        """Continue from the Newton iterate with scipy's L-BFGS-B on the same fast objective
        and gradient (never triggered on the test windows or the bundled hubs, from the box
        centre, the bounds or random starts; see docs/orientation.md). Returns a message."""
        res = minimize(lambda v: self.mdl.derivatives(v)[:2], self.x, jac=True,
                       method="L-BFGS-B", bounds=[(self.lo, self.hi)] * self.mdl.n,
                       options={"maxiter": 1000, "maxfun": 2000, "ftol": 1e-15,
                                "gtol": 0.5 * kkt_abs})
        x_fb = np.clip(res.x, self.lo, self.hi)
        new = self.mdl.derivatives(x_fb)
        if new[0] > self.f:
            return ""
        self.x, (self.f, self.g, self.hv, self.curv) = x_fb, new
        return f"; L-BFGS-B fallback ({res.nit} it)"


def solve_exact(
    prob: OrientationProblem, x0: np.ndarray | None = None, options: ExactOptions = ExactOptions()
) -> SolveReport:
    """Solve ``prob`` to (local, KKT-checked) optimality; see the module docstring."""
    t0 = time.perf_counter()
    lo, hi = prob.theta_min, prob.theta_max  # the box is the same for every variable
    if prob.model == "paper":
        x = np.full(prob.n_vars, 0.5 * (lo + hi))
        return SolveReport(x, float(prob.objective(x)), "exact", True, time.perf_counter() - t0, 0,
                           "paper model: a constant pair is a global minimum (objective 0)")
    mdl = BandedAxisModel(prob)
    centre = np.full(mdl.n, 0.5 * (lo + hi))
    xb = centre if x0 is None else _clip(mdl.to_band(np.asarray(x0, float)), lo, hi)
    nt = _Newton(mdl, xb, lo, hi, options)
    g_ref = max(float(np.abs(nt.g if x0 is None else mdl.derivatives(centre)[1]).max()), 1e-12)
    kkt_abs = options.kkt_tolerance * g_ref
    it, message = nt.iterate(kkt_abs)
    kkt = _pg_norm(nt.x, nt.g, lo, hi)
    fallback = kkt > kkt_abs and options.fallback
    if fallback:
        message += nt.fallback(kkt_abs)
        kkt = _pg_norm(nt.x, nt.g, lo, hi)
    x, f = mdl.from_band(nt.x), nt.f
    # every iterate is clipped into the box; checked anyway (prob.in_bounds' tolerance)
    success = kkt <= kkt_abs and lo - 1e-9 <= float(x.min()) and float(x.max()) <= hi + 1e-9
    if not success:
        message += f"; KKT residual {kkt:.3g} (gradient scale {g_ref:.3g})"
    # cross-check the fast model against the problem's own objective (~50 us): the reported
    # objective is the problem's, and a disagreement (the fast tables out of step with the
    # angle convention) is a failure, never a silent success
    f_ref = float(prob.objective(x))
    if abs(f_ref - f) > 1e-9 * max(abs(f_ref), 1e-12):
        success = False
        message += (f"; internal model disagrees with the problem: objective {f:.9g} vs "
                    f"{f_ref:.9g}")
    elapsed = time.perf_counter() - t0
    log.debug("%s: exact axis solve %d it, J=%.6g, kkt=%.2g, %.2f ms", prob.name, it, f_ref, kkt,
              1e3 * elapsed)
    return SolveReport(x, f_ref, "exact", success, elapsed, it, message,
                       {"kkt_residual": kkt, "gradient_scale": g_ref,
                        "convex_model_steps": nt.convex_models, "banded_solves": nt.solves,
                        "safeguard_steps": nt.safeguard_steps, "fallback": bool(fallback)})
