"""Analytic inverse kinematics for OPW robots (orthoparallel arm + spherical wrist).

Brandstoetter, Angerer, Hofbaur (2014): the wrist centre C = p_BF - c4 z_F fixes joints 1-3 (two
shoulder x two elbow branches), the wrist rotation R_ce = R_0c^T R_BF fixes joints 4-6 as
ZYZ Euler angles (two wrist branches): up to 8 solutions. Written out here (vectorised over
poses, a few microseconds per pose) because no maintained Python package offers it; Drake's
numerical IK is the independent check in the tests/benchmarks.

Branch bookkeeping: every solution carries ``(shoulder, elbow, wrist)`` signs (+1/-1):
- shoulder: +1 if the wrist centre is in front of axis 1 (along the direction J1 points),
- elbow: +1 if the wrist centre lies in front of the lower-arm line (J2 -> J3),
- wrist: sign of the (OPW) joint-5 angle.
The vendor configuration data (ABB confdata, KUKA S/T, FANUC CONFIG) are derived from these and
from the joint turns in :mod:`drakedeburr.robots.configuration`.

Selection follows the paper: joints 1-3 by minimum travel weighted by link length, then
joints 4-6 by the smallest change; along a path the configuration (branch) is kept when
possible and 2*pi turns of joints whose limits exceed +-pi are unwrapped toward the previous
point.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.robots.opw import OpwParameters, fk_opw

__all__ = [
    "JointLimits",
    "RobotKinematics",
    "IkSolutions",
    "JointPathResult",
    "ik_opw",
    "arm_branches",
    "joint_candidates",
    "select_solution",
    "solve_path",
    "travel_weights",
]

log = logging.getLogger(__name__)

_TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class JointLimits:
    """Joint position limits in the robot's convention [rad], shape (6,) each."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def contains(self, q: np.ndarray, slack: float = 1e-9) -> np.ndarray:
        """(..., 6) joints -> (...,) bool, True where every joint is inside its limits."""
        q = np.asarray(q, float)
        return np.all((q >= np.asarray(self.lower) - slack) & (q <= np.asarray(self.upper) + slack),
                      axis=-1)


@dataclass(frozen=True)
class RobotKinematics:
    """The kinematic view of an arm: OPW geometry, joint position limits, controller family.

    Attributes:
        opw: OPW parameters (model joints -> OPW joints, see :mod:`drakedeburr.robots.opw`).
        limits: joint position limits in the model's joint convention [rad].
        controller: "abb", "kuka" or "fanuc": which configuration data the arm's programs use.
        name: registry name (e.g. "irb1600") or a free label.
    """

    opw: OpwParameters
    limits: JointLimits
    controller: str = "abb"
    name: str = ""


@dataclass(frozen=True)
class IkSolutions:
    """All analytic IK branches of N poses.

    Attributes:
        q: (N, 8, 6) joints in the robot convention [rad], each wrapped to (-pi, pi]; NaN
            rows where the branch does not exist (out of reach).
        valid: (N, 8) bool, branch exists (reachable; joint limits NOT applied here).
        branch: (8, 3) int signs (shoulder, elbow, wrist), the same for every pose.
    """

    q: np.ndarray
    valid: np.ndarray
    branch: np.ndarray


_BRANCHES = np.array([[s, e, w] for s in (1, -1) for e in (1, -1) for w in (1, -1)], dtype=int)


def _wrap(a: np.ndarray) -> np.ndarray:
    """Angles to (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, _TWO_PI)


def ik_opw(params: OpwParameters, X_BF: np.ndarray, reach_slack: float = 1e-9) -> IkSolutions:
    """All (up to 8) joint solutions for flange poses.

    Args:
        params: OPW geometry of the robot.
        X_BF: (4, 4) or (N, 4, 4) flange poses in the robot base frame [m].
        reach_slack: relative slack on the triangle inequality before a branch is declared
            out of reach (clamps round-off at the stretched-arm boundary).

    Returns:
        IkSolutions with q of shape (N, 8, 6) (N = 1 for a single pose).
    """
    X_BF = np.asarray(X_BF, float)
    if X_BF.ndim == 2:
        X_BF = X_BF[None]
    n = X_BF.shape[0]
    R = X_BF[:, :3, :3]
    C = X_BF[:, :3, 3] - params.c4 * R[:, :, 2]
    a1, a2, b, c1, c2, c3 = params.a1, params.a2, params.b, params.c1, params.c2, params.c3
    k = np.hypot(a2, c3)
    psi3 = np.arctan2(a2, c3)
    r2 = C[:, 0] ** 2 + C[:, 1] ** 2 - b * b
    r = np.sqrt(np.clip(r2, 0.0, None))
    # the four arm branches (shoulder, elbow) = (+,+), (+,-), (-,+), (-,-), shape (n, 4)
    s_sign = np.array([1.0, 1.0, -1.0, -1.0])
    e_sign = np.array([1.0, -1.0, 1.0, -1.0])
    cx1 = r[:, None] * s_sign
    q0 = np.arctan2(C[:, 1], C[:, 0])[:, None] - np.arctan2(b, cx1)
    x = cx1 - a1
    z = (C[:, 2] - c1)[:, None]
    cphi = (x * x + z * z - c2 * c2 - k * k) / (2.0 * c2 * k)
    ok = (np.abs(cphi) <= 1.0 + reach_slack) & (r2 >= -reach_slack)[:, None]
    phi = e_sign * np.arccos(np.clip(cphi, -1.0, 1.0))
    q1 = np.arctan2(x, z) - np.arctan2(k * np.sin(phi), c2 + k * np.cos(phi))
    q2 = phi - psi3
    # wrist: R_ce = R_0c^T R, R_0c = Rz(q0) Ry(q1 + q2)
    s1, co1 = np.sin(q0), np.cos(q0)
    s2, co2 = np.sin(q1 + q2), np.cos(q1 + q2)
    # rows of R_0c^T: (c1 c2, s1 c2, -s2), (-s1, c1, 0), (c1 s2, s1 s2, c2)
    Rt0 = np.stack([co1 * co2, s1 * co2, -s2], -1)
    Rt1 = np.stack([-s1, co1, np.zeros_like(s1)], -1)
    Rt2 = np.stack([co1 * s2, s1 * s2, co2], -1)
    # R_ce[a, b] = Rt_a . R[:, b]
    r02 = np.einsum("nbi,ni->nb", Rt0, R[:, :, 2])
    r12 = np.einsum("nbi,ni->nb", Rt1, R[:, :, 2])
    r22 = np.einsum("nbi,ni->nb", Rt2, R[:, :, 2])
    r20 = np.einsum("nbi,ni->nb", Rt2, R[:, :, 0])
    r21 = np.einsum("nbi,ni->nb", Rt2, R[:, :, 1])
    q4 = np.arctan2(np.hypot(r02, r12), r22)
    q3 = np.arctan2(r12, r02)
    q5 = np.arctan2(r21, -r20)
    # at q4 ~ 0 (wrist singular) only q3 + q5 is defined: put it all in q5
    sing = np.abs(np.sin(q4)) < 1e-12
    if np.any(sing):
        r00 = np.einsum("nbi,ni->nb", Rt0, R[:, :, 0])
        r10 = np.einsum("nbi,ni->nb", Rt1, R[:, :, 0])
        q5 = np.where(sing, np.arctan2(r10, r00), q5)
        q3 = np.where(sing, 0.0, q3)
    up = np.stack([q0, q1, q2, q3, q4, q5], -1)  # (n, 4, 6)
    flip = np.stack([q0, q1, q2, q3 + np.pi, -q4, q5 + np.pi], -1)
    q_opw = np.stack([up, flip], 2).reshape(n, 8, 6)  # order matches _BRANCHES
    q_rob = _wrap(params.q_robot_from_opw(q_opw))
    q_all = np.where(np.repeat(ok, 2, axis=1)[:, :, None], q_rob, np.nan)
    valid = ~np.any(np.isnan(q_all), axis=-1)
    return IkSolutions(q=q_all, valid=valid, branch=_BRANCHES.copy())


def arm_branches(params: OpwParameters, q_robot: np.ndarray) -> np.ndarray:
    """Branch signs (shoulder, elbow, wrist) of joint vectors, from the geometry.

    Args:
        params: OPW geometry.
        q_robot: (..., 6) joints in the robot convention [rad].

    Returns:
        (..., 3) int array of +1/-1 (0 exactly on a singular boundary).
    """
    q = params.q_opw_from_robot(np.asarray(q_robot, float))
    q1, q2, q4 = q[..., 1], q[..., 2], q[..., 4]
    k = np.hypot(params.a2, params.c3)
    psi3 = np.arctan2(params.a2, params.c3)
    # wrist centre in the arm plane, relative to axis 1 (x along J1's direction)
    cx1 = params.c2 * np.sin(q1) + k * np.sin(q1 + q2 + psi3) + params.a1
    shoulder = np.sign(cx1)
    # elbow: side of the wrist centre w.r.t. the lower arm (J2->J3, direction (sin q1, cos q1))
    # forward normal of the lower arm (cos q1, -sin q1): component of the upper arm
    elbow = np.sign(np.sin(q2 + psi3))
    wrist = np.sign(np.sin(q4))
    return np.stack([shoulder, elbow, wrist], -1).astype(int)


def joint_candidates(q: np.ndarray, limits: JointLimits) -> np.ndarray:
    """All 2*pi-turn variants of joint vectors that lie inside the limits.

    Args:
        q: (M, 6) joint vectors [rad] (NaN rows are dropped).
        limits: joint limits.

    Returns:
        (K, 6) joint vectors inside the limits (K may be 0).
    """
    q = np.asarray(q, float)
    q = q[~np.any(np.isnan(q), axis=1)]
    lo, hi = np.asarray(limits.lower), np.asarray(limits.upper)
    out = []
    for row in q:
        options = []
        for j in range(6):
            kmin = int(np.ceil((lo[j] - row[j]) / _TWO_PI - 1e-12))
            kmax = int(np.floor((hi[j] - row[j]) / _TWO_PI + 1e-12))
            options.append([row[j] + _TWO_PI * kk for kk in range(kmin, kmax + 1)])
        if any(len(o) == 0 for o in options):
            continue
        grids = np.meshgrid(*options, indexing="ij")
        out.append(np.stack([g.ravel() for g in grids], -1))
    return np.concatenate(out, 0) if out else np.zeros((0, 6))


def travel_weights(params: OpwParameters) -> np.ndarray:
    """Per-joint travel weights [m/rad]: J1-J3 by the link length they swing (paper's rule).

    J1 swings the whole arm (a1 + c2 + c3 + c4), J2 swings c2 + c3 + c4, J3 swings c3 + c4.
    Joints 4-6 get weight 1 (they are compared among themselves only).
    """
    w1 = params.a1 + params.c2 + params.c3 + params.c4
    w2 = params.c2 + params.c3 + params.c4
    w3 = params.c3 + params.c4
    return np.array([w1, w2, w3, 1.0, 1.0, 1.0])


def select_solution(
    candidates: np.ndarray,
    q_prev: np.ndarray,
    weights: np.ndarray,
    arm_tol: float = 1e-9,
) -> int:
    """Index of the candidate the paper's rule picks.

    First the arm (J1-J3) with minimum travel weighted by link length; among candidates within
    ``arm_tol`` of that minimum, the wrist (J4-J6) with the smallest change.

    Args:
        candidates: (K, 6) joint vectors [rad], K >= 1.
        q_prev: (6,) previous joints [rad].
        weights: (6,) travel weights (see :func:`travel_weights`).
        arm_tol: tie tolerance on the arm cost [m].
    """
    d = np.abs(candidates - np.asarray(q_prev)[None])
    arm = d[:, :3] @ weights[:3]
    wrist = d[:, 3:] @ weights[3:]
    ties = np.flatnonzero(arm <= arm.min() + arm_tol)
    return int(ties[np.argmin(wrist[ties])])


@dataclass(frozen=True)
class JointPathResult:
    """Joint solution of a pose sequence.

    Attributes:
        q: (N, 6) joints [rad], NaN rows at unreachable points.
        reachable: (N,) bool, a solution inside the joint limits exists.
        branch: (N, 3) int branch signs (shoulder, elbow, wrist) of the chosen solution
            (0 at unreachable points).
        configuration_changes: indices i where the branch differs from point i-1's.
        failed: indices of unreachable points.
    """

    q: np.ndarray
    reachable: np.ndarray
    branch: np.ndarray
    configuration_changes: tuple[int, ...] = field(default=())
    failed: tuple[int, ...] = field(default=())

    @property
    def ok(self) -> bool:
        return len(self.failed) == 0


def solve_path(
    robot: RobotKinematics,
    X_BF: np.ndarray,
    q_start: np.ndarray | None = None,
    keep_configuration: bool = True,
    progress: Callable[[int, int, str], None] | None = None,
) -> JointPathResult:
    """Joints for a sequence of flange poses with configuration continuity.

    At each point all IK branches and 2*pi turns inside the limits are candidates. With
    ``keep_configuration`` the candidates of the previous point's branch are preferred when
    there are any; the paper's rule (:func:`select_solution`) picks among them. The first
    point is chosen relative to ``q_start`` (default: zeros, the robot's calibration pose).

    Args:
        robot: kinematics and limits.
        X_BF: (N, 4, 4) flange poses in the robot base frame [m].
        q_start: (6,) joints the robot comes from [rad].
        keep_configuration: prefer the previous branch.
        progress: optional callback (done, total, label).

    Returns:
        JointPathResult; unreachable points are listed in ``failed``, never raised.
    """
    X_BF = np.asarray(X_BF, float).reshape(-1, 4, 4)
    n = X_BF.shape[0]
    sols = ik_opw(robot.opw, X_BF)
    weights = travel_weights(robot.opw)
    q_prev = np.zeros(6) if q_start is None else np.asarray(q_start, float)
    branch_prev: np.ndarray | None = None
    q_out = np.full((n, 6), np.nan)
    br_out = np.zeros((n, 3), int)
    reach = np.zeros(n, bool)
    changes: list[int] = []
    failed: list[int] = []
    for i in range(n):
        cand = joint_candidates(sols.q[i], robot.limits)
        if cand.shape[0] == 0:
            failed.append(i)
        else:
            br = arm_branches(robot.opw, cand)
            if keep_configuration and branch_prev is not None:
                same = np.all(br == branch_prev[None], axis=1)
                if np.any(same):
                    cand, br = cand[same], br[same]
            j = select_solution(cand, q_prev, weights)
            q_out[i], br_out[i], reach[i] = cand[j], br[j], True
            if branch_prev is not None and np.any(br[j] != branch_prev):
                changes.append(i)
            q_prev, branch_prev = cand[j], br[j]
        if progress is not None and (i + 1 == n or (i + 1) % 100 == 0):
            progress(i + 1, n, "IK")
    if failed:
        log.info("%d of %d poses unreachable for %s", len(failed), n, robot.name)
    return JointPathResult(q=q_out, reachable=reach, branch=br_out,
                           configuration_changes=tuple(changes), failed=tuple(failed))


def fk_flange(robot: RobotKinematics, q: np.ndarray) -> np.ndarray:
    """Flange pose(s) X_BF for joints (convenience alias of :func:`fk_opw`)."""
    return fk_opw(robot.opw, q)
