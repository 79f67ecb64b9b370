"""5-axis CL data on a 6-axis robot: resolve the free spin about the tool axis.

A CL point fixes the tool tip and the tool axis (i, j, k) = tip -> spindle = -Z_T; the
rotation about Z_T (the spin) is free. Three rules:

- ``"min_travel"`` (default): the path of least weighted joint travel
  (:func:`~drakedeburr.robots.opw_ik.travel_weights`), counted from the start pose, with a
  penalty per configuration change. A dynamic programme over (16-value spin grid x 8 IK
  branches) states picks the branch and spin basin of every point for the whole path at once;
  three finer passes (+-1 previous spacing on 17 values, branch kept, the same programme)
  bring the spin to 0.044 deg;
- ``"theta6_zero"``: the paper's choice, J6 = 0 (or as small as the pose allows): the same
  programme with |J6| as the main cost and travel 1e-3 of it, then Newton steps on J6 = 0;
- ``"greedy"``: point by point with no look-ahead, the state closest to the previous point's
  joints (5 deg grid, then 4 zooms of 1/16 on the chosen branch): the baseline rule.

Workpiece in hand (``X_WS`` given): the spindle stands still at ``X_WS`` in the robot base and
the robot carries the part; the CL points and axes are then in the held part's frame O, the
flange-carried frame is O (``X_FT`` = X_FO) and the flange pose at a spin is
``X_WF = X_WS X_OC(spin)^-1 X_FO^-1`` (the CL tool frame C brought onto the spindle's TCP).

When the tool's axis lies on the flange axis (TCP on the flange Z axis, Z_T parallel to Z_F),
the spin only turns joint 6: joints 1-5 follow from one IK per point and the rules are exact
(J6 held still for min_travel and greedy, J6 = 0 for theta6_zero; the branch sequence by the
same programme). The IK is vectorised over points and spins (chunks of 1024 poses), and the
path is solved in segments of :data:`SEGMENT` points, each looking :data:`OVERLAP` points
ahead before it is committed, so memory does not grow with the path.

:func:`path_travel` measures the weighted joint travel of a result, to compare rules.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.frames.vectors import inverse_transform
from drakedeburr.robots.opw_ik import RobotKinematics, ik_opw, travel_weights

__all__ = [
    "SPIN_MODES",
    "ToolAxisOptions",
    "SEGMENT",
    "OVERLAP",
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
SEGMENT = 2048  # points solved together (bounded memory; the DP restarts at each segment)
_TWO_PI = 2 * np.pi
_IK_CHUNK = 1024  # poses per IK call: the vectorised IK is fastest at this size (cache)
_BRANCH_CHANGE_COST = 1e3  # [m] travel-equivalent penalty for a configuration change
_THETA6_WEIGHT = 10.0  # [m/rad] cost of |J6| in theta6_zero; joint travel weighs 1e-3 there
_LOCAL = 8  # finer passes: +-1 previous spacing on 2 * 8 + 1 values (spacing / 8 each pass)
_STAGES = 3  # 22.5 deg grid -> 2.8 -> 0.35 -> 0.044 deg
_GREEDY_SPINS = 72  # 5 deg grid of the greedy rule
OVERLAP = 256  # points solved beyond a segment's end so its last choices see the path ahead


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
class ToolAxisOptions:
    """Start and spin grid of :func:`solve_tool_axis_path`.

    Attributes:
        q_start: (6,) joints before the first point [rad] (None: :data:`READY_POSE`).
        n_spin: spin grid of the dynamic programme (then refined continuously), >= 4.
        x_ref_W: spin-0 reference direction of X_T.
    """

    q_start: np.ndarray | None = None
    n_spin: int = 16
    x_ref_W: tuple[float, float, float] | np.ndarray = (1.0, 0.0, 0.0)


@dataclass(frozen=True)
class ToolAxisPathResult:
    """Joints for 5-axis CL data.

    Attributes:
        q: (N, 6) joints [rad]; NaN rows at unreachable points.
        X_WT: (N, 4, 4) poses of the flange-carried frame with the chosen spin [m]: the tool,
            or the held part (workpiece in hand).
        spin: (N,) chosen spin about Z_T [rad] (NaN where unreachable).
        reachable: (N,) bool.
        failed: indices of unreachable points.
        configuration_changes: indices where the branch differs from the previous reachable
            point's, or a joint turns by more than pi (a 2*pi unwind forced by its limits).
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


@dataclass(frozen=True)
class _Problem:
    """Everything the per-segment solvers share. Arrays over all points of the path."""

    robot: RobotKinematics
    p_W: np.ndarray  # (N, 3)
    axis_W: np.ndarray  # (N, 3)
    X_TF: np.ndarray  # (4, 4)
    x_ref_W: np.ndarray  # (3,)
    mode: str
    lo: np.ndarray
    hi: np.ndarray
    wraps: np.ndarray  # (6,) bool, joint range > 2 pi: compared modulo 2 pi
    period: np.ndarray  # (6,) 2 pi where wraps, inf elsewhere
    w_edge: np.ndarray  # (6,) travel weights of one step
    w_node6: float  # weight of |J6| at each point (theta6_zero)
    X_WS: np.ndarray | None = None  # (4, 4) stationary tool (workpiece in hand), else None

    def carried(self, idx: np.ndarray, spins: np.ndarray) -> np.ndarray:
        """(K, 4, 4) pose in the base of the flange-carried frame at points ``idx``, ``spins``:
        the tool (tool in hand) or the held part (workpiece in hand)."""
        X_C = tool_frames(self.p_W[idx], self.axis_W[idx], spins, self.x_ref_W)
        return X_C if self.X_WS is None else self.X_WS @ inverse_transform(X_C)

    def ik(self, idx: np.ndarray, spins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K, 8, 6) joints wrapped to (-pi, pi] and (K, 8) feasible, for points ``idx`` (K,)
        at ``spins`` (K,) [rad]. Joints with a range over 2*pi are feasible at any angle."""
        k = idx.shape[0]
        q = np.empty((k, 8, 6))
        ok = np.empty((k, 8), bool)
        for a in range(0, k, _IK_CHUNK):
            sl = slice(a, a + _IK_CHUNK)
            X = self.carried(idx[sl], spins[sl]) @ self.X_TF
            sols = ik_opw(self.robot.opw, X)
            inside = ((sols.q >= self.lo) & (sols.q <= self.hi)) | self.wraps
            q[sl] = np.nan_to_num(sols.q)
            ok[sl] = sols.valid & np.all(inside, axis=-1)
        return q, ok

    def dist(self, qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
        """Weighted joint travel between broadcastable (..., 6) arrays (wrap-aware) [m]."""
        d = np.abs(qa - qb)
        np.minimum(d, self.period - d, out=d)  # period inf for joints that do not wrap
        return d @ self.w_edge

    def node(self, q: np.ndarray) -> np.ndarray | float:
        """Cost of the joints themselves: w * |J6| (theta6_zero), else 0."""
        return self.w_node6 * np.abs(q[..., 5]) if self.w_node6 else 0.0


def _flange_axis_tool(X_FT: np.ndarray, tol: float = 1e-9) -> bool:
    """True when the TCP is on the flange Z axis and Z_T is parallel to Z_F: then the spin
    about Z_T only turns joint 6."""
    return bool(np.abs(X_FT[:2, 3]).max() < tol and np.abs(X_FT[:2, 2]).max() < tol)


def _single_branch_path(prob: _Problem, Q: np.ndarray, OK: np.ndarray, q0: np.ndarray,
                        b0: int) -> np.ndarray | None:
    """The DP's answer, vectorised, when one state per branch (Q (L, B, 6), OK (L, B)) and
    keeping one branch throughout costs at most one configuration change: every path that
    changes branch costs more. None when that does not hold (then the DP runs)."""
    rows = OK.any(1)
    if not rows.any():
        return np.full(Q.shape[0], -1)
    Qr = Q[rows]
    whole = OK[rows].all(0)
    if not whole.any():
        return None
    node = prob.node(Qr)
    cost = (prob.dist(q0, Qr[0]) + (node.sum(0) if np.ndim(node) else 0.0)
            + prob.dist(Qr[1:], Qr[:-1]).sum(0))
    if b0 >= 0:
        cost = cost + _BRANCH_CHANGE_COST * (np.arange(Q.shape[1]) != b0)
    cost = np.where(whole, cost, np.inf)
    b = int(cost.argmin())
    if cost[b] > _BRANCH_CHANGE_COST:
        return None
    choice = np.full(Q.shape[0], -1)
    choice[rows] = b
    return choice


def _dp_one_branch(prob: _Problem, Q: np.ndarray, OK: np.ndarray, q0: np.ndarray
                   ) -> np.ndarray:
    """:func:`_dp` for one branch: Q (L, M, 6), OK (L, M); returns (L,) state, -1 where none."""
    L, M, _ = Q.shape
    back = np.full((L, M), -1, np.int64)
    stepped = OK.any(1)
    cols = np.arange(M)
    acc = qp = None
    for i in np.flatnonzero(stepped):
        qc = Q[i]
        if acc is None:
            new = prob.dist(q0, qc) + prob.node(qc)
        else:
            tot = acc[:, None] + prob.dist(qp[:, None, :], qc[None, :, :])
            src = tot.argmin(0)
            back[i] = src
            new = tot[src, cols] + prob.node(qc)
        acc = np.where(OK[i], new, np.inf)
        qp = qc
    choice = np.full(L, -1)
    if acc is None:
        return choice
    k = int(acc.argmin())
    for i in np.flatnonzero(stepped)[::-1]:
        choice[i] = k
        k = int(back[i, k])
    return choice


def _dp(prob: _Problem, Q: np.ndarray, OK: np.ndarray, q0: np.ndarray, b0: int) -> np.ndarray:
    """Least-cost state per point: Q (L, 8, M, 6) joints, OK (L, 8, M) feasible, starting from
    joints q0 (6,) in branch b0 (-1: none). Returns (L,) flat state b * M + m, -1 where no
    state is feasible. Cost: node terms + weighted travel + a penalty per branch change; the
    step into a new branch is taken from the best previous state."""
    L, B, M, _ = Q.shape
    if M == 1:
        fast = _single_branch_path(prob, Q[:, :, 0], OK[:, :, 0], q0, b0)
        if fast is not None:
            return fast
    if B == 1:
        return _dp_one_branch(prob, Q[:, 0], OK[:, 0], q0)
    back = np.full((L, B, M), -1, np.int64)
    stepped = np.zeros(L, bool)
    branch_ids = np.arange(B)[:, None]
    acc = qp = None
    for i in range(L):
        if not OK[i].any():
            continue
        qc, node = Q[i], prob.node(Q[i])
        if acc is None:
            new = prob.dist(q0, qc) + node
            if b0 >= 0:
                new = new + _BRANCH_CHANGE_COST * (branch_ids != b0)
            src = np.full((B, M), -1)
        else:
            within = acc[:, :, None] + prob.dist(qp[:, :, None, :], qc[:, None, :, :])
            src_m = within.argmin(1)
            val = np.take_along_axis(within, src_m[:, None, :], 1)[:, 0]
            k = int(acc.argmin())
            cross = acc.flat[k] + prob.dist(qp.reshape(-1, 6)[k], qc) + _BRANCH_CHANGE_COST
            use = (cross < val) & (branch_ids != k // M)
            src = np.where(use, k, branch_ids * M + src_m)
            new = np.where(use, cross, val) + node
        acc = np.where(OK[i], new, np.inf)
        back[i], stepped[i], qp = src, True, qc
    choice = np.full(L, -1)
    if acc is None:
        return choice
    k = int(acc.argmin())
    for i in range(L - 1, -1, -1):
        if stepped[i]:
            choice[i] = k
            k = int(back[i].flat[k])
    return choice


def _segment_greedy(prob: _Problem, idx: np.ndarray, q_before: np.ndarray, b_before: int,
                    n_spin: int) -> _Segment:
    """Point by point (no look-ahead): the grid state closest to the previous point's joints
    (branch changes penalised), then zoomed in on its branch: 4 passes of 33 spins, each
    1/16 of the previous span (resolution ~1e-6 rad for a 5 deg grid)."""
    L = idx.size
    grid = np.linspace(-np.pi, np.pi, n_spin, endpoint=False)
    Qg, OKg = prob.ik(np.repeat(idx, n_spin), np.tile(grid, L))
    Qg, OKg = Qg.reshape(L, n_spin * 8, 6), OKg.reshape(L, n_spin * 8)
    branch_of = np.tile(np.arange(8), n_spin)
    seg = _Segment(idx, np.full(L, np.nan), np.zeros(L, int), np.zeros((L, 6)), np.zeros(L, bool))
    qp, bp = q_before, b_before
    for i in range(L):
        c = np.where(OKg[i], prob.dist(qp, Qg[i]) + prob.node(Qg[i]), np.inf)
        if bp >= 0:
            c = c + _BRANCH_CHANGE_COST * (branch_of != bp)
        k = int(c.argmin())
        if not np.isfinite(c[k]):
            continue
        s_best, b, c_best, q_best = grid[k // 8], k % 8, c[k], Qg[i, k]
        span = _TWO_PI / n_spin
        for _ in range(4):
            spins = s_best + np.linspace(-span, span, 33)
            qq, okk = prob.ik(np.full(33, idx[i]), spins)
            cc = np.where(okk[:, b], prob.dist(qp, qq[:, b]) + prob.node(qq[:, b]), np.inf)
            j = int(cc.argmin())
            if cc[j] < c_best:
                s_best, c_best, q_best = spins[j], cc[j], qq[j, b]
            span /= 16.0
        seg.spin[i], seg.branch[i], seg.q[i], seg.ok[i] = s_best, b, q_best, True
        qp, bp = q_best, b
    return seg


@dataclass
class _Segment:
    """The state of one segment: points ``idx``, chosen spin, branch, joints (wrapped)."""

    idx: np.ndarray  # (L,) point indices
    spin: np.ndarray  # (L,)
    branch: np.ndarray  # (L,) int
    q: np.ndarray  # (L, 6)
    ok: np.ndarray  # (L,) bool


def _local_stage(prob: _Problem, seg: _Segment, step: float, q_before: np.ndarray) -> None:
    """One finer pass: each spin may move within +-step on a grid of 2 * _LOCAL + 1 values
    (its branch kept); the DP (or greedy rule) picks the whole sequence again."""
    L, k = seg.idx.size, 2 * _LOCAL + 1
    S = seg.spin[:, None] + np.linspace(-step, step, k)[None]
    sel = np.flatnonzero(seg.ok)
    Qs, OKs = prob.ik(np.repeat(seg.idx[sel], k), S[sel].ravel())
    rows = np.repeat(seg.branch[sel], k)
    Q = np.zeros((L, 1, k, 6))
    OK = np.zeros((L, 1, k), bool)
    Q[sel, 0] = Qs[np.arange(rows.size), rows].reshape(sel.size, k, 6)
    OK[sel, 0] = OKs[np.arange(rows.size), rows].reshape(sel.size, k)
    choice = _dp(prob, Q, OK, q_before, -1)
    good = choice >= 0  # the centre (the previous choice) is always feasible
    seg.spin[good] = S[good, choice[good]]
    seg.q[good] = Q[good, 0, choice[good]]


def _theta6_polish(prob: _Problem, seg: _Segment, iters: int = 4, h: float = 1e-6) -> None:
    """Newton steps on J6(spin) = 0 in each point's branch (theta6_zero); a step is kept
    where it lowers |J6| and the pose stays feasible."""
    sel = np.flatnonzero(seg.ok)
    rows, br = np.arange(sel.size), seg.branch[sel]
    for _ in range(iters):
        if sel.size == 0:
            return
        s = seg.spin[sel]
        q1, _ = prob.ik(seg.idx[sel], s + h)
        slope = (_wrap_angle(q1[rows, br, 5] - seg.q[sel, 5])) / h
        s_new = s - seg.q[sel, 5] / np.where(np.abs(slope) > 1e-9, slope, np.inf)
        qn, okn = prob.ik(seg.idx[sel], s_new)
        qn, okn = qn[rows, br], okn[rows, br]
        better = okn & (np.abs(qn[:, 5]) < np.abs(seg.q[sel, 5]))
        seg.spin[sel[better]], seg.q[sel[better]] = s_new[better], qn[better]


def _wrap_angle(a: np.ndarray) -> np.ndarray:
    return np.pi - np.mod(np.pi - a, _TWO_PI)


def _segment_grid(prob: _Problem, idx: np.ndarray, q_before: np.ndarray, b_before: int,
                  n_spin: int) -> _Segment:
    """General tool: spin grid x 8 branches, DP (or greedy), then continuous refinement."""
    grid = np.linspace(-np.pi, np.pi, n_spin, endpoint=False)
    L = idx.size
    Qg, OKg = prob.ik(np.repeat(idx, n_spin), np.tile(grid, L))
    Q = Qg.reshape(L, n_spin, 8, 6).transpose(0, 2, 1, 3)
    OK = OKg.reshape(L, n_spin, 8).transpose(0, 2, 1)
    choice = _dp(prob, Q, OK, q_before, b_before)
    ok = choice >= 0
    b, m = np.where(ok, choice // n_spin, 0), np.where(ok, choice % n_spin, 0)
    seg = _Segment(idx, np.where(ok, grid[m], 0.0), b, Q[np.arange(L), b, m], ok)
    step = _TWO_PI / n_spin
    for _ in range(_STAGES if ok.any() else 0):
        _local_stage(prob, seg, step, q_before)
        step /= _LOCAL
    if prob.mode == "theta6_zero":
        _theta6_polish(prob, seg)
    seg.spin[~ok] = np.nan
    return seg


def _segment_flange_axis(prob: _Problem, idx: np.ndarray, q_before: np.ndarray,
                         b_before: int, j6_target: float, sign6: float) -> _Segment:
    """Tool on the flange axis: joints 1-5 do not depend on the spin; J6 is set to
    ``j6_target`` and the branch sequence comes from the DP over joints 1-5."""
    L = idx.size
    Q, OK = prob.ik(idx, np.zeros(L))
    w = prob.w_edge.copy()
    w[5] = 0.0
    no_j6 = dataclasses.replace(prob, w_edge=w, w_node6=0.0)
    choice = _dp(no_j6, Q[:, :, None, :], OK[:, :, None], q_before, b_before)
    ok = choice >= 0
    b = np.where(ok, choice, 0)
    q6_0 = Q[np.arange(L), b, 5]
    spin = _wrap_angle(sign6 * (j6_target - q6_0))
    q, okk = prob.ik(idx, np.where(ok, spin, 0.0))
    q = q[np.arange(L), b]
    ok &= okk[np.arange(L), b]
    return _Segment(idx, np.where(ok, spin, np.nan), b, q, ok)


def _unwrap(prob: _Problem, q: np.ndarray, ok: np.ndarray, q_start: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """Joint turns of the reachable rows of q (N, 6): each wide-range joint takes the turn
    nearest the previous point's; where that leaves its limits the rest of the path shifts
    by 2*pi (returned as jump indices)."""
    idx = np.flatnonzero(ok)
    out = q.copy()
    jumps: list[int] = []
    if idx.size == 0:
        return out, np.array([], int)
    Q = q[idx]
    for j in np.flatnonzero(prob.wraps):
        d = np.diff(np.concatenate([[q_start[j]], Q[:, j]]))
        u = q_start[j] + np.cumsum(_wrap_angle(d))
        while True:
            bad = np.flatnonzero((u < prob.lo[j] - 1e-12) | (u > prob.hi[j] + 1e-12))
            if bad.size == 0:
                break
            t = int(bad[0])
            u[t:] -= _TWO_PI * np.sign(u[t])
            jumps.append(int(idx[t]))
            if not prob.lo[j] - 1e-12 <= u[t] <= prob.hi[j] + 1e-12:
                break  # cannot happen for a range over 2*pi; stop rather than loop
        Q[:, j] = u
    out[idx] = Q
    return out, np.array(sorted(set(jumps)), int)


def _problem(robot: RobotKinematics, p_W, axis_W, X_FT, mode: str, x_ref_W,
             X_WS: np.ndarray | None = None) -> _Problem:
    if mode not in SPIN_MODES:
        raise InputError(f"spin mode {mode!r}: use one of {', '.join(SPIN_MODES)}")
    p_W = np.atleast_2d(np.asarray(p_W, float))
    axis_W = np.atleast_2d(np.asarray(axis_W, float))
    if p_W.shape != axis_W.shape or p_W.shape[1] != 3:
        raise InputError(f"p_W {p_W.shape} and axis_W {axis_W.shape} must both be (N, 3)")
    lo, hi = np.asarray(robot.limits.lower, float), np.asarray(robot.limits.upper, float)
    w = travel_weights(robot.opw)
    wraps = (hi - lo) > _TWO_PI + 1e-9
    theta6 = mode == "theta6_zero"
    return _Problem(robot=robot, p_W=p_W, axis_W=axis_W,
                    X_TF=np.linalg.inv(np.asarray(X_FT, float)),
                    x_ref_W=np.asarray(x_ref_W, float), mode=mode, lo=lo, hi=hi,
                    wraps=wraps, period=np.where(wraps, _TWO_PI, np.inf),
                    w_edge=w * (1e-3 if theta6 else 1.0),
                    w_node6=_THETA6_WEIGHT if theta6 else 0.0,
                    X_WS=None if X_WS is None else np.asarray(X_WS, float))


def solve_tool_axis_path(
    robot: RobotKinematics,
    p_W: np.ndarray,
    axis_W: np.ndarray,
    X_FT: np.ndarray,
    mode: str = "min_travel",
    options: ToolAxisOptions = ToolAxisOptions(),
    progress: Callable[[int, int, str], None] | None = None,
    X_WS: np.ndarray | None = None,
) -> ToolAxisPathResult:
    """Joints for tool tip positions and axes, resolving the free spin (see module docstring).

    Args:
        robot: kinematics and limits.
        p_W: (N, 3) tool tip positions in the robot base [m].
        axis_W: (N, 3) unit tool axes tip -> spindle (CAM convention) in the robot base.
        X_FT: (4, 4) tool in the flange frame [m].
        mode: "min_travel", "greedy" or "theta6_zero".
        options: start joints and spin grid (:class:`ToolAxisOptions`).
        progress: optional callback (done, total, label), once per segment.
        X_WS: (4, 4) the stationary tool's TCP in the robot base (workpiece in hand); then
            ``p_W``/``axis_W`` are in the held part's frame O, ``X_FT`` is O in the flange
            frame, and the result's ``X_WT`` are the part's poses in the base.

    Returns:
        ToolAxisPathResult; unreachable points are listed, not raised.
    """
    q_start, n_spin = options.q_start, options.n_spin
    prob = _problem(robot, p_W, axis_W, X_FT, mode, options.x_ref_W, X_WS)
    if n_spin < 4:
        raise InputError(f"n_spin must be >= 4, got {n_spin}")
    n = prob.p_W.shape[0]
    q0 = READY_POSE.copy() if q_start is None else np.asarray(q_start, float)
    X_FT = np.asarray(X_FT, float)
    flange_axis = X_WS is None and _flange_axis_tool(X_FT)
    j6 = float(np.clip(0.0 if mode == "theta6_zero" else q0[5], prob.lo[5], prob.hi[5]))
    sign6 = float(np.sign(X_FT[2, 2]) * robot.opw.sign_corrections[5])
    q_out, spin, branch = np.zeros((n, 6)), np.full(n, np.nan), np.zeros(n, int)
    reach = np.zeros(n, bool)
    q_before, b_before = q0, -1
    for a in range(0, n, SEGMENT):
        ahead = 0 if mode == "greedy" else OVERLAP
        idx = np.arange(a, min(a + SEGMENT + ahead, n))
        if flange_axis:
            seg = _segment_flange_axis(prob, idx, q_before, b_before, j6, sign6)
        elif mode == "greedy":
            seg = _segment_greedy(prob, idx, q_before, b_before, _GREEDY_SPINS)
        else:
            seg = _segment_grid(prob, idx, q_before, b_before, n_spin)
        k = min(SEGMENT, idx.size)  # commit the segment, not the look-ahead
        idx = idx[:k]
        q_out[idx], spin[idx], branch[idx], reach[idx] = (
            seg.q[:k], seg.spin[:k], seg.branch[:k], seg.ok[:k])
        if seg.ok[:k].any():
            last = int(np.flatnonzero(seg.ok[:k])[-1])
            q_before, b_before = seg.q[last], int(seg.branch[last])
        if progress is not None:
            progress(int(idx[-1]) + 1, n, "spin + IK")
    return _result(prob, q_out, spin, branch, reach, q0)


def _result(prob: _Problem, q: np.ndarray, spin: np.ndarray, branch: np.ndarray,
            reach: np.ndarray, q0: np.ndarray) -> ToolAxisPathResult:
    q, jumps = _unwrap(prob, q, reach, q0)
    q[~reach] = np.nan
    idx = np.flatnonzero(reach)
    changed = np.zeros(prob.p_W.shape[0], bool)
    if idx.size > 1:
        big = np.abs(np.diff(q[idx], axis=0)).max(axis=1) > np.pi
        changed[idx[1:]] = (branch[idx[1:]] != branch[idx[:-1]]) | big
    changed[jumps] = True
    X = prob.carried(np.arange(prob.p_W.shape[0]), np.nan_to_num(spin))
    failed = tuple(int(i) for i in np.flatnonzero(~reach))
    if failed:
        log.info("%d of %d CL points unreachable", len(failed), reach.size)
    return ToolAxisPathResult(q=q, X_WT=X, spin=spin, reachable=reach, failed=failed,
                              configuration_changes=tuple(int(i) for i in np.flatnonzero(changed)),
                              mode=prob.mode)


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
