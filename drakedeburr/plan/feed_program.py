"""The feed held through a fillet: the tool orientation along a stretch of the cut chosen so the
joints can follow it at a constant feed, by a sequence of small convex programs.

Where the timed cut slows below the feed band at a fillet, the joint accelerations bind: at a
constant feed ``v`` the joints need ``|q_j''(s)| v^2 <= A_j`` (and ``|q_j'(s)| v <= V_j``), and
q(s) is fixed by the tool poses. The positions are the program's and stay; the orientation is
free inside the cone (axis) and about the axis (spin). So, over a stretch of dense samples:

* each sample's frame may turn by a small rotation ``w_k`` about the tool point; the analytic
  IK's joints change by ``G_k w_k`` to first order (``G_k`` by finite differences of the IK on
  the cut's branch);
* ``q''`` is the cubic spline's that the timing uses (:func:`drakedeburr.plan.timing.time_path`
  interpolates the dense joints with scipy's ``CubicSpline``), written exactly as its
  tridiagonal equations with the second derivatives ``M`` as variables, fixed to the whole
  cut's spline at both ends of a padded range: ``h_{k-1} M_{k-1} + 2 (h_{k-1} + h_k) M_k +
  h_k M_{k+1} = 6 (dq_k / h_k - dq_{k-1} / h_{k-1})``;
* ``|M_kj| <= A_j / v^2 (1 + sigma_k)``, likewise the spline's ``q'`` against ``V_j / v``,
  the axis inside its cone (a second-order cone on the linearised axis, as
  :func:`drakedeburr.plan.cut_path.smooth_axes` does), ``|w| <= trust``; minimise
  ``sum sigma`` plus a small smoothness term. ``sigma = 0`` means the feed holds there;
* the IK re-solves the joints at the turned frames (exact), and the program is linearised
  again, a few times (sequential convex programming).

The stretch is *held* when the program ends with ``sum sigma`` ~ 0; the caller re-times the cut
with the new orientation and keeps it only if the whole cut is faster, in its cones, clear and
on one configuration. A stretch the program cannot hold needs a slower feed somewhere (a
corner of the position path itself, or a cone too narrow for the turn): it is left as it was.

Why hand-written: a joint-space KinematicTrajectoryOptimization over the same stretch (the
previous fillet repair, :func:`drakedeburr.plan.fillets.stretch_kto`) took 3-25 s a fillet; the
program here uses the analytic IK for the kinematics and Drake's ``MathematicalProgram`` +
Clarabel for each convex step (0.1-1 s a fillet).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

__all__ = ["FeedProgramOptions", "FeedResult", "FeedStretch", "hold_feed"]


@dataclass(frozen=True)
class FeedProgramOptions:
    """Settings of the feed program.

    Attributes:
        iterations: convex programs in sequence at most (the first that holds the feed ends
            the sequence: its frames are re-solved by the exact IK and the caller re-times the
            whole cut).
        trust: largest rotation of a frame per program [rad].
        pad: samples on each side of the stretch whose spline rows are constrained too (the
            spline couples neighbours) but whose frames stay.
        fixed: samples at each end of the stretch kept as they are (continuity with the cut).
        cone_margin: the axis stays this far inside its cone [rad].
        limit_share: share of the timing's joint limits the program may use (the rest covers
            the linearisation's error).
        infeasible: a first program whose ``sum sigma`` exceeds this ends the search: the feed
            cannot be held there (a hold ends at ~0; the fillets the program cannot hold read
            10-300).
        smooth: weight of the frames' first differences (keeps the turn spread out).
        solver_iterations: Clarabel's iteration cap: a program that holds the feed converged
            in 10-12 iterations on the bundled hubs; one that cannot hold it grinds on (24 to
            over 30) and is cut short as not held.
        tolerance: Clarabel's gap tolerance (sigma is read to 1e-3).
    """

    iterations: int = 4
    trust: float = 0.08
    pad: int = 40
    fixed: int = 2
    cone_margin: float = 3e-3
    limit_share: float = 0.98
    infeasible: float = 2.0
    smooth: float = 1e-2
    solver_iterations: int = 16
    tolerance: float = 1e-4


@dataclass(frozen=True, eq=False)
class FeedResult:
    """Outcome of :func:`hold_feed`.

    Attributes:
        R: (n, 3, 3) the frames' new orientations at the stretch's samples ``lo..hi`` (None when
            no program succeeded); held: the last program held the feed (``sum sigma`` < 1e-3).
        sigma: ``sum sigma`` of each program; seconds: time spent [s].
    """

    R: np.ndarray | None
    held: bool
    sigma: tuple
    seconds: float


@dataclass(frozen=True, eq=False)
class FeedStretch:
    """The timed cut and the stretch of it whose frames :func:`hold_feed` turns.

    Attributes:
        s: (N,) travel [m]; X_HT: (N, 4, 4) tool poses in H; q: (N, 6) their joints [rad].
        cone: (N, 3) cone axes (tip -> spindle); half_angle: [rad].
        lo, hi: the stretch (sample indices).
    """

    s: np.ndarray
    X_HT: np.ndarray
    q: np.ndarray
    cone: np.ndarray
    half_angle: float
    lo: int
    hi: int


def _near_ik(kin, X_HT: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """Joints at poses ``X_HT`` (n, 4, 4) on the branch of ``q_ref`` (n, 6), each joint turned
    to the nearest of its 2 pi copies to ``q_ref`` (NaN where the branch does not reach)."""
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X_HT))
    b0 = kin.branch_of(q_ref[0])
    match = np.flatnonzero(np.all(branches == b0[None], axis=1))
    if match.size == 0:
        return np.full_like(q_ref, np.nan)
    q = q_all[:, match[0]]
    return q_ref + np.mod(q - q_ref + np.pi, 2 * np.pi) - np.pi


def _turned(w: np.ndarray, R: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(w).as_matrix() @ R


def _poses(R: np.ndarray, P: np.ndarray) -> np.ndarray:
    X = np.repeat(np.eye(4)[None], len(R), axis=0)
    X[:, :3, :3], X[:, :3, 3] = R, P
    return X


def _jacobian(kin, R: np.ndarray, P: np.ndarray, q: np.ndarray, eps: float = 1e-6):
    """(n, 6, 3) d q / d w: the joints' change per small frame rotation w about the tool
    point (finite differences of the analytic IK)."""
    G = np.zeros((len(R), 6, 3))
    for e in range(3):
        w = np.zeros((len(R), 3))
        w[:, e] = eps
        G[:, :, e] = (_near_ik(kin, _poses(_turned(w, R), P), q) - q) / eps
    return G


@dataclass(frozen=True)
class _Layout:
    """Variable layout: frame rotations w (nf x 3), interior spline second derivatives M
    ((ns - 2) x 6), slacks sigma (ns)."""

    nf: int
    ns: int

    @property
    def nw(self) -> int:
        return 3 * self.nf

    @property
    def n(self) -> int:
        return self.nw + 6 * (self.ns - 2) + self.ns

    def w(self, m, e):
        return 3 * np.asarray(m) + e

    def M(self, k, j):
        return self.nw + 6 * (np.asarray(k) - 1) + j

    def sigma(self, k):
        return self.nw + 6 * (self.ns - 2) + np.asarray(k)


@dataclass(frozen=True, eq=False)
class _Linearised:
    """One linearisation of the padded range: spacings ``h`` (ns - 1,), joints ``qs`` (ns, 6),
    ``G`` (nf, 6, 3) d q / d w at the free samples, ``free_of`` (ns,) each sample's free index
    (-1: fixed) and the whole cut's spline second derivatives ``M_end`` (2, 6) at the ends."""

    h: np.ndarray
    qs: np.ndarray
    G: np.ndarray
    free_of: np.ndarray
    M_end: np.ndarray


def _spline_rows(lay: _Layout, lin: _Linearised):
    """Equality rows (A, b) of the spline's tridiagonal equations at the interior samples, with
    the joints ``qs + G w`` at the free samples and ``M`` fixed to ``M_end`` (2, 6) at the ends."""
    h, qs, G, free_of, M_end = lin.h, lin.qs, lin.G, lin.free_of, lin.M_end
    ns = lay.ns
    rows, cols, vals, rhs = [], [], [], np.zeros((ns - 2, 6))
    k = np.arange(1, ns - 1)
    r = lambda j: (k - 1) * 6 + j  # noqa: E731
    for j in range(6):
        for kk, cf in ((k - 1, h[k - 1]), (k, 2 * (h[k - 1] + h[k])), (k + 1, h[k])):
            inner = (kk > 0) & (kk < ns - 1)
            rows.append(r(j)[inner]), cols.append(lay.M(kk[inner], j)), vals.append(cf[inner])
            end = ~inner
            rhs[(k - 1)[end], j] -= cf[end] * M_end[(kk[end] > 0).astype(int), j]
        for kk, cf in ((k + 1, -6 / h[k]), (k, 6 / h[k] + 6 / h[k - 1]), (k - 1, -6 / h[k - 1])):
            rhs[:, j] -= cf * qs[kk, j]
            m = free_of[kk]
            on = m >= 0
            for e in range(3):
                rows.append(r(j)[on]), cols.append(lay.w(m[on], e))
                vals.append(cf[on] * G[m[on], j, e])
    A = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=((ns - 2) * 6, lay.n))
    return A, rhs.reshape(-1)


def _limit_rows(lay: _Layout, lin: _Linearised, v, dv, acc_max, vel_max):
    """Inequality rows (A, ub) at the interior samples k, for the feed profile ``v`` (ns,) with
    slope ``dv`` = dv/ds: joint accelerations ``|v_k^2 M_kj + v_k dv_k q'_kj| <= acc_max_j (1 +
    sigma_k)`` and speeds ``|v_k q'_kj| <= vel_max_j (1 + sigma_k)``, q' the spline's first
    derivative ``(Q_{k+1} - Q_k) / h_k - h_k (2 M_k + M_{k+1}) / 6``."""
    h, qs, G, free_of, M_end = lin.h, lin.qs, lin.G, lin.free_of, lin.M_end
    ns = lay.ns
    k = np.arange(1, ns - 1)
    n = len(k)
    rows, cols, vals, ub = [], [], [], []
    n_row = 0

    def family(j):
        """The joint's q' and q'' at every k: lists of (row index into k, column, coefficient)
        and their constant parts."""
        dq_terms, dq_c = [], np.zeros(n)
        for kk, cf in ((k + 1, 1.0 / h[k]), (k, -1.0 / h[k])):
            dq_c += cf * qs[kk, j]
            m = free_of[kk]
            on = np.flatnonzero(m >= 0)
            dq_terms += [(on, lay.w(m[on], e), cf[on] * G[m[on], j, e]) for e in range(3)]
        for kk, cf in ((k, -h[k] / 3.0), (k + 1, -h[k] / 6.0)):
            inner = kk < ns - 1
            dq_terms.append((np.flatnonzero(inner), lay.M(kk[inner], j), cf[inner]))
            dq_c[~inner] += cf[~inner] * M_end[1, j]
        return dq_terms, dq_c

    def add(terms, const, bound):
        nonlocal n_row
        for sgn in (1.0, -1.0):
            for idx, cc, vv in terms:
                rows.append(n_row + idx), cols.append(cc), vals.append(sgn * vv)
            rows.append(n_row + np.arange(n)), cols.append(lay.sigma(k))
            vals.append(np.full(n, -bound))
            ub.append(bound - sgn * const)
            n_row += n

    every = np.arange(n)
    vk, ak = v[k], v[k] * dv[k]
    for j in range(6):
        dq_terms, dq_c = family(j)
        acc = [(every, lay.M(k, j), vk ** 2)] + [(i, c, x * ak[i]) for i, c, x in dq_terms]
        add(acc, ak * dq_c, acc_max[j])
        add([(i, c, x * vk[i]) for i, c, x in dq_terms], vk * dq_c, vel_max[j])
    A = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(n_row, lay.n))
    return A, np.concatenate(ub)


def _scaled(A, b):
    """Rows divided by their largest coefficient (the spline rows carry 1/h ~ 4e3)."""
    sc = 1.0 / np.maximum(abs(A).max(axis=1).toarray().ravel(), 1e-300)
    return sps.diags(sc) @ A, b * sc


def _program(lay, eq, ineq, R, cone, half, opt: FeedProgramOptions, m_scale: float = 1.0):
    """One convex step: (w (nf, 3), sigma (ns)) or None, under the equality rows ``eq`` =
    (A_eq, b_eq) and the inequality rows ``ineq`` = (A_in, ub). The spline's second derivatives
    are solved for in units of ``m_scale`` (their bound's size; w is ~0.01 rad)."""
    from pydrake.solvers import ClarabelSolver, MathematicalProgram, SolverOptions

    (A_eq, b_eq), (A_in, ub) = eq, ineq
    col = np.ones(lay.n)
    col[lay.nw:lay.nw + 6 * (lay.ns - 2)] = m_scale
    A_eq, A_in = A_eq @ sps.diags(col), A_in @ sps.diags(col)
    prog = MathematicalProgram()
    x = prog.NewContinuousVariables(lay.n, "x")
    w = x[:lay.nw].reshape(lay.nf, 3)
    sig = x[lay.sigma(np.arange(lay.ns))]
    prog.AddBoundingBoxConstraint(-opt.trust, opt.trust, x[:lay.nw])
    prog.AddBoundingBoxConstraint(0.0, np.inf, sig)
    A_s, b_s = _scaled(A_eq, b_eq)
    prog.AddLinearEqualityConstraint(A_s, b_s, x)
    A_s, ub_s = _scaled(A_in, ub)
    prog.AddLinearConstraint(A_s, np.full(len(ub_s), -np.inf), ub_s, x)
    # the turned axis a + w x a inside the cone about c: |a'| <= a'.c / cos(half - margin)
    a = -R[:, :, 2]
    cos_h = np.cos(half - opt.cone_margin)
    for k in range(lay.nf):
        B = np.array([[0.0, a[k, 2], -a[k, 1]], [-a[k, 2], 0.0, a[k, 0]], [a[k, 1], -a[k, 0], 0.0]])
        prog.AddLorentzConeConstraint(np.vstack([cone[k] @ B / cos_h, B]),
                                      np.concatenate([[cone[k] @ a[k] / cos_h], a[k]]), w[k])
    prog.AddLinearCost(np.ones(lay.ns), sig)
    D1 = sps.diags([-1.0, 1.0], [0, 1], shape=(lay.nf - 1, lay.nf))
    Q = (opt.smooth * (D1.T @ D1) + 1e-4 * sps.identity(lay.nf)).toarray()
    for e in range(3):
        prog.AddQuadraticCost(2.0 * Q, np.zeros(lay.nf), w[:, e], is_convex=True)
    so = SolverOptions()
    sid = ClarabelSolver().solver_id()
    for key, value in (("tol_gap_abs", opt.tolerance), ("tol_gap_rel", opt.tolerance),
                       ("tol_feas", 0.1 * opt.tolerance), ("max_iter", opt.solver_iterations)):
        so.SetOption(sid, key, value)
    res = ClarabelSolver().Solve(prog, None, so)
    if not res.is_success():
        return None
    return res.GetSolution(w), res.GetSolution(sig)


def hold_feed(kin, cut: FeedStretch, v: float | np.ndarray, acc_max: np.ndarray,
              vel_max: np.ndarray, options: FeedProgramOptions = FeedProgramOptions()
              ) -> FeedResult:
    """Frames of the cut's samples ``cut.lo..cut.hi`` that let the joints follow it at the
    constant feed ``v`` (module docstring).

    Args:
        kin: the cell's :class:`drakedeburr.plan.kinematics.CellKinematics`.
        cut: the timed cut's travel, poses, joints, cones and the stretch
            (:class:`FeedStretch`).
        v: the feed to hold [m/s]: a constant, or (N,) a speed profile along ``cut.s``;
            acc_max, vel_max: (6,) the joint limits the timing uses [rad/s^2], [rad/s] (its
            shares of the model's).
    """
    import time

    t0 = time.perf_counter()
    opt = options
    s, X_HT, q, cone, half_angle, lo, hi = (cut.s, cut.X_HT, cut.q, cut.cone, cut.half_angle,
                                            cut.lo, cut.hi)
    a0, a1 = max(lo - opt.pad, 0), min(hi + opt.pad, len(s) - 1)
    free = np.arange(lo + opt.fixed, hi - opt.fixed + 1)
    lay = _Layout(nf=len(free), ns=a1 - a0 + 1)
    free_of = -np.ones(lay.ns, int)
    free_of[free - a0] = np.arange(lay.nf)
    h = np.diff(s[a0:a1 + 1])
    R, P = X_HT[free, :3, :3].copy(), X_HT[free, :3, 3]
    qs = np.array(q[a0:a1 + 1], float)
    acc_lim = opt.limit_share * np.asarray(acc_max, float)
    vel_lim = opt.limit_share * np.asarray(vel_max, float)
    v_all = np.broadcast_to(np.asarray(v, float), s.shape)
    if not np.all(v_all > 0):
        raise ValueError("hold_feed: the feed to hold must be positive along the cut")
    v_sub = v_all[a0:a1 + 1]
    dv_sub = np.gradient(v_all, s)[a0:a1 + 1]
    sigmas: list[float] = []
    held, out = False, None
    for _ in range(opt.iterations):
        qf = qs[free - a0]
        G = _jacobian(kin, R, P, qf)
        if not np.all(np.isfinite(G)):
            break
        q_full = np.array(q, float)
        q_full[a0:a1 + 1] = qs
        M_end = CubicSpline(s, q_full, axis=0)(s[[a0, a1]], 2)
        lin = _Linearised(h, qs, G, free_of, M_end)
        step = _program(lay, _spline_rows(lay, lin),
                        _limit_rows(lay, lin, v_sub, dv_sub, acc_lim, vel_lim), R, cone[free],
                        half_angle, opt, m_scale=float(np.max(acc_lim) / np.min(v_sub) ** 2))
        if step is None:
            break
        w, sig = step
        sigmas.append(float(sig.sum()))
        R = _turned(w, R)
        q_new = _near_ik(kin, _poses(R, P), qf)
        if not np.all(np.isfinite(q_new)):
            break
        qs[free - a0] = q_new
        out = R.copy()
        held = sigmas[-1] < 1e-3
        if held or sigmas[0] > opt.infeasible:
            break
    if out is not None:
        full = np.array(X_HT[lo:hi + 1, :3, :3])
        full[free - lo] = out
        out = full
    return FeedResult(R=out, held=held, sigma=tuple(sigmas), seconds=time.perf_counter() - t0)
