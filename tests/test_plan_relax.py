"""Recipe relaxation (plan.relax): milder tilt boxes in order, the first that plans clean kept
with its deviation recorded; what was tried recorded where none does; the window's run modes;
the burr for the whole hub. When the relaxed plan is kept, and the records of windows relaxed
in vain, are the policy's: tests/test_plan_policy.py."""

from __future__ import annotations

import functools
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.config import OrientationBounds, ProcessParameters
from drakedeburr.plan.options import PlanContext, PlanOptions, RunMode
from drakedeburr.plan.relax import TILT_STEPS, relax_windows, window_ladder
from drakedeburr.plan.results import (
    CutTargets,
    Deviation,
    PlanDraft,
    PlanRecord,
    WindowPlan,
    WindowStatus,
)
from drakedeburr.plan.types import FailureRecord


@functools.cache
def _edge(kind: str = "large"):
    from drakedeburr.hub import load_hub

    hub = load_hub("h5_split")
    return next(w for w in hub.windows if w.kind == kind)


def relaxed_targets(edge, params, reason, plan_one):
    """One window through relax_windows: (targets or None, deviation or None, tried)."""
    accepted, tried = relax_windows([edge], params, {edge.index: reason},
                                    lambda es: [window_ladder(e, params, plan_one) for e in es])
    wt, _, dev = accepted.get(edge.index, (None, None, None))
    return wt, dev, tried[edge.index]


def _plan(failures=()) -> WindowPlan:
    """A window's plan with these failure records (what a ladder step reads of it)."""
    return WindowPlan(0, WindowStatus.DEGRADED if failures else WindowStatus.OK,
                      failures=list(failures))


def _draft(failures=(), deviations=()) -> PlanDraft:
    """A hub's plan with these failure records and deviations (what choose_tool reads)."""
    return PlanDraft(failures=tuple(failures), record=PlanRecord(deviations=tuple(deviations)))


def test_the_first_milder_box_that_plans_clean_is_kept_and_recorded():
    edge = _edge("large")
    params = ProcessParameters()
    seen = []

    def plan_one(wt):
        seen.append(wt)
        return _plan([FailureRecord(edge.index, "ik", "unreachable")] if len(seen) == 1 else [])

    wt, dev, tried = relaxed_targets(edge, params, "ik: unreachable", plan_one)
    assert len(seen) == 2 and wt is seen[1]
    assert dev.window == edge.index and dev.item == "tool tilt"
    assert dev.used == "theta box 0.00-0.15 rad"
    assert dev.default == (f"theta box {params.bounds_large.theta_min:.2f}-"
                           f"{params.bounds_large.theta_max:.2f} rad")
    assert "ik: unreachable" in dev.reason
    assert [t for t, _ in tried] == ["theta box 0.09-0.26 rad"]
    # the kept targets really come from the milder box: its bounds, both angles inside
    tp, first = wt.tool_path, seen[0].tool_path
    assert (tp.bounds.theta_min, tp.bounds.theta_max) == (0.0, 0.15)
    assert (first.bounds.theta_min, first.bounds.theta_max) == (0.09, 0.26)
    for th in (tp.theta_A, tp.theta_B):
        assert np.all(th >= -1e-6) and np.all(th <= 0.15 + 1e-6)
    assert np.allclose(tp.p_HC, first.p_HC)  # the same CL points


def test_nothing_milder_helps_and_every_try_is_said():
    edge = _edge("large")
    wt, dev, tried = relaxed_targets(
        edge, ProcessParameters(), "why",
        lambda wt: _plan([FailureRecord(edge.index, "dense", "too close to the hub")]))
    assert wt is None and dev is None
    assert [t for t, _ in tried] == [f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"
                                     for b in TILT_STEPS]
    assert all("too close to the hub" in r for _, r in tried)


def test_a_box_not_milder_than_the_recipes_is_skipped():
    edge = _edge("large")
    params = replace(ProcessParameters(), bounds_large=OrientationBounds(0.05, 0.20))
    calls = []
    relaxed_targets(edge, params, "why", lambda wt: calls.append(wt) or _plan(["x"]))
    # 0.09-0.26 is not milder than 0.05-0.20; 0-0.15 is, and 0-0.44 holds it in a wider cone
    assert len(calls) == 2


def test_a_box_whose_tool_path_gives_no_targets_is_said_and_the_next_is_tried(monkeypatch):
    """A real wheel's corner where a milder box points the axis into the part: the tool path
    raises InputError; the ladder records it and goes on (the hub still gets its report)."""
    from drakedeburr.errors import InputError
    from drakedeburr.plan import tool_paths

    edge, params = _edge("large"), ProcessParameters()
    real, first = tool_paths.tool_path, TILT_STEPS[0]

    def tool_path(e, p):
        if p.bounds_large == first:
            raise InputError("window 1, CL 53: the tool axis points into the hub")
        return real(e, p)

    monkeypatch.setattr(tool_paths, "tool_path", tool_path)
    seen = []
    wt, dev, tried = relaxed_targets(edge, params, "ik: unreachable",
                                     lambda wt: seen.append(wt) or _plan([]))
    assert len(seen) == 1 and wt is seen[0]          # the second box was planned and kept
    b = seen[0].tool_path.bounds
    assert (b.theta_min, b.theta_max) == (TILT_STEPS[1].theta_min, TILT_STEPS[1].theta_max)
    assert tried == [(f"theta box {first.theta_min:.2f}-{first.theta_max:.2f} rad",
                      "no targets: window 1, CL 53: the tool axis points into the hub")]
    assert dev.used == f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"


def test_every_failing_window_climbs_its_own_ladder_and_all_at_once():
    """The failing windows' ladders go to the planner together, one task each (no window waits
    for another's variant of a step): each window's variants in turn, milder each step, up to
    its first clean one; the same windows accepted and the same tries said as one batch per
    step gave."""
    from drakedeburr.hub import load_hub

    large = [w for w in load_hub("h5_split").windows if w.kind == "large"][:2]
    calls, planned = [], []

    def plan_one(wt):
        planned.append(wt.window_index)
        # the first window plans clean at the first step, the second never
        return _plan([] if wt.window_index == large[0].index else
                      [FailureRecord(wt.window_index, "ik", "x")])

    def ladders(edges):
        calls.append([e.index for e in edges])
        return [window_ladder(e, ProcessParameters(), plan_one) for e in edges]

    accepted, tried = relax_windows(large, ProcessParameters(), {}, ladders)
    assert calls == [[large[0].index, large[1].index]]
    assert planned == [large[0].index] + [large[1].index] * len(TILT_STEPS)
    assert list(accepted) == [large[0].index] and accepted[large[0].index][1].failures == []
    assert accepted[large[0].index][2].used == "theta box 0.09-0.26 rad"
    assert [t for t, _ in tried[large[1].index]] == [
        f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad" for b in TILT_STEPS]


def test_a_report_only_window_is_planned_once(monkeypatch):
    """RunMode.REPORT_ONLY: one pass (no second spin rule), from the first start configuration only
    (no further seeds, no rewound start, no start tracked back), whatever its failures."""
    from drakedeburr.plan import window as mut
    from drakedeburr.plan.results import WindowPlan

    rec = FailureRecord(0, "ik", "x")
    plans = []
    monkeypatch.setattr(mut, "_plan_window_once", lambda ctx, wt, q, mode: plans.append(
        WindowPlan(0, WindowStatus.DEGRADED, failures=[rec])) or plans[-1])
    monkeypatch.setattr(mut, "window_reference", lambda ctx, wt: None)
    ctx = PlanContext(cell=None, kin=None, checker=None, free_checker=None, config=None,
                      options=PlanOptions())
    assert mut.plan_window(ctx, SimpleNamespace(window_index=0), RunMode.REPORT_ONLY) \
        is plans[0]
    assert len(plans) == 1
    # the IK from the first of the window's start configurations only
    starts = []
    failed = SimpleNamespace(ok=np.array([True, False]), failures=[rec],
                             q=np.zeros((2, 6)), X_HT=np.tile(np.eye(4), (2, 1, 1)))
    monkeypatch.setattr(mut, "_seeds", lambda *a: [np.zeros(6), np.ones(6)])
    monkeypatch.setattr(mut, "solve_window_ik",
                        lambda *a, q_first, **k: starts.append(q_first) or failed)
    monkeypatch.setattr(mut, "rewound_start", lambda *a: np.full(6, 2.0))
    backs = []
    monkeypatch.setattr(mut, "_backward_seed", lambda *a: backs.append(1) or np.full(6, 3.0))
    monkeypatch.setattr(mut, "track_poses", lambda *a: SimpleNamespace(ok=np.array([True])))
    wt = _Window(window_index=0, retract_H=np.zeros((1, 3)), t_H=np.zeros((1, 3)),
                 cone_retract_H=np.zeros((1, 3)), cone_half_angle=0.1)
    # not report_only: the first seed, the rewound one, the second seed, then the one tracked
    # back from the failed target (once for that target)
    for report_only, n in ((True, [0.0]), (False, [0.0, 2.0, 1.0, 3.0])):
        starts.clear()
        backs.clear()
        ctx = PlanContext(cell=None, kin=SimpleNamespace(), checker=None, free_checker=None,
                          config=None, options=PlanOptions())
        mut._solve_ik(ctx, wt, np.zeros(6), CutTargets(np.array([0, 0]), np.zeros((2, 3)), 0.0),
                      RunMode.REPORT_ONLY if report_only else RunMode.FULL)
        assert [float(q[0]) for q in starts] == n, report_only
        assert len(backs) == (0 if report_only else 1)


class _Window(SimpleNamespace):
    """A one-target window for _solve_ik."""

    def __len__(self):
        return 1


@pytest.mark.parametrize(("first", "second", "kept"), [
    ("abandoned", "ok", "second"),  # the other spin rule cuts it cleanly: as before
    ("abandoned", "degraded", "abandoned"),  # fails either way: relaxed, or planned in full
    ("degraded", "abandoned", "abandoned"),  # which rule fails less needs the full passes
    ("degraded", "degraded-fewer", "second"),  # both in full: the one with fewer records
])
def test_a_fail_fast_window_keeps_only_what_a_full_pass_would(monkeypatch, first, second, kept):
    """plan_window in RunMode.FAIL_FAST: it returns a window plan only where planning in full would
    return the same one; otherwise ABANDONED (relaxed, or planned in full by _relax)."""
    from drakedeburr.plan import window as mut
    from drakedeburr.plan.results import WindowPlan

    rec = FailureRecord(0, "ik", "x")
    make = {"abandoned": lambda: WindowPlan.skipped(0, WindowStatus.ABANDONED, [rec]),
            "ok": lambda: WindowPlan(0, WindowStatus.OK,
                                     stats=SimpleNamespace(speed_in_band_fraction=0.9)),
            "degraded": lambda: WindowPlan(0, WindowStatus.DEGRADED, failures=[rec, rec]),
            "degraded-fewer": lambda: WindowPlan(0, WindowStatus.DEGRADED, failures=[rec])}
    made = iter([make[first](), make[second]()])
    plans = []
    monkeypatch.setattr(mut, "_plan_window_once",
                        lambda ctx, wt, q, mode: plans.append(next(made)) or plans[-1])
    monkeypatch.setattr(mut, "window_reference", lambda ctx, wt: None)
    ctx = PlanContext(cell=None, kin=None, checker=None, free_checker=None, config=None,
                      options=PlanOptions())
    out = mut.plan_window(ctx, SimpleNamespace(window_index=0), RunMode.FAIL_FAST)
    assert len(plans) == 2
    if kept == "second":
        assert out is plans[1]
    else:
        assert out.status is WindowStatus.ABANDONED and out.failures


@pytest.mark.parametrize(("band", "cut_first", "cut_second", "plans", "kept"), [
    (0.75, 3.0, 2.0, 1, 0),  # in the band enough: planned once, whatever the other rule gives
    (0.40, 3.0, 2.0, 2, 1),  # slow: the other rule planned, its faster clean plan kept
    (0.40, 3.0, 3.0, 2, 0),  # a tie keeps the first
    (0.40, 3.0, 4.0, 2, 0),
])
def test_a_clean_window_is_planned_with_the_frame_rule_and_again_only_when_slow(
        monkeypatch, band, cut_first, cut_second, plans, kept):
    """plan_window: the first plan uses the default warm-start spin rule (frame), the second
    the other (joint cost) and only when the first holds less than ``retry_in_band`` of its cut
    in the band; the faster clean plan is kept (needs_other_rule, better_of)."""
    from drakedeburr.plan import window as mut
    from drakedeburr.plan.results import WindowPlan

    made = iter([WindowPlan(0, WindowStatus.OK, stats=SimpleNamespace(
        speed_in_band_fraction=band, cut_seconds=cut_first)),
        WindowPlan(0, WindowStatus.OK, stats=SimpleNamespace(
            speed_in_band_fraction=0.8, cut_seconds=cut_second))])
    out_plans, rules = [], []

    def once(ctx, wt, q, mode):
        rules.append(ctx.options.ik.seed_spin)
        out_plans.append(next(made))
        return out_plans[-1]

    monkeypatch.setattr(mut, "_plan_window_once", once)
    monkeypatch.setattr(mut, "window_reference", lambda ctx, wt: None)
    ctx = PlanContext(cell=None, kin=None, checker=None, free_checker=None, config=None,
                      options=PlanOptions())
    out = mut.plan_window(ctx, SimpleNamespace(window_index=0))
    assert rules == ["frame", "joint_cost"][:plans]
    assert out is out_plans[kept]



@pytest.mark.parametrize("fail_fast", [True, False])
@pytest.mark.parametrize("least_mm", [1.9, 2.1])
def test_a_fail_fast_cut_under_the_clearance_is_abandoned_before_its_program(
        monkeypatch, fail_fast, least_mm):
    """execute_cut (the window pass's steps 3-4): a tracked cut that stays under the clearance
    (after its axis is pinned) fails this recipe whatever its program and timing would be;
    fail-fast (the first pass and the relaxed variants) abandons it there, with the tracking's
    records; a full pass, or a clear cut, goes on to the program."""
    from drakedeburr.plan import cut
    from drakedeburr.plan import window as mut
    from drakedeburr.plan.results import IkStep

    n = 50
    dist = np.full(n, least_mm * 1e-3 + 0.2e-3)
    dist[20:24] = least_mm * 1e-3
    rec = FailureRecord(0, "dense", "clearance")

    def track(ctx, wt, ik, step):
        records = (rec,) if dist.min() < ctx.cut_clearance else ()
        return cut._Try(cp=None, cut=SimpleNamespace(ok=np.ones(n, bool)), dist=dist,
                        spin_mode="ik", records=records)

    class Fitted(Exception):
        pass

    def fit(*args, **kwargs):
        raise Fitted

    monkeypatch.setattr(mut, "track_cut", track)
    monkeypatch.setattr(mut, "fit_program", fit)
    ctx = PlanContext(cell=None, kin=None, checker=None, free_checker=None,
                      config=SimpleNamespace(tolerances=SimpleNamespace(min_clearance=2e-3)),
                      options=PlanOptions())
    ik = IkStep(status=WindowStatus.OK, wik=SimpleNamespace(X_HT=np.zeros((3, 4, 4))),
                good=np.arange(3), order=np.arange(3), failures=(), seconds=0.0, starts=1)
    call = functools.partial(mut.execute_cut, ctx, SimpleNamespace(window_index=0), ik,
                             RunMode.FAIL_FAST if fail_fast else RunMode.FULL)
    if fail_fast and least_mm < 2.0:
        out = call()
        assert out.status is WindowStatus.ABANDONED and out.failures == (rec,)
    else:
        with pytest.raises(Fitted):
            call()


# ---------------------------------------------------------------- the burr, for the whole hub
_BODY = FailureRecord(0, "ik", "unreachable", where={
    "blocking_pair": ["spindle::spindle/spindle::spindle_body", "hub::hub/hub::piece_7"]})
_HEAD = FailureRecord(1, "dense", "too close", where={
    "pair": ["spindle::burr/spindle::burr_head", "hub::hub/hub::piece_2"]})
_SHANK = FailureRecord(2, "ik", "unreachable", where={
    "blocking_pair": ["spindle::burr/spindle::burr_shank", "hub::hub/hub::piece_1"]})
_STAND = FailureRecord(3, "ik", "unreachable", where={
    "blocking_pair": ["stand::stand/stand::spindle_body", "hub::hub/hub::piece_48"]})


@pytest.mark.parametrize("failures, tool, helps", [
    ([_BODY], "standard", True), ([_HEAD, _BODY], "standard", True),
    ([_HEAD], "standard", False), ([_SHANK], "standard", False), ([_STAND], "standard", True),
    ([FailureRecord(0, "transition", "joint limit")],
                                   "standard", False),
    ([_BODY], "long_reach", False), ([_BODY], None, False)])
def test_the_long_reach_is_tried_where_the_tool_body_blocked(failures, tool, helps):
    from drakedeburr.plan.relax import reach_may_help

    assert reach_may_help(_draft(failures), SimpleNamespace(tool=tool)) is helps


@pytest.mark.parametrize("alt_failures, kept", [
    ([], "long_reach"), ([FailureRecord(1, "ik", "x")] * 5, "long_reach"),
    ([FailureRecord(0, "ik", "x"), FailureRecord(1, "ik", "y")], "standard"),
    ([FailureRecord(2, "ik", "x"), FailureRecord(3, "ik", "y"), FailureRecord(4, "ik", "z")],
     "standard")])
def test_the_burr_leaving_fewer_windows_failing_is_kept_and_said(alt_failures, kept):
    """Standard: windows 0 and 1 fail. The long-reach plan is kept only with fewer failing
    windows; either way the kept plan says what the other burr did."""
    from drakedeburr.plan.relax import choose_tool

    std = _draft((_BODY, _HEAD, FailureRecord(1, "ik", "more")))
    home = Deviation(-1, "home", "the cell's", "moved", "r")
    alt = _draft(alt_failures, [home])
    out = choose_tool(std, alt)
    if kept == "long_reach":
        assert out.failures == tuple(alt_failures) and out.record is not alt.record
        assert alt.record.deviations == (home,)  # a new draft: the long-reach one not edited
        devs = out.record.meta()["recipe_deviations"]
        dev = devs[-1]
        assert devs[0] == home.record() and len(devs) == 2
        assert (dev["window"], dev["item"]) == (-1, "burr")
        assert "75 mm" in dev["used"] and "25 mm" in dev["default"]
        assert "[0, 1]" in dev["reason"] and "spindle" not in dev["used"]
    else:
        assert out.record is std.record and out.record.deviations == ()
        assert out.failures[:3] == std.failures
        notes = out.failures[3:]
        assert [n.window for n in notes] == [0, 1]
        assert all(n.kind == "relaxation" and n.tried == ("long-reach burr (75 mm stick-out)",)
                   for n in notes)
        assert all(f"{len({f.window for f in alt_failures})} window(s)" in n.reason
                   for n in notes)


def test_the_relaxation_and_home_import_no_planner_module():
    """relax makes its variants' tool paths by drakedeburr.plan.tool_paths.tool_path, the
    function the planner's own targets use, not by a planner private: no import circle
    planner -> relax/home/policy -> planner (an import inside a function counts)."""
    import ast
    import inspect

    from drakedeburr.plan import home, planner, policy, relax, tool_paths

    for mod in (relax, home, tool_paths, policy):
        tree = ast.parse(inspect.getsource(mod))
        mods = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert "drakedeburr.plan.planner" not in mods, mod.__name__
    assert planner.tool_path is tool_paths.tool_path


def test_a_box_the_tool_precheck_refuses_is_not_planned_and_the_next_is_tried():
    """window_ladder with ``refused`` (plan.window.precheck): a box whose targets the tool
    pre-check refuses can only be cut in part (a failure record), so its stretches are not
    planned: its result is the refusal alone, said in the tries, and the next box is planned
    (and kept when clean), as a planned box with failure records would have it."""
    edge, params = _edge("large"), ProcessParameters()
    refusal = FailureRecord(edge.index, "window", "at 9 of 90 CL points every tool axis ...",
                            where={"blocked_points": [3, 4]})
    asked, planned = [], []

    def refused(wt):
        asked.append(wt)
        return refusal if len(asked) == 1 else None

    accepted, tried = relax_windows(
        [edge], params, {edge.index: "why"},
        lambda es: [window_ladder(e, params, lambda wt: planned.append(wt) or _plan([]),
                                  refused=refused) for e in es])
    assert len(asked) == 2 and planned == [asked[1]]  # the refused box: asked, not planned
    wt, res, dev = accepted[edge.index]
    assert wt is asked[1] and not res.failures
    assert dev.used == _box_text(TILT_STEPS[1])
    assert tried[edge.index] == [(_box_text(TILT_STEPS[0]), str(refusal))]
    # the refused box's targets are the milder box's own (its bounds, angles inside)
    b = asked[0].tool_path.bounds
    assert (b.theta_min, b.theta_max) == (TILT_STEPS[0].theta_min, TILT_STEPS[0].theta_max)
    for th in (asked[0].tool_path.theta_A, asked[0].tool_path.theta_B):
        assert np.all(th >= b.theta_min - 1e-6) and np.all(th <= b.theta_max + 1e-6)


def test_every_box_refused_is_proven_and_one_box_clear_is_not(monkeypatch):
    """relax.refused_in_every_box: the recipe box's refusal when the pre-check refuses it and
    every milder box (milder_boxes: those window_ladder tries), None as soon as one is clear;
    a box without targets counts as refused (the ladder cannot keep it either)."""
    from drakedeburr.plan import relax, window
    from drakedeburr.plan.tool_paths import tool_path
    from drakedeburr.plan.window_targets import WindowTargets

    edge, params = _edge("large"), ProcessParameters()
    recipe = WindowTargets.from_tool_path(tool_path(edge, params))
    boxes = relax.milder_boxes(edge, params)
    assert boxes == list(TILT_STEPS)  # the source's large box: every step is milder
    rec = FailureRecord(edge.index, "window", "blocked")
    seen = []

    def precheck(ctx, wt):
        seen.append(wt.tool_path.bounds)
        return None if ctx == "clear" and wt.tool_path.bounds == boxes[-1] else rec

    monkeypatch.setattr(window, "precheck", precheck)
    # the milder boxes: searched up to a first proven point, the recipe's blocked ones first
    monkeypatch.setattr(window, "blocked_anywhere", lambda ctx, wt, first=(): precheck(ctx, wt))
    item = (edge, params, relax.first_cl_paths([recipe])[edge.index], recipe)
    assert relax.refused_in_every_box("blocked", item) is rec
    assert len(seen) == 1 + len(boxes)
    seen.clear()
    assert relax.refused_in_every_box("clear", item) is None
    assert len(seen) == 1 + len(boxes)
    # a box without targets: refused
    monkeypatch.setattr(relax, "box_targets", lambda e, p, b, cl: "no targets: into the hub")
    assert relax.refused_in_every_box("clear", item) is rec


def _box_text(b) -> str:
    return f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"
