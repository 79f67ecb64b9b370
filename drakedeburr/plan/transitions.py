"""Moves that do not cut: approach/retract along the tool axis, joint moves between windows and
home, each checked for collision; a joint move that collides is repaired with Drake's
``KinematicTrajectoryOptimization`` (minimum-distance constraints at sparse samples, joint
velocity/acceleration bounds everywhere, warm-started from the straight joint line through a
lifted via point). A straight move may be swapped for its TCP line (:func:`tcp_line`: the wrist
on the same joint line, the arm putting the tool point on the straight line between the ends),
a via move for the same polyline with its corners rounded (:func:`rounded_corners`), where that
is clear and faster under the move's timing (:func:`faster_move`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from drakedeburr.plan.interpolate import DensePath, track_poses
from drakedeburr.plan.kinematics import CellKinematics, ClearanceChecker

__all__ = ["JointMove", "approach_pose", "RETRACT_TILTS", "retract_pose", "LinearMove",
           "clear_retract", "joint_move", "check_joint_samples", "tcp_line",
           "rounded_corners", "faster_move"]

log = logging.getLogger(__name__)


def approach_pose(X_HT: np.ndarray, distance: float) -> np.ndarray:
    """The pose ``distance`` [m] back along the tool axis (toward the spindle) from ``X_HT``."""
    X = np.array(X_HT, float)
    X[:3, 3] = X[:3, 3] - distance * X[:3, 2]
    return X


#: tilts [rad] of a retract (and approach) off the tool axis toward the hub's face normal
#: +Z_H, tried in turn where the move along the axis passes the cell closer than the bound:
#: at a steep stretch's end the spindle body or collet can run within the clearance of the
#: rim's wall while it backs out along its own axis; lifted out of the face it leaves it
RETRACT_TILTS = np.radians((0.0, 30.0, 60.0, 90.0))


def retract_pose(X_HT: np.ndarray, distance: float, tilt: float = 0.0) -> np.ndarray:
    """The pose ``distance`` [m] from ``X_HT`` (same orientation) back along the tool axis
    turned by ``tilt`` [rad] toward +Z_H (at most onto +Z_H); ``tilt`` 0 is
    :func:`approach_pose`, bit for bit."""
    if tilt == 0.0:
        return approach_pose(X_HT, distance)
    a = -np.asarray(X_HT, float)[:3, 2]
    z = np.array([0.0, 0.0, 1.0])
    phi = float(np.arccos(np.clip(a @ z, -1.0, 1.0)))
    perp = z - (a @ z) * a
    if phi < 1e-9 or np.linalg.norm(perp) < 1e-12:  # the axis on +-Z_H: no turn toward it
        return approach_pose(X_HT, distance)
    t = min(float(tilt), phi)
    u = np.cos(t) * a + np.sin(t) * perp / np.linalg.norm(perp)
    X = np.array(X_HT, float)
    X[:3, 3] = X[:3, 3] + distance * u
    return X


@dataclass(frozen=True, eq=False)
class LinearMove:
    """A linear move off the cut (a retract from a stretch's end; an approach is its reverse)
    and its clearance: ``path`` (the tracked dense poses from the cut's end), ``clearance``
    [m] (least over its samples after the first, the cut's own end), ``tilt`` [rad] off the
    tool axis toward +Z_H (:data:`RETRACT_TILTS`), ``tried`` the tilts read (deg)."""

    path: DensePath
    clearance: float
    tilt: float
    tried: tuple[str, ...] = ()


def clear_retract(kin: CellKinematics, checker: ClearanceChecker, X_HT: np.ndarray,
                  q0: np.ndarray, distance: float, bound: float, step: float
                  ) -> LinearMove | None:
    """The retract of ``distance`` [m] from the cut's end ``X_HT`` (joints ``q0``): along the
    tool axis when every sample keeps ``bound`` [m] (``checker``: the burr's contact with the
    part filtered, as on the cut), else the first of :data:`RETRACT_TILTS` toward +Z_H that
    does; where none does, the one of least shortfall (its clearance says by how much). None
    when no tilt's move is reachable on ``q0``'s branch. Deterministic."""
    best, tried = None, []
    for tilt in RETRACT_TILTS:
        path = track_poses(kin, np.stack([X_HT, retract_pose(X_HT, distance, tilt)]), q0, step)
        tried.append(f"{np.degrees(tilt):.0f} deg")
        if not np.all(path.ok):
            continue
        d = float(np.min(checker.min_distances_along(path.q[1:], bound + 1e-3)))
        if best is None or d > best.clearance:
            best = LinearMove(path=path, clearance=d, tilt=float(tilt))
        if d >= bound:
            break
    return None if best is None else replace(best, tried=tuple(tried))


@dataclass(frozen=True, eq=False)
class JointMove:
    """A collision-checked joint-space move.

    Attributes:
        q: (N, 6) dense joint samples [rad] from start to goal.
        s: (N,) joint-space arc length [rad].
        clearance: minimum distance along it [m] (capped).
        method: "straight", "tcp_line", "via", "via_rounded" (:func:`faster_move`) or "kto".
        ok: clearance >= bound at every sample and joints in limits.
        info: solver details.
    """

    q: np.ndarray
    s: np.ndarray
    clearance: float
    method: str
    ok: bool
    info: dict = field(default_factory=dict)


def _densify(q_way: np.ndarray, step: float) -> np.ndarray:
    out = [q_way[:1]]
    for a, b in zip(q_way[:-1], q_way[1:], strict=True):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        f = np.linspace(0, 1, n + 1)[1:, None]
        out.append(a + f * (b - a))
    return np.concatenate(out)


def check_joint_samples(checker: ClearanceChecker, q: np.ndarray, bound: float) -> float:
    """Minimum clearance [m] over joint samples (stops early below ``bound``)."""
    return _clear_share(checker, q, bound)[0]


def _clear_share(checker: ClearanceChecker, q: np.ndarray, bound: float) -> tuple[float, float]:
    """(minimum clearance [m] over joint samples, stopping at the first one under ``bound``;
    the share of the samples before that one)."""
    if len(q) == 0:
        return float(np.inf), 1.0
    # the same value as a query at every sample, with far fewer queries (plan.clearance)
    d = checker.min_distances_along(np.asarray(q, float), bound + 1e-3)
    below = np.flatnonzero(d < bound)
    if len(below):
        k = int(below[0])
        return float(d[:k + 1].min()), k / len(q)
    return float(d.min()), 1.0


def _arc(q: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])


def joint_move(cell, kin: CellKinematics, checker: ClearanceChecker, q0: np.ndarray,
               q1: np.ndarray, *, min_distance: float = 2e-3, step: float = 0.01,
               lift: float = 0.08) -> JointMove:
    """A collision-free joint move from ``q0`` to ``q1``.

    Tries, in order: the straight joint line; lines through via points (the mid-pose lifted
    by ``lift`` and 2.5 ``lift`` along the hub's face normal, both ends lifted, home, both ends
    lifted with home between them; solved by the analytic IK); KinematicTrajectoryOptimization
    warm-started from the first via path, solved again from its own result with 3x the
    collision samples when the dense check finds it too close between them.

    Args:
        q0, q1: (6,) joints [rad]. step: joint-space sample spacing [rad].
        min_distance: clearance bound [m]; lift: via-point lift [m].
    """
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    q = _densify(np.stack([q0, q1]), step)
    d = check_joint_samples(checker, q, min_distance)
    if d >= min_distance:
        return JointMove(q=q, s=_arc(q), clearance=d, method="straight", ok=True)
    # via points, in order of preference: the lifted mid-pose at growing heights, both ends
    # lifted, home
    candidates = []
    for h in (lift, 2.5 * lift):
        v = _via(kin, q0, q1, h)
        if v is not None:
            candidates.append(np.vstack([q0, v, q1]))
    a, b = _lifted(kin, q0, 2.5 * lift), _lifted(kin, q1, 2.5 * lift)
    if a is not None and b is not None:
        candidates.append(np.vstack([q0, a, b, q1]))
    candidates.append(np.vstack([q0, kin.q_home, q1]))
    # a wrist that must unwind most of a turn between windows (the workpiece cell winds J4/J6
    # around each loop) sweeps the part through the spindle on any of those lines: back off
    # first, unwind at home, come back in
    if a is not None and b is not None:
        candidates.append(np.vstack([q0, a, kin.q_home, b, q1]))
    a2, b2 = _lifted(kin, q0, 5.0 * lift), _lifted(kin, q1, 5.0 * lift)
    if a2 is not None and b2 is not None:
        candidates.append(np.vstack([q0, a2, kin.q_home, b2, q1]))
    guess, guess_reach = None, -1.0
    for way in candidates:
        q = _densify(way, step)
        d, reach = _clear_share(checker, q, min_distance)
        if d >= min_distance:
            return JointMove(q=q, s=_arc(q), clearance=d, method="via", ok=True,
                             info=dict(via_points=len(way) - 2, waypoints=way))
        if reach > guess_reach:
            guess, guess_reach = way, reach  # the KTO starts from the via path clear longest
    guess = guess if guess is not None else np.stack([q0, q1])
    # KTO repair: the distance constraint holds at its collision samples only, so where the
    # dense check still finds the arm too close in between, solve again from that result with
    # three times the samples
    info: dict = {}
    for samples in (25, 75):
        q_kto, info = _kto(cell, checker, q0, q1, guess, min_distance,
                           num_collision_samples=samples)
        if q_kto is None:
            break
        q = _densify(q_kto, step)
        d = check_joint_samples(checker, q, min_distance)
        info["collision_samples"] = samples
        if d >= min_distance:
            break
        guess = q_kto[np.linspace(0, len(q_kto) - 1, 24).astype(int)]
    if q_kto is not None:
        return JointMove(q=q, s=_arc(q), clearance=d, method="kto", ok=d >= min_distance,
                         info=info)
    return JointMove(q=q, s=_arc(q), clearance=d, method="via", ok=False, info=info)


def tcp_line(kin: CellKinematics, q0: np.ndarray, q1: np.ndarray, step: float = 0.01,
             tol: float = 1e-9) -> np.ndarray | None:
    """Dense joints from ``q0`` to ``q1`` whose wrist (J4-J6) runs the straight joint line and
    whose arm (J1-J3) puts the tool point on the straight line between the ends' tool points
    (relative to the hub, at the same share of the way): Newton steps on the arm's 3x3
    position Jacobian (central differences of ``kin.p_HT``) from the straight joint line.

    Where a wrist unwinds (J4/J6 turning by up to a half turn between windows) the straight
    joint line swings the tool point about the flange, up to 1.8x the straight distance on the
    default hub; under the programmed TCP speed that travel is the move's time. Returns None
    where Newton does not settle to ``tol`` [m], a joint leaves its limits or steps more than
    ``step`` [rad] between samples (even after doubling the samples once)."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    p0, p1 = kin.p_HT(np.stack([q0, q1]))
    n = max(1, int(np.ceil(np.max(np.abs(q1 - q0)) / step)))
    for m in (n, 2 * n):
        u = np.linspace(0.0, 1.0, m + 1)[:, None]
        q = q0 + u * (q1 - q0)
        goal = (1.0 - u) * p0 + u * p1
        for _ in range(20):
            r = goal - kin.p_HT(q)
            if np.max(np.abs(r)) <= tol:
                break
            h = 1e-6
            J = np.stack([(kin.p_HT(q + h * e) - kin.p_HT(q - h * e)) / (2 * h)
                          for e in np.eye(6)[:3]], axis=-1)  # (m + 1, 3, 3)
            with np.errstate(all="ignore"):
                q[:, :3] += np.linalg.solve(J, r[..., None])[..., 0]
            if not np.all(np.isfinite(q)):
                return None
        else:
            return None
        q[[0, -1]] = q0, q1
        if not np.all((q >= kin.q_lower) & (q <= kin.q_upper)):
            return None
        if np.max(np.abs(np.diff(q, axis=0))) <= step * (1 + 1e-9):
            return q
    return None


def rounded_corners(way: np.ndarray, share: float, step: float = 0.01) -> np.ndarray:
    """Dense joints along the joint polyline ``way`` (K, 6) with each interior corner
    replaced by a quadratic Bezier blend that starts ``share`` (in (0, 1]) of the shorter
    adjacent leg before the corner and ends as far after it (a leg with a corner at both ends
    lends each at most half of itself, so blends never overlap): tangent-continuous, inside
    the joints' box wherever the polyline is (a blend is a convex combination of its three
    points), at most ``step`` [rad] between samples."""
    way = np.asarray(way, float)
    legs = np.diff(way, axis=0)
    length = np.linalg.norm(legs, axis=1)
    usable = length * np.where((np.arange(len(legs)) > 0)
                               & (np.arange(len(legs)) < len(legs) - 1), 0.5, 1.0)
    pieces, cur = [], way[0]
    for k in range(1, len(way) - 1):
        r = share * min(usable[k - 1], usable[k])
        a = way[k] - r * legs[k - 1] / length[k - 1]
        b = way[k] + r * legs[k] / length[k]
        pieces += [(cur, a), (a, way[k], b)]
        cur = b
    pieces.append((cur, way[-1]))
    out = [way[:1]]
    for pc in pieces:
        if len(pc) == 2:  # a straight stretch (none between two blends that meet)
            a, b = pc
            if np.max(np.abs(b - a)) <= 1e-9 * step:
                continue
            n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
            f = np.linspace(0.0, 1.0, n + 1)[1:, None]
            out.append(a + f * (b - a))
        else:  # |dB/du| <= 2 max(|v - a|, |b - v|) per joint
            a, v, b = pc
            n = max(2, int(np.ceil(2 * max(np.max(np.abs(v - a)), np.max(np.abs(b - v)))
                                   / step)))
            f = np.linspace(0.0, 1.0, n + 1)[1:, None]
            out.append((1 - f) ** 2 * a + 2 * f * (1 - f) * v + f ** 2 * b)
    q = np.concatenate(out)
    q[-1] = way[-1]  # the move's end exactly (the next stretch starts there)
    return q


#: shares of the shorter adjacent leg a via path's corners are rounded by, tried in order
_ROUNDING = (0.9, 0.6, 0.3)


def faster_move(kin: CellKinematics, checker: ClearanceChecker, mv: JointMove,
                duration: Callable[[np.ndarray, np.ndarray], float], min_distance: float,
                step: float = 0.01) -> JointMove:
    """``mv`` or a faster path between its ends: a straight move's :func:`tcp_line`, a via
    move's corners rounded (:func:`rounded_corners`, the widest rounding of
    :data:`_ROUNDING` first: a kink in a joint path is a stop). The first of them that
    ``duration(q, s)`` [s] (the caller's timing of the move) finds faster by 1 ms or more and
    that keeps ``min_distance`` at every sample (the check ``joint_move`` makes); else ``mv``.
    """
    if not mv.ok or len(mv.q) < 2 or not mv.s[-1] > 0:  # no move (a window's ends coincide)
        return mv
    if mv.method == "straight":
        tries = [("tcp_line", lambda: tcp_line(kin, mv.q[0], mv.q[-1], step))]
    elif mv.method == "via" and "waypoints" in mv.info:
        way = mv.info["waypoints"]
        tries = [("via_rounded", lambda f=f: rounded_corners(way, f, step)) for f in _ROUNDING]
    else:
        return mv
    t_old = duration(mv.q, mv.s)
    for method, make in tries:
        q = make()
        if q is None:
            continue
        s = _arc(q)
        t_new = duration(q, s)
        if t_new > t_old - 1e-3:
            continue
        d = check_joint_samples(checker, q, min_distance)
        if d >= min_distance:
            info = dict(mv.info, before_seconds=float(t_old), seconds=float(t_new))
            return replace(mv, q=q, s=s, clearance=d, method=method, info=info)
    return mv


def _lifted(kin: CellKinematics, q: np.ndarray, lift: float) -> np.ndarray | None:
    """Joints of the pose at ``q`` lifted by ``lift`` along +Z_H (same branch); where that
    leaves the joint limits (a wrist wound to its J4 limit at the end of a window), the
    largest of lift/2, /4, /8 that stays inside; where none does (a wrist at its J5 limit:
    every lift bends it further), the same lifts turned about the tool axis by up to 90 deg
    (the burr is round: a pose off the cut may take any turn about its axis), the least
    turn first."""
    X = kin.X_HT_from_q(q)
    for spin in _SPINS:
        R = X[:3, :3] @ _rot_z(spin)
        for h in (lift, 0.5 * lift, 0.25 * lift, 0.125 * lift):
            Xh = X.copy()
            Xh[:3, :3] = R
            Xh[2, 3] += h
            qq, ok = kin.track(kin.X_WF_from_X_HT(Xh[None]), q)
            if ok[0]:
                return qq[0]
    return None


_SPINS = np.radians([0.0, 15.0, -15.0, 30.0, -30.0, 45.0, -45.0, 60.0, -60.0, 90.0, -90.0])


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _via(kin: CellKinematics, q0: np.ndarray, q1: np.ndarray, lift: float) -> np.ndarray | None:
    """Joints of the mid-pose lifted by ``lift`` along +Z_H (same branch as q0)."""
    from scipy.spatial.transform import Rotation, Slerp

    X0, X1 = kin.X_HT_from_q(q0), kin.X_HT_from_q(q1)
    X = np.eye(4)
    ends = Rotation.from_matrix(np.stack([X0[:3, :3], X1[:3, :3]]))
    X[:3, :3] = Slerp([0, 1], ends)(0.5).as_matrix()
    X[:3, 3] = 0.5 * (X0[:3, 3] + X1[:3, 3])
    X[2, 3] = max(X0[2, 3], X1[2, 3]) + lift
    q, ok = kin.track(kin.X_WF_from_X_HT(X[None]), 0.5 * (q0 + q1))
    return q[0] if ok[0] else None


def _kto(cell, checker: ClearanceChecker, q0: np.ndarray, q1: np.ndarray, guess: np.ndarray,
         min_distance: float, num_control_points: int = 12, num_collision_samples: int = 25):
    from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint
    from pydrake.planning import KinematicTrajectoryOptimization
    from pydrake.solvers import SnoptSolver, SolverOptions
    from pydrake.trajectories import BsplineTrajectory, PiecewisePolynomial

    kto = KinematicTrajectoryOptimization(6, num_control_points, spline_order=4)
    prog = kto.get_mutable_prog()
    kto.AddDurationCost(1.0)
    kto.AddPathLengthCost(1.0)
    kto.AddPositionBounds(cell.q_lower, cell.q_upper)
    kto.AddVelocityBounds(cell.v_lower, cell.v_upper)
    kto.AddDurationConstraint(0.2, 20.0)
    kto.AddPathPositionConstraint(q0, q0, 0.0)
    kto.AddPathPositionConstraint(q1, q1, 1.0)
    kto.AddPathVelocityConstraint(np.zeros(6), np.zeros(6), 0.0)
    kto.AddPathVelocityConstraint(np.zeros(6), np.zeros(6), 1.0)
    constraint = MinimumDistanceLowerBoundConstraint(cell.plant, min_distance + 1e-3,
                                                     checker.plant_context, None, 0.01)
    keep = [constraint]  # the program holds raw references: keep the constraint alive
    for r in np.linspace(0.0, 1.0, num_collision_samples)[1:-1]:
        kto.AddPathPositionConstraint(constraint, float(r))
    times = np.linspace(0.0, 1.0, len(guess))
    init = PiecewisePolynomial.FirstOrderHold(times, guess.T)
    basis = kto.basis()
    cps = np.array([init.value(t).ravel() for t in np.linspace(0, 1, num_control_points)]).T
    kto.SetInitialGuess(BsplineTrajectory(basis, list(cps.T[:, :, None])))
    opts = SolverOptions()
    opts.SetOption(SnoptSolver().solver_id(), "Major iterations limit", 300)
    result = SnoptSolver().Solve(prog, None, opts)
    info = dict(kto_success=bool(result.is_success()), kto_solver=result.get_solver_id().name())
    if not result.is_success():
        log.debug("KTO transition repair did not converge")
    traj = kto.ReconstructTrajectory(result)
    keep.clear()
    ts = np.linspace(traj.start_time(), traj.end_time(), 200)
    return np.array([traj.value(t).ravel() for t in ts]), info
