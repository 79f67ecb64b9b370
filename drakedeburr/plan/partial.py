"""Partial windows: the clear runs of a closed window loop the tool pre-check could not clear
whole (:func:`drakedeburr.plan.window.tool_refusal` proves some CL points blocked).

A run is a maximal stretch of consecutive CL points (around the loop: a run may cross the
loop's start, index M-1 -> 0) that stays at least ``margin`` of edge length from every proven
blocked point, and is at least ``min_length`` of edge long. The margin and the minimum are
the burr's own footprint (:func:`clear_runs_margin`): within one burr radius of a blocked
point the burr's cutting circle overlaps the blocked point's, so the same shank/collet sits
over the same material (likely blocked too) and the tool must enter and leave the cut there;
a run shorter than the burr's diameter is a plunge, not a pass along the edge.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from drakedeburr.plan.options import PlanContext, RunMode
from drakedeburr.plan.results import Stretch, WindowPlan, WindowStats, WindowStatus
from drakedeburr.plan.stretch import joint_stretch
from drakedeburr.plan.targets import contact_geometry
from drakedeburr.plan.types import FailureRecord

__all__ = ["Run", "clear_runs", "uncut_runs", "subset", "plan_partial", "run_limits"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Run:
    """A run of CL points of a closed loop: ``indices`` (in loop order, may wrap past M-1 -> 0)
    and its edge length [m] (for a cut run: along its points; for an uncut one: the loop from
    the last cut point before it to the first cut point after it)."""

    indices: tuple
    length_m: float

    @property
    def first(self) -> int:
        return int(self.indices[0])

    @property
    def last(self) -> int:
        return int(self.indices[-1])

    def record(self) -> dict:
        return {"cl": [self.first, self.last], "cl_points": len(self.indices),
                "length_mm": round(1e3 * self.length_m, 2)}


def _segments(p: np.ndarray) -> np.ndarray:
    """(M,) closed-loop segment lengths: segment i runs from point i to point i+1 (mod M)."""
    return np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)


def _circular_runs(mask: np.ndarray) -> list[list[int]]:
    """Maximal runs of True in a circular mask (a run across M-1 -> 0 is one run)."""
    m = len(mask)
    if mask.all():
        return [list(range(m))]
    start = int(np.flatnonzero(~mask)[0])
    runs, cur = [], []
    for k in range(1, m + 1):
        i = (start + k) % m
        if mask[i]:
            cur.append(i)
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    return runs


def clear_runs(p_HC: np.ndarray, blocked, margin: float, min_length: float) -> list[Run]:
    """The clear runs of the closed loop ``p_HC`` (M, 3) [m] with CL points ``blocked``
    proven blocked: every point at least ``margin`` of loop arc length from each blocked
    point, runs of ``min_length`` [m] of edge or longer and of 3 CL points or more (module
    docstring). Empty when nothing is blocked is not asked (the whole loop is one run)."""
    p = np.asarray(p_HC, float)
    m = len(p)
    seg = _segments(p)
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    total = float(seg.sum())
    b = np.asarray(sorted(set(int(i) for i in blocked)), int)
    if not b.size:
        return [Run(tuple(range(m)), total)]
    d = np.abs(s[:, None] - s[b][None, :])
    d = np.minimum(d, total - d).min(axis=1)
    runs = []
    for idx in _circular_runs(d >= margin):
        length = float(sum(seg[i] for i in idx[:-1]))
        if len(idx) >= 3 and length >= min_length:
            runs.append(Run(tuple(idx), length))
    return runs


def uncut_runs(p_HC: np.ndarray, cut: list[Run]) -> list[Run]:
    """The stretches of the closed loop between the cut runs ``cut`` (their CL points are
    the ones not cut; the length is the loop from the last cut point before to the first cut
    point after), so cut and uncut lengths add up to the loop's."""
    p = np.asarray(p_HC, float)
    m = len(p)
    seg = _segments(p)
    if not cut:
        return [Run(tuple(range(m)), float(seg.sum()))]
    mask = np.zeros(m, bool)
    for r in cut:
        mask[list(r.indices)] = True
    out = []
    for idx in _circular_runs(~mask):
        before = (idx[0] - 1) % m
        length = float(seg[before] + sum(seg[i] for i in idx))
        out.append(Run(tuple(idx), length))
    # two cut runs that touch (never here: a margin lies between them) leave no uncut run
    return out


def subset(wt, indices) -> object:
    """The open stretch of ``wt``'s CL points ``indices`` (in that order; may wrap around the
    loop start): :meth:`~drakedeburr.plan.window_targets.WindowTargets.points`."""
    return wt.points(indices)


def run_limits() -> tuple[float, float]:
    """(margin, min_length) [m] of :func:`clear_runs` for a partial window: the burr's
    nominal contact radius and its diameter (module docstring; the burr's own footprint, not
    a property of any hub)."""
    r_burr, _ = contact_geometry(None)
    return float(r_burr), float(2.0 * r_burr)


def _global_targets(targets: list, idx: np.ndarray) -> list:
    """A stretch's program targets with their CL indices into the whole window's loop."""
    return [replace(t, cl_index=int(idx[t.cl_index])) if t.cl_index >= 0 else t
            for t in targets]


def _merged_stats(parts: list, loop: dict) -> WindowStats:
    """One window's figures from its planned stretches' (``parts``: (indices, WindowPlan)):
    counts, lengths and times added, ranges the widest, clearance the least, the in-band share
    weighted by cut time; ``loop``: the partial record (:attr:`WindowStats.partial`)."""
    st = [p.stats for _, p in parts]
    cut_s = sum(s.cut_seconds for s in st)
    ik = dict(st[0].ik)
    ik["stretches"] = [s.ik for s in st]
    return replace(
        st[0], cl_points=sum(s.cl_points for s in st), reached=sum(s.reached for s in st),
        edge_length_m=sum(s.edge_length_m for s in st),
        tool_travel_m=sum(s.tool_travel_m for s in st),
        dense_samples=sum(s.dense_samples for s in st), cut_seconds=cut_s,
        j4_range_deg=max(s.j4_range_deg for s in st), j5_range_deg=max(s.j5_range_deg for s in st),
        j6_range_deg=max(s.j6_range_deg for s in st),
        min_abs_j5_deg=min(s.min_abs_j5_deg for s in st),
        min_clearance_m=min(s.min_clearance_m for s in st),
        axis_in_theta_box_fraction=None,
        speed_in_band_fraction=(sum(s.speed_in_band_fraction * s.cut_seconds for s in st)
                                / max(cut_s, 1e-12)),
        ik=ik, joint_fit_deviation_m=max(s.joint_fit_deviation_m for s in st),
        orientation_smoothing_rad=max(s.orientation_smoothing_rad for s in st),
        via_targets=sum(s.via_targets for s in st),
        least_axis_acceleration_radps2=min(s.least_axis_acceleration_radps2 for s in st),
        q_ik_rad=[q for s in st for q in s.q_ik_rad],
        q_smoothed_rad=[q for s in st for q in s.q_smoothed_rad],
        cl_order=[int(idx[c]) for (idx, _), s in zip(parts, st, strict=True) for c in s.cl_order],
        speed_in_band_bound=None, fillets=[f for s in st for f in s.fillets],
        chamfer_relief=next((s.chamfer_relief for s in st if s.chamfer_relief), None),
        partial=loop)


#: how many times a window's clear runs are split again at the CL points their stretches'
#: IK missed (each round plans only the runs it has not planned before): a bound on the
#: planning a partial window costs, at most 1 + RESPLIT_ROUNDS passes over its runs
RESPLIT_ROUNDS = 2


def _ik_misses(res: WindowPlan, idx) -> dict:
    """{CL index of the whole loop: its record} of the CL points a stretch (``idx``: its CL
    points) did not cut cleanly: the targets its IK missed, and those its executed cut passes
    under the clearance (:func:`_clearance_misses`)."""
    out = _clearance_misses(res, idx)
    out.update({int(idx[f.point]): f for f in res.failures
                if f.kind == "ik" and 0 <= f.point < len(idx)})
    return out


def _clearance_misses(res: WindowPlan, idx) -> dict:
    """{CL index of the whole loop: its record} of the CL targets around each stretch of a
    planned stretch's executed cut under the clearance (records of kind "dense" with
    ``s_range_mm``: tool travel from the cut's start, the approach's last target): the CL
    targets on that travel and the nearest one before and after it on the program."""
    recs = [f for f in res.failures if f.kind == "dense" and "s_range_mm" in (f.where or {})]
    app = next((st for st in res.stretches if st.kind == "approach"), None)
    cut = next((st for st in res.stretches if st.kind == "cut"), None)
    if not recs or app is None or cut is None:
        return {}
    tg = [app.targets[-1], *cut.targets]
    p = np.array([t.X_HT[:3, 3] for t in tg])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    cl = np.array([t.cl_index for t in tg])
    out = {}
    for f in recs:
        a, b = 1e-3 * np.asarray(f.where["s_range_mm"], float)
        k0 = max(int(np.searchsorted(s, a, side="right")) - 1, 0)
        k1 = min(int(np.searchsorted(s, b, side="left")), len(tg) - 1)
        while k0 > 0 and cl[k0] < 0:
            k0 -= 1
        while k1 < len(tg) - 1 and cl[k1] < 0:
            k1 += 1
        out.update({int(idx[cl[k]]): f for k in range(k0, k1 + 1) if 0 <= cl[k] < len(idx)})
    return out


def _why_uncut(run: Run, blocked: set, misses: dict, refused: list, reason: str) -> list[str]:
    """Why the CL points of an uncut ``run`` are not cut: the proven blocked ones (the
    pre-check's ``reason``), those the IK missed (its reason), the stretches inside it that
    did not plan (``refused``: (Run, WindowPlan)); the rest lie within the margin of these."""
    cl = set(run.indices)
    out = []
    n = len(cl & blocked)
    if n:
        out.append(f"{n} CL point(s) proven blocked: {reason}")
    for i in sorted(set(misses) & cl, key=run.indices.index):
        what = "IK missed" if misses[i].kind == "ik" else "executed cut under the clearance at"
        out.append(f"{what} CL {i}: {misses[i].reason}")
    for r, res in refused:
        if set(r.indices) <= cl:
            first = next((str(f) for f in res.failures), "no record")
            out.append(f"stretch CL {r.first}..{r.last} {res.status.value}: {first}")
    return out


def _uncut_record(wt, refusal: FailureRecord, loop: dict) -> FailureRecord:
    """The window's record of the edge it leaves uncut (kind "window", as a refusal)."""
    left = "; ".join(f"CL {u['cl'][0]}..{u['cl'][1]} ({u['length_mm']:.1f} mm)"
                     for u in loop["uncut"])
    missed = len(loop["ik_missed"])
    reason = (f"cut {loop['cut_mm']:.1f} of {loop['loop_mm']:.1f} mm of edge "
              f"({100 * loop['cut_share']:.0f} %) in {len(loop['cut'])} stretch(es); left "
              f"uncut: {left}"
              + (f" ({missed} CL point(s) the stretches' IK missed or cut under the clearance)"
                 if missed else "")
              + f": {refusal.reason}")
    return replace(refusal, reason=reason, where={**refusal.where, "partial": loop},
                   tried=(*refusal.tried, "the clear runs planned as open stretches, "
                          f"{1e3 * loop['margin_m']:.1f} mm of edge kept from each proven "
                          f"point, none shorter than {1e3 * loop['min_length_m']:.1f} mm",
                          f"split again at the points their IK missed or cut under the clearance "
                          f"({loop['rounds']} of "
                          f"at most {RESPLIT_ROUNDS} rounds)"))


def _plan_runs(ctx: PlanContext, wt, blocked: list, mode: RunMode, plan_whole):
    """The clear runs of ``wt`` planned as open stretches, split again (at most
    :data:`RESPLIT_ROUNDS` times) at the CL points their IK missed, each such point then kept
    the margin off as a blocked one is. Returns (the last runs, {run indices: its plan}, the
    missed points {CL: record}, rounds used), or the plan of a stretch abandoned (the
    fail-fast pass: relaxation next)."""
    margin, min_len = run_limits()
    misses: dict = {}
    done: dict = {}
    rounds = 0
    while True:
        runs = clear_runs(wt.p_HC, [*blocked, *misses], margin, min_len)
        found = {}
        for run in runs:
            if run.indices not in done:
                res = plan_whole(ctx, subset(wt, run.indices), mode)
                if res.status is WindowStatus.ABANDONED:
                    return res
                done[run.indices] = res
            found.update(_ik_misses(done[run.indices], run.indices))
        if not found or rounds == RESPLIT_ROUNDS:
            misses.update(found)
            return runs, done, misses, rounds
        log.info("window %d: the stretches' IK missed or cut under the clearance %d CL "
                 "point(s); splitting the runs "
                 "there (round %d of %d)", wt.window_index, len(found), rounds + 1,
                 RESPLIT_ROUNDS)
        misses.update(found)
        rounds += 1


def plan_partial(ctx: PlanContext, wt, refusal: FailureRecord, mode: RunMode,
                 plan_whole) -> WindowPlan:
    """The clear runs of a window the pre-check refused (``refusal``, its
    ``where["blocked_points"]``), each planned as an open stretch by ``plan_whole`` (the
    window pipeline, every check of a whole window) and split again where its IK misses CL
    points (:func:`_plan_runs`), joined by checked joint moves in loop order; the rest recorded
    as uncut, with why (one failure record, the window's :attr:`WindowStats.partial`). What is
    planned is complete: a stretch whose IK still misses points after the last round, or that
    does not plan, is uncut too (its records in the uncut record); none planned: the window is
    refused with the record."""
    margin, min_len = run_limits()
    blocked = [int(i) for i in refusal.where["blocked_points"]]
    out = _plan_runs(ctx, wt, blocked, mode, plan_whole)
    if isinstance(out, WindowPlan):  # relaxation next (policy): as a whole window
        return WindowPlan.skipped(wt.window_index, out.status, [refusal, *out.failures])
    runs, done, misses, rounds = out
    parts, refused, failures = [], [], []
    for run in runs:
        res = done[run.indices]
        if res.status.planned and not _ik_misses(res, run.indices):
            parts.append((np.asarray(run.indices, int), res, run))
            failures += res.failures
        else:
            refused.append((run, res))
    cut = [run for _, _, run in parts]
    loop_m = float(_segments(wt.p_HC).sum())
    cut_m = sum(r.length_m for r in cut)
    uncut = [{**r.record(), "why": _why_uncut(r, set(blocked), misses, refused, refusal.reason)}
             for r in uncut_runs(wt.p_HC, cut)]
    loop = {"loop_mm": round(1e3 * loop_m, 2), "cut_mm": round(1e3 * cut_m, 2),
            "cut_share": cut_m / loop_m, "cut": [r.record() for r in cut], "uncut": uncut,
            "clear_runs": [r.record() for r in runs], "margin_m": margin,
            "min_length_m": min_len, "reason": refusal.reason, "rounds": rounds,
            "ik_missed": [{"cl": i, "kind": f.kind, "reason": f.reason}
                          for i, f in sorted(misses.items())],
            "stretches_planned": len(done)}
    record = _uncut_record(wt, refusal, loop)
    log.info("window %d: %s", wt.window_index, record.reason)
    if not parts:
        return WindowPlan.skipped(wt.window_index, WindowStatus.IK_FAILED, [record])
    return _joined(ctx, wt, parts, [record, *failures], loop)


def _joined(ctx: PlanContext, wt, parts: list, failures: list, loop: dict) -> WindowPlan:
    """The planned stretches ``parts`` ((indices, WindowPlan, Run), loop order) joined by
    checked joint moves into one window's plan, their targets' CL indices the whole loop's."""
    failures = list(failures)
    stretches = list(parts[0][1].stretches)
    for (_, a, _), (_, b, run) in zip(parts[:-1], parts[1:], strict=True):
        js, _mv, recs = joint_stretch(ctx, a.stretches[-1].timed.q[-1], b.q_start,
                                      ctx.config.process.window_switch_speed, "transition",
                                      f"window {wt.window_index} to CL {run.first}",
                                      wt.window_index)
        failures += recs
        stretches += [js, *b.stretches]
    idx_all = {id(st): idx for idx, p, _ in parts for st in p.stretches}
    stretches = [Stretch(st.kind, st.window_index, st.timed,
                         _global_targets(st.targets, idx_all[id(st)]))
                 if id(st) in idx_all else st for st in stretches]
    seconds = {k: sum(p.seconds.get(k) or 0.0 for _, p, _ in parts)
               for k in parts[0][1].seconds if k != "window"}
    return WindowPlan(window=wt.window_index, status=WindowStatus.DEGRADED, stretches=stretches,
                      stats=_merged_stats([(i, p) for i, p, _ in parts], loop),
                      q_start=parts[0][1].q_start, failures=failures,
                      seconds={"window": wt.window_index, **seconds})
