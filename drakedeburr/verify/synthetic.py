"""A reference plan built by analytic construction, consistent by design: a yardstick for the
verifier (tests, tutorial, benchmark) that does not depend on the planner.

What it builds, for chosen windows of a bundled hub in a cell:

* CL points on the hub's ground-truth window edge, chosen greedily so that every chord keeps
  the chord-height error below ``chord_height`` and the chord length below ``l_max``;
* local frames ``R_HL = [N, T, B]`` from the edge's tangent and inner-side normal; one fixed
  tool axis per window (default +Z_H) whose (theta_A, theta_B) range, widened by a margin,
  becomes the window's box (or, on request, fixed angles in the local frame and the process
  bounds); a spin transported without twist along the edge;
* the cutting point T offset from the CL point by the burr's contact radius along the inner
  normal (in the plane normal to the axis): the flank's nominal contact circle touches the edge;
* the Cartesian program: home, per window a joint move to a point ``retract`` above the first CL
  point, a linear approach, linear moves around the closed edge, a linear retract; home again;
* the joint trajectory: the linear moves sampled every ``sample_step`` of tool travel, solved by
  Newton iterations on the Drake plant (warm started along the path), timed at the grinding
  speed with smooth (raised-cosine) speed ramps where the tool stops, and joint moves as cubic
  Hermite pieces with zero end velocities, slow enough for the joint and speed limits.

The knots lie exactly on the program (IK to 1e-12 m), so the trajectory agrees with the program
to the Hermite interpolation error between knots (well below the 0.05 mm tolerance). It is not a
planner: it does not optimise the axis inside the cone and does not avoid collisions.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from drakedeburr.config import OrientationBounds, ProcessParameters
from drakedeburr.frames.local_frames import (
    R_HL_from_normals,
    angles_from_zT_H,
    axis_from_angles,
)
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment

__all__ = ["reference_plan", "ReferenceOptions", "greedy_cl_indices", "solve_pose_newton"]

log = logging.getLogger(__name__)


def greedy_cl_indices(p: np.ndarray, chord_height: float, l_max: float) -> np.ndarray:
    """Indices into a closed polyline so that each chord stays within both limits.

    Args:
        p: (N, 3) closed loop points [m] (first point not repeated).
        chord_height: largest distance of skipped points from their chord [m].
        l_max: longest chord [m].

    Returns:
        (M,) increasing indices starting at 0.
    """
    n = len(p)
    out = [0]
    i = 0
    while True:
        j = i + 1
        best = j
        while j <= n:
            a, b = p[i % n], p[j % n]
            ab = b - a
            length = float(np.linalg.norm(ab))
            if length > l_max:
                break
            mid = p[[k % n for k in range(i + 1, j)]]
            if len(mid):
                u = ab / max(length, 1e-15)
                d = mid - a
                h = np.linalg.norm(d - np.outer(d @ u, u), axis=1).max()
                if h > chord_height:
                    break
            best = j
            j += 1
        if best >= n:
            break
        out.append(best)
        i = best
    return np.asarray(out, int)


def _rotation_log(R: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_rotvec()


def solve_pose_newton(cell, X_HT: np.ndarray, q0: np.ndarray, *, iterations: int = 20,
                      tol: float = 1e-12, context=None) -> tuple[np.ndarray, float]:
    """Joints putting tool frame T at ``X_HT`` relative to the hub frame H, by Newton steps.

    Args:
        cell: a :class:`drakedeburr.cell.Cell`.
        X_HT: (4, 4) wanted pose of T in H [m].
        q0: (6,) start [rad] (close to the answer: this is a local method).
        context: a plant context to reuse (default: a new one).

    Returns:
        (q, residual): joints [rad] and the final pose error (rotation [rad] + position [m]).
    """
    from pydrake.multibody.tree import JacobianWrtVariable

    plant = cell.plant
    context = context if context is not None else plant.CreateDefaultContext()
    q = np.array(q0, float)
    err = np.inf
    for _ in range(iterations):
        plant.SetPositions(context, q)
        X = cell.tool_frame.CalcPose(context, cell.hub_frame)
        R, p = X.rotation().matrix(), X.translation()
        e = np.concatenate([_rotation_log(X_HT[:3, :3] @ R.T), X_HT[:3, 3] - p])
        err = float(np.linalg.norm(e))
        if err < tol:
            break
        J = plant.CalcJacobianSpatialVelocity(context, JacobianWrtVariable.kQDot, cell.tool_frame,
                                              np.zeros(3), cell.hub_frame, cell.hub_frame)
        q = q + np.linalg.solve(J, e)
    return q, err


def _ik_drake(cell, X_HT: np.ndarray, q_seed: np.ndarray, context) -> np.ndarray:
    """Global-ish IK for the first pose of a window (position + orientation, from a seed)."""
    from pydrake.math import RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import Solve

    ik = InverseKinematics(cell.plant)
    ik.AddPositionConstraint(cell.tool_frame, np.zeros(3), cell.hub_frame,
                             X_HT[:3, 3] - 1e-6, X_HT[:3, 3] + 1e-6)
    ik.AddOrientationConstraint(cell.hub_frame, RotationMatrix(X_HT[:3, :3]), cell.tool_frame,
                                RotationMatrix(), 1e-4)
    lo, hi = np.asarray(cell.q_lower), np.asarray(cell.q_upper)
    q = ik.q()
    prog = ik.get_mutable_prog()
    prog.AddBoundingBoxConstraint(lo, hi, q)
    prog.AddQuadraticErrorCost(np.eye(6), q_seed, q)
    wrist = prog.AddBoundingBoxConstraint(-np.inf, np.inf, q[4])
    seeds = [np.asarray(q_seed, float), np.asarray(cell.q_home, float)]
    # keep the wrist away from J5 = 0, on the seed's side first
    first = 1.0 if q_seed[4] >= 0 else -1.0
    for seed in seeds:
        for sign in (first, -first):
            if sign > 0:
                wrist.evaluator().UpdateLowerBound([0.2])
                wrist.evaluator().UpdateUpperBound([hi[4]])
            else:
                wrist.evaluator().UpdateLowerBound([lo[4]])
                wrist.evaluator().UpdateUpperBound([-0.2])
            prog.SetInitialGuess(q, seed)
            result = Solve(prog)
            if result.is_success():
                q_sol, err = solve_pose_newton(cell, X_HT, result.GetSolution(q),
                                               context=context)
                if err <= 1e-9:
                    return q_sol
    raise RuntimeError("reference_plan: no IK solution for a window's first pose")


def _ramp_times(s: np.ndarray, length: float, v: float, t_ramp: float,
                ramp_in: bool, ramp_out: bool) -> tuple[np.ndarray, np.ndarray, float]:
    """Times and speeds at arc lengths ``s`` of a move of ``length`` at cruise speed ``v``.

    Speed ramps are raised cosines of duration ``t_ramp`` (distance v t_ramp / 2 each), at the
    start and/or end. Returns (t (N,), sdot (N,), duration).
    """
    d_ramp = 0.5 * v * t_ramp
    n_ramps = int(ramp_in) + int(ramp_out)
    if n_ramps and n_ramps * d_ramp > length:  # short move: shrink the ramps
        t_ramp = length / (n_ramps * 0.5 * v)
        d_ramp = 0.5 * v * t_ramp
    t_cruise = (length - n_ramps * d_ramp) / v
    duration = n_ramps * t_ramp + t_cruise

    def s_of_t(t):
        t = np.asarray(t, float)
        out = np.zeros_like(t)
        t1 = t_ramp if ramp_in else 0.0
        # ramp in: s = v/2 (t - t_r/pi sin(pi t / t_r))
        if ramp_in:
            m = t < t1
            out[m] = 0.5 * v * (t[m] - t_ramp / np.pi * np.sin(np.pi * t[m] / t_ramp))
        s1 = d_ramp if ramp_in else 0.0
        m = (t >= t1) & (t <= t1 + t_cruise)
        out[m] = s1 + v * (t[m] - t1)
        if ramp_out:
            t2 = t1 + t_cruise
            m = t > t2
            tau = t[m] - t2
            out[m] = s1 + v * t_cruise + 0.5 * v * (
                tau + t_ramp / np.pi * np.sin(np.pi * tau / t_ramp))
        return out

    def sdot_of_t(t):
        t = np.asarray(t, float)
        out = np.full_like(t, v)
        if ramp_in:
            m = t < t_ramp
            out[m] = 0.5 * v * (1 - np.cos(np.pi * t[m] / t_ramp))
        if ramp_out:
            t2 = duration - t_ramp
            m = t > t2
            out[m] = 0.5 * v * (1 + np.cos(np.pi * (t[m] - t2) / t_ramp))
        return out

    # invert s(t) on a fine grid (monotone)
    tg = np.linspace(0.0, duration, max(2000, int(duration / 1e-4)))
    sg = s_of_t(tg)
    t = np.interp(np.clip(s, 0, length), sg, tg)
    return t, sdot_of_t(t), duration


def _interp_pose(X0: np.ndarray, X1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(N, 4, 4) poses on the linear move X0 -> X1 (position linear, orientation slerp)."""
    from scipy.spatial.transform import Rotation, Slerp

    rots = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([X0[:3, :3], X1[:3, :3]])))(f)
    out = np.tile(np.eye(4), (len(f), 1, 1))
    out[:, :3, :3] = rots.as_matrix()
    out[:, :3, 3] = X0[:3, 3] + np.outer(f, X1[:3, 3] - X0[:3, 3])
    return out


@dataclass(frozen=True)
class ReferenceOptions:
    """Settings of :func:`reference_plan` (see its docstring for each)."""

    theta: dict[int, tuple[float, float]] | None = None
    cl_chord_height: float = 0.01e-3
    retract: float = 0.04
    sample_step: float = 1e-3
    ramp_time: float | None = None
    spin_direction_H: tuple[float, float, float] = (1.0, 0.0, 0.0)
    contact_radius: float = 1.5e-3
    bounds: OrientationBounds | None = None
    fixed_retract_H: tuple[float, float, float] = (0.0, 0.0, 1.0)
    box_margin: float = 0.05
    axis_tilt: dict[int, float] | None = None


class _Builder:
    """The program and the knots of a reference plan, built move by move."""

    def __init__(self, cell, params: ProcessParameters, opt: ReferenceOptions) -> None:
        self.cell, self.params, self.opt = cell, params, opt
        self.context = cell.plant.CreateDefaultContext()
        self.targets: list[CartesianTarget] = []
        self.segments: list[PlanSegment] = []
        self.t: list[float] = []
        self.q: list[np.ndarray] = []
        self.qd: list[np.ndarray] = []

    def add_target(self, window, kind, cl_index, X_HT, q, speed) -> None:
        # home and transition targets are reached by joint moves (MoveAbsJ / PTP / J)
        self.targets.append(CartesianTarget(
            window_index=window, segment=kind, cl_index=cl_index,
            X_HT=np.asarray(X_HT, float), X_WF=self.cell.X_WF(q).GetAsMatrix4(),
            q=np.asarray(q, float).copy(), speed=float(speed),
            motion="joint" if kind in ("home", "transition") else "linear"))

    def add_segment(self, window: int, kind: str, k0: int, t0: float) -> None:
        self.segments.append(PlanSegment(window, kind, (k0, len(self.targets)), (t0, self.t[-1])))

    def append_knots(self, t, q, qd) -> None:
        t0 = self.t[-1] if self.t else 0.0
        for i in range(1 if self.t else 0, len(t)):  # the first knot repeats the previous end
            self.t.append(t0 + float(t[i]))
            self.q.append(np.asarray(q[i], float))
            self.qd.append(np.asarray(qd[i], float))

    def joint_move(self, q_to, v_tcp) -> float:
        """A cubic joint move from the last knot, slow enough for the joint and TCP limits."""
        cell = self.cell
        q_from = self.q[-1]
        dq = np.abs(q_to - q_from)
        v_lim = 0.8 * np.asarray(cell.v_upper)
        a_lim = 0.8 * np.asarray(cell.a_upper)
        T = max(0.2, float(np.max(1.5 * dq / v_lim)), float(np.max(np.sqrt(6 * dq / a_lim))))
        for _ in range(30):  # lengthen until the TCP speed keeps below 90 % of the limit
            sig = 3 * np.linspace(0, 1, 101) ** 2 - 2 * np.linspace(0, 1, 101) ** 3
            p = np.array([cell.X_HT(q_from + (q_to - q_from) * s).translation() for s in sig])
            if np.linalg.norm(np.diff(p, axis=0), axis=1).max() / (T / 100) <= 0.9 * v_tcp:
                break
            T *= 1.2
        self.append_knots(np.array([0.0, T]), np.stack([q_from, q_to]), np.zeros((2, 6)))
        return T

    def linear_chain(self, poses: list[np.ndarray], v: float, q_start: np.ndarray):
        """Linear moves through ``poses`` at speed v, stopping at both ends. Returns the joints
        at every pose."""
        from scipy.interpolate import CubicSpline

        Xs, s_acc, at_target = [poses[0]], [0.0], [0]
        for X0, X1 in zip(poses[:-1], poses[1:], strict=True):
            length = float(np.linalg.norm(X1[:3, 3] - X0[:3, 3]))
            n = max(1, int(np.ceil(length / self.opt.sample_step)))
            f = np.arange(1, n + 1) / n
            Xs.extend(_interp_pose(X0, X1, f))
            s_acc.extend(s_acc[-1] + f * length)
            at_target.append(len(Xs) - 1)
        s_acc = np.asarray(s_acc)
        q = np.zeros((len(Xs), 6))
        prev = q_start
        for i, X in enumerate(Xs):
            prev, err = solve_pose_newton(self.cell, X, prev, context=self.context)
            if err > 1e-9:
                raise RuntimeError(f"reference_plan: Newton IK failed ({err:.3g}) on a linear move")
            q[i] = prev
        # raised-cosine ramps whose peak acceleration (pi v / (2 t_ramp)) is the process's TCP
        # acceleration: the plan starts and stops as fast as the process allows
        t_ramp = self.opt.ramp_time or np.pi * v / (2.0 * self.params.tcp_acceleration)
        t, sdot, _ = _ramp_times(s_acc, s_acc[-1], v, t_ramp, True, True)
        # slopes from a C2 spline through the IK samples: consistent knot velocities keep the
        # Hermite pieces' accelerations at the path's own (corner) curvature
        qd = CubicSpline(s_acc, q, axis=0)(s_acc, 1) * sdot[:, None]
        qd[0] = 0.0
        qd[-1] = 0.0
        self.append_knots(t, q, qd)
        return q[at_target]


def _window_axes(w: int, edge, R_HL: np.ndarray, params, opt: ReferenceOptions):
    """-> (retract_H (M, 3) tip -> spindle, theta_A, theta_B, box, cone axis +Z_T, inner, outer)."""
    from drakedeburr.orientation.orient import cone_half_angles

    m = len(R_HL)
    if opt.theta is not None and w in opt.theta:
        # the source's way: fixed angles in the local frame (the axis swings with it)
        box = opt.bounds or params.bounds(edge.kind)
        a, b = opt.theta[w]
        retract_H = -(R_HL @ axis_from_angles(a, b))
        th_A, th_B = np.full(m, a), np.full(m, b)
    else:
        # one fixed axis per window: no swing, so the joints stay slow at any feed
        fixed = np.asarray(opt.fixed_retract_H, float)
        retract_H = np.tile(fixed / np.linalg.norm(fixed), (m, 1))
        th_A, th_B = angles_from_zT_H(R_HL, -retract_H)
        box = opt.bounds or OrientationBounds(
            float(min(th_A.min(), th_B.min())) - opt.box_margin,
            float(max(th_A.max(), th_B.max())) + opt.box_margin)
    mid = 0.5 * (box.theta_min + box.theta_max)
    cone_zT_H = R_HL @ axis_from_angles(mid, mid)  # +Z_T, the ToolPath convention
    inner, outer = cone_half_angles(box)
    if not (opt.theta is not None and w in opt.theta):
        # the reference plan's admissible cone: 0.1 rad about its fixed axis
        cone_zT_H = -retract_H.copy()
        inner = outer = 0.1
        tilt = (opt.axis_tilt or {}).get(w, 0.0)
        if tilt:
            from scipy.spatial.transform import Rotation

            retract_H = Rotation.from_rotvec([0.0, tilt, 0.0]).apply(retract_H)
    return retract_H, th_A, th_B, box, cone_zT_H, inner, outer


def _window_tool_path(w: int, edge, idx: np.ndarray, X_WH, params, opt: ReferenceOptions):
    """The window's ToolPath (CL points on the true edge, local frames, the reference axes)."""
    from pydrake.math import RigidTransform

    from drakedeburr.orientation.types import ToolPath
    from drakedeburr.path.types import ClPath

    p_HC = edge.p_HE[idx]
    t_H = edge.t_H[idx] / np.linalg.norm(edge.t_H[idx], axis=1, keepdims=True)
    # the project's local frames and angle convention (drakedeburr.frames.local_frames)
    R_HL = R_HL_from_normals(t_H, edge.n_wall_H[idx], name=f"window {w}")
    retract_H, th_A, th_B, box, cone_zT_H, inner, outer = _window_axes(w, edge, R_HL, params, opt)
    seg = np.linalg.norm(np.diff(np.vstack([edge.p_HE, edge.p_HE[:1]]), axis=0), axis=1)
    arc_all = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(arc_all[-1])
    cl = ClPath(window_index=w, kind=edge.kind, method="reference_greedy",
                u=arc_all[idx] / total, p_HC=p_HC, t_H=t_H, kappa=np.zeros(len(idx)),
                arc_length=arc_all[idx], total_length=total, metrics={})
    return ToolPath(
        window_index=w, kind=edge.kind, cl_path=cl, X_WH=RigidTransform(X_WH), p_HC=p_HC,
        R_HL=R_HL, zT_H=-retract_H, theta_A=th_A, theta_B=th_B,
        bounds=box, cone_zT_H=cone_zT_H, cone_half_angle=inner,
        cone_outer_half_angle=outer, depth_of_cut=params.depth_of_cut(edge.kind),
        model="reference", solver="none", objective=0.0, success=True, solve_seconds=0.0,
        stats={}, message="reference plan (fixed angles)")


def _window_poses(tp, opt: ReferenceOptions) -> tuple[np.ndarray, np.ndarray]:
    """Tool poses at the CL points and the loop's closing pose: spin by parallel transport (no
    twist about the axis) from ``opt.spin_direction_H``; the edge touches the flank at radius
    ``opt.contact_radius`` (T sits on the axis at that circle's height)."""
    from drakedeburr.cell.tools import BURR

    z_T, N, p_HC = tp.zT_H, tp.R_HL[:, :, 0], tp.p_HC
    m = len(p_HC)
    X_HT = np.tile(np.eye(4), (m, 1, 1))
    x = np.asarray(opt.spin_direction_H, float).copy()
    # the flank point at radius r lies (apex - r/tan) along +Z_T from the apex
    dz = (BURR.contact_radius - opt.contact_radius) / np.tan(BURR.cone_half_angle)
    for i in range(m):
        x = x - (x @ z_T[i]) * z_T[i]
        x /= np.linalg.norm(x)
        n_perp = N[i] - (N[i] @ z_T[i]) * z_T[i]
        n_perp /= np.linalg.norm(n_perp)
        X_HT[i, :3, :3] = np.column_stack([x, np.cross(z_T[i], x), z_T[i]])
        X_HT[i, :3, 3] = p_HC[i] + opt.contact_radius * n_perp - dz * z_T[i]
    # closing the loop: the last move returns to CL point 0 with the transported spin
    x = x - (x @ z_T[0]) * z_T[0]
    x /= np.linalg.norm(x)
    X_close = X_HT[0].copy()
    X_close[:3, :3] = np.column_stack([x, np.cross(z_T[0], x), z_T[0]])
    return X_HT, X_close


def _add_window(b: _Builder, w: int, tp, X_HT: np.ndarray, X_close: np.ndarray) -> None:
    """Transition, approach, the closed cut and the retract of one window."""
    params, retract = b.params, b.opt.retract
    up = -tp.zT_H[0]
    X_up = X_HT[0].copy()
    X_up[:3, 3] += retract * up
    X_end_up = X_close.copy()
    X_end_up[:3, 3] += retract * up
    k0, t0 = len(b.targets), b.t[-1]
    q_up = _ik_drake(b.cell, X_up, b.q[-1], b.context)
    b.joint_move(q_up, params.window_switch_speed)
    b.add_target(-1, "transition", -1, X_up, q_up, params.window_switch_speed)
    b.add_segment(-1, "transition", k0, t0)
    k0, t0 = len(b.targets), b.t[-1]
    qs = b.linear_chain([X_up, X_HT[0]], params.grinding_speed, q_up)
    b.add_target(w, "approach", 0, X_HT[0], qs[-1], params.grinding_speed)
    b.add_segment(w, "approach", k0, t0)
    k0, t0 = len(b.targets), b.t[-1]
    loop = [X_HT[i] for i in range(len(X_HT))] + [X_close]
    qs = b.linear_chain(loop, params.grinding_speed, qs[-1])
    for i in range(1, len(loop)):
        b.add_target(w, "cut", i % len(X_HT), loop[i], qs[i], params.grinding_speed)
    b.add_segment(w, "cut", k0, t0)
    k0, t0 = len(b.targets), b.t[-1]
    qs = b.linear_chain([X_close, X_end_up], params.grinding_speed, qs[-1])
    b.add_target(w, "retract", -1, X_end_up, qs[-1], params.grinding_speed)
    b.add_segment(w, "retract", k0, t0)


def reference_plan(
    scenario: str,
    hub: str,
    windows: Sequence[int] | None = None,
    *,
    params: ProcessParameters,
    options: ReferenceOptions = ReferenceOptions(),
    progress: Callable[[int, int, str], None] | None = None,
) -> Plan:
    """Build the reference plan (see module docstring).

    Args:
        scenario: bundled scenario name or path.
        hub: bundled hub name or hub folder.
        windows: window indices to include (default: all, in index order).
        params: process parameters (speeds, bounds, depth of cut): the run's recipe.
        options (:class:`ReferenceOptions`):
            theta: optional {window: (theta_A, theta_B)} [rad]: that window's axis at these
                fixed angles in the local frame (the source's way; the axis then swings with
                the frame at every fillet, which at 150 mm/s exceeds the wrist's limits: see
                docs/verify.md). Other windows use ``fixed_retract_H``.
            cl_chord_height: chord-height error of the CL points [m].
            retract: approach/retract distance along the tool axis [m].
            sample_step: tool travel between trajectory knots on linear moves [m].
            ramp_time: duration of each speed ramp [s] (None: the raised cosine whose peak
                acceleration is the process's TCP acceleration).
            spin_direction_H: hub-frame direction +X_T starts from (then transported without
                twist along the edge).
            contact_radius: radius of the flank circle that touches the edge [m].
            bounds: (theta_A, theta_B) box written into every ToolPath (default: for ``theta``
                windows the kind's bounds from ``params``; otherwise the range the fixed axis
                spans, widened by ``box_margin`` [rad]).
            fixed_retract_H: tool axis (tip -> spindle) in H of the fixed-axis windows.
            axis_tilt: {window: angle [rad]}: tilt that window's axis about +Y_H *after* its
                box is set (a plan that must fail the cone check).
        progress: optional callback (done, total, label).

    Returns:
        A :class:`~drakedeburr.plan.types.Plan` with ``tool_path`` = {window: ToolPath}.
    """
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub.model import load_hub

    cell = load_cell(scenario, hub)
    hub_model = load_hub(hub)
    chosen = list(range(len(hub_model.windows))) if windows is None else list(windows)
    X_WH = cell.X_WH(cell.q_home).GetAsMatrix4()
    b = _Builder(cell, params, options)
    X_home = cell.X_HT(cell.q_home).GetAsMatrix4()
    b.add_target(-1, "home", -1, X_home, cell.q_home, params.home_speed)
    b.append_knots([0.0], [np.asarray(cell.q_home, float)], [np.zeros(6)])
    tool_paths = {}
    for n_done, w in enumerate(chosen):
        edge = hub_model.windows[w]
        idx = greedy_cl_indices(edge.p_HE, options.cl_chord_height, params.l_max)
        tool_paths[w] = tp = _window_tool_path(w, edge, idx, X_WH, params, options)
        _add_window(b, w, tp, *_window_poses(tp, options))
        if progress is not None:
            progress(n_done + 1, len(chosen), f"window {w}")
    k0, t0 = len(b.targets), b.t[-1]
    b.joint_move(np.asarray(cell.q_home, float), params.home_speed)
    b.add_target(-1, "home", -1, X_home, cell.q_home, params.home_speed)
    b.add_segment(-1, "home", k0, t0)
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(cell)
    trajectory = JointTrajectory.from_hermite(t=np.asarray(b.t), q=np.asarray(b.q),
                                              qd=np.asarray(b.qd))
    return Plan(scenario=str(scenario), hub=str(hub), mode=cell.mode, X_WH=X_WH,
                targets=tuple(b.targets), segments=tuple(b.segments), trajectory=trajectory,
                tool_path=tool_paths, failures=(),
                meta={"planner": "drakedeburr.verify.synthetic.reference_plan",
                      "windows": chosen, "robot": cell.arm.name, "X_FT": kin.X_FT.tolist(),
                      "X_FH": kin.X_FH.tolist(), "X_WT": kin.X_WT.tolist(),
                      "X_WB": kin.X_WB.tolist()})
