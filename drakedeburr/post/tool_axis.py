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

import dataclasses
import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots.opw_ik import (
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

SPIN_MODES = ("min_travel", "greedy", "theta6_zero")
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


_BRANCH_CHANGE_COST = 1e3  # [m] travel-equivalent penalty for a configuration change
_DP_SPINS = 24  # spin grid of the dynamic programme (15 deg); refined per point afterwards


def _dp_spins(robot: RobotKinematics, p_W: np.ndarray, axis_W: np.ndarray, X_TF: np.ndarray,
              q_start: np.ndarray, grid: np.ndarray, x_ref_W: np.ndarray, w: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Globally least-travel (spin index, branch index) per point; -1 where no state exists.

    States are (spin, branch) pairs; joints whose range exceeds 2*pi are compared modulo
    2*pi (their turn is unwrapped afterwards).
    """
    n, m = p_W.shape[0], grid.size
    lo, hi = np.asarray(robot.limits.lower), np.asarray(robot.limits.upper)
    wraps = (hi - lo) > _TWO_PI + 1e-9
    qs, oks = [], []
    for i in range(n):
        X = tool_frames(np.repeat(p_W[i:i + 1], m, 0), np.repeat(axis_W[i:i + 1], m, 0), grid,
                        x_ref_W) @ X_TF
        sols = ik_opw(robot.opw, X)
        q = sols.q.reshape(m * 8, 6)
        inside = np.all(((q >= lo) & (q <= hi)) | wraps, axis=1)
        qs.append(np.nan_to_num(q))
        oks.append(sols.valid.reshape(-1) & inside)
    branch = np.tile(ik_opw(robot.opw, np.eye(4)).branch, (m, 1))  # (m*8, 3) per state
    same = np.all(branch[:, None] == branch[None], axis=-1)
    penalty = np.where(same, 0.0, _BRANCH_CHANGE_COST)

    def dist(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
        d = qa[:, None, :] - qb[None, :, :]
        d = np.where(wraps, np.abs(np.pi - np.mod(np.pi - d, _TWO_PI)), np.abs(d))
        return d @ w

    acc = None
    back: list[np.ndarray | None] = []
    prev_q = None
    for i in range(n):
        if not oks[i].any():
            back.append(None)
            continue
        if acc is None:
            acc_new = dist(q_start[None], qs[i])[0]
            bp = np.full(m * 8, -1)
        else:
            total = acc[:, None] + dist(prev_q, qs[i]) + penalty
            bp = np.argmin(total, axis=0)
            acc_new = total[bp, np.arange(m * 8)]
        acc = np.where(oks[i], acc_new, np.inf)
        back.append(bp)
        prev_q = qs[i]
    choice = np.full(n, -1)
    if acc is None:
        return choice, choice.copy()
    k = int(np.argmin(acc))
    for i in range(n - 1, -1, -1):
        if back[i] is None:
            continue
        choice[i] = k
        k = int(back[i][k])
    spin_idx = np.where(choice >= 0, choice // 8, -1)
    branch_idx = np.where(choice >= 0, choice % 8, -1)
    return spin_idx, branch_idx


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
        mode: "min_travel", "greedy" or "theta6_zero".
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
    dp_spin = dp_branch = None
    dp_grid = np.linspace(-np.pi, np.pi, _DP_SPINS, endpoint=False)
    if mode == "min_travel":
        dp_spin, dp_branch = _dp_spins(robot, p_W, axis_W, X_TF, q_prev, dp_grid,
                                       np.asarray(x_ref_W, float), w)

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
        step = _TWO_PI / n_spin
        s_best, c_best = grid[k_best[0]], c[k_best]
        if dp_spin is not None and dp_spin[i] >= 0:
            # the globally chosen state; refined within +-1 DP grid step below
            s_dp = float(dp_grid[dp_spin[i]])
            X = tool_frames(p_W[i:i + 1], axis_W[i:i + 1], s_dp, x_ref_W)
            qq, okk, bb = _candidates(robot, X @ X_TF, q_prev)
            c_dp = cost_of(qq[0], okk[0], bb[0], q_prev, br_prev)[dp_branch[i]]
            if np.isfinite(c_dp):
                k_best = (k_best[0], int(dp_branch[i]))
                s_best, c_best, step = s_dp, c_dp, _TWO_PI / _DP_SPINS
        if not np.isfinite(c_best):
            failed.append(i)
            X_out[i] = tool_frames(p_W[i:i + 1], axis_W[i:i + 1], 0.0, x_ref_W)[0]
            continue
        branch_idx = k_best[1]
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
    result = ToolAxisPathResult(q=q_out, X_WT=X_out, spin=spin_out, reachable=reach,
                                failed=tuple(failed), configuration_changes=tuple(changes),
                                mode=mode)
    if mode == "min_travel":
        # the DP works on a 15 deg grid; where the continuous greedy path is better (e.g. a
        # tool on the flange axis, where keeping J6 still is optimal) take that one
        greedy = solve_tool_axis_path(robot, p_W, axis_W, X_FT, "greedy", q_start, n_spin,
                                      x_ref_W)
        if (len(greedy.failed), len(greedy.configuration_changes),
                path_travel(robot, greedy.q)["weighted"]) < (
                len(result.failed), len(result.configuration_changes),
                path_travel(robot, result.q)["weighted"]):
            result = dataclasses.replace(greedy, mode=mode)
    return result


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
