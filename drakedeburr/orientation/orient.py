"""Orientation stage entry point: ClPath + inner-side normals -> ToolPath."""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from pydrake.math import RigidTransform

from drakedeburr.config import OrientationBounds, ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.frames.contact_frames import FULL_TURN_SLOPE, steep_contact_frames
from drakedeburr.frames.local_frames import R_HL_from_normals, axis_from_angles
from drakedeburr.frames.vectors import angle_between
from drakedeburr.orientation.corner_normals import side_consistent_normals
from drakedeburr.orientation.exact import ExactOptions, SolveReport, solve_exact
from drakedeburr.orientation.models import ModelName, OrientationProblem, make_problem
from drakedeburr.orientation.pso import PsoOptions, pso_minimize
from drakedeburr.orientation.smoothing import gaussian_smooth_mirror
from drakedeburr.orientation.stats import angle_statistics
from drakedeburr.orientation.types import ToolPath
from drakedeburr.path.types import ClPath

__all__ = ["OrientOptions", "SolverName", "orient_window", "solve_problem", "problem_for",
           "cone_half_angles", "tool_path_summary"]

log = logging.getLogger(__name__)

SolverName = Literal["exact", "pso"]


@dataclass(frozen=True)
class OrientOptions:
    """Solver settings of the orientation stage.

    Attributes:
        second_difference_weight: axis model second-difference weight [m^2] (0 = off).
        smooth: Gaussian smoothing with mirror padding after the solve; None = as the source
            does for PSO (True) and not after the exact solver (False: it would only move an
            optimum away from optimality).
        smooth_sigma: kernel standard deviation [CL points] (the source gives no value).
        pso: swarm settings (source: 50, 200, 0.8, 2, 2; seeded).
        exact: sequential-convex settings.
        max_frame_slope: [rad] where the edge's slope to the face plane (X_H Y_H) exceeds this
            (issue 42: a real wheel's loop descends spoke flanks at 45-90 deg, where an axis
            perpendicular to the edge leans 45-90 deg off the hub axis), the local frame is the
            source's turned about the edge bisector by the conical burr's contact rule
            (:mod:`drakedeburr.frames.contact_frames`): the box centre nearest +Z_H with every
            box axis >= 45 deg (the burr's half-angle) from the edge line. Loops within it
            (every bundled hub: <= 43.5 deg) keep the source's frames bit for bit.
        full_frame_slope: [rad] from this slope up the contact rule's turn applies in full;
            between ``max_frame_slope`` and here a smoothstep share of it
            (:func:`drakedeburr.frames.contact_frames.turn_share`), so that the frame does
            not jump where a loop passes ``max_frame_slope``.
    """

    second_difference_weight: float = 0.0
    max_frame_slope: float = math.radians(45.0)
    full_frame_slope: float = FULL_TURN_SLOPE
    smooth: bool | None = None
    smooth_sigma: float = 2.0
    pso: PsoOptions = field(default_factory=PsoOptions)
    exact: ExactOptions = field(default_factory=ExactOptions)


def slope_limited_tangents(t_H: np.ndarray, n_H: np.ndarray, max_slope: float) -> np.ndarray:
    """(M, 3) unit tangents ``t_H`` (M, 3) with their slope to the X_H Y_H plane limited to
    ``max_slope`` [rad], keeping the sign of their climb. The plan direction of a limited
    tangent is ``n x Z_H`` of its inner-side normal ``n_H`` (along a CCW loop, across the
    normal: the plan direction of a steep tangent itself is noise, and one along the normal
    would fold the frame). Without a steep tangent ``t_H`` itself is returned (bit for bit)."""
    t = np.asarray(t_H, float) / np.linalg.norm(t_H, axis=1, keepdims=True)
    slope = np.arcsin(np.clip(np.abs(t[:, 2]), 0.0, 1.0))
    steep = slope > max_slope
    if not steep.any():  # the input itself, not its re-normalised copy: a flat loop's frames
        return np.asarray(t_H, float)  # are bit for bit those before the limit existed
    h = np.cross(np.asarray(n_H, float)[steep], [0.0, 0.0, 1.0])
    h[:, 2] = 0.0
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-12)
    out = t.copy()
    out[steep] = (math.cos(max_slope) * h
                  + math.sin(max_slope) * np.sign(t[steep, 2])[:, None] * np.array([0, 0, 1.0]))
    return out


def _bounds_for(kind: str, params: ProcessParameters) -> OrientationBounds:
    return params.bounds_large if kind == "large" else params.bounds_small


def problem_for(cl: ClPath, R_HL: np.ndarray, model: ModelName = "axis",
                params: ProcessParameters | None = None,
                options: OrientOptions = OrientOptions()) -> OrientationProblem:
    """The orientation problem of one window (bounds from its kind)."""
    params = params or ProcessParameters()
    b = _bounds_for(cl.kind, params)
    return make_problem(model, cl.p_HC, R_HL, b, w1=params.w1, w2=params.w2,
                        second_difference_weight=options.second_difference_weight,
                        name=f"window {cl.window_index}")


def solve_problem(prob: OrientationProblem, solver: SolverName = "exact",
                  options: OrientOptions = OrientOptions(),
                  x0: np.ndarray | None = None) -> SolveReport:
    """Solve ``prob`` with the exact solver or the PSO baseline (+ optional smoothing).

    The reported objective and seconds are those of the returned angles, smoothing included.
    """
    smooth = options.smooth if options.smooth is not None else (solver == "pso")
    t0 = time.perf_counter()
    if solver == "exact":
        rep = solve_exact(prob, x0=x0, options=options.exact)
        x, info, success, msg, it = rep.x, dict(rep.info), rep.success, rep.message, rep.iterations
    elif solver == "pso":
        pr = pso_minimize(prob.objective, prob.lower, prob.upper, options.pso, x0=x0)
        x, info, success, it = pr.x, {"evaluations": pr.evaluations}, True, options.pso.iterations
        msg = f"PSO {options.pso.particles} particles x {options.pso.iterations} iterations"
    else:
        raise InputError(f"{prob.name}: unknown solver {solver!r}; use 'exact' or 'pso'")
    objective = float(rep.objective if solver == "exact" else pr.objective)  # of x, unsmoothed
    info["objective_raw"] = objective
    if smooth:
        th = gaussian_smooth_mirror(x.reshape(prob.m, 2), options.smooth_sigma)
        x = np.clip(th.reshape(-1), prob.lower, prob.upper)
        msg += f"; Gaussian smoothing (mirror padding, sigma {options.smooth_sigma:g} points)"
        objective = float(prob.objective(x))
    elapsed = time.perf_counter() - t0
    success = success and bool(prob.in_bounds(x).all())
    return SolveReport(x, objective, solver, success, elapsed, it, msg, info)


def cone_half_angles(bounds: OrientationBounds, samples: int = 64) -> tuple[float, float]:
    """(inner, outer) half-angles [rad] of cones about the box-centre axis: the largest cone
    inside the (theta_A, theta_B) box and the smallest containing it (frame independent)."""
    lo, hi = bounds.theta_min, bounds.theta_max
    c = 0.5 * (lo + hi)
    s = np.linspace(lo, hi, samples)
    edge_a = np.concatenate([s, s, np.full(samples, lo), np.full(samples, hi)])
    edge_b = np.concatenate([np.full(samples, lo), np.full(samples, hi), s, s])
    v = axis_from_angles(edge_a, edge_b)
    ang = angle_between(v, axis_from_angles(c, c))
    # the boundary's closest point may lie between samples: shrink by the sampling step
    step = (hi - lo) / (samples - 1)
    return float(ang.min() - step), float(ang.max())


def orient_window(
    cl: ClPath,
    n_H: np.ndarray,
    *,
    X_WH: RigidTransform | None = None,
    model: ModelName = "axis",
    solver: SolverName = "exact",
    params: ProcessParameters | None = None,
    options: OrientOptions = OrientOptions(),
    x0: np.ndarray | None = None,
) -> ToolPath:
    """Choose the tool axis at every CL point of one window.

    Args:
        cl: the window's CL points (H frame).
        n_H: (M, 3) inner-side normals at the CL points (out of the material into the
            opening), e.g. from :func:`drakedeburr.frames.normals.inner_normals_from_cloud`.
        X_WH: hub pose in world (default identity); only stored, the solve is in H.
        model: "axis" (default) or "paper" (eq. 11 literally).
        solver: "exact" (default) or "pso" (the source's baseline).
        params: process parameters (bounds, weights, depth of cut); default ProcessParameters().
        options: solver settings.
        x0: optional warm start (2M,) [theta_A_0, theta_B_0, ...] [rad].

    Returns:
        ToolPath; ``success`` False (with a message) when the solver's checks fail.
    """
    params = params or ProcessParameters()
    n = np.asarray(n_H, float)
    if n.shape != cl.p_HC.shape:
        raise InputError(f"window {cl.window_index}: n_H has shape {n.shape}, "
                         f"expected {cl.p_HC.shape} (one normal per CL point)")
    t_frame = slope_limited_tangents(cl.t_H, n, options.max_frame_slope)
    # a CL point beside a tessellated corner may carry the wall normal of the corner's other
    # side (the frame upside down): it gets its neighbour's (orientation.corner_normals)
    n, fixed = side_consistent_normals(t_frame, n)
    if fixed:
        log.debug("window %d: inner normal from across a corner at CL %s: the neighbour's "
                  "carried over", cl.window_index, fixed)
    name = f"window {cl.window_index}"
    bounds = _bounds_for(cl.kind, params)
    # steep stretches: the source's frame on the true tangent turned about the edge bisector
    # toward the box centre nearest +Z_H with every box axis touching with the flank, by a
    # share growing from 0 at max_frame_slope to 1 at full_frame_slope
    # (frames.contact_frames); the same array when nothing is steep
    R_HL = steep_contact_frames(R_HL_from_normals(t_frame, n, name=name), cl.t_H, n,
                                bounds.theta_min, bounds.theta_max, options.max_frame_slope,
                                options.full_frame_slope, name=name)
    prob = problem_for(cl, R_HL, model, params, options)
    rep = solve_problem(prob, solver, options, x0=x0)
    th = rep.x.reshape(prob.m, 2)
    zT_H = prob.axes(rep.x)
    c = 0.5 * (bounds.theta_min + bounds.theta_max)
    cone_zT_H = prob.axes(np.full(prob.n_vars, c))
    inner, outer = cone_half_angles(bounds)
    stats = angle_statistics(th[:, 0], th[:, 1], cl.p_HC, zT_H)
    stats["solver_info"] = {**rep.info, "iterations": rep.iterations}
    depth = params.depth_of_cut_large if cl.kind == "large" else params.depth_of_cut_small
    log.debug("window %d: %s/%s objective %.6g in %.1f ms (%s)", cl.window_index, model, solver,
             rep.objective, 1e3 * rep.solve_seconds, rep.message)
    return ToolPath(
        window_index=cl.window_index, kind=cl.kind, cl_path=cl,
        X_WH=RigidTransform() if X_WH is None else RigidTransform(X_WH),
        p_HC=np.asarray(cl.p_HC, float), R_HL=R_HL, zT_H=zT_H,
        theta_A=th[:, 0].copy(), theta_B=th[:, 1].copy(), bounds=bounds,
        cone_zT_H=cone_zT_H, cone_half_angle=inner, cone_outer_half_angle=outer,
        depth_of_cut=depth, model=model, solver=solver, objective=rep.objective,
        success=rep.success, solve_seconds=rep.solve_seconds, stats=stats, message=rep.message,
    )


def tool_path_summary(tp: ToolPath) -> dict:
    """JSON-ready summary of one window's ToolPath (angles in rad, lengths in mm)."""
    return {
        "window": tp.window_index,
        "kind": tp.kind,
        "n_points": len(tp),
        "model": tp.model,
        "solver": tp.solver,
        "objective": tp.objective,
        "solve_seconds": tp.solve_seconds,
        "success": tp.success,
        "message": tp.message,
        "bounds_rad": [tp.bounds.theta_min, tp.bounds.theta_max],
        "cone_half_angle_rad": tp.cone_half_angle,
        "cone_outer_half_angle_rad": tp.cone_outer_half_angle,
        "depth_of_cut_mm": tp.depth_of_cut * 1e3,
        "theta_A": tp.stats["theta_A"],
        "theta_B": tp.stats["theta_B"],
        "axis_turn_deg_per_mm": tp.stats["axis_turn_deg_per_mm"],
        "axis_turn_total_deg": tp.stats["axis_turn_total_deg"],
        "solver_info": tp.stats.get("solver_info", {}),
    }
