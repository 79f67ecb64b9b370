"""Partial windows (plan.partial, plan.window.plan_window; issue 42): the clear runs of a window
the tool pre-check refuses are planned as open stretches, the rest recorded as uncut.

The splitting is checked on its own (runs, margins, wrap-around, lengths adding up). The
planned stretches are checked on a bundled hub with the pre-check's answer replaced (the
splitting alone is under test there; the stretches go through the real IK, cut and checks):
FK of the executed cut stays on the stretch's CL points within the path tolerance, and no
executed pose cuts near a blocked point.
"""

from __future__ import annotations

import numpy as np
import pytest

import drakedeburr.plan.partial as mut
from drakedeburr.config import Tolerances, load_config
from drakedeburr.plan.types import FailureRecord
from drakedeburr.resources import hub_names

TOL = Tolerances()


def _circle(m: int = 100, radius: float = 0.05) -> np.ndarray:
    a = 2 * np.pi * np.arange(m) / m
    return np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(m)], axis=1)


def _arc(p, i, j) -> float:
    """Loop arc length between CL points i and j (the shorter way)."""
    seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    d = abs(s[i] - s[j])
    return min(d, seg.sum() - d)


def test_clear_runs_keep_the_margin_and_wrap_the_loop_start():
    p = _circle()  # 100 points, 3.14 mm apart
    blocked = [40, 41, 42, 70]
    margin, min_len = 5e-3, 8e-3
    runs = mut.clear_runs(p, blocked, margin, min_len)
    assert len(runs) == 2
    for r in runs:  # every point at least the margin from every blocked point (own reading)
        assert min(_arc(p, i, b) for i in r.indices for b in blocked) >= margin - 1e-12
        assert all((b - a) % 100 == 1 for a, b in zip(r.indices[:-1], r.indices[1:], strict=True))
        assert r.length_m >= min_len
    wrap = next(r for r in runs if 0 in r.indices)
    assert wrap.first > wrap.last and 99 in wrap.indices  # one run across M-1 -> 0
    # the points next to the margin are kept: the runs are maximal
    kept = {i for r in runs for i in r.indices}
    for i in set(range(100)) - kept:
        assert min(_arc(p, i, b) for b in blocked) < margin
    uncut = mut.uncut_runs(p, runs)
    loop = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1).sum()
    assert sum(r.length_m for r in runs) + sum(r.length_m for r in uncut) == pytest.approx(loop)
    assert all(set(blocked) & set(r.indices) for r in uncut)


def test_short_runs_are_dropped():
    p = _circle()
    # points 3.14 mm apart, margin 2.5 spacings: CL 13..17 are clear between the two blocks,
    # 12.6 mm of edge, shorter than the 15 mm asked
    runs = mut.clear_runs(p, [10, 20], 2 * np.pi * 0.05 / 100 * 2.5, 15e-3)
    assert all(20 not in r.indices and 15 not in r.indices for r in runs)
    assert len(runs) == 1 and 50 in runs[0].indices


def test_the_margin_is_the_burrs_footprint():
    from drakedeburr.plan.targets import contact_geometry

    margin, min_len = mut.run_limits()
    assert margin == pytest.approx(contact_geometry(None)[0])
    assert min_len == pytest.approx(2 * margin)


def _circle_targets(m: int, window: int):
    """WindowTargets of a flat circular loop of ``m`` CL points (tangents along it, normals
    to the centre, the tool axis +z)."""
    from drakedeburr.plan.window_targets import WindowTargets

    p = _circle(m)
    t = np.roll(p, -1, axis=0) - p
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = -p / np.linalg.norm(p, axis=1, keepdims=True)
    z = np.tile([0.0, 0.0, 1.0], (m, 1))
    return WindowTargets(window_index=window, kind="large", p_HC=p, t_H=t, n_H=n, retract_H=z,
                         cone_retract_H=z, cone_half_angle=0.1, depth_of_cut=1e-4)


def test_subset_rolls_the_targets_across_the_start():
    wt = _circle_targets(20, 3)
    p = wt.p_HC
    sub = mut.subset(wt, [18, 19, 0, 1, 2])
    assert not sub.closed and len(sub) == 5
    np.testing.assert_array_equal(sub.p_HC, p[[18, 19, 0, 1, 2]])
    assert "CL 18..2" in sub.source


@pytest.fixture(scope="module")
def partial_plan():
    """Window 0 of the default hub (the chain's ToolPath targets, tool in hand), the
    pre-check's answer replaced by blocked CL points at two places of the loop: one clear run
    crosses the loop start."""
    if not hub_names():
        pytest.skip("no bundled hub models")
    import drakedeburr.plan.window as window
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan.planner import plan_windows, window_targets_for_hub

    cell = load_cell("tool_in_hand", DEFAULT_HUB)
    wt = window_targets_for_hub(load_hub(DEFAULT_HUB), source="toolpath", windows=[0])[0]
    m = len(wt)
    blocked = [m // 3 + k for k in range(-2, 3)] + [(2 * m) // 3 + k for k in range(-2, 3)]

    def fake(ctx, w):
        return FailureRecord(window=w.window_index, kind="window", point=blocked[2],
                             value=-0.01, limit=ctx.min_clearance, unit="m",
                             reason="test: the spindle body in the part",
                             where={"blocked_points": blocked}, tried=("test",))

    mp = pytest.MonkeyPatch()
    mp.setattr(window, "tool_refusal", fake)
    try:
        plan = plan_windows(cell, [wt], load_config("tool_in_hand", DEFAULT_HUB))
    finally:
        mp.undo()
    return cell, wt, blocked, plan


def test_the_clear_runs_are_planned_and_recorded(partial_plan):
    _, wt, blocked, plan = partial_plan
    cuts = [s for s in plan.segments if s.kind == "cut"]
    assert len(cuts) == 2
    rec = [f for f in plan.failures if f.window == wt.window_index and f.kind == "window"]
    assert len(rec) == 1
    loop = rec[0].where["partial"]
    assert plan.meta["windows"][0]["partial"]["cut_share"] == pytest.approx(loop["cut_share"])
    assert 0.3 < loop["cut_share"] < 1.0 and len(loop["cut"]) == 2 and len(loop["uncut"]) == 2
    assert "left uncut: CL" in rec[0].reason and "test: the spindle body" in rec[0].reason
    assert any(c["cl"][0] > c["cl"][1] for c in loop["cut"])  # the run across the loop start
    total = loop["cut_mm"] + sum(u["length_mm"] for u in loop["uncut"])
    assert total == pytest.approx(loop["loop_mm"], abs=0.05)
    cl = {t.cl_index for t in plan.targets if t.segment == "cut" and t.cl_index >= 0}
    assert not cl & set(blocked)
    margin, _ = mut.run_limits()
    assert all(_arc(wt.p_HC, i, b) >= margin for i in cl for b in blocked)


def test_fk_of_the_executed_cut_stays_on_the_stretches(partial_plan):
    """Drake's FK of the trajectory on each cut segment: the tool point within the path
    tolerance of the commanded targets' polyline, and the edge point it cuts never within the
    margin of a blocked CL point."""
    from drakedeburr.plan.targets import edge_point_from_tool_pose

    cell, wt, blocked, plan = partial_plan
    margin, _ = mut.run_limits()
    for seg in (s for s in plan.segments if s.kind == "cut"):
        tg = plan.targets[seg.target_range[0] - 1:seg.target_range[1]]
        poly = np.array([t.X_HT[:3, 3] for t in tg])
        tt = np.linspace(*seg.t_range, 400)
        X = np.array([cell.X_HT(q).GetAsMatrix4() for q in plan.trajectory.value(tt)])
        p = X[:, :3, 3]
        a, b = poly[:-1], poly[1:]
        ab = b - a
        f = np.clip(np.einsum("kj,nkj->nk", ab, p[:, None] - a[None]) / np.sum(ab * ab, 1), 0, 1)
        d = np.linalg.norm(p[:, None] - (a[None] + f[:, :, None] * ab[None]), axis=2).min(axis=1)
        assert d.max() <= TOL.path_deviation
        cl = np.array([t.cl_index for t in tg if t.cl_index >= 0])
        k = np.argmin(np.linalg.norm(p[:, None] - wt.p_HC[cl][None], axis=2), axis=1)
        e = edge_point_from_tool_pose(X, wt.n_H[cl][k], wt.depth_of_cut,
                                      plan.meta["contact_radius_m"], plan.meta["contact_lift_m"])
        near = np.linalg.norm(e[:, None] - wt.p_HC[blocked][None], axis=2).min()
        assert near >= margin - TOL.edge_deviation - 1e-3  # chordal distance <= arc


def test_partial_windows_off_restores_the_refusal(partial_plan, monkeypatch):
    import drakedeburr.plan.window as window
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.results import WindowStatus

    _, wt, blocked, _ = partial_plan
    rec = FailureRecord(window=wt.window_index, kind="window", reason="test",
                        where={"blocked_points": blocked})
    monkeypatch.setattr(window, "tool_refusal", lambda ctx, w: rec)
    ctx = PlanContext(cell=None, kin=None, checker=object(), free_checker=None, config=None,
                      options=PlanOptions(partial_windows=False))
    res = window.plan_window(ctx, wt)
    assert res.status is WindowStatus.IK_FAILED and res.failures == [rec]


@pytest.fixture(scope="module")
def partial_report(partial_plan):
    """The verifier's report of the partial plan."""
    from drakedeburr.hub import DEFAULT_HUB
    from drakedeburr.verify import verify_plan

    cell, _, _, plan = partial_plan
    return verify_plan(plan, load_config("tool_in_hand", DEFAULT_HUB), expected_windows=[0],
                       cell=cell)


def test_each_stretch_is_read_at_the_feed_on_its_own(partial_plan, partial_report):
    """The speed band of a partial window (verify.checks_process): each planned stretch starts
    and stops its cut at rest, so each has its own slow start and slow end, read along its own
    travel (FK of the trajectory); none spans two stretches (the moves off the edge between
    them are not cut); the limit binding there is in use, so slowdowns_justified passes; the
    time budget adds the stretches' cut times."""
    cell, wt, _, plan = partial_plan
    cuts = [g for g in plan.segments if g.kind == "cut"]
    travel = []
    for g in cuts:
        p = np.array([cell.X_HT(q).GetAsMatrix4()[:3, 3]
                      for q in plan.trajectory.value(np.linspace(*g.t_range, 2000))])
        travel.append(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()))
    ends = np.concatenate([[0.0], np.cumsum(travel)])
    band = partial_report.item("tcp_speed_band").per_window[wt.window_index]
    slow = band["slow_stretches"]
    for k in range(len(cuts)):
        mine = [st for st in slow if st["stretch"] == k]
        assert [st["at"] for st in mine][0] == "start" and mine[-1]["at"] == "end"
        assert sum(st["at"] != "inside" for st in mine) == 2
        assert mine[0]["from_m"] == pytest.approx(ends[k], abs=1e-3)
        assert mine[-1]["to_m"] == pytest.approx(ends[k + 1], abs=1e-3)
        for st in mine:
            assert ends[k] - 1e-3 <= st["from_m"] <= st["to_m"] <= ends[k + 1] + 1e-3
            assert st["from_m"] <= st["least_at_m"] <= st["to_m"]
    item = partial_report.item("slowdowns_justified")
    assert item.passed and item.value >= Tolerances().forced_slowdown
    budget = partial_report.item("time_budget").per_window[wt.window_index]
    assert budget["cut_s"] == pytest.approx(sum(g.t_range[1] - g.t_range[0] for g in cuts))


def test_verdict_and_partial_export(partial_plan, partial_report, tmp_path, monkeypatch):
    """The report of the partial plan fails on uncut_edge (cut N of M mm per window, the
    uncut stretches and why) while the geometric checks of the motion planned pass (edge
    coverage of the stretches, edge, path, cone, clearance, windows' CL points, slowdowns);
    export refuses it; ``--partial`` writes only a plan failing on uncut_edge alone, with a
    PARTIAL header naming the uncut stretches."""
    import json

    import drakedeburr.verify.gate as gate_mod
    from drakedeburr.cli import main
    from drakedeburr.plan.io import save_plan
    from drakedeburr.verify.html import write_report_files

    _, wt, _, plan = partial_plan
    folder = save_plan(plan, tmp_path / "plan")
    rep = partial_report
    assert not rep.passed
    write_report_files(rep, folder, plan=plan, replay=False)
    report = json.loads((folder / "report.json").read_text())
    items = {i["name"]: i for i in report["items"]}
    assert "uncut_edge" in report["summary"]["failed"]
    for name in ("planner_failures", "windows", "edge_coverage", "edge_deviation",
                 "path_deviation", "cone", "clearance", "clearance_certificate", "structure",
                 "fk_agreement", "target_consistency", "burr_engagement",
                 "slowdowns_justified"):
        assert items[name]["passed"] and items[name]["required"], (name, items[name]["detail"])
    item = items["uncut_edge"]
    loop = item["per_window"][str(wt.window_index)]
    assert f"window {wt.window_index}: cut {loop['cut_mm']:.1f} of {loop['loop_mm']:.1f} mm" \
        in item["detail"] and "test: the spindle body" in item["detail"]
    out = tmp_path / "p.mod"
    args = ["-q", "export", str(folder), "--format", "rapid", "-o", str(out)]
    assert main(args) == 1 and not out.exists()
    only_uncut = report["summary"]["failed"] == ["uncut_edge"]
    assert (main([*args, "--partial"]) == 0) is only_uncut
    if not only_uncut:  # another required check failed: --partial does not write it; the
        # header as it is written when uncut_edge alone fails (the gate's answer then)
        real = gate_mod.gate

        def uncut_only(folder_, plan_):
            g = real(folder_, plan_)
            return gate_mod.GateResult(False, "FORCED", g.reason, partial=item["detail"])

        monkeypatch.setattr(gate_mod, "gate", uncut_only)
        assert main([*args, "--partial"]) == 0
    text = out.read_text()
    u = loop["uncut"][0]
    assert "PARTIAL" in text and f"CL {u['cl'][0]}..{u['cl'][1]}" in text
    assert "FORCED" not in text
    from rapidchecker.check import check_format  # a checker we did not write
    from rapidchecker.whitespace_checks import check_whitespace

    assert [str(e) for e in check_format(text) + check_whitespace(text)] == []


def _missing_ik(run_idx, at: int, window: int = 0) -> FailureRecord:
    return FailureRecord(window=window, kind="ik", point=at,
                         reason="test: position/cone not met", tried=("test",))


def test_resplitting_is_bounded_and_reports_the_ik_misses():
    """A stretch whose IK misses a point is split there again; a planner that misses a point
    in every stretch it is given stops after RESPLIT_ROUNDS rounds (1 + 2 + 4 stretches
    planned), nothing is planned, and every uncut stretch says which CL points the IK missed
    and why."""
    from drakedeburr.plan.options import RunMode
    from drakedeburr.plan.results import WindowPlan, WindowStatus

    wt = _circle_targets(200, 0)  # 1.57 mm apart, 314 mm of loop
    p = wt.p_HC
    refusal = FailureRecord(window=0, kind="window", reason="test: blocked",
                            where={"blocked_points": [0]})
    calls = []

    def always_misses(ctx, sub, mode):
        calls.append(len(sub))
        return WindowPlan.skipped(0, WindowStatus.IK_FAILED, [_missing_ik(None, len(sub) // 2)])

    res = mut.plan_partial(None, wt, refusal, RunMode.FULL, always_misses)
    assert mut.RESPLIT_ROUNDS == 2 and len(calls) == 1 + 2 + 4
    assert not res.status.planned
    loop = res.failures[0].where["partial"]
    assert loop["rounds"] == 2 and loop["cut"] == [] and loop["stretches_planned"] == 7
    assert len(loop["ik_missed"]) == 7 and len(res.failures) == 1
    missed = {m["cl"] for m in loop["ik_missed"]}
    why = " ".join(w for u in loop["uncut"] for w in u["why"])
    assert all(f"IK missed CL {i}: test: position/cone not met" in why for i in missed)
    margin, _ = mut.run_limits()
    for r in loop["clear_runs"]:  # the last runs (each missing one point, the last round's)
        first, last = r["cl"]  # keep the margin off the points missed before
        idx = [(first + k) % 200 for k in range((last - first) % 200 + 1)]
        own = missed & set(idx)
        assert len(own) == 1
        assert min(_arc(p, i, b) for i in idx for b in (missed - own) | {0}) >= margin - 1e-12


def test_a_stretch_is_split_again_where_its_ik_misses(partial_plan, monkeypatch):
    """The faked-block window, its stretches' IK made to miss one CL point in the middle of
    the longer clear run: that run is split there (the margin kept off the point), the halves
    planned; the plan records no IK failure and targets no CL point within the margin; the
    uncut record names the point and the IK's reason."""
    import drakedeburr.plan.window as window
    from drakedeburr.hub import DEFAULT_HUB
    from drakedeburr.plan.planner import plan_windows

    cell, wt, blocked, plan0 = partial_plan
    loop0 = next(f for f in plan0.failures if "partial" in f.where).where["partial"]
    longest = max(loop0["cut"], key=lambda c: c["cl_points"])
    m = len(wt)
    bad = (longest["cl"][0] + longest["cl_points"] // 2) % m
    real = window.plan_whole
    calls = []

    def misses_bad(ctx, sub, mode):
        res = real(ctx, sub, mode)
        idx = [int(np.argmin(np.linalg.norm(wt.p_HC - q, axis=1))) for q in sub.p_HC]
        calls.append(idx)
        if bad in idx and res.status.planned:
            res.failures = [*res.failures, _missing_ik(idx, idx.index(bad))]
        return res

    def fake(ctx, w):
        return FailureRecord(window=w.window_index, kind="window", point=blocked[2],
                             reason="test: the spindle body in the part",
                             where={"blocked_points": blocked}, tried=("test",))

    monkeypatch.setattr(window, "tool_refusal", fake)
    monkeypatch.setattr(window, "plan_whole", misses_bad)
    plan = plan_windows(cell, [wt], load_config("tool_in_hand", DEFAULT_HUB))
    loop = next(f for f in plan.failures if "partial" in f.where).where["partial"]
    assert loop["rounds"] == 1 and [m_["cl"] for m_ in loop["ik_missed"]] == [bad]
    assert len(calls) == 4 and len(loop["cut"]) == 3  # two runs, then the halves of one
    assert not [f for f in plan.failures if f.kind == "ik"]
    margin, _ = mut.run_limits()
    cl = {t.cl_index for t in plan.targets if t.segment == "cut" and t.cl_index >= 0}
    assert all(_arc(wt.p_HC, i, b) >= margin for i in cl for b in [*blocked, bad])
    why = [w for u in loop["uncut"] for w in u["why"]]
    assert f"IK missed CL {bad}: test: position/cone not met" in why
    assert loop["cut_mm"] < loop0["cut_mm"]


def test_what_else_was_tried_on_an_uncut_edge_is_the_uncut_edge_item():
    """plan.relax.on_uncut_edge: a relaxation record of a window cut in part (milder recipes
    or the long-reach burr tried in vain) is about its uncut edge: planner_failures leaves it
    to uncut_edge; the same record of a whole window, and a partial window's own records of
    its planned motion, still fail planner_failures."""
    from types import SimpleNamespace

    from drakedeburr.plan.relax import on_uncut_edge
    from drakedeburr.verify.checks_plan import failures_item, uncut_edge

    loop = {"loop_mm": 100.0, "cut_mm": 60.0, "cut_share": 0.6, "cut": [], "uncut": [],
            "reason": "test"}
    part = FailureRecord(window=2, kind="window", reason="cut 60 of 100 mm",
                         where={"partial": loop})
    dense = FailureRecord(window=2, kind="dense", reason="clearance 1.9 mm")
    notes = [FailureRecord(window=w, kind="relaxation", reason=f"milder recipes failed too {w}")
             for w in (2, 5)]
    marked = on_uncut_edge([part, dense], notes)
    assert marked[0].where == {"uncut_edge": True} and marked[1].where == {}
    item = failures_item(SimpleNamespace(failures=[part, dense, *marked]))
    assert item.value == 2.0 and set(item.per_window) == {2, 5}
    assert item.per_window[2]["kinds"] == ["dense"]
    plan = SimpleNamespace(failures=[part, *marked],
                           meta={"windows": [{"window": 2, "partial": loop}]})
    u = uncut_edge(SimpleNamespace(plan=plan), None)
    assert not u.passed and u.per_window[2]["also_tried"] == ["milder recipes failed too 2"]
    assert failures_item(SimpleNamespace(failures=[part, marked[0]])).passed


def test_a_cut_under_the_clearance_marks_the_cl_targets_around_it():
    """plan.partial._clearance_misses: a stretch's executed cut under the clearance over some
    mm of its travel (the planner's "dense" record) names the CL targets on that travel and
    the nearest CL target before and after it (via targets skipped), in the loop's indices;
    the stretch is then split there like at an IK miss."""
    from types import SimpleNamespace as NS

    def tgt(x_mm, cl):
        X = np.eye(4)
        X[0, 3] = 1e-3 * x_mm
        return NS(X_HT=X, cl_index=cl)

    # tool points every 2 mm along x, one via target (cl -1) at 7 mm
    app = NS(kind="approach", targets=[tgt(0, 0)])
    cut = NS(kind="cut", targets=[tgt(2, 1), tgt(4, 2), tgt(6, 3), tgt(7, -1), tgt(8, 4),
                                  tgt(10, 5), tgt(12, 6)])
    rec = FailureRecord(window=0, kind="dense", reason="clearance 1.9 mm",
                        where={"s_range_mm": [6.5, 7.5]})
    res = NS(failures=[rec], stretches=[app, cut])
    idx = np.arange(100, 107)  # the stretch's CL points in the loop
    got = mut._clearance_misses(res, idx)
    assert sorted(got) == [103, 104] and got[103] is rec
    res.failures = [rec, FailureRecord(window=0, kind="ik", point=6, reason="cone")]
    assert sorted(mut._ik_misses(res, idx)) == [103, 104, 106]
