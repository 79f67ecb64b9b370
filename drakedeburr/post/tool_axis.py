"""5-axis CL data on a 6-axis robot: resolve the free spin about the tool axis.

A CL point fixes the tool tip and the tool axis (i, j, k) = tip -> spindle = -Z_T; the
rotation about Z_T is free. Two rules:

- ``"min_travel"``: at each point the spin whose IK solution (same configuration as the
  previous point when possible) moves the joints least, weighted per
  :func:`~drakedeburr.post.opw_ik.travel_weights` (a grid over the spin, then a bounded
  scalar refinement with scipy);
- ``"theta6_zero"``: the paper's choice, the spin that makes joint 6 zero (or as small as the
  pose allows).

:func:`path_travel` measures the weighted joint travel of a result, to compare the two.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.post.opw_ik import (
    RobotKinematics,
    arm_branches,
    ik_opw,
    travel_weights,
)

__all__ = [
    "SPIN_MODES",
    "ToolAxisPathResult",
    "tool_frames",
    "solve_tool_axis_path",
    "path_travel",
    "READY_POSE",
]

log = logging.getLogger(__name__)

SPIN_MODES = ("min_travel", "theta6_zero")
# a neutral start: arm up, wrist bent 90 deg so a tool on the flange axis points down
READY_POSE = np.array([0.0, 0.0, 0.0, 0.0, np.pi / 2, 0.0])
_TWO_PI = 2 * np.pi


def tool_frames(p_W: np.ndarray, axis_W: np.ndarray, spin: np.ndarray | float = 0.0,
                x_ref_W: np.ndarray = (1.0, 0.0, 0.0)) -> np.ndarray:
    """Tool poses from tip positions, CAM tool axes and spins.

    Z_T = -axis. With spin 0, X_T is ``x_ref_W`` projected onto the plane normal to Z_T
    (world y when the two are nearly parallel); ``spin`` rotates the frame about Z_T.

    Args:
        p_W: (N, 3) tool tip positions [m].
        axis_W: (N, 3) unit tool axes tip -> spindle.
        spin: (N,) or scalar rotation about Z_T [rad].
        x_ref_W: (3,) reference direction for X_T.

    Returns:
        (N, 4, 4) X_WT.
    """
    p_W = np.atleast_2d(np.asarray(p_W, float))
    z = -np.atleast_2d(np.asarray(axis_W, float))
    z = z / np.linalg.norm(z, axis=1, keepdims=True)
    ref = np.broadcast_to(np.asarray(x_ref_W, float), z.shape).copy()
    near = np.abs(np.einsum("ij,ij->i", ref / np.linalg.norm(ref, axis=1, keepdims=True), z)) > 0.99
    ref[near] = [0.0, 1.0, 0.0]
    x0 = ref - np.einsum("ij,ij->i", ref, z)[:, None] * z
    x0 /= np.linalg.norm(x0, axis=1, keepdims=True)
    y0 = np.cross(z, x0)
    s = np.broadcast_to(np.asarray(spin, float), (z.shape[0],))
    x = np.cos(s)[:, None] * x0 + np.sin(s)[:, None] * y0
    y = np.cross(z, x)
    X = np.zeros((z.shape[0], 4, 4))
    X[:, :3, 0], X[:, :3, 1], X[:, :3, 2], X[:, :3, 3] = x, y, z, p_W
    X[:, 3, 3] = 1.0
    return X


@dataclass(frozen=True)
class ToolAxisPathResult:
    """Joints for 5-axis CL data.

    Attributes:
        q: (N, 6) joints [rad]; NaN rows at unreachable points.
        X_WT: (N, 4, 4) tool poses with the chosen spin [m].
        spin: (N,) chosen spin about Z_T [rad] (NaN where unreachable).
        reachable: (N,) bool.
        failed: indices of unreachable points.
        configuration_changes: indices where the branch differs from the previous point's.
        mode: the spin rule used.
    """

    q: np.ndarray
    X_WT: np.ndarray
    spin: np.ndarray
    reachable: np.ndarray
    failed: tuple[int, ...]
    configuration_changes: tuple[int, ...]
    mode: str

    @property
    def ok(self) -> bool:
        return len(self.failed) == 0


def _nearest_turns(q: np.ndarray, q_prev: np.ndarray, lo: np.ndarray, hi: np.ndarray
                   ) -> np.ndarray:
    """Shift each joint by 2*pi turns toward q_prev where the limits allow. q: (M, 6)."""
    k = np.round((q_prev[None] - q) / _TWO_PI)
    q2 = q + _TWO_PI * k
    bad = (q2 < lo) | (q2 > hi)
    return np.where(bad, q, q2)


def _candidates(robot: RobotKinematics, X_WF: np.ndarray, q_prev: np.ndarray):
    """(M, 8, 6) joints unwrapped toward q_prev, (M, 8) valid-and-inside, (M, 8, 3) branches."""
    sols = ik_opw(robot.opw, X_WF)
    lo, hi = np.asarray(robot.limits.lower), np.asarray(robot.limits.upper)
    q = sols.q.reshape(-1, 6)
    ok = ~np.any(np.isnan(q), axis=1)
    q[ok] = _nearest_turns(q[ok], q_prev, lo, hi)
    inside = ok & robot.limits.contains(np.nan_to_num(q))
    m = X_WF.shape[0]
    return q.reshape(m, 8, 6), inside.reshape(m, 8), np.broadcast_to(
        sols.branch[None], (m, 8, 3))


def solve_tool_axis_path(
    robot: RobotKinematics,
    p_W: np.ndarray,
    axis_W: np.ndarray,
    X_FT: np.ndarray,
    mode: str = "min_travel",
    q_start: np.ndarray | None = None,
    n_spin: int = 72,
    x_ref_W: np.ndarray = (1.0, 0.0, 0.0),
    progress: Callable[[int, int, str], None] | None = None,
) -> ToolAxisPathResult:
    """Joints for tool tip positions and axes, resolving the free spin (see module docstring).

    Args:
        robot: kinematics and limits.
        p_W: (N, 3) tool tip positions in the robot base [m].
        axis_W: (N, 3) unit tool axes tip -> spindle (CAM convention) in the robot base.
        X_FT: (4, 4) tool in the flange frame [m].
        mode: "min_travel" or "theta6_zero".
        q_start: (6,) joints before the first point [rad] (default :data:`READY_POSE`).
        n_spin: grid size over the spin before refinement.
        x_ref_W: spin-0 reference direction of X_T.
        progress: optional callback (done, total, label).

    Returns:
        ToolAxisPathResult; unreachable points are listed, not raised.
    """
    if mode not in SPIN_MODES:
        raise InputError(f"spin mode {mode!r}: use one of {', '.join(SPIN_MODES)}")
    p_W = np.atleast_2d(np.asarray(p_W, float))
    axis_W = np.atleast_2d(np.asarray(axis_W, float))
    if p_W.shape != axis_W.shape or p_W.shape[1] != 3:
        raise InputError(f"p_W {p_W.shape} and axis_W {axis_W.shape} must both be (N, 3)")
    n = p_W.shape[0]
    X_TF = np.linalg.inv(np.asarray(X_FT, float))
    w = travel_weights(robot.opw)
    q_prev = READY_POSE.copy() if q_start is None else np.asarray(q_start, float)
    br_prev: np.ndarray | None = None
    grid = np.linspace(-np.pi, np.pi, n_spin, endpoint=False)
    q_out = np.full((n, 6), np.nan)
    spin_out = np.full(n, np.nan)
    X_out = np.zeros((n, 4, 4))
    failed, changes = [], []

    def cost_of(q: np.ndarray, ok: np.ndarray, br: np.ndarray, qp: np.ndarray,
                bp: np.ndarray | None) -> np.ndarray:
        c = np.abs(q - qp) @ w
        if mode == "theta6_zero":
            c = np.abs(q[..., 5]) * 10.0 + 1e-3 * c
        if bp is not None:
            c = c + 1e3 * np.any(br != bp, axis=-1)  # keep the configuration if possible
        return np.where(ok, c, np.inf)

    for i in range(n):
        X_WT = tool_frames(np.repeat(p_W[i:i + 1], n_spin, 0), np.repeat(axis_W[i:i + 1],
                           n_spin, 0), grid, x_ref_W)
        q, ok, br = _candidates(robot, X_WT @ X_TF, q_prev)
        if br_prev is None and mode == "theta6_zero":
            # first point: the branch closest to q_start (as in min_travel), then J6 = 0 in it
            c_travel = np.where(ok, np.abs(q - q_prev) @ w, np.inf)
            k0 = np.unravel_index(np.argmin(c_travel), c_travel.shape)
            if np.isfinite(c_travel[k0]):
                br_prev = br[k0]
        c = cost_of(q, ok, br, q_prev, br_prev)
        k_best = np.unravel_index(np.argmin(c), c.shape)
        if not np.isfinite(c[k_best]):
            failed.append(i)
            X_out[i] = tool_frames(p_W[i:i + 1], axis_W[i:i + 1], 0.0, x_ref_W)[0]
            continue
        branch_idx = k_best[1]
        s_best, c_best = grid[k_best[0]], c[k_best]
        step = _TWO_PI / n_spin
        # vectorised zoom around the best grid spin (same branch): 21 samples, /10 per level
        while step > 1e-9:
            local = s_best + np.linspace(-step, step, 21)
            X = tool_frames(np.repeat(p_W[i:i + 1], 21, 0), np.repeat(axis_W[i:i + 1], 21, 0),
                            local, x_ref_W)
            qq, okk, bb = _candidates(robot, X @ X_TF, q_prev)
            cc = cost_of(qq[:, branch_idx], okk[:, branch_idx], bb[:, branch_idx], q_prev,
                         br_prev)
            j = int(np.argmin(cc))
            if cc[j] <= c_best:
                s_best, c_best = float(local[j]), cc[j]
            step /= 10.0
        X = tool_frames(p_W[i:i + 1], axis_W[i:i + 1], s_best, x_ref_W)
        qq, okk, bb = _candidates(robot, X @ X_TF, q_prev)
        q_out[i], spin_out[i], X_out[i] = qq[0, branch_idx], s_best, X[0]
        b_now = arm_branches(robot.opw, q_out[i])
        if br_prev is not None and np.any(b_now != br_prev):
            changes.append(i)
        q_prev, br_prev = q_out[i], b_now
        if progress is not None and (i + 1 == n or (i + 1) % 50 == 0):
            progress(i + 1, n, "spin + IK")
    reach = ~np.any(np.isnan(q_out), axis=1)
    if failed:
        log.info("%d of %d CL points unreachable", len(failed), n)
    return ToolAxisPathResult(q=q_out, X_WT=X_out, spin=spin_out, reachable=reach,
                              failed=tuple(failed), configuration_changes=tuple(changes),
                              mode=mode)


def path_travel(robot: RobotKinematics, q: np.ndarray) -> dict[str, float]:
    """Joint travel of a path (reachable rows only).

    Returns:
        {'weighted': sum of travel_weights . |dq| [m], 'arm': J1-J3 [rad], 'wrist': J4-J6 [rad],
         'j6': J6 alone [rad]}.
    """
    q = np.asarray(q, float)
    q = q[~np.any(np.isnan(q), axis=1)]
    d = np.abs(np.diff(q, axis=0))
    return {"weighted": float((d @ travel_weights(robot.opw)).sum()),
            "arm": float(d[:, :3].sum()), "wrist": float(d[:, 3:].sum()),
            "j6": float(d[:, 5].sum())}
