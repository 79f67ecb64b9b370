"""The executed cut of one window as a smooth Cartesian path: blended corners, smooth axis.

A controller runs the program as linear moves between targets; with a zone at each target it
rounds the corner there instead of stopping (ABB ``zonedata``, KUKA ``C_DIS``, FANUC ``CNT``).
Without rounding, the tool direction kinks at every target, the joint path q(s) has a slope
kink there, and any timing crawls through it. So the motion simulated here is:

* **position**: the polyline of the targets with every corner replaced by a quadratic Bezier
  blend whose legs ``d_k`` are the zone at that target, chosen so the blend stays within
  ``deviation`` of the corner (a symmetric quadratic blend with legs ``d`` and a turn ``phi``
  misses the corner by ``d/2 * sin(phi/2)``) and uses at most ``leg_share`` of each adjacent
  move;
* **tool axis**: one small convex program (second-order cone program, Drake
  ``MathematicalProgram`` + Clarabel) over the dense samples: minimise the axis' turning
  energy along the path (first and second differences, so the rotation needed at a fillet is
  spread over as much travel as the cones allow) plus a soft pull toward the preferred axis,
  with the admissible cone as a hard constraint at every sample. The axis is written in
  gnomonic coordinates ``u`` about the mean cone axis (``a ~ E u + z0``): a cone about any
  axis is then the second-order cone ``|E u + z0| <= (E u + z0).c / cos(alpha)``, exactly;
* **spin** about the axis: the target orientations' spin, interpolated and Gaussian-smoothed
  along the travel (the IK keeps J6 continuous at the targets).

Why hand-written: the blend is the controllers' zone model (no library has it), and the axis
program is a 20-line use of Drake's ``MathematicalProgram``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation, Slerp

from drakedeburr.frames.vectors import perpendicular_basis
from drakedeburr.plan.program_reading import cone_axes_on_moves

log = logging.getLogger(__name__)

__all__ = ["BlendedPath", "blend_corners", "AxisSmoothing", "smooth_axes",
           "least_axis_curvature", "CutPath", "CutPathOptions", "cut_path", "axes_interp",
           "target_cones_held"]


@dataclass(frozen=True, eq=False)
class BlendedPath:
    """Dense samples of a polyline with blended corners.

    Attributes:
        s: (N,) arc length along the blended path from the first target [m].
        p: (N, 3) points [m].
        target_s: (K,) arc length at each target's closest point on the path [m].
        target_index: (K,) dense sample index nearest each target.
        zone: (K,) blend leg at each target [m] (0 at the ends).
    """

    s: np.ndarray
    p: np.ndarray
    target_s: np.ndarray
    target_index: np.ndarray
    zone: np.ndarray


def blend_corners(P: np.ndarray, deviation: float | np.ndarray, step: float,
                  leg_share: float = 0.45, max_zone: float = 5e-3,
                  zone_quantum: float = 0.05e-3) -> BlendedPath:
    """Round the corners of a polyline as a controller's zones do.

    Args:
        P: (K, 3) target points [m], K >= 2, consecutive points distinct.
        deviation: largest distance of a blend from its corner [m] (or (K,) per target).
        step: largest spacing of the dense samples [m].
        leg_share: largest share of an adjacent move a blend leg may use.
        max_zone: largest blend leg [m].
        zone_quantum: zones are rounded down to multiples of this [m] (a program then holds a
            few dozen distinct zones, not one per target; rounding down keeps the deviation).

    Returns:
        BlendedPath (first and last targets are on the path; the others within ``deviation``).
    """
    P = np.asarray(P, float)
    K = len(P)
    seg = np.diff(P, axis=0)
    L = np.linalg.norm(seg, axis=1)
    if np.any(L <= 0):
        raise ValueError("blend_corners: repeated target point")
    u = seg / L[:, None]
    zone = np.zeros(K)
    dev = np.broadcast_to(np.asarray(deviation, float), (K,))
    for k in range(1, K - 1):
        c = float(np.clip(u[k - 1] @ u[k], -1.0, 1.0))
        phi = np.arccos(c)
        if phi < 1e-9:
            continue
        d_dev = 2.0 * dev[k] / np.sin(phi / 2.0)
        zone[k] = min(d_dev, leg_share * L[k - 1], leg_share * L[k], max_zone)
        if zone_quantum > 0 and zone[k] > zone_quantum:
            zone[k] = np.floor(zone[k] / zone_quantum) * zone_quantum
    # pieces: straight from (P_k + zone_k u_k) to (P_{k+1} - zone_{k+1} u_k), then blend at k+1
    s_acc = 0.0
    out_s = [np.zeros(1)]
    out_p = [P[:1]]
    target_s = np.zeros(K)
    for k in range(K - 1):
        a = P[k] + zone[k] * u[k]
        b = P[k + 1] - zone[k + 1] * u[k]
        # straight piece cur(=a) -> b
        ln = float(np.linalg.norm(b - a))
        if ln > 0:
            n = max(1, int(np.ceil(ln / step)))
            f = np.arange(1, n + 1) / n
            out_p.append(a + np.outer(f, b - a))
            out_s.append(s_acc + f * ln)
            s_acc += ln
        if k + 1 == K - 1:
            target_s[K - 1] = s_acc
            break
        # quadratic Bezier b -> P_{k+1} -> c
        c_end = P[k + 1] + zone[k + 1] * u[k + 1]
        if zone[k + 1] <= 0:
            target_s[k + 1] = s_acc
            continue
        tt = np.linspace(0.0, 1.0, 401)
        B = ((1 - tt) ** 2)[:, None] * b + (2 * (1 - tt) * tt)[:, None] * P[k + 1] \
            + (tt ** 2)[:, None] * c_end
        sl = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(B, axis=0), axis=1))])
        n = max(2, int(np.ceil(sl[-1] / step)))
        s_mid = float(np.interp(0.5, tt, sl))  # where the path passes the target
        # the passing point is a sample: the target's sample is exactly where the program's
        # move ends (its speed is read there), not up to half a step beyond
        sq = np.arange(1, n + 1) / n * sl[-1]
        j = int(np.argmin(np.abs(sq[:-1] - s_mid)))
        if abs(sq[j] - s_mid) < 0.25 * sl[-1] / n:
            sq[j] = s_mid  # moved onto it (no near-duplicate sample)
        else:
            sq = np.union1d(sq, [s_mid])
        tq = np.interp(sq, sl, tt)
        Bq = ((1 - tq) ** 2)[:, None] * b + (2 * (1 - tq) * tq)[:, None] * P[k + 1] \
            + (tq ** 2)[:, None] * c_end
        out_p.append(Bq)
        out_s.append(s_acc + sq)
        target_s[k + 1] = s_acc + s_mid
        s_acc += sl[-1]
    s = np.concatenate(out_s)
    p = np.concatenate(out_p)
    keep = np.concatenate([[True], np.diff(s) > 1e-12])
    s, p = s[keep], p[keep]
    idx = np.clip(np.searchsorted(s, target_s), 0, len(s) - 1)
    prev = np.clip(idx - 1, 0, len(s) - 1)
    idx = np.where(np.abs(s[prev] - target_s) < np.abs(s[idx] - target_s), prev, idx)
    return BlendedPath(s=s, p=p, target_s=target_s, target_index=idx, zone=zone)


def _add_cone(prog, u_i, axis: np.ndarray, cos_a: float) -> None:
    """Angle between the axis v = (u1, u2, 1) (gnomonic, basis E) and the unit ``axis`` (in
    basis E) at most arccos(cos_a): ``[v.axis / cos_a; v]`` in the Lorentz cone."""
    A = np.zeros((4, 2))
    b = np.zeros(4)
    A[0] = axis[:2] / cos_a
    b[0] = axis[2] / cos_a
    A[1, 0] = 1.0
    A[2, 1] = 1.0
    b[3] = 1.0
    prog.AddLorentzConeConstraint(A, b, u_i)


#: a pinned axis keeps this far inside its cone [rad] (:func:`smooth_axes`): at an unseen hub's
#: small-window corner, where the cone turns 0.16 rad between two CL points, via targets
#: 0.03 mm off the CL chord moved the verifier's reading of the cone by 0.13 mrad against the
#: planner's (an axis pinned 0.1 mrad inside read 0.03 mrad outside)
PIN_MARGIN = 0.5e-3


@dataclass(frozen=True)
class AxisSmoothing:
    """Weights and margins of :func:`smooth_axes`.

    Attributes:
        margin: kept inside the cone [rad] (a pinned sample keeps ``min(PIN_MARGIN, margin)``).
        w_pref, w_rate, w_curv: weights of the distance to the preferred axes, of the
            axis' rate and of its curvature (per metre of path).
        pin_angle: a pinned sample's axis stays within this of its pin axis [rad].
    """

    margin: float = 2e-3
    w_pref: float = 1.0
    w_rate: float = 1e-4
    w_curv: float = 1e-10
    pin_angle: float = 0.004


def smooth_axes(s: np.ndarray, a_pref: np.ndarray, cone_axis: np.ndarray, half_angle: float,
                weights: AxisSmoothing = AxisSmoothing(), pin: np.ndarray | None = None,
                pin_axes: np.ndarray | None = None,
                held: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Smoothest tool-axis curve inside per-sample cones (a second-order cone program).

    Minimises ``w_rate * sum |du/ds|^2 ds + w_curv * sum |d2u/ds2|^2 ds + w_pref * sum |u -
    u_pref|^2 ds`` over gnomonic coordinates ``u`` of the axis, subject to the angle between
    the axis and the cone axis being at most ``half_angle - margin`` at every sample.

    Args:
        s: (N,) arc length [m], increasing.
        a_pref: (N, 3) preferred unit axes; cone_axis: (N, 3) unit cone axes.
        half_angle: cone half-angle [rad].
        weights: margin, weights and pin angle (:class:`AxisSmoothing`).
        pin: (N,) bool samples whose axis must stay within ``weights.pin_angle`` of the
            preferred one (where the smoothed axis cost clearance: the preferred axes come
            from the clearance-constrained IK); pin_axes: (N, 3) the axes to stay near
            (default ``a_pref``).
        held: (sample indices (H,), unit cone axes (H, 3)): samples whose axis must also lie
            in these cones, with the sample's own margin (a program target's own cone where
            the reading at its sample is off it, :func:`target_cones_held`).

    Returns:
        (N, 3) unit axes, or None if the program fails (no axis curve in the cones).
    """
    from pydrake.solvers import ClarabelSolver, MathematicalProgram

    margin, w_pref, w_rate, w_curv = (weights.margin, weights.w_pref, weights.w_rate,
                                      weights.w_curv)
    s = np.asarray(s, float)
    a_pref = np.asarray(a_pref, float)
    c = np.asarray(cone_axis, float)
    N = len(s)
    E = perpendicular_basis(np.mean(c, axis=0))
    # preferred axes in gnomonic coordinates
    loc = a_pref @ E
    u_pref = loc[:, :2] / loc[:, 2:3]
    prog = MathematicalProgram()
    u = prog.NewContinuousVariables(N, 2, "u")
    ds = np.maximum(np.diff(s), 1e-6)
    w_s = np.concatenate([[ds[0]], 0.5 * (ds[:-1] + ds[1:]), [ds[-1]]]) / max(s[-1] - s[0], 1e-9)
    # sparse quadratic cost (scaled by path length so the weights are per metre)
    from scipy.sparse import diags

    n = N
    D1 = diags([-1.0, 1.0], [0, 1], shape=(n - 1, n)).tocsr()
    D1 = diags(1.0 / ds) @ D1
    h = 0.5 * (ds[:-1] + ds[1:])
    D2 = diags([1.0 / ds[:-1], -(1.0 / ds[:-1] + 1.0 / ds[1:]), 1.0 / ds[1:]], [0, 1, 2],
               shape=(n - 2, n)).tocsr()
    D2 = diags(1.0 / h) @ D2
    W1 = diags(ds / s[-1])
    W2 = diags(h / s[-1])
    Q = (w_rate * (D1.T @ W1 @ D1) + w_curv * (D2.T @ W2 @ D2) + w_pref * diags(w_s)).tocsc()
    # Drake's AddQuadraticCost takes a dense Q; build it once for both coordinates
    Qd = 2.0 * Q.toarray()
    for j in range(2):
        prog.AddQuadraticCost(Qd, -2.0 * w_pref * w_s * u_pref[:, j], u[:, j], is_convex=True)
    # the margin applies where the axis is free; a pinned axis follows the IK's, which may use
    # the cone up to its rim: it keeps PIN_MARGIN inside, what the cone's reading between the
    # program's targets may move by where the program changes (via targets) at a corner whose
    # cone turns fast
    half_i = np.full(N, max(half_angle - margin, 1e-3))
    if pin is not None:
        half_i[np.asarray(pin, bool)] = max(half_angle - min(PIN_MARGIN, margin), 1e-3)
    cos_i = np.cos(half_i)
    cl = c @ E  # cone axes in the (e1, e2, z0) basis
    for i in range(N):
        _add_cone(prog, u[i], cl[i], cos_i[i])
    if held is not None:
        for i, axis in zip(np.asarray(held[0], int), np.asarray(held[1], float) @ E, strict=True):
            _add_cone(prog, u[i], axis / np.linalg.norm(axis), cos_i[i])
    if pin is not None:
        ap = (a_pref if pin_axes is None else np.asarray(pin_axes, float)) @ E
        ap /= np.linalg.norm(ap, axis=1, keepdims=True)
        for i in np.flatnonzero(pin):
            _add_cone(prog, u[i], ap[i], np.cos(weights.pin_angle))
    prog.SetInitialGuess(u, u_pref)
    res = ClarabelSolver().Solve(prog)
    if not res.is_success():
        log.debug("axis smoothing program failed (%s)", res.get_solution_result())
        return None
    uu = res.GetSolution(u)
    v = np.column_stack([uu, np.ones(N)]) @ E.T
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def least_axis_curvature(p: np.ndarray, cone_axis: np.ndarray, half_angle: float, *,
                         closed: bool = True, step: float = 0.5e-3) -> float:
    """The least peak ``|d2a/ds2|`` [rad/m^2] of any tool-axis curve a(s) inside the cones
    along a path: a lower bound on what the orientation box asks of the robot. At a constant
    feed ``v`` the axis' angular acceleration is ``|d2a/ds2| v^2``; if that exceeds what the
    wrist can give, no planner can hold the feed through the turn and the TCP must slow down.

    A second-order cone program (Drake ``MathematicalProgram`` + Clarabel) on gnomonic
    coordinates about the mean cone axis (as :func:`smooth_axes`): minimise t subject to the
    cone at every sample and ``|u[i-1] - 2 u[i] + u[i+1]| / h^2 <= t``. The gnomonic map
    stretches angles by up to 1/cos^2 of the tilt from the mean axis (under 1.3 for the
    source's boxes): the figure is an estimate of that accuracy, not a certificate.

    Args:
        p: (M, 3) path points [m] (e.g. the CL points) in order; cone_axis: (M, 3) unit cone
            axes there; half_angle: cone half-angle [rad].
        closed: the path returns from the last point to the first.
        step: sample spacing along the path [m].

    Returns:
        The bound [rad/m^2] (NaN if the program fails).
    """
    from pydrake.solvers import ClarabelSolver, MathematicalProgram

    P = np.asarray(p, float)
    C = np.asarray(cone_axis, float)
    if closed:
        P, C = np.vstack([P, P[:1]]), np.vstack([C, C[:1]])
    ts = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    if ts[-1] < 3.0 * step:
        return 0.0  # a stretch shorter than three samples asks no curvature of the axis
    n = max(3, int(np.ceil(ts[-1] / step)))
    s = np.linspace(0.0, ts[-1], n + 1)
    if closed:
        s = s[:-1]  # the end is the start
    h = ts[-1] / n
    c = axes_interp(ts, C, s)
    E = perpendicular_basis(np.mean(c, axis=0))
    cl = c @ E
    N = len(s)
    prog = MathematicalProgram()
    u = prog.NewContinuousVariables(N, 2, "u")
    t = prog.NewContinuousVariables(1, "t")[0]
    cos_a = np.cos(half_angle)
    for i in range(N):
        _add_cone(prog, u[i], cl[i], cos_a)
    # |u[i-1] - 2 u[i] + u[i+1]| / h^2 <= t as a linear map into the Lorentz cone
    A = np.zeros((3, 7))
    A[0, 0] = 1.0
    for j in range(2):
        A[1 + j, [1 + j, 3 + j, 5 + j]] = np.array([1.0, -2.0, 1.0]) / h ** 2
    rows = range(N) if closed else range(1, N - 1)
    for i in rows:
        prog.AddLorentzConeConstraint(
            A, np.zeros(3), np.concatenate([[t], u[(i - 1) % N], u[i], u[(i + 1) % N]]))
    prog.AddLinearCost(t)
    res = ClarabelSolver().Solve(prog)
    return float(res.GetSolution(t)) if res.is_success() else float("nan")


@dataclass(frozen=True, eq=False)
class CutPath:
    """The smooth executed cut.

    Attributes:
        X_HT: (N, 4, 4) dense tool poses in H [m]; s: (N,) travel [m].
        target_index: (K,) dense sample at each target; X_target: (K, 4, 4) the target poses
            written to the program (positions = the given targets, orientations = the smooth
            ones there); zone: (K,) blend leg at each target [m].
        psi_ik: (N,) the IK's spin (smoothed) about each sample's Z relative to ``X_HT`` [rad]
            (the IK chose it with the clearance constraint: the spin search stays near it).
    """

    X_HT: np.ndarray
    s: np.ndarray
    target_index: np.ndarray
    X_target: np.ndarray
    zone: np.ndarray
    psi_ik: np.ndarray | None = None


def _rotate_axis_to(R: np.ndarray, a_new: np.ndarray) -> np.ndarray:
    """Rotate each frame minimally so that its -Z column becomes ``a_new``."""
    a_old = -R[:, :, 2]
    k = np.cross(a_old, a_new)
    sn = np.linalg.norm(k, axis=1)
    cs = np.sum(a_old * a_new, axis=1)
    ang = np.arctan2(sn, cs)
    axis = np.where(sn[:, None] > 1e-12, k / np.maximum(sn, 1e-12)[:, None], 0.0)
    return Rotation.from_rotvec(axis * ang[:, None]).as_matrix() @ R


@dataclass(frozen=True)
class CutPathOptions:
    """Settings of :func:`cut_path`.

    Attributes:
        step: dense sample spacing [m].
        spin_sigma: Gaussian width of the orientation smoothing before the axis program [m].
        spin: "fixed" (one X direction for the whole cut) or anything else (the smoothed
            IK's spin).
        axes: the axis program's margin inside the cone, weights and pin angle
            (:class:`AxisSmoothing`).
    """

    step: float = 0.5e-3
    spin_sigma: float = 3e-3
    spin: str = "fixed"
    axes: AxisSmoothing = AxisSmoothing()


def cut_path(X_targets: np.ndarray, cone_retract_H: np.ndarray, half_angle: float,
             options: CutPathOptions = CutPathOptions(), *,
             deviation: float | np.ndarray = 0.03e-3,
             pin: np.ndarray | None = None) -> CutPath:
    """The executed cut through target poses: blended corners, smooth axis and spin.

    Args:
        X_targets: (K, 4, 4) target tool poses in H from the IK (tool point on the CL target,
            axis in the cone) [m].
        cone_retract_H: (K, 3) unit cone axes at the targets (tip -> spindle); half_angle [rad].
        options: sampling, smoothing and the axis program's settings (:class:`CutPathOptions`).
        deviation: corner blend tolerance [m] (or (K,) per target).
        pin: (P, 2) travel intervals [m] whose axis stays near the IK's (see
            :func:`smooth_axes`).

    Returns:
        CutPath.
    """
    step, spin_sigma, spin = options.step, options.spin_sigma, options.spin
    X_targets = np.asarray(X_targets, float)
    bp = blend_corners(X_targets[:, :3, 3], deviation, step)
    rot = Rotation.from_matrix(X_targets[:, :3, :3])
    ts = bp.target_s
    # orientation of the targets interpolated along the travel, then Gaussian-smoothed
    R = Slerp(ts, rot)(np.clip(bp.s, ts[0], ts[-1])).as_matrix()
    a_ik = -R[:, :, 2]  # the IK's axes, linearly interpolated (clearance-checked at targets)
    quat = Rotation.from_matrix(R).as_quat()
    for i in range(1, len(quat)):
        if quat[i] @ quat[i - 1] < 0:
            quat[i] = -quat[i]
    if spin_sigma > 0:
        sig = spin_sigma / max(float(np.median(np.diff(bp.s))), 1e-9)
        quat = gaussian_filter1d(quat, sig, axis=0, mode="nearest")
    R = Rotation.from_quat(quat / np.linalg.norm(quat, axis=1, keepdims=True)).as_matrix()
    # the cone where the verifier reads it (on the program's moves); by travel where that
    # leaves the smoothing no axis (at a pinned sample of a tight corner)
    pin_s = _in_intervals(bp.s, pin)
    c_read = cone_axes_on_moves(bp.p, X_targets[:, :3, 3], cone_retract_H)
    kw = dict(weights=options.axes, pin=pin_s, pin_axes=a_ik,
              held=target_cones_held(c_read, cone_retract_H, bp.target_index, pin_s,
                                     options.axes.margin))
    a = smooth_axes(bp.s, -R[:, :, 2], c_read, half_angle, **kw)
    if a is None:
        log.debug("no smooth axis inside the cones read on the moves; reading them by travel")
        a = smooth_axes(bp.s, -R[:, :, 2], axes_interp(ts, cone_retract_H, bp.s), half_angle,
                        **kw)
    if a is None:
        log.warning("axis smoothing program failed; keeping the preferred axes")
        a = -R[:, :, 2] / np.linalg.norm(R[:, :, 2], axis=1, keepdims=True)
    R = _rotate_axis_to(R, a)
    R_ik = R.copy()
    if spin == "fixed":
        R = _fixed_spin(R, X_targets[:, :3, 0])
    # the IK's spin (clearance-checked at the targets) relative to the frames returned
    x, z = R[:, :, 0], R[:, :, 2]
    psi_ik = np.unwrap(np.arctan2(np.sum(np.cross(x, R_ik[:, :, 0]) * z, axis=1),
                                  np.sum(x * R_ik[:, :, 0], axis=1)))
    X = np.zeros((len(bp.s), 4, 4))
    X[:, :3, :3] = R
    X[:, :3, 3] = bp.p
    X[:, 3, 3] = 1.0
    Xt = X_targets.copy()
    Xt[:, :3, :3] = R[bp.target_index]
    return CutPath(X_HT=X, s=bp.s, target_index=bp.target_index, X_target=Xt, zone=bp.zone,
                   psi_ik=psi_ik)


def target_cones_held(c_read: np.ndarray, cone: np.ndarray, target_index: np.ndarray,
                      pin: np.ndarray | None, margin: float
                      ) -> tuple[np.ndarray, np.ndarray] | None:
    """The targets whose axis the axis program also holds in their own cone: those whose cone
    as read at their sample on the moves (``c_read`` (N, 3)) is more than half the sample's
    margin (``margin``; ``min(PIN_MARGIN, margin)`` where ``pin``) off their own cone axis
    (``cone`` (K, 3)). At a corner the blend passes its target up to its deviation inside, and
    the projection on the moves reads the cone a share of a move before or after the target:
    where the cone turns fast there (audibot rim window 7 CL 46 -> 47: 27 deg over 0.46 mm, the
    neighbouring cones of half-angle 7.1 deg apart) that share is 0.63 mrad of cone turn, more
    than the pinned margin, and the program's target came out 0.11 mrad outside its own cone.
    Elsewhere the reading is within a few urad of the target's cone: no target is held.
    Returns (sample indices, cone axes) or None."""
    idx = np.asarray(target_index, int)
    m = np.full(len(idx), margin)
    if pin is not None:
        m[np.asarray(pin, bool)[idx]] = min(PIN_MARGIN, margin)
    cos_off = np.sum(c_read[idx] * cone, axis=1)
    off = np.arctan2(np.linalg.norm(np.cross(c_read[idx], cone), axis=1), cos_off)
    sel = np.flatnonzero(off > 0.5 * m)
    if sel.size == 0:
        return None
    log.debug("axis program: %d target(s) also held in their own cone (reading off by up to "
              "%.2f mrad)", sel.size, 1e3 * float(off[sel].max()))
    return idx[sel], np.asarray(cone, float)[sel]


def _in_intervals(s: np.ndarray, iv: np.ndarray | None) -> np.ndarray | None:
    if iv is None or len(iv) == 0:
        return None
    iv = np.asarray(iv, float).reshape(-1, 2)
    return np.any((s[:, None] >= iv[None, :, 0]) & (s[:, None] <= iv[None, :, 1]), axis=1)


def _fixed_spin(R: np.ndarray, x_targets: np.ndarray) -> np.ndarray:
    """Frames with the same axes (Z) and X as close as possible to one fixed direction: the
    mean X of the targets. The spindle body then keeps pointing the same way while the axis
    precesses, and the spin turns only as much as the axis' tilt forces."""
    r = np.mean(np.asarray(x_targets, float), axis=0)
    z = R[:, :, 2]
    x = r[None] - (z @ r)[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    out = np.empty_like(R)
    out[:, :, 0] = x
    out[:, :, 1] = np.cross(z, x)
    out[:, :, 2] = z
    return out


def axes_interp(ts: np.ndarray, axes: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Unit axes interpolated linearly in ``ts`` and renormalised."""
    axes = np.asarray(axes, float)
    out = np.column_stack([np.interp(s, ts, axes[:, j]) for j in range(3)])
    return out / np.linalg.norm(out, axis=1, keepdims=True)
