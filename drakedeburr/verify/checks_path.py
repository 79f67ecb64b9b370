"""Checks of the tool path: the trajectory vs the program, the contact vs the true edge, the
burr's engagement, the tool axis vs its cone and box, the CL points vs the edge."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from drakedeburr.frames.local_frames import angles_from_zT_H
from drakedeburr.verify.geometry import point_segment
from drakedeburr.verify.report import CheckItem

__all__ = ["path_deviation", "orientation_agreement", "program_zones", "edge_deviation",
           "edge_coverage", "burr_engagement", "cone", "theta_box", "theta_statistics",
           "cl_chord_error", "cl_chord_length"]


def _not_measurable(name: str, unit: str = "m", why: str = "") -> CheckItem:
    return CheckItem(name, False, None, None, unit, "<=",
                     detail=why or "not measurable: no cut with tool paths and CL indices")


def path_deviation(sp, cfg) -> CheckItem:
    tol, pr = cfg.tolerances, sp.program
    if not np.isfinite(pr.path_dev).any():
        return _not_measurable("path_deviation", why="no linear moves in the plan")
    i_w = int(np.nanargmax(pr.path_dev))
    worst = float(pr.path_dev[i_w])
    if pr.program_to_path > worst and pr.program_worst is not None:
        worst, i_w = pr.program_to_path, int(pr.program_worst)
    return CheckItem(
        "path_deviation", worst <= tol.path_deviation, worst, tol.path_deviation, "m", "<=",
        **sp.where(i_w),
        detail=f"tool point T vs the linear program, both ways (trajectory->program "
               f"{np.nanmax(pr.path_dev) * 1e3:.4f} mm, program->trajectory "
               f"{pr.program_to_path * 1e3:.4f} mm), "
               f"{int(np.isfinite(pr.path_dev).sum())} samples")


def orientation_agreement(sp, cfg) -> CheckItem:
    tol, dev = cfg.tolerances, sp.program.orient_dev
    if not np.isfinite(dev).any():
        return _not_measurable("orientation_agreement", "rad", "no linear moves in the plan")
    i_o = int(np.nanargmax(dev))
    return CheckItem(
        "orientation_agreement", float(dev[i_o]) <= tol.orientation_match, float(dev[i_o]),
        tol.orientation_match, "rad", "<=", **sp.where(i_o),
        detail="tool orientation of the trajectory vs the slerp of the program")


def program_zones(sp, cfg) -> CheckItem:
    """The trajectory passes each target of a linear move within its zone (a fine point within
    the path tolerance): the program's zones are the blends the plan simulated."""
    tol, targets, p = cfg.tolerances, sp.targets, sp.samples.p_HT
    move = sp.program.move
    worst, worst_k = -np.inf, None
    for k in np.unique(move[move >= 0]):
        idx = np.flatnonzero((move == k) | (move == k + 1))
        if len(idx) < 2:
            continue
        d = point_segment(targets[k].X_HT[:3, 3][None], p[idx[:-1]], p[idx[1:]])[0][0]
        excess = d - max(targets[k].zone, tol.path_deviation)
        if excess > worst:
            worst, worst_k = float(excess), int(k)
    if worst_k is None:
        return _not_measurable("program_zones", why="no linear moves in the plan")
    t = targets[worst_k]
    return CheckItem(
        "program_zones", worst <= 0.0, worst, 0.0, "m", "<=", window=int(t.window_index),
        target_index=worst_k,
        detail=f"distance of each target from the executed path less its zone (fine point: the "
               f"path tolerance); largest at target {worst_k} (zone {t.zone * 1e3:.3f} mm)")


def edge_deviation(sp, cfg) -> CheckItem:
    tol, d = cfg.tolerances, sp.cut.edge_dev
    if not np.isfinite(d).any():
        return _not_measurable("edge_deviation")
    i_e = int(np.nanargmax(d))
    return CheckItem(
        "edge_deviation", float(d[i_e]) <= tol.edge_deviation, float(d[i_e]),
        tol.edge_deviation, "m", "<=", **sp.where(i_e),
        detail="executed contact point (tool pose x the target's tool-to-CL offset, "
               "interpolated) vs the hub's ground-truth edge")


def edge_coverage(sp, cfg) -> CheckItem:
    tol, cov = cfg.tolerances, sp.cut.coverage
    if not cov or not np.isfinite(sp.cut.edge_dev).any():
        return _not_measurable("edge_coverage")
    wc = max(cov, key=lambda w: cov[w][0])
    return CheckItem(
        "edge_coverage", cov[wc][0] <= tol.edge_deviation, cov[wc][0], tol.edge_deviation,
        "m", "<=", window=int(wc),
        detail=f"farthest ground-truth edge point from the executed contact path (edge "
               f"point {cov[wc][1]} of window {wc})",
        per_window={w: {"max_gap_m": v[0]} for w, v in cov.items()})


def burr_engagement(sp, cfg) -> CheckItem:
    tol, engage = cfg.tolerances, sp.cut.engagement
    if not np.isfinite(engage).any():
        return _not_measurable("burr_engagement")
    depth = np.array([sp.depth_of_cut(w) if w in sp.cut_windows else 0.0
                      for w in sp.samples.window])
    hi_lim = depth + tol.edge_deviation
    margin = np.minimum(engage + tol.edge_deviation, hi_lim - engage)
    i_g = int(np.nanargmin(margin))
    inside = engage[i_g] >= 0
    return CheckItem(
        "burr_engagement", float(margin[i_g]) >= 0, float(engage[i_g]),
        float(hi_lim[i_g]) if inside else -tol.edge_deviation, "m", "<=" if inside else ">=",
        **sp.where(i_g),
        detail=f"edge point's depth inside the burr cone (normal to the flank) must lie in "
               f"[-{tol.edge_deviation * 1e3:.2f}, depth of cut + "
               f"{tol.edge_deviation * 1e3:.2f}] mm; range "
               f"[{np.nanmin(engage) * 1e3:.3f}, {np.nanmax(engage) * 1e3:.3f}] mm")


def _target_cones(sp) -> dict:
    from drakedeburr.verify.cut_geometry import target_cones

    return sp.memo("target_cones", lambda: target_cones(sp.plan, sp.X_HT_targets, sp.refs,
                                                        sp.cut_windows))


def _cone_figures(sp, tc: dict) -> dict:
    """Per window: the samples' cone figures and the program targets' (``target_*``)."""
    out = {w: dict(v) for w, v in sp.cut.cone_per_window.items()}
    for w, v in tc["per_window"].items():
        out.setdefault(w, {}).update(v)
    return out


def cone(sp, cfg) -> CheckItem:
    """The executed tool axis inside its cone on the dense samples AND the program's own
    targets' axes (FK of their joints) inside the cone of the CL point each cuts
    (:func:`drakedeburr.verify.cut_geometry.target_cones`); the item names the worse."""
    tol, c = cfg.tolerances, sp.cut
    tc = _target_cones(sp)
    tm = tc["margin"]
    dense, targets = np.isfinite(c.cone_margin).any(), np.isfinite(tm).any()
    if not dense and not targets:
        return _not_measurable("cone", "rad")
    m_s = float(np.nanmin(c.cone_margin)) if dense else np.inf
    m_t = float(np.nanmin(tm)) if targets else np.inf
    n_out = int(np.sum(tm[np.isfinite(tm)] < -tol.cone_slack))
    summary = (f"; program targets: {int(np.isfinite(tm).sum())} read, smallest margin "
               f"{m_t:.3e} rad, {n_out} outside" if targets else
               "; program targets: none anchored on a CL point")
    if m_t < m_s:
        k = int(np.nanargmin(tm))
        where = {"window": int(sp.targets[k].window_index), "target_index": k}
        head = (f"program target {k}'s own axis (FK of its joints) vs the cone of the CL "
                f"point it cuts: smallest margin (dense samples: {m_s:.3e} rad)")
    else:
        i_c = int(np.nanargmin(c.cone_margin))
        where = sp.where(i_c)
        head = (f"executed tool axis inside its admissible cone (the IK's cone standing for "
                f"the (theta_A, theta_B) box), smallest margin; there theta_A="
                f"{c.theta_A[i_c]:.4f}, theta_B={c.theta_B[i_c]:.4f} rad")
    worst = min(m_s, m_t)
    return CheckItem("cone", worst >= -tol.cone_slack, worst, -tol.cone_slack, "rad", ">=",
                     **where, detail=head + summary, per_window=_cone_figures(sp, tc))


def theta_box(sp, cfg) -> CheckItem:
    tol, box = cfg.tolerances, sp.cut.box_margin
    limit = cfg.acceptance.theta_box_share
    if not np.isfinite(box).any():
        return CheckItem("theta_box", limit is None, None, limit, "-", ">=",
                         detail="not measurable: no cut with tool paths and CL indices")
    inside = np.isfinite(box)
    share = float(np.mean(box[inside] >= -tol.cone_slack))
    i_b = int(np.nanargmin(box))
    return CheckItem(
        "theta_box", limit is None or share >= limit, share, limit, "-", ">=", **sp.where(i_b),
        detail=f"share of cut samples whose axis keeps both angles inside the source's "
               f"(theta_A, theta_B) box (the cone is its smallest enclosing cone, so its "
               f"rim admits more); smallest margin {box[i_b]:.4f} rad")


def _describe(v: np.ndarray) -> dict:
    m = float(np.mean(v))
    return {"max": float(v.max()), "min": float(v.min()), "mean": m,
            "variance": float(np.var(v)), "cv": float(np.std(v) / abs(m)) if m else None}


def theta_statistics(sp, cfg) -> CheckItem:
    """theta statistics at the targets (Tab. 3-6 style), from the executed poses."""
    stats = {}
    for w in sp.cut_windows:
        ref = sp.refs[w]
        if ref is None:
            continue
        ks = [k for k, t in enumerate(sp.targets) if t.window_index == w and t.segment == "cut"
              and k in ref.cl_of]
        if not ks:
            continue
        cl = np.array([ref.cl_of[k] for k in ks])
        tA, tB = angles_from_zT_H(ref.R_HL[cl], sp.X_HT_targets[ks, :3, 2])
        tp = ref.tool_path
        diff = None
        if tp is not None:
            diff = max(float(np.abs(tA - np.asarray(tp.theta_A)[cl]).max()),
                       float(np.abs(tB - np.asarray(tp.theta_B)[cl]).max()))
        stats[w] = {"theta_A": _describe(tA), "theta_B": _describe(tB),
                    "max_diff_from_tool_path_rad": diff, "reference": ref.source}
    return CheckItem(
        "theta_statistics", True, None, None, "rad", "info",
        detail="theta_A/theta_B of the executed axis at the CL targets (source Tab. 3-6)",
        per_window=stats)


def _chord_heights(p: np.ndarray, edge: np.ndarray) -> list[float]:
    """Largest distance of the true edge from each chord between consecutive CL points."""
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
        a, b = p[i], p[(i + 1) % len(p)]
        ab = b - a
        L = max(np.linalg.norm(ab), 1e-300)
        dv = pts - a
        heights.append(float(np.linalg.norm(dv - np.outer(dv @ ab / L, ab / L), axis=1).max()))
    return heights


def _cl_stats(sp) -> dict:
    def compute():
        out = {}
        for w in sp.cut_windows:
            ref = sp.refs[w]
            if ref is None or w not in sp.edge_of:
                continue
            p = ref.p_HC
            chords = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
            heights = _chord_heights(p, np.asarray(sp.edge_of[w].p_HE, float))
            mu = chords.mean()
            out[w] = {"count": len(p), "cv": float(chords.std() / mu) if mu > 0 else None,
                      "max_chord_height_m": max(heights),
                      "max_chord_length_m": float(chords.max())}
        return out

    return sp.memo("cl_stats", compute)


_NO_CL = "not measurable: no window has CL targets in the plan"


def cl_chord_error(sp, cfg) -> CheckItem:
    stats = _cl_stats(sp)
    worst_w = max(stats, key=lambda w: stats[w]["max_chord_height_m"], default=None)
    worst = stats[worst_w]["max_chord_height_m"] if worst_w is not None else None
    inferred = not all(r is None or r.tool_path is not None for r in sp.refs.values())
    return CheckItem(
        "cl_chord_error", bool(stats) and worst <= cfg.process.delta_max, worst,
        cfg.process.delta_max, "m", "<=", window=worst_w,
        detail=("largest distance of the true edge from a chord between consecutive CL points"
                + (" (CL points inferred from the targets: the plan carries no ToolPath)"
                   if inferred else "")) if stats else _NO_CL,
        per_window=stats)


def cl_chord_length(sp, cfg) -> CheckItem:
    stats = _cl_stats(sp)
    worst_w = max(stats, key=lambda w: stats[w]["max_chord_length_m"], default=None)
    worst = stats[worst_w]["max_chord_length_m"] if worst_w is not None else None
    return CheckItem(
        "cl_chord_length", bool(stats) and worst <= cfg.process.l_max + 1e-12, worst,
        cfg.process.l_max, "m", "<=", window=worst_w,
        detail="longest chord between CL points" if stats else _NO_CL)
