"""Process figures and speed checks: the share of each cut at the feed and what slows it,
the TCP speed against the programmed speeds, J4-J6 ranges, the cycle time and where it goes
(:func:`time_budget`: per window the cut against its edge length over the feed, the moves off
the cut against the joint-space minimum time of their joint displacement, the wrist ranges and
the limit that binds on each slow stretch)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from drakedeburr.verify.geometry import slow_stretches
from drakedeburr.verify.report import CheckItem
from drakedeburr.verify.types import KIND_CODE

__all__ = ["tcp_speed_band", "slowdowns_justified", "tcp_speed_max", "program_speeds",
           "j4_j6_range", "cycle_time", "speed_band_per_window", "time_budget",
           "AirMove", "WindowTime", "min_time_1d", "joint_move_bound"]


#: (what, kind) of the columns of :func:`_limit_ratios`
_LIMITS = ([(f"J{j + 1}", "speed") for j in range(6)]
           + [(f"J{j + 1}", "acceleration") for j in range(6)] + [("TCP", "acceleration")])


def _limit_ratios(sp, cfg, t0: float, t1: float, dt: float = 0.5e-3):
    """On a ``dt`` grid over [t0, t1] (independent of the verification sampling) and at the
    trajectory's knots inside it (both sides: the timing bounds the limits there, and between
    knots a degree-6 piece's acceleration can fall off within a fraction of a millisecond, so
    a grid alone misses the peaks: 0.83-0.85 of a limit read on a slow stretch where the joint
    is at 0.90 at every knot): times, tool travel from t0 [m], per
    limit of :data:`_LIMITS` its share in use (|qd|/v_max, |qdd|/a_max, |TCP path
    acceleration|/the process's), and which points are the grid's."""
    from drakedeburr.verify.sampling import path_acceleration

    traj = sp.plan.trajectory
    grid = np.linspace(t0, t1, max(3, int(np.ceil((t1 - t0) / dt)) + 1))
    knots = np.asarray(traj.t, float)
    knots = knots[(knots > t0) & (knots < t1)]
    t = np.concatenate([grid, knots, np.maximum(knots - 1e-9, t0)])
    order = np.argsort(t, kind="stable")
    t, on_grid = t[order], (np.arange(len(t)) < len(grid))[order]
    p = sp.kin.X_HT(traj.value(t))[:, :3, 3]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    lim = sp.limits
    ratios = np.concatenate([
        np.abs(traj.derivative(t, 1)) / lim.velocity,
        np.abs(traj.derivative(t, 2)) / lim.acceleration,
        np.abs(path_acceleration(traj, sp.kin, t, p))[:, None] / cfg.process.tcp_acceleration],
        axis=1)
    return t, s, ratios, on_grid


def _windowed_max(s: np.ndarray, r: np.ndarray, reach: float, centres: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Per point of travel ``s[centres]``: the largest of ``r`` (n, L) over all the points
    within ``reach`` of it, and the column (limit) it comes from."""
    peak = r.max(axis=1)
    which = r.argmax(axis=1)
    c = s[centres]
    lo = np.searchsorted(s, c - reach)
    hi = np.searchsorted(s, c + reach, side="right")
    best = np.array([a + int(np.argmax(peak[a:b])) for a, b in zip(lo, hi, strict=True)])
    return peak[best], which[best]


def _cut_pieces(sp, w: int) -> list[np.ndarray]:
    """The sample indices of window ``w``'s cut, one array per cut segment (a partial window,
    issue 42, has one per planned stretch: its cuts are apart in time and travel, the moves
    off the edge between them)."""
    idx = sp.samples_of(w)
    if len(idx) < 2:
        return [idx]
    cut = np.flatnonzero((np.diff(idx) != 1) | (np.diff(sp.samples.segment[idx]) != 0)) + 1
    return np.split(idx, cut)


def _piece_band(sp, cfg, idx: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray, list]:
    """One cut segment's (sample indices ``idx``) interval lengths, in-band marks and slow
    stretches, each with the limit that binds there (:func:`_speed_band`); travel from the
    segment's start."""
    s, tol = sp.samples, cfg.tolerances
    ds = np.linalg.norm(np.diff(s.p_HT[idx], axis=0), axis=1)
    vm = 0.5 * (s.speed[idx][1:] + s.speed[idx][:-1])
    inside = np.abs(vm / cfg.process.grinding_speed - 1.0) <= tol.speed_band
    stretches = slow_stretches(inside, ds, vm)
    if stretches:
        _, s_all, r_f, on_grid = _limit_ratios(sp, cfg, s.t[idx[0]], s.t[idx[-1]])
        bound, which = _windowed_max(s_all, r_f, reach, on_grid)
        s_f = s_all[on_grid]
        for st in stretches:
            on = np.flatnonzero((s_f >= st["from_m"]) & (s_f <= st["to_m"]))
            if not len(on):  # shorter than the fine grid: its nearest point
                on = np.array([int(np.argmin(np.abs(s_f - st["from_m"])))])
            k = on[int(np.argmin(bound[on]))]
            joint, kind = _LIMITS[which[k]]
            st.update(joint=joint, limit=kind, ratio=float(bound[k]),
                      least_at_m=float(s_f[k]))
            del st["a"], st["b"]
    return ds, inside, stretches


def _speed_band(sp, cfg, reach: float = 1e-3) -> dict:
    """Per cut window: the share of its travel in the feed band, extreme speeds and its slow
    stretches, each with the least, over its points, of the largest share of a limit in use
    within ``reach`` of tool travel of the point (the limit that binds there: on a time-optimal
    timing one always does, switching from one to another where the timing switches between
    accelerating and braking), and that limit.

    Each cut segment is read on its own (a partial window's stretches: their travel and the
    limits along it are the segment's own, a stretch's ends are where its cut starts and
    stops); ``from_m``/``to_m``/``least_at_m`` count cutting travel from the window's first
    cut, ``stretch`` is the cut segment's number in the window."""
    s = sp.samples
    out = {}
    for w in sp.cut_windows:
        idx = sp.samples_of(w)
        if len(idx) < 2:
            continue
        ds_all, in_all, stretches, run = [], [], [], 0.0
        for k, piece in enumerate(p for p in _cut_pieces(sp, w) if len(p) >= 2):
            ds, inside, found = _piece_band(sp, cfg, piece, reach)
            for st in found:
                st.update(from_m=st["from_m"] + run, to_m=st["to_m"] + run,
                          least_at_m=st["least_at_m"] + run, stretch=k)
            ds_all.append(ds)
            in_all.append(inside)
            stretches += found
            run += float(ds.sum())
        ds, inside = np.concatenate(ds_all), np.concatenate(in_all)
        out[w] = {"fraction_in_band": float(ds[inside].sum() / max(ds.sum(), 1e-300)),
                  "min_mps": float(s.speed[idx].min()), "max_mps": float(s.speed[idx].max()),
                  "slow_stretches": stretches}
    return out


def speed_band_per_window(sp, cfg) -> dict:
    """The per-window speed figures (computed once per sampled plan)."""
    return sp.memo("speed_band", lambda: _speed_band(sp, cfg))


def _planner_bounds(sp) -> dict:
    """{window: the planner's own figure of the share of the cut that could be in the band}
    (``plan.meta["windows"][i]["speed_in_band_bound"]``, where the plan records one)."""
    out = {}
    for w in (sp.plan.meta or {}).get("windows", []):
        b = w.get("speed_in_band_bound") if isinstance(w, dict) else None
        if b is not None and "window" in w:
            out[int(w["window"])] = float(b)
    return out


def tcp_speed_band(sp, cfg) -> CheckItem:
    """The measured share of each cut in the feed band (this verifier's reading), beside the
    planner's figure of what share could be (its fillet repair's bound, when recorded)."""
    per = speed_band_per_window(sp, cfg)
    worst_w = min(per, key=lambda w: per[w]["fraction_in_band"], default=None)
    worst = 1.0 if worst_w is None else per[worst_w]["fraction_in_band"]
    worst_w = worst_w if worst < 1.0 else None
    limit = cfg.acceptance.speed_band_fraction
    tol = cfg.tolerances
    bounds = _planner_bounds(sp)
    shown = {w: ({**info, "planner_bound_in_band": bounds[w]} if w in bounds else info)
             for w, info in per.items()}
    detail = (f"share of cutting travel within +-{tol.speed_band * 100:.0f} % of "
              f"{cfg.process.grinding_speed * 1e3:.0f} mm/s (worst window, measured here)")
    if bounds:
        least = min(bounds, key=bounds.get)
        detail += ("; the planner's own figure of the share that could be in the band "
                   "(its fillet repair: every slow stretch where it found the feed can be held "
                   "cut at the feed): worst window "
                   f"{least}: {100 * bounds[least]:.1f} %")
        if worst_w is not None and worst_w in bounds:
            detail += (f"; window {worst_w}: measured {100 * worst:.1f} %, planner's figure "
                       f"{100 * bounds[worst_w]:.1f} %")
    return CheckItem(
        "tcp_speed_band", limit is None or worst >= limit, worst, limit, "-", ">=",
        window=worst_w, detail=detail, per_window=shown)


def slowdowns_justified(sp, cfg) -> CheckItem:
    """No needless slack: wherever a cut runs below the feed band, a limit binds there."""
    per = speed_band_per_window(sp, cfg)
    least, at = np.inf, None
    for w, info in per.items():
        for st in info["slow_stretches"]:
            if st["ratio"] < least:
                least, at = st["ratio"], (w, st)
    tol = cfg.tolerances
    forced = 1.0 if at is None else float(least)
    where = "" if at is None else (
        f"; least at window {at[0]}, {1e3 * at[1]['from_m']:.1f}-{1e3 * at[1]['to_m']:.1f} mm "
        f"of its cut ({at[1]['at']}), {at[1]['joint']} {at[1]['limit']}")
    return CheckItem(
        "slowdowns_justified", forced >= tol.forced_slowdown, forced, tol.forced_slowdown,
        "ratio", ">=", window=None if at is None else at[0],
        detail="wherever a cut runs below the feed band, a limit is in use there: a joint's "
               "speed or acceleration, or the TCP's path acceleration, at this share of its "
               "limit at least within 1 mm of tool travel (read every 0.5 ms and at the "
               "trajectory's knots); below it the "
               "plan slows for no reason the robot imposes" + where)


def _programmed_speed(sp, step: float) -> np.ndarray:
    """(N,) the programmed speed each sample runs under [m/s]: its linear move's (the target
    the move ends at), else the fastest target speed of its segment (joint moves). Which move
    a sample lies on is read to the sampling ``step``: within it of a move's start or end
    target, the neighbouring move's speed counts too (a controller changes speed there)."""
    s, targets = sp.samples, sp.targets
    seg_speed = np.array([max([targets[k].speed for k in range(*g.target_range)
                               if k < len(targets)] or [np.inf]) for g in sp.segments])
    move = sp.program.move
    speeds = np.array([t.speed for t in targets])
    P = np.array([t.X_HT[:3, 3] for t in targets])
    k = np.maximum(move, 0)
    v = speeds[k]
    near_start = np.linalg.norm(s.p_HT - P[np.maximum(k - 1, 0)], axis=1) <= step
    near_end = np.linalg.norm(s.p_HT - P[k], axis=1) <= step
    v = np.where(near_start & (k >= 1), np.maximum(v, speeds[np.maximum(k - 1, 0)]), v)
    nxt = np.minimum(k + 1, len(targets) - 1)
    v = np.where(near_end, np.maximum(v, speeds[nxt]), v)
    return np.where(move >= 0, v, seg_speed[s.segment])


def tcp_speed_max(sp, cfg) -> CheckItem:
    s, tol = sp.samples, cfg.tolerances
    v_lim = (1 + tol.speed_band) * _programmed_speed(sp, tol.dense_step)
    ratio = s.speed / v_lim
    i = int(np.argmax(ratio))
    return CheckItem(
        "tcp_speed_max", bool(ratio[i] <= 1.0), float(s.speed[i]), float(v_lim[i]), "m/s", "<=",
        **sp.where(i),
        detail="TCP speed never above the programmed speed of its move + band")


def program_speeds(sp, cfg) -> CheckItem:
    """Each cutting move's programmed speed is the speed the verified motion runs there: the
    fastest sample on the move within the band below it (and the quantum the program rounds
    up to); faster is caught by ``tcp_speed_max``."""
    s, tol, targets = sp.samples, cfg.tolerances, sp.targets
    move = sp.program.move
    cut = (s.kind == KIND_CODE["cut"]) & (move >= 0)
    worst, worst_k, n_moves = np.inf, None, 0
    for k in np.unique(move[cut]):
        on = np.flatnonzero(cut & (move == k))
        # the move from its start target to its end target: its samples and the ones just
        # before and after it (the plan's speed at the targets themselves)
        span = np.arange(max(on[0] - 1, 0), min(on[-1] + 2, len(s.speed)))
        v_prog = targets[k].speed
        v_max = float(s.speed[span].max())
        floor = v_prog * (1 - tol.speed_band) - tol.speed_quantum
        n_moves += 1
        ratio = v_max / max(floor, 1e-12)
        if ratio < worst:
            worst, worst_k = ratio, int(k)
    where = {} if worst_k is None else {
        "window": int(targets[worst_k].window_index), "target_index": worst_k}
    detail = (f"{n_moves} cutting moves: the fastest sample of each move (from its start "
              "target to its end target) against its programmed speed less the band and the "
              "quantum")
    if worst_k is not None:
        detail += (f"; least at target {worst_k}: programmed "
                   f"{targets[worst_k].speed * 1e3:.0f} mm/s")
    return CheckItem("program_speeds", worst >= 1.0, None if worst_k is None else worst, 1.0,
                     "ratio", ">=", detail=detail, **where)


def _wrist_ranges(sp) -> dict:
    """{window: (3,) the J4-J6 ranges over its cut's samples [rad]}."""
    out = {}
    for w in sp.cut_windows:
        idx = sp.samples_of(w)
        if len(idx):
            out[w] = np.ptp(sp.samples.q[idx][:, 3:6], axis=0)
    return out


def j4_j6_range(sp, cfg) -> CheckItem:
    acc = cfg.acceptance
    ranges = {}
    worst, worst_w, worst_lim = -np.inf, None, None
    for w, rng in _wrist_ranges(sp).items():
        large = w in sp.edge_of and sp.edge_of[w].kind == "large"
        lim = acc.j6_range_large if large else acc.j6_range_small
        ranges[w] = {"J4_range_rad": float(rng[0]), "J5_range_rad": float(rng[1]),
                     "J6_range_rad": float(rng[2]), "J6_limit_rad": lim}
        # the window furthest over its threshold (without thresholds: the widest J6 range)
        excess = rng[2] - (lim if lim is not None else 0.0)
        if worst_w is None or excess > worst - (worst_lim if worst_lim is not None else 0.0):
            worst, worst_w, worst_lim = float(rng[2]), w, lim
    return CheckItem(
        "j4_j6_range", worst_lim is None or worst <= worst_lim,
        worst if worst_w is not None else None, worst_lim, "rad", "<=", window=worst_w,
        detail="J4-J6 ranges per window; J6 against the recipe's threshold where it sets one "
               "(the source: 20 deg large / 10 deg small windows)", per_window=ranges)


def _straight_seconds(sp, g) -> float | None:
    """A segment's straight moves (target to target) at its last target's programmed speed
    [s], None where the segment has no previous target."""
    a, b = g.target_range
    targets = sp.targets
    if a < 1 or b > len(targets):
        return None
    travel = sum(np.linalg.norm(targets[k].X_HT[:3, 3] - targets[k - 1].X_HT[:3, 3])
                 for k in range(a, b))
    return float(travel / max(targets[b - 1].speed, 1e-9))


def _physical_seconds(sp, cfg) -> float:
    """Edge length over the feed plus straight moves at their programmed speeds [s]."""
    total, v_g, seen = 0.0, cfg.process.grinding_speed, set()
    for g in sp.segments:
        if g.kind == "cut" and g.window_index in sp.edge_of:
            if g.window_index in seen:  # a partial window's next stretch: its edge counted
                continue
            seen.add(g.window_index)
            e = np.asarray(sp.edge_of[g.window_index].p_HE)
            total += float(np.linalg.norm(np.diff(np.vstack([e, e[:1]]), axis=0),
                                          axis=1).sum()) / v_g
        else:
            total += _straight_seconds(sp, g) or 0.0
    return total


def cycle_time(sp, cfg) -> CheckItem:
    duration = sp.plan.trajectory.duration
    physical = _physical_seconds(sp, cfg)
    ratio = duration / physical if physical > 0 else np.inf
    limit = cfg.acceptance.cycle_time_ratio
    return CheckItem(
        "cycle_time", limit is None or bool(ratio <= limit), float(ratio), limit, "ratio", "<=",
        detail=f"cycle {duration:.3f} s vs physical limit {physical:.3f} s (edge length / "
               "grinding speed + straight moves at their programmed speeds)")


# -- where the cycle's time goes ----------------------------------------------------------------


def min_time_1d(d: float, v0: float, v1: float, v_max: float, a_max: float
                ) -> tuple[float, bool]:
    """The least time one joint needs to move by ``d`` [rad] from velocity ``v0`` to ``v1``
    [rad/s] under |velocity| <= ``v_max`` and |acceleration| <= ``a_max``, and whether that
    profile cruises at ``v_max`` (velocity-bound) or not (acceleration-bound).

    The time-optimal control of a double integrator with a velocity bound is bang-bang with one
    switch, with a cruise at the bound between (Kröger & Wahl, IEEE T-RO 26(1) 2010, type I
    profiles): accelerate at ``sigma a_max`` (sigma = +-1) to a peak ``p``, brake at
    ``-sigma a_max`` to ``v1``. In the frame where sigma = +1 (``D, a, b`` = sigma ``d, v0,
    v1``), ``D = (p^2 - a^2) / (2 a_max) + (p^2 - b^2) / (2 a_max)``, so
    ``p^2 = a_max D + (a^2 + b^2) / 2`` with ``p >= max(a, b)`` and
    ``T = (2 p - a - b) / a_max``; when ``p > v_max`` the joint cruises at ``v_max`` for
    ``(D - (2 v_max^2 - a^2 - b^2) / (2 a_max)) / v_max``. The least T over both signs and
    both roots of p. Rest to rest this is the trapezoid (Lynch & Park, Modern Robotics
    sec. 9.2.2): ``T = |d| / v_max + v_max / a_max`` when ``|d| >= v_max^2 / a_max``, else
    ``2 sqrt(|d| / a_max)``."""
    v0 = float(np.clip(v0, -v_max, v_max))
    v1 = float(np.clip(v1, -v_max, v_max))
    best, cruise = np.inf, False
    for sigma in (1.0, -1.0):
        D, a, b = sigma * d, sigma * v0, sigma * v1
        p2 = a_max * D + 0.5 * (a * a + b * b)
        if p2 < 0.0:
            continue
        for p in (np.sqrt(p2), -np.sqrt(p2)):
            if p < max(a, b) - 1e-12 * max(v_max, 1.0):
                continue
            if p > v_max:
                T = ((2 * v_max - a - b) / a_max
                     + (D - (2 * v_max ** 2 - a * a - b * b) / (2 * a_max)) / v_max)
                c = True
            else:
                T, c = (2 * p - a - b) / a_max, False
            if T < best:
                best, cruise = float(max(T, 0.0)), c
    return best, cruise


def joint_move_bound(q0, q1, qd0, qd1, v_max, a_max) -> tuple[float, int, bool]:
    """The least time of a joint-space move from (``q0``, ``qd0``) to (``q1``, ``qd1``) at the
    joint limits (6,) [rad, rad/s]: the largest over the joints of :func:`min_time_1d` (a lower
    bound: every joint must make its own displacement), the joint that sets it and whether
    that joint is velocity-bound there."""
    per = [min_time_1d(float(q1[j] - q0[j]), float(qd0[j]), float(qd1[j]), float(v_max[j]),
                       float(a_max[j])) for j in range(len(q0))]
    j = int(np.argmax([p[0] for p in per]))
    return per[j][0], j, per[j][1]


@dataclass(frozen=True)
class AirMove:
    """One move off the cut (home, transition, approach, retract) against its bound.

    Attributes:
        kind: the segment's kind; window: its window (-1 home/transition).
        duration_s: its time in the plan [s].
        bound_s: the least time of its joint displacement (and end velocities) at the joint
            velocity/acceleration limits (:func:`joint_move_bound`) [s].
        bound_joint: the joint that sets ``bound_s`` ("J1".."J6"); bound_limit: "speed" when it
            cruises at its velocity limit, else "acceleration".
        programmed_s: its straight moves at its programmed TCP speed [s] (the figure
            ``cycle_time`` counts), None without a previous target.
        peak_joint / peak_limit / peak_ratio: the limit most in use during the move (a joint's
            speed or acceleration, or the TCP acceleration) and its share.
    """

    kind: str
    window: int
    duration_s: float
    bound_s: float
    bound_joint: str
    bound_limit: str
    programmed_s: float | None
    peak_joint: str
    peak_limit: str
    peak_ratio: float

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class WindowTime:
    """Where one window's time goes.

    Attributes:
        window: the window. cut_s: its cut's time in the plan [s] (a partial window, issue
            42: its stretches' cuts added, the moves between them in ``air_before``).
        edge_length_m: the closed polyline through its CL points (the ones the cut is checked
            against: the plan's ToolPath, else read off the hub's true edge) [m];
            tool_path_m: the programmed tool-point path of the cut (from the approach's end
            through every cut target) [m].
        feed_mps: the grinding speed [m/s]; edge_seconds: edge_length_m / feed_mps [s];
            cut_ratio: cut_s / edge_seconds.
        fraction_in_band: share of the cut's travel in the feed band (``tcp_speed_band``).
        j4_range_rad, j5_range_rad, j6_range_rad: the wrist's ranges over the cut [rad].
        slow_stretches: each stretch below the band with the limit that binds there
            (``tcp_speed_band``'s: from_m, to_m, min_mps, at, joint, limit, ratio).
        air_before: the moves off the cut from the previous window's cut (or the start) to this
            one's, in order; air_before_s / air_bound_s: their time and the sum of their bounds.
    """

    window: int
    cut_s: float
    edge_length_m: float
    tool_path_m: float
    feed_mps: float
    edge_seconds: float
    cut_ratio: float
    fraction_in_band: float
    j4_range_rad: float
    j5_range_rad: float
    j6_range_rad: float
    slow_stretches: tuple
    air_before: tuple[AirMove, ...]
    air_before_s: float
    air_bound_s: float

    def as_dict(self) -> dict:
        d = asdict(self)
        d["slow_stretches"] = [dict(st) for st in self.slow_stretches]
        d["air_before"] = [m.as_dict() for m in self.air_before]
        return d


def _air_move(sp, cfg, g) -> AirMove:
    traj, lim = sp.plan.trajectory, sp.limits
    t0, t1 = (float(x) for x in g.t_range)
    q = traj.value(np.array([t0, t1]))
    qd = traj.derivative(np.array([t0, t1]), 1)
    bound, j, cruise = joint_move_bound(q[0], q[1], qd[0], qd[1], lim.velocity,
                                        lim.acceleration)
    if t1 > t0:
        _, _, r, _ = _limit_ratios(sp, cfg, t0, t1)
        peak = r.max(axis=0)
        k = int(np.argmax(peak))
        pj, pl, pr = *_LIMITS[k], float(peak[k])
    else:
        pj, pl, pr = "-", "-", 0.0
    return AirMove(kind=g.kind, window=int(g.window_index), duration_s=t1 - t0,
                   bound_s=float(bound), bound_joint=f"J{j + 1}",
                   bound_limit="speed" if cruise else "acceleration",
                   programmed_s=_straight_seconds(sp, g), peak_joint=pj, peak_limit=pl,
                   peak_ratio=pr)


def _edge_and_tool_path(sp, g) -> tuple[float, float]:
    """(closed polyline length of the window's CL points, programmed tool-point path length)
    of a cut segment [m]. The CL points are the ones its cut is checked against
    (:class:`drakedeburr.verify.refs.WindowRef`: the plan's ToolPath, else read off the hub's
    true edge), else the cut targets' own."""
    a, b = g.target_range
    targets = sp.targets
    ref = (sp.refs or {}).get(g.window_index)
    if ref is not None:
        c = np.asarray(ref.p_HC, float).reshape(-1, 3)
    else:
        c = np.array([t.p_HC for t in targets[a:b] if t.p_HC is not None],
                     float).reshape(-1, 3)
    edge = (float(np.linalg.norm(np.diff(np.vstack([c, c[:1]]), axis=0), axis=1).sum())
            if len(c) > 1 else 0.0)
    p = np.array([t.X_HT[:3, 3] for t in targets[max(a - 1, 0):b]], float)
    tool = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) > 1 else 0.0
    return edge, tool


def window_times(sp, cfg) -> tuple[dict, tuple[AirMove, ...]]:
    """({window: :class:`WindowTime`}, the moves after the last cut), computed once."""
    return sp.memo("window_times", lambda: _window_times(sp, cfg))


def _window_times(sp, cfg):
    band = speed_band_per_window(sp, cfg)
    wrist = _wrist_ranges(sp)
    v_g = cfg.process.grinding_speed
    out, pending = {}, []
    for g in sp.segments:
        if g.kind != "cut":
            pending.append(_air_move(sp, cfg, g))
            continue
        w = int(g.window_index)
        edge, tool = _edge_and_tool_path(sp, g)
        cut_s = float(g.t_range[1] - g.t_range[0])
        if w in out:  # a partial window's next stretch: its cut and the moves before it added
            r = out[w]
            out[w] = replace(r, cut_s=r.cut_s + cut_s, tool_path_m=r.tool_path_m + tool,
                             cut_ratio=(r.cut_s + cut_s) / r.edge_seconds
                             if r.edge_seconds > 0 else np.inf,
                             air_before=(*r.air_before, *pending),
                             air_before_s=r.air_before_s + sum(m.duration_s for m in pending),
                             air_bound_s=r.air_bound_s + sum(m.bound_s for m in pending))
            pending = []
            continue
        edge_s = edge / v_g
        rng = wrist.get(w, np.full(3, np.nan))
        info = band.get(w, {})
        out[w] = WindowTime(
            window=w, cut_s=cut_s, edge_length_m=edge, tool_path_m=tool, feed_mps=v_g,
            edge_seconds=edge_s, cut_ratio=cut_s / edge_s if edge_s > 0 else np.inf,
            fraction_in_band=float(info.get("fraction_in_band", np.nan)),
            j4_range_rad=float(rng[0]), j5_range_rad=float(rng[1]), j6_range_rad=float(rng[2]),
            slow_stretches=tuple(info.get("slow_stretches", ())),
            air_before=tuple(pending), air_before_s=sum(m.duration_s for m in pending),
            air_bound_s=sum(m.bound_s for m in pending))
        pending = []
    return out, tuple(pending)


def time_budget(sp, cfg) -> CheckItem:
    """Where the cycle's time goes: per window (:class:`WindowTime`) its cut against the edge
    length over the feed, the moves before it against their joint-space bound, its wrist
    ranges and the limit binding on each slow stretch; key -1: the moves after the last cut.
    The value: the cycle over the sum of the cuts' edge time and the moves' bounds."""
    per, after = window_times(sp, cfg)
    cycle = float(sp.plan.trajectory.duration)
    cut_s = sum(r.cut_s for r in per.values())
    edge_s = sum(r.edge_seconds for r in per.values())
    air = [m for r in per.values() for m in r.air_before] + list(after)
    air_s = sum(m.duration_s for m in air)
    air_bound = sum(m.bound_s for m in air)
    prog = sum(m.programmed_s or 0.0 for m in air)
    bound = edge_s + air_bound
    ratio = cycle / bound if bound > 0 else None
    shown = {w: r.as_dict() for w, r in per.items()}
    if after:
        shown[-1] = {"air_after": [m.as_dict() for m in after],
                     "air_after_s": sum(m.duration_s for m in after),
                     "air_bound_s": sum(m.bound_s for m in after)}
    worst = max(per, key=lambda w: per[w].cut_ratio, default=None)
    return CheckItem(
        "time_budget", True, ratio, None, "ratio", "info", window=worst,
        detail=(f"cycle {cycle:.3f} s = cuts {cut_s:.3f} s (edge length / feed {edge_s:.3f} s)"
                f" + moves off the cut {air_s:.3f} s (least time of their joint displacement "
                f"at the joint limits {air_bound:.3f} s; at their programmed TCP speeds "
                f"{prog:.3f} s); value: cycle / ({edge_s:.3f} + {air_bound:.3f}) s"
                + ("" if worst is None else
                   f"; slowest cut: window {worst}, {per[worst].cut_ratio:.3f} x its edge "
                   "time")),
        per_window=shown)
