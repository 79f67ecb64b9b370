"""Dense, independent re-check of a plan -> :class:`VerificationReport`.

Nothing the planner computed is trusted beyond the plan itself (targets, segments, joint
trajectory, tool paths): the cell is loaded afresh from the plan's scenario and hub, forward
kinematics is evaluated twice (the Drake plant and the analytic OPW model of
``drakedeburr.post.opw``, which must agree to ``Tolerances.fk_match``), distances come from the
scene graph's narrow phase pair by pair (see :mod:`drakedeburr.verify.distances`), and the true
window edges come from the hub model's ground truth.

Both faces of the plan are checked:

* the **timed joint trajectory**, sampled every ``Tolerances.dense_step`` of tool travel (tool
  point T relative to the hub H) and at least every ``time_step`` seconds; joint limits are
  checked exactly on the cubic Hermite pieces (their extremes are found analytically);
* the **Cartesian program** as a controller executes it: linear moves between consecutive
  targets (position linear, orientation slerp) for approach/cut/retract (or any target whose
  ``motion`` attribute is ``"linear"``), joint moves for home/transition; the two faces must
  agree both ways (program samples vs trajectory path and trajectory samples vs program path).

Frames and conventions: DESIGN.md (T tool frame, +Z_T spindle -> tip; the tool axis of the
source's theta_A/theta_B is -Z_T). theta_A = atan2(a.N, a.B), theta_B = asin(-a.T) for the axis
a in the local frame [N, T, B] (docs/orientation.md), recomputed here from its definition.
"""

from __future__ import annotations

import datetime as _dt
import logging
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.config import ProcessParameters, Tolerances
from drakedeburr.errors import InputError
from drakedeburr.frames.local_frames import R_HL_from_normals, angles_from_axis_H
from drakedeburr.plan.program_reading import (
    moves_in_order,
    passing_fractions,
    rot_angle,
    slerp_pairs,
)
from drakedeburr.verify.report import CheckItem, VerificationReport

__all__ = ["verify_plan", "LINEAR_KINDS"]

log = logging.getLogger(__name__)

#: segment kinds executed as linear Cartesian moves unless a target says otherwise
LINEAR_KINDS = ("approach", "cut", "retract")
_TOLERANCES = Tolerances()
_PARAMS = ProcessParameters()
_KIND_CODE = {"home": 0, "transition": 1, "approach": 2, "cut": 3, "retract": 4}


# ----------------------------------------------------------------------------- geometry helpers
def _slow_stretches(inside: np.ndarray, ds: np.ndarray, v_mid: np.ndarray, qd: np.ndarray,
                    qdd: np.ndarray, vlim: np.ndarray, alim: np.ndarray,
                    reach: float = 2e-3) -> list[dict]:
    """The stretches of one window's cut outside the speed band, in order: where they lie
    (``from_m``/``to_m``: tool travel from the cut's start), the slowest speed, whether the
    stretch touches the cut's start or end (``at``: "start"/"end", where the tool starts or stops
    at rest) or lies inside it, and the joint limit nearest to binding there (largest
    |qd|/limit or |qdd|/limit over the stretch's samples and those within ``reach`` of tool
    travel either side - the limit that holds the speed down can bind just before the speed
    leaves the band: ``joint``, ``limit``, ``ratio``).

    ``inside`` (M,) marks the intervals between the M + 1 samples that are in the band; ``ds``
    and ``v_mid`` are their lengths and mid speeds; ``qd``/``qdd`` (M + 1, 6) at the samples.
    """
    run = np.concatenate([[0.0], np.cumsum(ds)])
    out = np.diff(np.concatenate([[0], (~inside).astype(int), [0]]))
    starts, ends = np.flatnonzero(out == 1), np.flatnonzero(out == -1)
    rv, ra = np.abs(qd) / vlim, np.abs(qdd) / alim
    stretches = []
    for a, b in zip(starts, ends, strict=True):  # intervals a..b-1, samples a..b
        lo = int(np.searchsorted(run, run[a] - reach))
        hi = int(np.searchsorted(run, run[b] + reach, side="right"))
        peak_v, peak_a = rv[lo:hi].max(axis=0), ra[lo:hi].max(axis=0)
        j = int(np.argmax(np.maximum(peak_v, peak_a)))
        kind = "speed" if peak_v[j] > peak_a[j] else "acceleration"
        stretches.append({
            "from_m": float(run[a]), "to_m": float(run[b]),
            "min_mps": float(v_mid[a:b].min()),
            "at": "start" if a == 0 else "end" if b == len(inside) else "inside",
            "joint": f"J{j + 1}", "limit": kind, "ratio": float(max(peak_v[j], peak_a[j]))})
    return stretches


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 256):
    """Distance of points to a set of segments.

    Args:
        p: (N, 3) points. a, b: (S, 3) segment ends.

    Returns:
        (d (N,), index of the closest segment (N,), fraction along it (N,)).
    """
    d_out = np.empty(len(p))
    i_out = np.empty(len(p), int)
    f_out = np.empty(len(p))
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    for s in range(0, len(p), chunk):
        pc = p[s:s + chunk]
        ap = pc[:, None, :] - a[None]
        f = np.clip(np.einsum("nsk,sk->ns", ap, ab) / L2, 0.0, 1.0)
        d = np.linalg.norm(ap - f[..., None] * ab[None], axis=2)
        k = d.argmin(axis=1)
        r = np.arange(len(pc))
        d_out[s:s + chunk], i_out[s:s + chunk], f_out[s:s + chunk] = d[r, k], k, f[r, k]
    return d_out, i_out, f_out


def _closed_polyline_distance(p: np.ndarray, loop: np.ndarray, tree=None):
    """Distance of points (N, 3) to a closed polyline (M, 3), exact, via its nearest vertices.

    Returns (d (N,), closest point (N, 3)).
    """
    from scipy.spatial import cKDTree

    tree = tree or cKDTree(loop)
    m = len(loop)
    _, idx = tree.query(p, k=min(4, m))
    idx = np.atleast_2d(idx)
    best = np.full(len(p), np.inf)
    best_pt = np.zeros_like(p)
    for col in range(idx.shape[1]):
        for off in (-1, 0):
            i0 = (idx[:, col] + off) % m
            a, b = loop[i0], loop[(i0 + 1) % m]
            ab = b - a
            f = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(
                np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
            c = a + f[:, None] * ab
            d = np.linalg.norm(p - c, axis=1)
            better = d < best
            best[better] = d[better]
            best_pt[better] = c[better]
    return best, best_pt


def _lerp_frames(R0: np.ndarray, R1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Local frames [N, T, B] between CL points: T and N interpolated linearly and
    re-orthonormalised, B completed with the frames' own handedness ([N, T, B] with
    B = T x N is left-handed: slerp does not apply)."""
    T = (1 - f)[:, None] * R0[:, :, 1] + f[:, None] * R1[:, :, 1]
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    Nv = (1 - f)[:, None] * R0[:, :, 0] + f[:, None] * R1[:, :, 0]
    Nv -= np.einsum("ij,ij->i", Nv, T)[:, None] * T
    Nv /= np.linalg.norm(Nv, axis=1, keepdims=True)
    sign = np.sign(np.linalg.det(R0))
    B = sign[:, None] * np.cross(Nv, T)
    return np.stack([Nv, T, B], axis=2)


# ----------------------------------------------------------------------------- spline extremes
def _hermite_coefficients(traj) -> tuple[np.ndarray, np.ndarray]:
    """Piece coefficients c (4, K-1, 6) (c0 x^3 + c1 x^2 + c2 x + c3) and widths h (K-1,)."""
    from scipy.interpolate import CubicHermiteSpline

    spline = CubicHermiteSpline(traj.t, traj.q, traj.qd, axis=0)
    return spline.c, np.diff(traj.t)


def _spline_extremes(traj):
    """Exact extremes of q, qd, qdd over the trajectory, per joint.

    Returns dict of (value (K-1, n, 6), x (K-1, n)) candidate arrays for "q", "qd", "qdd".
    """
    c, h = _hermite_coefficients(traj)
    c0, c1, c2, c3 = c
    H = np.broadcast_to(h[:, None], c0.shape)
    zeros = np.zeros_like(c0)
    # acceleration: linear per piece -> ends
    acc = np.stack([2 * c1, 6 * c0 * H + 2 * c1], axis=1)
    acc_x = np.stack([zeros, H], axis=1)
    # velocity: quadratic -> ends and vertex
    with np.errstate(divide="ignore", invalid="ignore"):
        xv = np.where(np.abs(c0) > 1e-300, -c1 / (3 * c0), 0.0)
    xv = np.where((xv > 0) & (xv < H), xv, 0.0)
    vel_x = np.stack([zeros, H, xv], axis=1)
    vel = 3 * c0[:, None] * vel_x**2 + 2 * c1[:, None] * vel_x + c2[:, None]
    # position: cubic -> ends and roots of the velocity
    A, B, C = 3 * c0, 2 * c1, c2
    disc = B * B - 4 * A * C
    sq = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(np.abs(A) > 1e-300, (-B + sq) / (2 * A), -C / np.where(B == 0, 1, B))
        r2 = np.where(np.abs(A) > 1e-300, (-B - sq) / (2 * A), 0.0)
    ok = disc >= 0
    r1 = np.where(ok & (r1 > 0) & (r1 < H), r1, 0.0)
    r2 = np.where(ok & (r2 > 0) & (r2 < H), r2, 0.0)
    pos_x = np.stack([zeros, H, r1, r2], axis=1)
    pos = (c0[:, None] * pos_x**3 + c1[:, None] * pos_x**2 + c2[:, None] * pos_x
           + c3[:, None])
    return {"q": (pos, pos_x), "qd": (vel, vel_x), "qdd": (acc, acc_x)}


# ----------------------------------------------------------------------------- kinematics
class _Kinematics:
    """Tool pose relative to the hub from joints, by the analytic OPW model (vectorised), plus
    the Drake plant for the cross-check. Works for both cells."""

    def __init__(self, cell) -> None:
        from drakedeburr.robots import IRB1600_10_120

        self.cell = cell
        self.opw = IRB1600_10_120
        q0 = np.asarray(cell.q_home, float)
        ctx = cell.plant.CreateDefaultContext()
        cell.plant.SetPositions(ctx, q0)
        self.mode = cell.mode
        X_WF0 = cell.flange_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        X_W_base = cell.base_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        self.X_WB = X_W_base
        if cell.mode == "tool":
            self.X_FT = np.linalg.inv(X_WF0) @ cell.tool_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
            self.X_WH = cell.hub_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        else:
            self.X_FH = np.linalg.inv(X_WF0) @ cell.hub_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
            self.X_WT = cell.tool_frame.CalcPoseInWorld(ctx).GetAsMatrix4()

    def X_WF(self, q: np.ndarray) -> np.ndarray:
        from drakedeburr.robots.opw import fk_opw

        return self.X_WB @ fk_opw(self.opw, q)

    def X_HT(self, q: np.ndarray) -> np.ndarray:
        """(N, 4, 4) tool pose in hub frame for (N, 6) joints."""
        X_WF = self.X_WF(np.atleast_2d(q))
        if self.mode == "tool":
            return np.linalg.inv(self.X_WH) @ X_WF @ self.X_FT
        X_WH = X_WF @ self.X_FH
        return np.linalg.inv(X_WH) @ self.X_WT


# ----------------------------------------------------------------------------- the verifier
def _target_motion(target) -> str:
    """"linear" or "joint": the target's ``motion`` (plan contract), else by segment kind."""
    motion = getattr(target, "motion", None)
    if motion in ("linear", "joint"):
        return motion
    return "linear" if target.segment in LINEAR_KINDS else "joint"


def _tool_paths(plan) -> dict:
    tp = plan.tool_path
    if tp is None:
        return {}
    if isinstance(tp, dict):
        return {int(k): v for k, v in tp.items()}
    return {int(t.window_index): t for t in tp}


@dataclass(frozen=True, eq=False)
class _WindowRef:
    """What a window's cut is checked against: CL points, local frames, the box, and which
    CL point each target aims at. From the plan's ToolPath, or - when the plan carries none -
    from the hub's ground truth (nearest edge point to each target's tool point)."""

    p_HC: np.ndarray
    R_HL: np.ndarray
    bounds: object
    cl_of: dict
    tool_path: object = None
    source: str = "ToolPath"
    #: via targets (``cl_index`` -1 between CL targets): target -> (CL before, CL after,
    #: share of the travel between their targets), so a via stands for the edge chord point
    via_of: dict = field(default_factory=dict)

    def anchor(self, k: int) -> tuple[int, int, float] | None:
        """The CL point target ``k`` stands for, as (CL a, CL b, share from a to b)."""
        if k in self.cl_of:
            return self.cl_of[k], self.cl_of[k], 0.0
        return self.via_of.get(k)


def _via_anchors(targets, w: int, cl_of: dict) -> dict:
    """Via targets of window ``w``: each between the CL targets before and after it, at its
    share of the target polyline's length between them (the verifier's own reading, from the
    targets' tool points; not the planner's ``p_HC``)."""
    out = {}
    ks = [k for k, t in enumerate(targets) if t.window_index == w and t.segment == "cut"
          and t.cl_index < 0]
    for k in ks:
        a = next((j for j in range(k - 1, -1, -1) if j in cl_of), None)
        b = next((j for j in range(k + 1, len(targets)) if j in cl_of), None)
        if a is None or b is None or targets[b].window_index != w:
            continue
        P = np.array([targets[j].X_HT[:3, 3] for j in range(a, b + 1)])
        run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
        out[k] = (cl_of[a], cl_of[b], float(run[k - a] / max(run[-1], 1e-15)))
    return out


def _window_ref(w, targets, tool_path, edge, params) -> _WindowRef | None:
    ks = [k for k, t in enumerate(targets) if t.window_index == w and t.segment == "cut"]
    if tool_path is not None:
        cl_of = {k: int(targets[k].cl_index) for k in range(len(targets))
                 if targets[k].window_index == w and targets[k].cl_index >= 0}
        bounds = getattr(tool_path, "bounds", None) or (
            params.bounds_large if edge.kind == "large" else params.bounds_small)
        return _WindowRef(np.asarray(tool_path.p_HC, float), np.asarray(tool_path.R_HL, float),
                          bounds, cl_of, tool_path, via_of=_via_anchors(targets, w, cl_of))
    if edge is None or edge.t_H is None or edge.n_wall_H is None or not ks:
        return None
    from scipy.spatial import cKDTree

    p_E = np.asarray(edge.p_HE, float)
    # the targets of the cut loop (the one before the first cut target starts the loop)
    loop = [ks[0] - 1] + ks if ks[0] >= 1 else ks
    p_T = np.array([targets[k].X_HT[:3, 3] for k in loop])
    _, C = _closed_polyline_distance(p_T, p_E)
    _, v = cKDTree(p_E).query(C)
    # the project's one definition of the local frames (frames.local_frames, right-handed)
    R_HL = R_HL_from_normals(edge.t_H[v], edge.n_wall_H[v], name=f"window {w}")
    # a closed loop ends on its first point: one CL point for both
    unique, cl_of = [], {}
    for i, k in enumerate(loop):
        j = next((u for u, c in enumerate(unique) if np.linalg.norm(C[c] - C[i]) < 1e-6), None)
        if j is None:
            unique.append(i)
            j = len(unique) - 1
        cl_of[k] = j
    sel = np.asarray(unique)
    bounds = params.bounds_large if edge.kind == "large" else params.bounds_small
    return _WindowRef(C[sel], R_HL[sel], bounds, cl_of, None,
                      "hub edge (the plan carries no ToolPath)")


def _cone_half_angle(plan, window: int, tool_path) -> float:
    """The cone half-angle the plan was made with (recorded per window by the planner), else
    the ToolPath's enclosing cone (the planner's default mapping)."""
    for st in (plan.meta or {}).get("windows", []):
        if (isinstance(st, dict) and int(st.get("window", -1)) == int(window)
                and "cone_half_angle_rad" in st):
            return float(st["cone_half_angle_rad"])
    return float(getattr(tool_path, "cone_outer_half_angle", tool_path.cone_half_angle))


def _validate(plan) -> None:
    traj = plan.trajectory
    t, q, qd = (np.asarray(traj.t, float), np.asarray(traj.q, float), np.asarray(traj.qd, float))
    if t.ndim != 1 or len(t) < 2:
        raise InputError(f"plan for hub {plan.hub}: trajectory needs >= 2 knots, got {t.shape}")
    if q.shape != (len(t), 6) or qd.shape != (len(t), 6):
        raise InputError(f"plan for hub {plan.hub}: trajectory q/qd must be ({len(t)}, 6), got "
                         f"{q.shape}/{qd.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise InputError(f"plan for hub {plan.hub}: trajectory holds NaN/inf")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise InputError(f"plan for hub {plan.hub}: knot times not strictly increasing at knot "
                         f"{int(bad[0]) + 1}")
    if not plan.targets:
        raise InputError(f"plan for hub {plan.hub}: no targets")


def verify_plan(
    plan,
    *,
    tolerances: Tolerances = _TOLERANCES,
    params: ProcessParameters = _PARAMS,
    time_step: float = 0.02,
    joint_move_step: float = 2e-3,
    expected_windows: list[int] | None = None,
    cell=None,
    hub_model=None,
    progress: Callable[[int, int, str], None] | None = None,
) -> VerificationReport:
    """Re-check a plan densely and independently (see module docstring).

    Args:
        plan: a :class:`drakedeburr.plan.types.Plan`.
        tolerances: acceptance limits (config.Tolerances).
        params: process numbers (speeds, depth of cut, bounds, L_max, delta_max).
        time_step: longest time between trajectory samples [s] (travel sampling is
            ``tolerances.dense_step`` on approach/cut/retract).
        joint_move_step: tool travel between samples on home/transition moves [m] (these run
            at 450-600 mm/s away from the edge; sampling them every 0.5 mm would triple the
            cost for no information).
        expected_windows: windows the plan must cut (default: every window of the hub); give
            a subset to verify a partial plan (e.g. one re-planned window).
        cell: an already loaded cell for the plan's scenario and hub (default: load afresh).
        hub_model: the hub's :class:`drakedeburr.hub.HubModel` (default: ``load_hub(plan.hub)``).
        progress: optional callback (done, total, label).

    Returns:
        The VerificationReport; ``passed`` is False if any required item failed.

    Raises:
        InputError: the plan is malformed (trajectory shapes, non-increasing knots, no targets).
    """
    from drakedeburr.cell.station import load_cell
    from drakedeburr.cell.tools import BURR
    from drakedeburr.hub.model import load_hub
    from drakedeburr.verify.distances import DistanceProbe

    started = _time.perf_counter()
    _validate(plan)
    tol = tolerances
    if cell is None:
        cell = load_cell(plan.scenario, plan.hub)
    if hub_model is None:
        hub_model = load_hub(plan.hub)
    kin = _Kinematics(cell)
    traj = plan.trajectory
    targets = plan.targets
    segments = list(plan.segments)
    tool_paths = _tool_paths(plan)
    items: list[CheckItem] = []
    windows_hub = [w.index for w in hub_model.windows]
    if expected_windows is not None:
        bad = [w for w in expected_windows if w not in windows_hub]
        if bad:
            raise InputError(f"hub {hub_model.name} has no window(s) {bad} (has {windows_hub})")
        windows_hub = sorted(int(w) for w in expected_windows)
    edge_of = {w.index: w for w in hub_model.windows}

    # ---------------------------------------------------------------- structure
    problems = []
    t_end = float(traj.t[-1])
    if abs(float(traj.t[0])) > 1e-9:
        problems.append(f"trajectory starts at t={traj.t[0]:.6g} s, not 0")
    prev_t, prev_k = float(traj.t[0]), None
    for i, s in enumerate(segments):
        a, b = s.target_range
        if not (0 <= a < b <= len(targets)):
            problems.append(f"segment {i} ({s.kind}): target_range {s.target_range} invalid")
        if prev_k is not None and a != prev_k:
            problems.append(f"segment {i} ({s.kind}): targets start at {a}, previous ended at "
                            f"{prev_k}")
        if abs(s.t_range[0] - prev_t) > 1e-9 or s.t_range[1] < s.t_range[0]:
            problems.append(f"segment {i} ({s.kind}): t_range {s.t_range} does not continue "
                            f"at {prev_t:.6g} s")
        for k in range(max(a, 0), min(b, len(targets))):
            if targets[k].segment != s.kind:
                problems.append(f"target {k} is '{targets[k].segment}' inside a '{s.kind}' "
                                "segment")
                break
        prev_t, prev_k = s.t_range[1], b
    if segments and abs(prev_t - t_end) > 1e-9:
        problems.append(f"segments end at {prev_t:.6g} s, trajectory at {t_end:.6g} s")
    if not segments:
        problems.append("no segments")
    items.append(CheckItem(
        "structure", not problems, float(len(problems)), 0.0, "count", "<=",
        detail="; ".join(problems[:5]) or "segments tile the trajectory and the target list"))
    items.append(CheckItem(
        "planner_failures", not plan.failures, float(len(plan.failures)), 0.0, "count", "<=",
        detail=(f"{len(plan.failures)} failure record(s) in the plan, first: {plan.failures[0]}"
                if plan.failures else "the plan records no failed points")))

    # ---------------------------------------------------------------- sampling
    seg_samples = []
    for si, s in enumerate(segments):
        t0, t1 = float(s.t_range[0]), float(s.t_range[1])
        if t1 <= t0:
            seg_samples.append(np.array([t0]))
            continue
        step = tol.dense_step if s.kind in LINEAR_KINDS else joint_move_step
        n = max(3, int(np.ceil((t1 - t0) / 2e-3)) + 1)
        for _ in range(6):
            tf = np.linspace(t0, t1, n)
            p = kin.X_HT(traj.value(tf))[:, :3, 3]
            ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
            if ds.max(initial=0.0) <= 0.5 * step:
                break
            n = 2 * n
        s_acc = np.concatenate([[0.0], np.cumsum(ds)])
        k_travel = np.arange(0.0, s_acc[-1], 0.95 * step)  # margin: chords of a fine grid
        t_travel = np.interp(k_travel, s_acc, tf)
        t_time = np.arange(t0, t1, time_step)
        knots = traj.t[(traj.t > t0) & (traj.t < t1)]
        ts = np.unique(np.concatenate([[t0, t1], t_travel, t_time, knots]))
        seg_samples.append(ts)
        if progress is not None:
            progress(si + 1, 2 * len(segments), f"sampling {s.kind}")
    seg_index = np.concatenate([np.full(len(ts), i) for i, ts in enumerate(seg_samples)]) \
        if seg_samples else np.zeros(0, int)
    ts_all = np.concatenate(seg_samples) if seg_samples else np.zeros(0)
    q_all = traj.value(ts_all)
    qd_all = traj.derivative(ts_all, 1)
    X_HT_all = kin.X_HT(q_all)
    p_all = X_HT_all[:, :3, 3]
    h = 1e-6
    v_all = np.linalg.norm(kin.X_HT(traj.value(np.clip(ts_all + h, 0, t_end)))[:, :3, 3]
                           - kin.X_HT(traj.value(np.clip(ts_all - h, 0, t_end)))[:, :3, 3],
                           axis=1) / (np.clip(ts_all + h, 0, t_end) - np.clip(ts_all - h, 0,
                                                                                t_end))
    kind_all = np.array([_KIND_CODE.get(segments[i].kind, -1) for i in seg_index], int)
    win_all = np.array([segments[i].window_index for i in seg_index], int)
    N = len(ts_all)

    seg_k = np.full(N, -1)  # program move (index of the target it ends at) of each sample

    # ---------------------------------------------------------------- FK twice + distances
    probe = DistanceProbe(cell, tol.query_distance)
    from pydrake.multibody.tree import JacobianWrtVariable

    plant = cell.plant
    pc = probe.plant_context
    fk_diff = 0.0
    clear = np.full(N, np.inf)
    clear_pair = [("", "")] * N
    selfd = np.full(N, np.inf)
    self_pair = [("", "")] * N
    burr = np.full(N, np.inf)
    burr_pair = [("", "")] * N
    manip = np.full(N, np.nan)
    X_WF_opw = kin.X_WF(q_all)
    report_every = max(1, N // 50)
    for i in range(N):
        d = probe.measure(q_all[i])  # sets the positions in probe's context
        X_WF_d = cell.flange_frame.CalcPoseInWorld(pc).GetAsMatrix4()
        X_HT_d = cell.tool_frame.CalcPose(pc, cell.hub_frame).GetAsMatrix4()
        fk_diff = max(fk_diff, float(np.abs(X_WF_d - X_WF_opw[i]).max()),
                      float(np.abs(X_HT_d - X_HT_all[i]).max()))
        J = plant.CalcJacobianSpatialVelocity(pc, JacobianWrtVariable.kQDot, cell.flange_frame,
                                              np.zeros(3), plant.world_frame(),
                                              plant.world_frame())
        manip[i] = abs(float(np.linalg.det(J)))
        clear[i], clear_pair[i] = d.clearance, d.clearance_pair
        selfd[i], self_pair[i] = d.self_distance, d.self_pair
        burr[i], burr_pair[i] = d.burr, d.burr_pair
        if progress is not None and (i % report_every == 0 or i == N - 1):
            progress(len(segments) + int(len(segments) * (i + 1) / N), 2 * len(segments),
                     "distances")

    def where(i):
        """Worst-location fields of sample i: its window, time and the target its move ends at
        (the linear move it lies on, else its segment's last target)."""
        i = int(i)
        s = segments[seg_index[i]]
        k = int(seg_k[i]) if seg_k[i] >= 0 else s.target_range[1] - 1
        return {"window": int(s.window_index), "time": float(ts_all[i]),
                "target_index": int(min(max(k, 0), len(targets) - 1))}

    items.append(CheckItem(
        "fk_agreement", fk_diff <= tol.fk_match, fk_diff, tol.fk_match, "m", "<=",
        detail="Drake plant vs analytic OPW: flange pose in world and tool pose in hub, max "
               f"element difference over {N} samples"))

    # ---------------------------------------------------------------- targets
    tgt_q = np.array([t.q for t in targets], float)
    X_HT_t = kin.X_HT(tgt_q)
    pos_err = np.array([np.linalg.norm(X_HT_t[k, :3, 3] - targets[k].X_HT[:3, 3])
                        for k in range(len(targets))])
    rot_err = rot_angle(X_HT_t[:, :3, :3], np.array([t.X_HT[:3, :3] for t in targets]))
    X_WF_t = kin.X_WF(tgt_q)
    wf_err = np.array([np.linalg.norm(X_WF_t[k, :3, 3] - targets[k].X_WF[:3, 3])
                       for k in range(len(targets))])
    # the trajectory reaches each segment's last target at the segment's end time
    reach_err = []
    for s in segments:
        if s.target_range[1] - 1 < len(targets):
            Xe = kin.X_HT(traj.value(np.array([s.t_range[1]])))[0]
            reach_err.append(np.linalg.norm(Xe[:3, 3] - targets[s.target_range[1] - 1].X_HT[:3, 3]))
    worst = np.maximum(pos_err, wf_err)
    k_w = int(np.argmax(worst))
    val = float(max(worst.max(), max(reach_err, default=0.0)))
    ok = val <= tol.path_deviation and float(rot_err.max()) <= tol.orientation_match
    items.append(CheckItem(
        "target_consistency", ok, val, tol.path_deviation, "m", "<=",
        window=int(targets[k_w].window_index), target_index=k_w,
        detail=f"FK(target.q) vs target.X_HT / X_WF and trajectory at segment ends; max "
               f"orientation error {np.degrees(rot_err.max()):.3g} deg"))

    # ---------------------------------------------------------------- program vs trajectory
    path_dev = np.full(N, np.nan)
    orient_dev = np.full(N, np.nan)
    prog_to_traj = 0.0
    prog_worst = None
    contact = np.full((N, 3), np.nan)   # executed contact point C in H (cut samples)
    seg_f = np.full(N, np.nan)
    for si, s in enumerate(segments):
        a, b = s.target_range
        if a < 1 or b > len(targets) or b <= a:
            continue
        ks = [k for k in range(a, b) if _target_motion(targets[k]) == "linear"]
        if not ks:
            continue
        idx = np.flatnonzero(seg_index == si)
        P0 = np.array([targets[k - 1].X_HT[:3, 3] for k in ks])
        P1 = np.array([targets[k].X_HT[:3, 3] for k in ks])
        d, m, f = moves_in_order(p_all[idx], P0, P1)
        path_dev[idx] = d
        seg_k[idx] = np.asarray(ks)[m]
        seg_f[idx] = f
        # orientation at the share of each move travelled between passing its targets
        # (program_reading: the projection stands still in a corner zone while the tool turns
        # on); a stretch of moves that is not one chain of targets is read by the projection
        ka = np.asarray(ks)
        if len(idx) >= 2 and np.all(np.diff(ka) == 1):
            chain = np.arange(ka[0] - 1, ka[-1] + 1)
            m_o, f_o = passing_fractions(p_all[idx], np.array([targets[k].X_HT[:3, 3]
                                                               for k in chain]))
            k_o = ka[m_o]
        else:
            k_o, f_o = ka[m], f
        R_prog = slerp_pairs(np.array([targets[k - 1].X_HT[:3, :3] for k in k_o]),
                             np.array([targets[k].X_HT[:3, :3] for k in k_o]), f_o)
        orient_dev[idx] = rot_angle(R_prog, X_HT_all[idx, :3, :3])
        # program samples vs the trajectory's path in this segment
        prog_pts = []
        for k in ks:
            A, B = targets[k - 1].X_HT[:3, 3], targets[k].X_HT[:3, 3]
            n = max(1, int(np.ceil(np.linalg.norm(B - A) / tol.dense_step)))
            fr = np.arange(n + 1) / n
            prog_pts.append(A + np.outer(fr, B - A))
        prog_pts = np.concatenate(prog_pts)
        if len(idx) >= 2:
            dd, _, _ = _point_segment(prog_pts, p_all[idx[:-1]], p_all[idx[1:]])
            j = int(np.argmax(dd))
            if dd[j] > prog_to_traj:
                prog_to_traj = float(dd[j])
                _, jj, _ = _point_segment(prog_pts[j:j + 1], p_all[idx[:-1]], p_all[idx[1:]])
                prog_worst = idx[int(jj[0])]
    finite = np.isfinite(path_dev)
    if finite.any():
        i_w = int(np.nanargmax(path_dev))
        worst_val = float(path_dev[i_w])
        if prog_to_traj > worst_val and prog_worst is not None:
            worst_val, i_w = prog_to_traj, int(prog_worst)
        items.append(CheckItem(
            "path_deviation", worst_val <= tol.path_deviation, worst_val, tol.path_deviation,
            "m", "<=", **where(i_w),
            detail=f"tool point T vs the linear program, both ways (trajectory->program "
                   f"{np.nanmax(path_dev) * 1e3:.4f} mm, program->trajectory "
                   f"{prog_to_traj * 1e3:.4f} mm), {int(finite.sum())} samples"))
        i_o = int(np.nanargmax(orient_dev))
        items.append(CheckItem(
            "orientation_agreement", float(orient_dev[i_o]) <= tol.orientation_match,
            float(orient_dev[i_o]), tol.orientation_match, "rad", "<=", **where(i_o),
            detail="tool orientation of the trajectory vs the slerp of the program"))
    else:
        items.append(CheckItem("path_deviation", False, None, tol.path_deviation, "m", "<=",
                               detail="no linear moves in the plan"))

    # ---------------------------------------------------------------- edge, cone, windows
    cut_windows = sorted({s.window_index for s in segments if s.kind == "cut"})
    missing = [w for w in windows_hub if w not in cut_windows]
    refs = {w: _window_ref(w, targets, tool_paths.get(w), edge_of.get(w), params)
            for w in cut_windows}
    cl_missing = {}
    for w in cut_windows:
        ref = refs[w]
        if ref is None:
            cl_missing[w] = "neither a ToolPath nor ground-truth edge frames"
            continue
        have = {ref.cl_of[k] for k, t in enumerate(targets)
                if t.window_index == w and t.segment in ("approach", "cut") and k in ref.cl_of}
        lost = sorted(set(range(len(ref.p_HC))) - have)
        if lost:
            cl_missing[w] = f"CL points {lost[:5]}{'...' if len(lost) > 5 else ''} not targeted"
    unknown = [w for w in cut_windows if w not in edge_of]
    ok = not missing and not cl_missing and not unknown
    det = []
    if missing:
        det.append(f"window(s) {missing} of hub {hub_model.name} have no cut")
    if cl_missing:
        det.append("; ".join(f"window {w}: {m}" for w, m in cl_missing.items()))
    if unknown:
        det.append(f"window(s) {unknown} not in the hub")
    items.append(CheckItem(
        "windows", ok, float(len(missing) + len(cl_missing) + len(unknown)), 0.0, "count", "<=",
        window=(missing or list(cl_missing) or unknown or [None])[0],
        detail="; ".join(det) or f"all {len(windows_hub)} windows cut, every CL point targeted",
        per_window={w: {"cut": w in cut_windows} for w in windows_hub}))

    edge_dev = np.full(N, np.nan)
    engage = np.full(N, np.nan)
    theta_A = np.full(N, np.nan)
    theta_B = np.full(N, np.nan)
    cone_margin = np.full(N, np.nan)
    box_margin = np.full(N, np.nan)
    s_cut = np.full(N, np.nan)
    coverage = {}
    cone_per_window = {}
    from scipy.spatial import cKDTree

    for w in cut_windows:
        ref = refs[w]
        if ref is None or w not in edge_of:
            continue
        edge = np.asarray(edge_of[w].p_HE, float)
        tree = cKDTree(edge)
        idx = np.flatnonzero((win_all == w) & (kind_all == _KIND_CODE["cut"]) & (seg_k >= 1))
        if not len(idx):
            continue
        k1 = seg_k[idx]
        k0 = k1 - 1
        anchors = {int(k): ref.anchor(int(k)) for k in np.unique(np.concatenate([k0, k1]))}
        if any(a is None for a in anchors.values()):
            continue
        # the CL point each move end stands for (a via: the chord point between its CL points)
        an0 = np.array([anchors[int(k)] for k in k0])
        an1 = np.array([anchors[int(k)] for k in k1])
        ca0, cb0, g0 = an0[:, 0].astype(int), an0[:, 1].astype(int), an0[:, 2]
        ca1, cb1, g1 = an1[:, 0].astype(int), an1[:, 1].astype(int), an1[:, 2]
        f = seg_f[idx]
        p_HC = ref.p_HC
        P0 = (1 - g0)[:, None] * p_HC[ca0] + g0[:, None] * p_HC[cb0]
        P1 = (1 - g1)[:, None] * p_HC[ca1] + g1[:, None] * p_HC[cb1]

        def p_TC(k, p):
            X = np.asarray(targets[k].X_HT)
            return X[:3, :3].T @ (p - X[:3, 3])

        off = np.array([(1 - fi) * p_TC(a_, pa) + fi * p_TC(b_, pb)
                        for a_, b_, pa, pb, fi in zip(k0, k1, P0, P1, f, strict=True)])
        C = np.einsum("nij,nj->ni", X_HT_all[idx, :3, :3], off) + p_all[idx]
        contact[idx] = C
        d, E = _closed_polyline_distance(C, edge, tree)
        edge_dev[idx] = d
        # burr engagement: the true edge point in the tool frame vs the cone flank
        R = X_HT_all[idx, :3, :3]
        p_TE = np.einsum("nji,nj->ni", R, E - p_all[idx])
        r = np.linalg.norm(p_TE[:, :2], axis=1)
        z = p_TE[:, 2]
        alpha = BURR.cone_half_angle
        engage[idx] = ((BURR.apex_offset - z) * np.tan(alpha) - r) * np.cos(alpha)
        # coverage: every true edge point near the executed contact path
        dc, _, _ = _point_segment(edge, C[:-1], C[1:]) if len(C) > 1 else (np.array([np.inf]),
                                                                             None, None)
        jc = int(np.argmax(dc))
        coverage[w] = (float(dc[jc]), jc)
        # theta box: executed axis in the interpolated local frame (the source's bounds)
        R_loc = _lerp_frames(_lerp_frames(ref.R_HL[ca0], ref.R_HL[cb0], g0),
                             _lerp_frames(ref.R_HL[ca1], ref.R_HL[cb1], g1), f)
        tA, tB = angles_from_axis_H(R_loc, R[:, :, 2])  # the executed +Z_T
        theta_A[idx], theta_B[idx] = tA, tB
        lo, hi = ref.bounds.theta_min, ref.bounds.theta_max
        box_margin[idx] = np.minimum.reduce([tA - lo, hi - tA, tB - lo, hi - tB])
        # cone: the IK's constraint that stands for the box (AngleBetweenVectorsConstraint;
        # docs/plan.md), about the cone axis interpolated between the CL points
        cone_info = {}
        tp_w = ref.tool_path
        if tp_w is not None and getattr(tp_w, "cone_axis_H", None) is not None:
            half = _cone_half_angle(plan, w, tp_w)
            c_H = np.asarray(tp_w.cone_axis_H, float)
            c0 = (1 - g0)[:, None] * c_H[ca0] + g0[:, None] * c_H[cb0]
            c1 = (1 - g1)[:, None] * c_H[ca1] + g1[:, None] * c_H[cb1]
            c0 /= np.linalg.norm(c0, axis=1, keepdims=True)
            c1 /= np.linalg.norm(c1, axis=1, keepdims=True)
            c = (1 - f)[:, None] * c0 + f[:, None] * c1
            c /= np.linalg.norm(c, axis=1, keepdims=True)
            ang = np.arccos(np.clip(np.sum(c * R[:, :, 2], axis=1), -1.0, 1.0))
            cone_margin[idx] = half - ang
            cone_info = {"cone_half_angle": half, "max_angle_to_cone_axis": float(ang.max())}
        else:
            cone_margin[idx] = box_margin[idx]
            cone_info = {"cone": "no cone axes in the plan: the theta box is checked"}
        cone_per_window[w] = {"theta_A_min": float(tA.min()), "theta_A_max": float(tA.max()),
                              "theta_B_min": float(tB.min()), "theta_B_max": float(tB.max()),
                              "bounds": [lo, hi], "reference": ref.source,
                              "in_box_share": float(np.mean(box_margin[idx] >= -tol.cone_slack)),
                              **cone_info}
        sc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p_all[idx], axis=0),
                                                             axis=1))])
        s_cut[idx] = sc

    if np.isfinite(edge_dev).any():
        i_e = int(np.nanargmax(edge_dev))
        items.append(CheckItem(
            "edge_deviation", float(edge_dev[i_e]) <= tol.edge_deviation, float(edge_dev[i_e]),
            tol.edge_deviation, "m", "<=", **where(i_e),
            detail="executed contact point (tool pose x the target's tool-to-CL offset, "
                   "interpolated) vs the hub's ground-truth edge"))
        wc = max(coverage, key=lambda w: coverage[w][0])
        items.append(CheckItem(
            "edge_coverage", coverage[wc][0] <= tol.edge_deviation, coverage[wc][0],
            tol.edge_deviation, "m", "<=", window=int(wc),
            detail=f"farthest ground-truth edge point from the executed contact path (edge "
                   f"point {coverage[wc][1]} of window {wc})",
            per_window={w: {"max_gap_m": v[0]} for w, v in coverage.items()}))
        depth_of = {w: (params.depth_of_cut_large if edge_of[w].kind == "large"
                        else params.depth_of_cut_small) for w in cut_windows if w in edge_of}
        hi_lim = np.array([depth_of.get(w, 0.0) for w in win_all]) + tol.edge_deviation
        margin = np.minimum(engage + tol.edge_deviation, hi_lim - engage)
        i_g = int(np.nanargmin(margin))
        items.append(CheckItem(
            "burr_engagement", float(margin[i_g]) >= 0, float(engage[i_g]),
            float(hi_lim[i_g]) if engage[i_g] >= 0 else -tol.edge_deviation, "m",
            "<=" if engage[i_g] >= 0 else ">=", **where(i_g),
            detail=f"edge point's depth inside the burr cone (normal to the flank) must lie in "
                   f"[-{tol.edge_deviation * 1e3:.2f}, depth of cut + "
                   f"{tol.edge_deviation * 1e3:.2f}] mm; range "
                   f"[{np.nanmin(engage) * 1e3:.3f}, {np.nanmax(engage) * 1e3:.3f}] mm"))
        i_c = int(np.nanargmin(cone_margin))
        items.append(CheckItem(
            "cone", float(cone_margin[i_c]) >= -tol.cone_slack, float(cone_margin[i_c]),
            -tol.cone_slack, "rad", ">=", **where(i_c),
            detail=f"executed tool axis inside its admissible cone (the IK's cone standing for "
                   f"the (theta_A, theta_B) box), smallest margin; there theta_A="
                   f"{theta_A[i_c]:.4f}, theta_B={theta_B[i_c]:.4f} rad",
            per_window=cone_per_window))
        in_box = np.isfinite(box_margin)
        share = float(np.mean(box_margin[in_box] >= -tol.cone_slack)) if in_box.any() else 0.0
        i_b = int(np.nanargmin(box_margin))
        items.append(CheckItem(
            "theta_box", share >= 1.0, share, 1.0, "-", ">=", required=False, **where(i_b),
            detail=f"share of cut samples whose axis keeps both angles inside the source's "
                   f"(theta_A, theta_B) box (the cone is its smallest enclosing cone, so its "
                   f"rim admits more); smallest margin {box_margin[i_b]:.4f} rad"))
    else:
        for name in ("edge_deviation", "edge_coverage", "burr_engagement", "cone"):
            items.append(CheckItem(name, False, None, None, "m", "<=",
                                   detail="not measurable: no cut with tool paths and CL indices"))

    # theta statistics at the targets (Tab. 3-6 style), recomputed from the executed poses
    stats = {}
    for w in cut_windows:
        ref = refs[w]
        if ref is None:
            continue
        ks = [k for k, t in enumerate(targets) if t.window_index == w and t.segment == "cut"
              and k in ref.cl_of]
        cl = np.array([ref.cl_of[k] for k in ks])
        if not len(ks):
            continue
        tA, tB = angles_from_axis_H(ref.R_HL[cl], X_HT_t[ks, :3, 2])
        tp = ref.tool_path
        dA = float(np.abs(tA - np.asarray(tp.theta_A)[cl]).max()) if tp is not None else None
        dB = float(np.abs(tB - np.asarray(tp.theta_B)[cl]).max()) if tp is not None else None

        def describe(v):
            m = float(np.mean(v))
            return {"max": float(v.max()), "min": float(v.min()), "mean": m,
                    "variance": float(np.var(v)),
                    "cv": float(np.std(v) / abs(m)) if m else None}

        stats[w] = {"theta_A": describe(tA), "theta_B": describe(tB),
                    "max_diff_from_tool_path_rad": None if dA is None else max(dA, dB),
                    "reference": ref.source}
    items.append(CheckItem(
        "theta_statistics", True, None, None, "rad", "info", required=False,
        detail="theta_A/theta_B of the executed axis at the CL targets (source Tab. 3-6)",
        per_window=stats))

    # ---------------------------------------------------------------- distances
    i_c = int(np.argmin(clear))
    items.append(CheckItem(
        "clearance", bool(clear[i_c] >= tol.min_clearance), float(clear[i_c]),
        tol.min_clearance, "m", ">=", pair=clear_pair[i_c] if np.isfinite(clear[i_c]) else None,
        **where(i_c),
        detail=("smallest distance robot/tool to hub and cell, burr head-hub excepted"
                + ("" if np.isfinite(clear[i_c]) else
                   f" (nothing within {tol.query_distance * 1e3:.0f} mm)"))))
    i_s = int(np.argmin(selfd))
    items.append(CheckItem(
        "self_collision", bool(selfd[i_s] > 0.0), float(selfd[i_s]), 0.0, "m", ">=",
        pair=self_pair[i_s] if np.isfinite(selfd[i_s]) else None, **where(i_s),
        detail="smallest distance between unfiltered robot/tool geometries"))
    contact_kinds = np.isin(kind_all, [_KIND_CODE[k] for k in LINEAR_KINDS])
    depth_w = np.array([(params.depth_of_cut_large if edge_of[w].kind == "large"
                         else params.depth_of_cut_small) if w in edge_of else 0.0
                        for w in win_all])
    # the collision pieces are convex hulls that may reach past the true surface (the hub
    # generator splits a piece that reaches > 0.5 mm into an opening); the burr's true
    # engagement is checked against the true edge above (burr_engagement)
    burr_lim = np.where(contact_kinds,
                        -(depth_w + tol.edge_deviation + tol.collision_model_excess),
                        tol.min_clearance)
    i_b = int(np.argmin(burr - burr_lim))
    items.append(CheckItem(
        "burr_contact", bool(burr[i_b] >= burr_lim[i_b]), float(burr[i_b]), float(burr_lim[i_b]),
        "m", ">=", pair=burr_pair[i_b] if np.isfinite(burr[i_b]) else None, **where(i_b),
        detail=f"burr head vs hub collision pieces: penetration at most the depth of cut + "
               f"edge tolerance + {tol.collision_model_excess * 1e3:.2f} mm collision-model "
               f"excess on approach/cut/retract (burr_engagement checks the true edge), full "
               f"clearance elsewhere"))

    # ---------------------------------------------------------------- joint limits (exact)
    ext = _spline_extremes(traj)
    lo, hi = np.asarray(cell.q_lower), np.asarray(cell.q_upper)
    vlim = np.maximum(np.abs(cell.v_lower), np.abs(cell.v_upper))
    alim = np.maximum(np.abs(cell.a_lower), np.abs(cell.a_upper))
    names = [f"J{j + 1}" for j in range(6)]

    def worst_piece(values, xs, limit_fn):
        ratio = limit_fn(values)
        piece, cand, joint = np.unravel_index(np.argmax(ratio), ratio.shape)
        t_at = float(traj.t[piece] + xs[piece, cand, joint])
        return ratio[piece, cand, joint], int(joint), t_at, values[piece, cand, joint]

    def seg_at(t):
        for s_i, s in enumerate(segments):
            if s.t_range[0] - 1e-12 <= t <= s.t_range[1] + 1e-12:
                return s_i
        return None

    def loc(t):
        s_i = seg_at(t)
        if s_i is None:
            return {"time": t}
        s = segments[s_i]
        return {"window": int(s.window_index), "time": t,
                "target_index": int(min(s.target_range[1] - 1, len(targets) - 1))}

    pos, pos_x = ext["q"]
    margin = np.minimum(pos - lo, hi - pos)
    piece, cand, joint = np.unravel_index(np.argmin(margin), margin.shape)
    t_at = float(traj.t[piece] + pos_x[piece, cand, joint])
    m_val = float(margin[piece, cand, joint])
    items.append(CheckItem(
        "joint_position", m_val >= 0, m_val, 0.0, "rad", ">=", **loc(t_at),
        detail=f"smallest margin to a position limit: {names[joint]} at "
               f"{np.degrees(pos[piece, cand, joint]):.2f} deg (exact on the Hermite pieces)"))
    r, j, t_at, v = worst_piece(*ext["qd"], lambda x: np.abs(x) / vlim)
    items.append(CheckItem(
        "joint_velocity", r <= 1.0, float(r), 1.0, "ratio", "<=", **loc(t_at),
        detail=f"worst |qd|/limit: {names[j]} {v:.4g} rad/s of {vlim[j]:.4g}"))
    r, j, t_at, v = worst_piece(*ext["qdd"], lambda x: np.abs(x) / alim)
    items.append(CheckItem(
        "joint_acceleration", r <= 1.0, float(r), 1.0, "ratio", "<=", **loc(t_at),
        detail=f"worst |qdd|/limit: {names[j]} {v:.4g} rad/s^2 of {alim[j]:.4g}"))
    rest = float(max(np.abs(traj.qd[0]).max(), np.abs(traj.qd[-1]).max()))
    items.append(CheckItem("rest_at_ends", rest <= 1e-9, rest, 1e-9, "rad/s", "<=",
                           detail="joint velocity at the first and last knot"))
    home = float(max(np.abs(traj.q[0] - cell.q_home).max(),
                     np.abs(traj.q[-1] - cell.q_home).max()))
    items.append(CheckItem("start_end_home", home <= 1e-6, home, 1e-6, "rad", "<=",
                           required=False, detail="trajectory starts and ends at q_home"))

    # ---------------------------------------------------------------- configuration
    q_opw = kin.opw.q_opw_from_robot(q_all)
    wrist = np.sign(q_all[:, 4])
    elbow = np.sign(q_opw[:, 2] + np.arctan2(kin.opw.a2, kin.opw.c3))
    c = X_WF_opw[:, :3, 3] - kin.opw.c4 * X_WF_opw[:, :3, 2]
    shoulder = np.sign(c[:, 0] * np.cos(q_all[:, 0]) + c[:, 1] * np.sin(q_all[:, 0])
                       - kin.opw.a1)
    flips = {}
    for w in cut_windows:
        idx = np.flatnonzero((win_all == w) & contact_kinds)
        changed = [name for name, sgn in (("wrist", wrist), ("elbow", elbow),
                                          ("shoulder", shoulder))
                   if len(np.unique(sgn[idx][sgn[idx] != 0])) > 1]
        if changed:
            flips[w] = changed
    items.append(CheckItem(
        "configuration", not flips, float(len(flips)), 0.0, "count", "<=",
        window=next(iter(flips), None),
        detail=("; ".join(f"window {w}: {', '.join(v)} flip" for w, v in flips.items())
                or "one shoulder/elbow/wrist configuration per window")))

    # ---------------------------------------------------------------- TCP speed
    v_g = params.grinding_speed
    band_per_window = {}
    worst_frac, worst_w = 1.0, None
    least_bound, least_at = np.inf, None  # the least-forced slow stretch inside a cut
    is_cut = kind_all == _KIND_CODE["cut"]
    qdd_cut = np.zeros_like(qd_all)  # joint accelerations at the cut samples (one spline)
    qdd_cut[is_cut] = traj.derivative(ts_all[is_cut], 2)
    for w in cut_windows:
        idx = np.flatnonzero((win_all == w) & (kind_all == _KIND_CODE["cut"]))
        if len(idx) < 2:
            continue
        dsw = np.linalg.norm(np.diff(p_all[idx], axis=0), axis=1)
        vm = 0.5 * (v_all[idx][1:] + v_all[idx][:-1])
        inside = np.abs(vm / v_g - 1.0) <= tol.speed_band
        frac = float(dsw[inside].sum() / max(dsw.sum(), 1e-300))
        stretches = _slow_stretches(inside, dsw, vm, qd_all[idx], qdd_cut[idx], vlim, alim)
        band_per_window[w] = {"fraction_in_band": frac, "min_mps": float(v_all[idx].min()),
                              "max_mps": float(v_all[idx].max()), "slow_stretches": stretches}
        if frac < worst_frac:
            worst_frac, worst_w = frac, w
        for st in stretches:
            if st["at"] == "inside" and st["ratio"] < least_bound:
                least_bound, least_at = st["ratio"], (w, st)
    items.append(CheckItem(
        "tcp_speed_band", worst_frac >= tol.speed_band_fraction, worst_frac,
        tol.speed_band_fraction, "-", ">=", window=worst_w,
        detail=f"share of cutting travel within +-{tol.speed_band * 100:.0f} % of "
               f"{v_g * 1e3:.0f} mm/s (worst window)", per_window=band_per_window))
    forced = 1.0 if least_at is None else float(least_bound)
    items.append(CheckItem(
        "tcp_speed_forced", forced >= tol.forced_slowdown, forced, tol.forced_slowdown, "ratio",
        ">=", required=False, window=None if least_at is None else least_at[0],
        detail=("no slow stretch inside a cut" if least_at is None else
                "the stretches of the cuts slower than the band (away from the cut ends, which "
                "start and stop at rest): the least, over them, of the largest share of a "
                "joint's acceleration or speed limit used in the stretch (at the bound or "
                "above: the timing is at the robot's limits along this joint path, though "
                "another joint path may be faster there); least at "
                f"window {least_at[0]}, {1e3 * least_at[1]['from_m']:.1f}-"
                f"{1e3 * least_at[1]['to_m']:.1f} mm of its cut, {least_at[1]['joint']} "
                f"{least_at[1]['limit']}")))
    seg_speed = np.array([max([targets[k].speed for k in range(*s.target_range)
                               if k < len(targets)] or [np.inf]) for s in segments])
    v_lim_all = (1 + tol.speed_band) * np.where(kind_all == _KIND_CODE["cut"], v_g,
                                                seg_speed[seg_index])
    ratio = v_all / v_lim_all
    i_v = int(np.argmax(ratio))
    items.append(CheckItem(
        "tcp_speed_max", bool(ratio[i_v] <= 1.0), float(v_all[i_v]), float(v_lim_all[i_v]),
        "m/s", "<=", **where(i_v),
        detail="TCP speed never above the move's programmed speed + band (grinding speed on "
               "cuts)"))

    # ---------------------------------------------------------------- singularity, wrist, time
    j5 = np.abs(q_all[:, 4])
    i5 = int(np.argmin(j5))
    items.append(CheckItem(
        "wrist_singularity", bool(j5[i5] >= tol.wrist_margin), float(j5[i5]), tol.wrist_margin,
        "rad", ">=", **where(i5), detail="smallest |J5| (J5 = 0: axes 4 and 6 align)"))
    i_m = int(np.nanargmin(manip))
    items.append(CheckItem(
        "manipulability", bool(manip[i_m] >= tol.min_manipulability), float(manip[i_m]),
        tol.min_manipulability, "-", ">=", required=False, **where(i_m),
        detail="smallest |det J| of the flange's spatial Jacobian (Yoshikawa measure)"))
    ranges = {}
    worst_r, worst_rw, worst_lim = -np.inf, None, None
    for w in cut_windows:
        idx = np.flatnonzero((win_all == w) & (kind_all == _KIND_CODE["cut"]))
        if not len(idx):
            continue
        rng = np.ptp(q_all[idx][:, 3:6], axis=0)
        lim = tol.j6_range_large if (w in edge_of and edge_of[w].kind == "large") \
            else tol.j6_range_small
        ranges[w] = {"J4_range_rad": float(rng[0]), "J5_range_rad": float(rng[1]),
                     "J6_range_rad": float(rng[2]), "J6_limit_rad": lim}
        if rng[2] - lim > (worst_r - worst_lim if worst_lim is not None else -np.inf):
            worst_r, worst_rw, worst_lim = float(rng[2]), w, lim
    items.append(CheckItem(
        "j4_j6_range", bool(worst_lim is None or worst_r <= worst_lim),
        worst_r if worst_lim is not None else None, worst_lim, "rad", "<=", required=False,
        window=worst_rw, detail="J4-J6 ranges per window; J6 vs the paper's 20 deg (large) / "
                                "10 deg (small)", per_window=ranges))
    physical = 0.0
    for s in segments:
        a, b = s.target_range
        if s.kind == "cut" and s.window_index in edge_of:
            e = np.asarray(edge_of[s.window_index].p_HE)
            physical += float(np.linalg.norm(np.diff(np.vstack([e, e[:1]]), axis=0),
                                             axis=1).sum()) / v_g
        elif a >= 1 and b <= len(targets):
            travel = sum(np.linalg.norm(targets[k].X_HT[:3, 3] - targets[k - 1].X_HT[:3, 3])
                         for k in range(a, b))
            physical += travel / max(targets[b - 1].speed, 1e-9)
    ratio_t = traj.duration / physical if physical > 0 else np.inf
    items.append(CheckItem(
        "cycle_time", bool(ratio_t <= tol.cycle_time_ratio), float(ratio_t),
        tol.cycle_time_ratio, "ratio", "<=", required=False,
        detail=f"cycle {traj.duration:.3f} s vs physical limit {physical:.3f} s (edge length / "
               "grinding speed + straight moves at their programmed speeds)"))

    # ---------------------------------------------------------------- CL metrics
    cl_stats = {}
    worst_h, worst_hw, worst_l, worst_lw = 0.0, None, 0.0, None
    for w in cut_windows:
        ref = refs[w]
        if ref is None or w not in edge_of:
            continue
        p = ref.p_HC
        edge = np.asarray(edge_of[w].p_HE, float)
        chords = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        _, vi = cKDTree(edge).query(p)
        heights = []
        m = len(edge)
        for i in range(len(p)):
            i0, i1 = vi[i], vi[(i + 1) % len(p)]
            # the edge between two neighbouring CL points is the shorter way round the loop
            # (the CL points may run either way along the loop)
            span = (i1 - i0) % m
            if span > m - span:
                i0, span = i1, m - span
            pts = edge[(i0 + np.arange(span + 1)) % m]
            a_, b_ = p[i], p[(i + 1) % len(p)]
            ab = b_ - a_
            L = max(np.linalg.norm(ab), 1e-300)
            dv = pts - a_
            heights.append(float(np.linalg.norm(dv - np.outer(dv @ ab / L, ab / L), axis=1).max()))
        mu = chords.mean()
        cl_stats[w] = {"count": len(p), "cv": float(chords.std() / mu) if mu > 0 else None,
                       "max_chord_height_m": max(heights),
                       "max_chord_length_m": float(chords.max())}
        if max(heights) > worst_h:
            worst_h, worst_hw = max(heights), w
        if chords.max() > worst_l:
            worst_l, worst_lw = float(chords.max()), w
    items.append(CheckItem(
        "cl_chord_error", bool(cl_stats) and worst_h <= params.delta_max, worst_h,
        params.delta_max, "m", "<=", window=worst_hw,
        detail="largest distance of the true edge from a chord between consecutive CL points"
               + ("" if all(r is None or r.tool_path is not None for r in refs.values()) else
                  " (CL points inferred from the targets: the plan carries no ToolPath)"),
        per_window=cl_stats))
    items.append(CheckItem(
        "cl_chord_length", bool(cl_stats) and worst_l <= params.l_max + 1e-12, worst_l,
        params.l_max, "m", "<=", window=worst_lw, detail="longest chord between CL points"))

    passed = all(i.passed for i in items if i.required)
    windows_in_plan = sorted({t.window_index for t in targets if t.window_index >= 0})
    plan_info = {"scenario": str(plan.scenario), "hub": str(plan.hub), "mode": plan.mode,
                 "expected_windows": windows_hub, "windows": windows_in_plan,
                 "targets": len(targets), "segments": len(segments), "knots": len(traj.t),
                 "duration_s": traj.duration, "planner": str(plan.meta.get("planner", ""))}
    settings = {"tolerances": {k: getattr(tol, k) for k in tol.__dataclass_fields__},
                "time_step_s": time_step, "joint_move_step_m": joint_move_step, "samples": N,
                "grinding_speed": params.grinding_speed,
                "cut_samples": int((kind_all == _KIND_CODE["cut"]).sum())}
    series = {"t": ts_all, "q": q_all, "qd": qd_all, "speed": v_all, "clearance": clear,
              "self": selfd, "burr": burr, "kind": kind_all, "window": win_all,
              "path_dev": path_dev, "orient_dev": orient_dev, "edge_dev": edge_dev,
              "engagement": engage, "theta_A": theta_A, "theta_B": theta_B, "s_cut": s_cut,
              "cone_margin": cone_margin, "manipulability": manip, "p_HT": p_all,
              "contact_H": contact}
    import drakedeburr

    run = {"timestamp": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
           "elapsed_s": round(_time.perf_counter() - started, 3),
           "versions": {"drakedeburr": getattr(drakedeburr, "__version__", "")}}
    log.info("verified plan for %s (%s): %s, %d samples", plan.hub, plan.scenario,
             "PASS" if passed else "FAIL " + ", ".join(i.name for i in items
                                                       if i.required and not i.passed), N)
    return VerificationReport(passed=passed, items=tuple(items), plan_info=plan_info,
                              settings=settings, series=series, run=run)
