"""Checks of the plan's own consistency: structure, recorded failures, windows, FK, targets."""

from __future__ import annotations

import numpy as np

from drakedeburr.plan.program_reading import rot_angle
from drakedeburr.verify.report import CheckItem

__all__ = ["structure", "planner_failures", "failures_item", "windows", "fk_agreement",
           "target_consistency", "recipe_deviations", "uncut_edge", "partial_windows"]


def _structure_problems(plan) -> list[str]:
    traj, targets, segments = plan.trajectory, plan.targets, list(plan.segments)
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
    return problems


def structure(sp, cfg) -> CheckItem:
    problems = _structure_problems(sp.plan)
    return CheckItem(
        "structure", not problems, float(len(problems)), 0.0, "count", "<=",
        detail="; ".join(problems[:5]) or "segments tile the trajectory and the target list")


def _about_uncut(rec) -> bool:
    """A record of a partial window's uncut edge (its partial record, or a relaxation record
    of what else was tried to cut it: :func:`drakedeburr.plan.relax.on_uncut_edge`)."""
    where = rec.where or {}
    return "partial" in where or bool(where.get("uncut_edge"))


def failures_item(plan) -> CheckItem:
    """The planner's failure records: per window what failed, where, by how much and what was
    tried (``per_window``), the first of each window in the detail."""
    # the uncut rest of a partial window is its own item (uncut_edge), with what else was
    # tried to cut it (the relaxation's records marked "uncut_edge")
    f = [rec for rec in plan.failures if not _about_uncut(rec)]
    per: dict = {}
    for rec in f:
        entry = per.setdefault(rec.window, {"records": 0, "kinds": [], "first": str(rec),
                                            "reasons": {}, "tried": []})
        entry["records"] += 1
        if rec.kind not in entry["kinds"]:
            entry["kinds"].append(rec.kind)
            entry["reasons"][rec.kind] = str(rec)  # the first record of each kind
        if rec.value is not None:
            entry.setdefault("worst", {"value": rec.value, "limit": rec.limit, "unit": rec.unit})
        entry["tried"] += [t for t in rec.tried if t not in entry["tried"]]
    return CheckItem(
        "planner_failures", not f, float(len(f)), 0.0, "count", "<=",
        window=next(iter(per), None),
        detail=("; ".join(v["first"] for v in per.values())[:2000] if f
                else "the plan records no failed points"),
        per_window=per)


def planner_failures(sp, cfg) -> CheckItem:
    return failures_item(sp.plan)


def partial_windows(plan) -> dict:
    """Window -> its partial record (``plan.meta["windows"][i]["partial"]``, written by
    :mod:`drakedeburr.plan.partial`): the windows cut in open stretches, the rest uncut."""
    stats = (plan.meta or {}).get("windows")
    if not isinstance(stats, (list, tuple)):  # a plan recording no per-window figures
        return {}
    return {int(s["window"]): s["partial"] for s in stats
            if isinstance(s, dict) and s.get("partial")}


def _run_cl(run: dict, m: int) -> set:
    """CL indices of a recorded run ``{"cl": [first, last]}`` of a loop of ``m`` points."""
    first, last = run["cl"]
    return {(first + k) % m for k in range((last - first) % m + 1)}


def _missing_cl(sp) -> dict:
    out = {}
    partial = partial_windows(sp.plan)
    for w in sp.cut_windows:
        ref = sp.refs[w]
        if ref is None:
            out[w] = "neither a ToolPath nor ground-truth edge frames"
            continue
        have = {ref.cl_of[k] for k, t in enumerate(sp.targets)
                if t.window_index == w and t.segment in ("approach", "cut") and k in ref.cl_of}
        # a partial window: the CL points of its planned stretches (the rest: uncut_edge)
        want = (set().union(*(_run_cl(r, len(ref.p_HC)) for r in partial[w]["cut"]))
                if w in partial and ref.tool_path is not None else set(range(len(ref.p_HC))))
        lost = sorted(want - have)
        if lost:
            out[w] = f"CL points {lost[:5]}{'...' if len(lost) > 5 else ''} not targeted"
    return out


def windows(sp, cfg) -> CheckItem:
    expected, cut = sp.expected_windows, sp.cut_windows
    missing = [w for w in expected if w not in cut]
    cl_missing = _missing_cl(sp)
    unknown = [w for w in cut if w not in sp.edge_of]
    det = []
    if missing:
        det.append(f"window(s) {missing} of hub {sp.hub_model.name} have no cut")
    if cl_missing:
        det.append("; ".join(f"window {w}: {m}" for w, m in cl_missing.items()))
    if unknown:
        det.append(f"window(s) {unknown} not in the hub")
    return CheckItem(
        "windows", not (missing or cl_missing or unknown),
        float(len(missing) + len(cl_missing) + len(unknown)), 0.0, "count", "<=",
        window=(missing or list(cl_missing) or unknown or [None])[0],
        detail="; ".join(det) or f"all {len(expected)} windows cut, every CL point targeted",
        per_window={w: {"cut": w in cut} for w in expected})


def fk_agreement(sp, cfg) -> CheckItem:
    tol = cfg.tolerances
    d = sp.distances.fk_difference
    return CheckItem(
        "fk_agreement", d <= tol.fk_match, d, tol.fk_match, "m", "<=",
        detail="Drake plant vs analytic OPW: flange pose in world and tool pose in hub, max "
               f"element difference over {len(sp.samples)} samples")


def target_consistency(sp, cfg) -> CheckItem:
    tol, targets, kin = cfg.tolerances, sp.targets, sp.kin
    X_HT_t = sp.X_HT_targets
    pos_err = np.linalg.norm(X_HT_t[:, :3, 3] - np.array([t.X_HT[:3, 3] for t in targets]),
                             axis=1)
    rot_err = rot_angle(X_HT_t[:, :3, :3], np.array([t.X_HT[:3, :3] for t in targets]))
    X_WF_t = kin.X_WF(np.array([t.q for t in targets], float))
    wf_err = np.linalg.norm(X_WF_t[:, :3, 3] - np.array([t.X_WF[:3, 3] for t in targets]),
                            axis=1)
    # the trajectory reaches each segment's last target at the segment's end time
    reach_err = []
    for s in sp.segments:
        if s.target_range[1] - 1 < len(targets):
            Xe = kin.X_HT(sp.plan.trajectory.value(np.array([s.t_range[1]])))[0]
            reach_err.append(np.linalg.norm(Xe[:3, 3] - targets[s.target_range[1] - 1].X_HT[:3, 3]))
    worst = np.maximum(pos_err, wf_err)
    k_w = int(np.argmax(worst))
    val = float(max(worst.max(), max(reach_err, default=0.0)))
    ok = val <= tol.path_deviation and float(rot_err.max()) <= tol.orientation_match
    return CheckItem(
        "target_consistency", ok, val, tol.path_deviation, "m", "<=",
        window=int(targets[k_w].window_index), target_index=k_w,
        detail=f"FK(target.q) vs target.X_HT / X_WF and trajectory at segment ends; max "
               f"orientation error {np.degrees(rot_err.max()):.3g} deg")


def recipe_deviations(sp, cfg) -> CheckItem:
    """Where the plan departed from the part's recipe (the planner's automatic relaxation,
    :mod:`drakedeburr.plan.relax`) and where it placed the hub: shown, not judged."""
    meta = sp.plan.meta or {}
    devs = meta.get("recipe_deviations") or []
    place = meta.get("placement")
    parts = [f"{'all windows' if d['window'] < 0 else 'window ' + str(d['window'])}: "
             f"{d['item']} {d['default']} -> {d['used']} ({d['reason']})" for d in devs]
    if place:
        parts.append(f"hub placed turned {np.degrees(place['turn_rad']):.1f} deg, offset "
                     f"{1e3 * place['offset_m']:.0f} mm, seat {1e3 * place['seat_m']:.1f} mm "
                     f"on its mount (placement search)")
    return CheckItem(
        "recipe_deviations", True, float(len(devs)), None, "count", "info",
        detail="; ".join(parts) or "the plan follows the part's recipe",
        per_window={d["window"]: d for d in devs if d["window"] >= 0})


def uncut_edge(sp, cfg) -> CheckItem:
    """The edge the plan leaves uncut in its partial windows (:mod:`drakedeburr.plan.partial`):
    per window "cut N of M mm (x %)", the uncut stretches (CL range, mm) and the pre-check's
    reason; fails when any is left (the hub is not fully deburred), while every other item
    judges the motion that is planned."""
    partial = partial_windows(sp.plan)
    tried = {}
    for rec in sp.plan.failures:
        if (rec.where or {}).get("uncut_edge"):
            tried.setdefault(rec.window, []).append(rec.reason)
    per = {w: {"cut_mm": p["cut_mm"], "loop_mm": p["loop_mm"], "cut_share": p["cut_share"],
               "cut": p["cut"], "uncut": p["uncut"], "reason": p["reason"],
               "ik_missed": p.get("ik_missed", []), "also_tried": tried.get(w, [])}
           for w, p in partial.items()}
    uncut = sum(p["loop_mm"] - p["cut_mm"] for p in partial.values())
    lines = [f"window {w}: cut {p['cut_mm']:.1f} of {p['loop_mm']:.1f} mm "
             f"({100 * p['cut_share']:.0f} %); uncut "
             + ", ".join(f"CL {u['cl'][0]}..{u['cl'][1]} ({u['length_mm']:.1f} mm)"
                         for u in p["uncut"])
             + (f" ({len(p['ik_missed'])} CL point(s) the stretches' IK missed: "
                f"{p['ik_missed'][0]['reason']})" if p.get("ik_missed") else "")
             + f": {p['reason']}"
             for w, p in partial.items()]
    return CheckItem(
        "uncut_edge", not partial, 1e-3 * uncut, 0.0, "m", "<=",
        window=next(iter(partial), None),
        detail=("; ".join(lines)[:3000] if partial
                else "no window left partly uncut"), per_window=per)
