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

import numpy as np

from drakedeburr.config import OrientationBounds, ProcessParameters
from drakedeburr.frames.local_frames import (
    R_HL_from_normals,
    angles_from_axis_H,
    axis_from_angles,
)
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment

__all__ = ["reference_plan", "greedy_cl_indices", "solve_pose_newton"]

_PARAMS = ProcessParameters()

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
                      tol: float = 1e-12) -> tuple[np.ndarray, float]:
    """Joints putting tool frame T at ``X_HT`` relative to the hub frame H, by Newton steps.

    Args:
        cell: a :class:`drakedeburr.cell.Cell`.
        X_HT: (4, 4) wanted pose of T in H [m].
        q0: (6,) start [rad] (close to the answer: this is a local method).

    Returns:
        (q, residual): joints [rad] and the final pose error (rotation [rad] + position [m]).
    """
    from pydrake.multibody.tree import JacobianWrtVariable

    plant = cell.plant
    context = cell._cache.setdefault("newton_context", plant.CreateDefaultContext())
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


def _ik_drake(cell, X_HT: np.ndarray, q_seed: np.ndarray) -> np.ndarray:
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
                q_sol, err = solve_pose_newton(cell, X_HT, result.GetSolution(q))
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


def reference_plan(
    scenario: str = "tool_in_hand",
    hub: str = "h5_straight",
    windows: Sequence[int] | None = None,
    *,
    theta: dict[int, tuple[float, float]] | None = None,
    cl_chord_height: float = 0.01e-3,
    retract: float = 0.04,
    sample_step: float = 1e-3,
    ramp_time: float = 0.1,
    spin_direction_H: Sequence[float] = (1.0, 0.0, 0.0),
    contact_radius: float = 1.5e-3,
    bounds: OrientationBounds | None = None,
    fixed_axis_H: Sequence[float] = (0.0, 0.0, 1.0),
    box_margin: float = 0.05,
    axis_tilt: dict[int, float] | None = None,
    params: ProcessParameters = _PARAMS,
    progress: Callable[[int, int, str], None] | None = None,
) -> Plan:
    """Build the reference plan (see module docstring).

    Args:
        scenario: bundled scenario name or path.
        hub: bundled hub name or hub folder.
        windows: window indices to include (default: all, in index order).
        theta: optional {window: (theta_A, theta_B)} [rad]: that window's axis at these fixed
            angles in the local frame (the source's way; the axis then swings with the frame
            at every fillet, which at 150 mm/s exceeds the wrist's limits: see docs/verify.md).
            Other windows use ``fixed_axis_H``.
        cl_chord_height: chord-height error of the CL points [m].
        retract: approach/retract distance along the tool axis [m].
        sample_step: tool travel between trajectory knots on linear moves [m].
        ramp_time: duration of each speed ramp [s].
        spin_direction_H: hub-frame direction +X_T starts from (then transported without
            twist along the edge).
        bounds: (theta_A, theta_B) box written into every ToolPath (default: for ``theta``
            windows the kind's bounds from ``params``; otherwise the range the fixed axis
            spans, widened by ``box_margin``).
        fixed_axis_H: tool axis (tip -> spindle) in H of the fixed-axis windows.
        box_margin: [rad] margin of the data-derived box.
        axis_tilt: {window: angle [rad]}: tilt that window's axis about +Y_H *after* its box
            is set (a plan that must fail the cone check).
        contact_radius: radius of the flank circle that touches the edge [m] (below the
            burr's nominal contact radius keeps the shank farther from the edge).
        params: process parameters (speeds, bounds, depth of cut).
        progress: optional callback (done, total, label).

    Returns:
        A :class:`~drakedeburr.plan.types.Plan` with ``tool_path`` = {window: ToolPath}.
    """
    from drakedeburr.cell.station import load_cell
    from drakedeburr.cell.tools import BURR
    from drakedeburr.hub.model import load_hub
    from drakedeburr.orientation.orient import cone_half_angles
    from drakedeburr.orientation.types import ToolPath
    from drakedeburr.path.types import ClPath

    cell = load_cell(scenario, hub)
    hub_model = load_hub(hub)
    chosen = list(range(len(hub_model.windows))) if windows is None else list(windows)
    X_WH = cell.X_WH(cell.q_home).GetAsMatrix4()
    spin_H = np.asarray(spin_direction_H, float)

    targets: list[CartesianTarget] = []
    segments: list[PlanSegment] = []
    knots_t: list[float] = []
    knots_q: list[np.ndarray] = []
    knots_qd: list[np.ndarray] = []
    tool_paths = {}

    def X_WF(q):
        return cell.X_WF(q).GetAsMatrix4()

    def add_target(window, kind, cl_index, X_HT, q, speed):
        # home and transition targets are reached by joint moves (MoveAbsJ / PTP / J)
        targets.append(CartesianTarget(window_index=window, segment=kind, cl_index=cl_index,
                                       X_HT=np.asarray(X_HT, float), X_WF=X_WF(q),
                                       q=np.asarray(q, float).copy(), speed=float(speed),
                                       motion="joint" if kind in ("home", "transition")
                                       else "linear"))

    def append_knots(t, q, qd):
        t0 = knots_t[-1] if knots_t else 0.0
        start = 1 if knots_t else 0  # first knot duplicates the previous end
        for i in range(start, len(t)):
            knots_t.append(t0 + float(t[i]))
            knots_q.append(np.asarray(q[i], float))
            knots_qd.append(np.asarray(qd[i], float))

    def joint_move(q_to, v_tcp):
        q_from = knots_q[-1]
        dq = np.abs(q_to - q_from)
        v_lim = 0.8 * np.asarray(cell.v_upper)
        a_lim = 0.8 * np.asarray(cell.a_upper)
        T = max(0.2, float(np.max(1.5 * dq / v_lim)), float(np.max(np.sqrt(6 * dq / a_lim))))
        for _ in range(30):  # lengthen until the TCP speed keeps below 90 % of the limit
            tau = np.linspace(0, 1, 101)
            sig = 3 * tau**2 - 2 * tau**3
            p = np.array([cell.X_HT(q_from + (q_to - q_from) * s).translation() for s in sig])
            v = np.linalg.norm(np.diff(p, axis=0), axis=1).max() / (T / 100)
            if v <= 0.9 * v_tcp:
                break
            T *= 1.2
        append_knots(np.array([0.0, T]), np.stack([q_from, q_to]), np.zeros((2, 6)))
        return T

    def linear_chain(poses: list[np.ndarray], v: float, q_start: np.ndarray):
        """Linear moves through ``poses`` at speed v, stopping at both ends. Returns the joints
        at every pose."""
        # dense samples along each move
        Xs, s_acc, at_target = [poses[0]], [0.0], [0]
        for X0, X1 in zip(poses[:-1], poses[1:], strict=True):
            length = float(np.linalg.norm(X1[:3, 3] - X0[:3, 3]))
            n = max(1, int(np.ceil(length / sample_step)))
            f = np.arange(1, n + 1) / n
            Xs.extend(_interp_pose(X0, X1, f))
            s_acc.extend(s_acc[-1] + f * length)
            at_target.append(len(Xs) - 1)
        s_acc = np.asarray(s_acc)
        q = np.zeros((len(Xs), 6))
        prev = q_start
        for i, X in enumerate(Xs):
            prev, err = solve_pose_newton(cell, X, prev)
            if err > 1e-9:
                raise RuntimeError(f"reference_plan: Newton IK failed ({err:.3g}) on a linear move")
            q[i] = prev
        t, sdot, _ = _ramp_times(s_acc, s_acc[-1], v, ramp_time, True, True)
        # slopes from a C2 spline through the IK samples: consistent knot velocities keep the
        # Hermite pieces' accelerations at the path's own (corner) curvature
        from scipy.interpolate import CubicSpline

        dq_ds = CubicSpline(s_acc, q, axis=0)(s_acc, 1)
        qd = dq_ds * sdot[:, None]
        qd[0] = 0.0
        qd[-1] = 0.0
        append_knots(t, q, qd)
        return q[at_target]

    # start at home, at rest
    add_target(-1, "home", -1, cell.X_HT(cell.q_home).GetAsMatrix4(), cell.q_home,
               params.home_speed)
    knots_t.append(0.0)
    knots_q.append(np.asarray(cell.q_home, float))
    knots_qd.append(np.zeros(6))

    for n_done, w in enumerate(chosen):
        edge = hub_model.windows[w]
        idx = greedy_cl_indices(edge.p_HE, cl_chord_height, params.l_max)
        p_HC = edge.p_HE[idx]
        t_H = edge.t_H[idx] / np.linalg.norm(edge.t_H[idx], axis=1, keepdims=True)
        n_H = edge.n_wall_H[idx]
        # the project's local frames and angle convention (drakedeburr.frames.local_frames)
        R_HL = R_HL_from_normals(t_H, n_H, name=f"window {w}")
        N = R_HL[:, :, 0]
        if theta is not None and w in theta:
            # the source's way: fixed angles in the local frame (the axis swings with it)
            box = bounds or (params.bounds_large if edge.kind == "large" else params.bounds_small)
            a, b = theta[w]
            up_H = -(R_HL @ axis_from_angles(a, b))  # tip -> spindle
            th_A, th_B = np.full(len(idx), a), np.full(len(idx), b)
        else:
            # one fixed axis per window: no swing, so the joints stay slow at any feed
            up_H = np.tile(np.asarray(fixed_axis_H, float) / np.linalg.norm(fixed_axis_H),
                           (len(idx), 1))
            th_A, th_B = angles_from_axis_H(R_HL, -up_H)
            if bounds is not None:
                box = bounds
            else:
                box = OrientationBounds(float(min(th_A.min(), th_B.min())) - box_margin,
                                        float(max(th_A.max(), th_B.max())) + box_margin)
        mid = 0.5 * (box.theta_min + box.theta_max)
        cone_axis_H = R_HL @ axis_from_angles(mid, mid)  # +Z_T, the ToolPath convention
        inner, outer = cone_half_angles(box)
        if not (theta is not None and w in theta):
            # the reference plan's admissible cone: 0.1 rad about its fixed axis
            cone_axis_H = -up_H.copy()
            inner = outer = 0.1
            tilt = (axis_tilt or {}).get(w, 0.0)
            if tilt:
                from scipy.spatial.transform import Rotation

                up_H = Rotation.from_rotvec([0.0, tilt, 0.0]).apply(up_H)
        depth = params.depth_of_cut_large if edge.kind == "large" else params.depth_of_cut_small

        seg = np.linalg.norm(np.diff(np.vstack([edge.p_HE, edge.p_HE[:1]]), axis=0), axis=1)
        arc_all = np.concatenate([[0.0], np.cumsum(seg)])
        total = float(arc_all[-1])
        cl = ClPath(window_index=w, kind=edge.kind, method="reference_greedy",
                    u=arc_all[idx] / total, p_HC=p_HC, t_H=t_H, kappa=np.zeros(len(idx)),
                    arc_length=arc_all[idx], total_length=total, metrics={})
        from pydrake.math import RigidTransform

        tool_paths[w] = ToolPath(
            window_index=w, kind=edge.kind, cl_path=cl, X_WH=RigidTransform(X_WH), p_HC=p_HC,
            R_HL=R_HL, axis_H=-up_H, theta_A=th_A, theta_B=th_B,
            bounds=box, cone_axis_H=cone_axis_H, cone_half_angle=inner,
            cone_outer_half_angle=outer, depth_of_cut=depth, model="reference",
            solver="none", objective=0.0, success=True, solve_seconds=0.0, stats={},
            message="reference plan (fixed angles)")

        # tool poses at the CL points: spin by parallel transport (no twist about the axis),
        # starting from the hub direction spin_H; the edge touches the flank at radius
        # contact_radius (T sits on the axis at that circle's height)
        z_T = -up_H
        X_HT = np.tile(np.eye(4), (len(idx), 1, 1))
        x = spin_H.copy()
        apex = BURR.apex_offset
        for i in range(len(idx)):
            x = x - (x @ z_T[i]) * z_T[i]
            x /= np.linalg.norm(x)
            n_perp = N[i] - (N[i] @ z_T[i]) * z_T[i]
            n_perp /= np.linalg.norm(n_perp)
            X_HT[i, :3, :3] = np.column_stack([x, np.cross(z_T[i], x), z_T[i]])
            # the flank point at radius r lies (apex - r/tan) along +Z_T from the apex ...
            dz = BURR.contact_radius / np.tan(BURR.cone_half_angle) - contact_radius / np.tan(
                BURR.cone_half_angle)
            X_HT[i, :3, 3] = p_HC[i] + contact_radius * n_perp - dz * z_T[i]
        del apex
        # closing the loop: the last move returns to CL point 0 with the transported spin
        x = x - (x @ z_T[0]) * z_T[0]
        x /= np.linalg.norm(x)
        X_close = X_HT[0].copy()
        X_close[:3, :3] = np.column_stack([x, np.cross(z_T[0], x), z_T[0]])
        X_up = X_HT[0].copy()
        X_up[:3, 3] += retract * up_H[0]
        X_end_up = X_close.copy()
        X_end_up[:3, 3] += retract * up_H[0]

        # joint move to above the first CL point
        k0 = len(targets)
        q_up = _ik_drake(cell, X_up, knots_q[-1])
        t0 = knots_t[-1]
        joint_move(q_up, params.window_switch_speed)
        add_target(-1, "transition", -1, X_up, q_up, params.window_switch_speed)
        segments.append(PlanSegment(-1, "transition", (k0, k0 + 1), (t0, knots_t[-1])))
        # approach
        t0 = knots_t[-1]
        qs = linear_chain([X_up, X_HT[0]], params.grinding_speed, q_up)
        add_target(w, "approach", 0, X_HT[0], qs[-1], params.grinding_speed)
        segments.append(PlanSegment(w, "approach", (k0 + 1, k0 + 2), (t0, knots_t[-1])))
        # cut around the closed edge, back to the first point
        t0 = knots_t[-1]
        loop = [X_HT[i] for i in range(len(idx))] + [X_close]
        qs = linear_chain(loop, params.grinding_speed, qs[-1])
        k1 = len(targets)
        for i in range(1, len(loop)):
            add_target(w, "cut", i % len(idx), loop[i], qs[i], params.grinding_speed)
        segments.append(PlanSegment(w, "cut", (k1, len(targets)), (t0, knots_t[-1])))
        # retract
        t0 = knots_t[-1]
        qs = linear_chain([X_close, X_end_up], params.grinding_speed, qs[-1])
        add_target(w, "retract", -1, X_end_up, qs[-1], params.grinding_speed)
        segments.append(PlanSegment(w, "retract", (len(targets) - 1, len(targets)),
                                    (t0, knots_t[-1])))
        if progress is not None:
            progress(n_done + 1, len(chosen), f"window {w}")

    t0 = knots_t[-1]
    joint_move(np.asarray(cell.q_home, float), params.home_speed)
    add_target(-1, "home", -1, cell.X_HT(cell.q_home).GetAsMatrix4(), cell.q_home,
               params.home_speed)
    segments.append(PlanSegment(-1, "home", (len(targets) - 1, len(targets)), (t0, knots_t[-1])))

    trajectory = JointTrajectory(t=np.asarray(knots_t), q=np.asarray(knots_q),
                                 qd=np.asarray(knots_qd))
    return Plan(scenario=str(scenario), hub=str(hub), mode=cell.mode, X_WH=X_WH,
                targets=tuple(targets), segments=tuple(segments), trajectory=trajectory,
                tool_path=tool_paths, failures=(),
                meta={"planner": "drakedeburr.verify.synthetic.reference_plan",
                      "windows": chosen})
