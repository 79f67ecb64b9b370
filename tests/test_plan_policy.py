"""The hub-level policy (plan.policy) on typed stand-ins: the first pass's run mode, the
relaxation's choice between the relaxed and the recipe's plan, the report-only re-run of
abandoned windows, the long-reach retry's trigger and the record each kept plan carries; and
that the Plan's meta/run are what its record says, made once."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from drakedeburr.config import ProcessParameters, load_config
from drakedeburr.plan import policy
from drakedeburr.plan.options import PlanOptions, RunMode
from drakedeburr.plan.relax import TILT_STEPS
from drakedeburr.plan.results import (
    Deviation,
    PlanDraft,
    PlanMotion,
    PlanRecord,
    PlanStats,
    WindowPlan,
    WindowStatus,
)
from drakedeburr.plan.types import FailureRecord, JointTrajectory


@dataclass(frozen=True)
class _Wt:
    """A window's targets, as the policy reads them."""

    window_index: int
    relaxed: bool = False


@dataclass(frozen=True)
class _Edge:
    """A hub window (WindowEdge), as the relaxation reads it."""

    index: int
    kind: str = "large"


@dataclass
class _Cell:
    """Stand-in passes of one cell: every call recorded, results from the given tables."""

    first: dict  # window -> its first-pass WindowPlan
    in_full: dict = field(default_factory=dict)  # window -> its report-only WindowPlan
    ladder: dict = field(default_factory=dict)  # window -> [(box, targets, WindowPlan)]
    moves: int = 0  # failed moves between windows of a plan with a relaxed window
    calls: list = field(default_factory=list)
    assembled: list = field(default_factory=list)

    def plan(self, wts, mode, progress):
        self.calls.append(("plan", mode, [w.window_index for w in wts]))
        table = self.in_full if mode is RunMode.REPORT_ONLY else self.first
        return [table[w.window_index] for w in wts]

    def ladders(self, edges, mode):
        self.calls.append(("ladders", mode, [e.index for e in edges]))
        return [self.ladder[e.index] for e in edges]

    def assemble(self, wts, results):
        self.assembled.append((list(wts), list(results)))
        moves = (FailureRecord(-1, "transition", "no clear move"),) * (
            self.moves if any(w.relaxed for w in wts) else 0)
        return PlanDraft(failures=(*(f for r in results for f in r.failures), *moves),
                         record=PlanRecord(robot=f"assembly {len(self.assembled)}"))

    def passes(self) -> policy.CellPasses:
        return policy.CellPasses(plan=self.plan, ladders=self.ladders, assemble=self.assemble,
                                 params=ProcessParameters())


def _window(w: int, *records: FailureRecord, status=None) -> WindowPlan:
    status = status or (WindowStatus.DEGRADED if records else WindowStatus.OK)
    return WindowPlan(w, status, failures=list(records))


def _box(b) -> str:
    return f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"


@pytest.mark.parametrize("relaxing, mode", [(True, RunMode.FAIL_FAST), (False, RunMode.FULL)])
def test_the_first_pass_runs_fail_fast_only_when_relaxing(relaxing, mode):
    cell = _Cell(first={0: _window(0), 1: _window(1, FailureRecord(1, "ik", "x"))},
                 ladder={1: [(TILT_STEPS[0], _Wt(1, relaxed=True), _window(1))]})
    out = policy.cell_pass(cell.passes(), {0: _Edge(0), 1: _Edge(1)}, [_Wt(0), _Wt(1)],
                           relaxing)
    assert cell.calls[0] == ("plan", mode, [0, 1])
    if relaxing:  # window 1 failed: its ladder is climbed (fail-fast as well), and cuts it
        assert cell.calls[1:] == [("ladders", RunMode.FAIL_FAST, [1])]
        assert out.failures == () and [d.window for d in out.record.deviations] == [1]
    else:  # no relaxation: the first pass assembled as it is
        assert cell.calls == [("plan", mode, [0, 1])]
        assert out.failures == (FailureRecord(1, "ik", "x"),)


@pytest.mark.parametrize("moves, kept", [(0, "relaxed"), (1, "default"), (2, "default")])
def test_the_hub_is_assembled_again_and_kept_only_with_fewer_failures(moves, kept):
    """Window 0 relaxes at the first milder box, window 1 at none: the plan is assembled again
    from window 0's relaxed plan and window 1's first-pass plan (not planned again), kept with
    fewer records than the recipe's plan (2; the relaxed one: window 1's and ``moves`` failed
    moves between windows), and window 1's relaxation record is added to whichever plan is
    kept; the kept tilt is a recorded deviation only on the relaxed plan."""
    a, b = FailureRecord(0, "ik", "a"), FailureRecord(1, "ik", "b")
    first = {0: _window(0, a), 1: _window(1, b)}
    default_box = ProcessParameters().bounds_large
    steps = [s for s in TILT_STEPS if s.theta_max < default_box.theta_max
             or s.theta_min < default_box.theta_min]
    wt0, clean0 = _Wt(0, relaxed=True), _window(0)
    cell = _Cell(first=first, moves=moves, ladder={
        0: [(steps[0], wt0, clean0)], 1: [(s, _Wt(1), _window(1, b)) for s in steps]})
    wts = [_Wt(0), _Wt(1)]
    out = policy.relax_pass(cell.passes(), {0: _Edge(0), 1: _Edge(1)}, wts,
                            [first[0], first[1]])
    assert cell.calls == [("ladders", RunMode.FAIL_FAST, [0, 1])]  # nothing planned again
    assert cell.assembled[0] == ([wt0, wts[1]], [clean0, first[1]])
    if kept == "relaxed":
        assert len(cell.assembled) == 1 and out.record.robot == "assembly 1"
        (dev,) = out.record.deviations
        assert (dev.window, dev.item, dev.used) == (0, "tool tilt", _box(steps[0]))
        assert dev.default == _box(default_box)
        assert "window 0 (ik): a" in dev.reason  # why the recipe failed there
        base = (b,)
    else:  # no fewer records: the recipe's plan, assembled from the first pass, is kept
        assert cell.assembled[1] == (wts, [first[0], first[1]])
        assert out.record.robot == "assembly 2" and out.record.deviations == ()
        base = (a, b)
    assert out.failures[:len(base)] == base and len(out.failures) == len(base) + 1
    extra = out.failures[-1]
    assert extra.kind == "relaxation" and extra.window == 1
    assert extra.tried == tuple(_box(s) for s in steps)
    assert "window 1 (ik): b" in extra.reason
    assert "both spin rules" not in extra.reason  # window 1 was not abandoned


def test_an_abandoned_window_no_relaxation_helps_is_planned_in_full():
    """The first pass abandons window 0 at an unreachable target (with relaxation on). No
    milder box helps: it is planned in full once, for its report (RunMode.REPORT_ONLY), before
    the plan is assembled; the relaxation record says what was tried and that the records are
    the first start's."""
    rec = FailureRecord(0, "ik", "unreachable")
    abandoned = _window(0, rec, status=WindowStatus.ABANDONED)
    in_full = _window(0, rec, rec, rec)
    cell = _Cell(first={0: abandoned}, in_full={0: in_full},
                 ladder={0: [(TILT_STEPS[0], _Wt(0), _window(0, FailureRecord(0, "ik", "x")))]})
    out = policy.relax_pass(cell.passes(), {0: _Edge(0)}, [_Wt(0)], [abandoned])
    assert cell.calls == [("ladders", RunMode.FAIL_FAST, [0]), ("plan", RunMode.REPORT_ONLY, [0])]
    assert cell.assembled == [([_Wt(0)], [in_full])]
    assert len(out.failures) == 4 and out.failures[-1].kind == "relaxation"
    assert "both spin rules stopped at a first failure" in out.failures[-1].reason
    assert out.failures[-1].tried == (_box(TILT_STEPS[0]),)


def test_a_window_relaxed_keeps_no_report_only_pass_and_others_are_completed():
    """report_only_pass replaces only the abandoned results among the positions asked, in one
    REPORT_ONLY pass; the others are returned as they are."""
    r = FailureRecord(1, "ik", "x")
    results = [_window(0), _window(1, r, status=WindowStatus.ABANDONED),
               _window(2, r, status=WindowStatus.ABANDONED)]
    cell = _Cell(first={}, in_full={1: _window(1, r, r), 2: _window(2, r, r)})
    wts = [_Wt(0), _Wt(1), _Wt(2)]
    out = policy.report_only_pass(cell.passes(), wts, results, [0, 1])
    assert cell.calls == [("plan", RunMode.REPORT_ONLY, [1])]
    assert out[0] is results[0] and out[1] is cell.in_full[1] and out[2] is results[2]
    assert policy.report_only_pass(cell.passes(), wts, out, [0, 1]) == out  # nothing left


@dataclass(frozen=True)
class _Tool:
    tool: str | None


_BODY = FailureRecord(0, "ik", "unreachable", where={
    "blocking_pair": ["spindle::spindle/spindle::spindle_body", "hub::hub/hub::piece_7"]})
_HEAD = FailureRecord(1, "dense", "too close", where={
    "pair": ["spindle::burr/spindle::burr_head", "hub::hub/hub::piece_2"]})


@pytest.mark.parametrize("tool, failing, planned", [
    (None, [_BODY], [(None, None), ("long_reach", [0]), ("long_reach", None)]),
    (None, [_HEAD], [(None, None)]), ("standard", [_BODY], [(None, None)]),
    (None, [], [(None, None)])])
def test_the_hub_is_planned_again_with_the_long_reach_only_when_it_may_help(tool, failing,
                                                                           planned):
    """hub_pass: the hub is planned in the given cell; again with the long-reach burr only
    when no burr was asked for (long_reach_allowed, on the run's real configuration) and the
    standard's failures name the tool body; the kept long-reach plan records the burr."""
    config = load_config("tool_in_hand", "h5_straight", tool=tool)
    allowed = policy.long_reach_allowed(PlanOptions(), config)
    assert allowed is (tool is None)
    assert policy.long_reach_allowed(PlanOptions(relax=False), config) is False
    calls = []

    def plan_in(burr, only):
        calls.append((burr, None if only is None else sorted(only)))
        return PlanDraft(failures=tuple(failing) if burr is None else ())

    out = policy.hub_pass(plan_in, [0, 1, 2], _Tool(tool or "standard"), long_reach=allowed)
    assert calls == planned
    if len(planned) > 1:
        assert out.record.deviations[-1].item == "burr" and not out.failures
        t = out.record.timings
        assert t.standard_burr_seconds >= 0 and t.long_reach_seconds >= 0
        assert out.record.meta()["recipe_deviations"][-1]["item"] == "burr"
    else:
        assert out.record.timings.long_reach_seconds is None
        assert "long_reach_seconds" not in out.record.run()["timings"]


def test_moved_tool_points_are_a_recipe_deviation():
    """A window whose tool points the burr-depth reading moved out (plan.burr_depth) is
    recorded as a deviation from the recipe, with what is left if the move fell short."""
    relief = {"max_mm": 0.15, "cl_points": 25, "depth_read_mm": 1.45, "bound_mm": 1.37,
              "excess_left_mm": 0.0}
    rec = policy.relief_deviation({"window": 2, "chamfer_relief": relief}).record()
    assert rec["window"] == 2 and rec["item"] == "tool point"
    assert "0.150 mm at 25 CL points" in rec["used"]
    assert "1.450 mm" in rec["reason"] and "1.370 mm" in rec["reason"]
    assert "still" not in rec["reason"]
    relief["excess_left_mm"] = 0.02
    rec = policy.relief_deviation({"window": 2, "chamfer_relief": relief}).record()
    assert "still 0.020 mm too deep" in rec["reason"]


def test_the_plan_is_made_once_from_its_record():
    """PlanDraft.plan: meta and run are the record's, with the deviations in the order the
    passes recorded them (the home first, then the cell's, then the burr), the frames and
    poses as nested lists, optional items only when present; the draft is never edited (each
    step returns a new one)."""
    X = np.eye(4)
    X[:3, 3] = (0.1, 0.2, 0.3)
    home = Deviation(-1, "home", "cell", "moved", "r")
    tilt, burr = Deviation(0, "tool tilt", "a", "b", "r"), Deviation(-1, "burr", "s", "l", "r")
    motion = PlanMotion(scenario="s", hub="h", mode="tool", X_WH=X, targets=(), segments=(),
                        trajectory=JointTrajectory(t=np.array([0.0, 1.0]),
                                                   c=np.zeros((7, 1, 6))))
    base = PlanDraft(record=PlanRecord(robot="arm", X_FT=X, X_FH=X, X_WT=X, X_WB=X,
                                       figures={"cycle_seconds": 1.0}, deviations=(tilt,),
                                       timings=PlanStats(2.0, 0.5)), motion=motion)
    draft = (base.with_deviations(front=(home,)).with_deviations(back=(burr,))
             .with_record(q_home=np.arange(6.0), hub_pose=X, placement={"k": 1})
             .with_timings(targets_seconds=0.25, placement_seconds=0.75))
    assert base.record.deviations == (tilt,) and base.record.q_home is None  # not edited
    plan = draft.plan()
    assert [d["item"] for d in plan.meta["recipe_deviations"]] == ["home", "tool tilt", "burr"]
    assert plan.meta["X_FT"] == X.tolist() and plan.meta["hub_pose"] == X.tolist()
    assert plan.meta["q_home"] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    assert plan.meta["placement"] == {"k": 1} and plan.meta["cycle_seconds"] == 1.0
    assert plan.meta["robot"] == "arm" and "tool" not in plan.meta
    assert plan.run == {"timings": {"total_seconds": 2.0, "transition_seconds": 0.5,
                                    "targets_seconds": 0.25, "placement_seconds": 0.75},
                        "windows": []}
    bare = base.plan().meta
    assert not {"q_home", "hub_pose", "placement"} & set(bare)
    assert [d["item"] for d in bare["recipe_deviations"]] == ["tool tilt"]
    assert "recipe_deviations" not in PlanDraft(motion=motion).plan().meta


@pytest.mark.parametrize("refused, planned", [
    ({0: "r0", 2: "r2"}, []), ({0: "r0"}, [[0, 2]]), ({}, [[0, 2]])])
def test_the_long_reach_is_not_planned_when_its_precheck_refuses_every_failing_window(
        refused, planned):
    """long_reach_pass with ``refused``: when the long-reach pre-check refuses every window
    the standard burr left failing in every tilt box, each fails with it too, so its plan
    cannot leave fewer windows failing: it is not made and the standard plan is kept (as
    keep_standard/choose_tool would keep it), a record per window naming the refusal;
    otherwise the long-reach burr is planned as before."""
    records = {w: FailureRecord(w, "window", f"refused {w}") for w in refused}
    standard = PlanDraft(failures=(_BODY, FailureRecord(2, "ik", "unreachable", where={
        "blocking_pair": ["spindle::spindle/spindle::collet", "hub::hub/hub::piece_1"]})))
    calls, asked = [], []

    def plan_long_reach(only):
        calls.append(sorted(only))
        return PlanDraft(failures=tuple(FailureRecord(w, "window", "cut in part")
                                        for w in only))

    def ask(ws):
        asked.append(list(ws))
        return records

    out = policy.long_reach_pass(standard, [0, 1, 2], plan_long_reach, ask)
    assert asked == [[0, 2]] and calls == planned
    notes = out.failures[len(standard.failures):]
    assert out.failures[:2] == standard.failures and [n.window for n in notes] == [0, 2]
    assert all(n.kind == "relaxation" for n in notes)
    if not planned:
        assert all("was not planned" in n.reason for n in notes)
        assert [n.reason.rsplit("; here: ", 1)[1] for n in notes] == ["refused 0", "refused 2"]
    else:
        assert all("cut in part" in n.reason for n in notes)


def test_the_long_reach_precheck_is_not_asked_when_a_move_failed():
    """A failed move between windows (-1): the long-reach plan of the hub may leave fewer
    windows failing whatever the windows do, so the pre-check proves nothing: not asked."""
    standard = PlanDraft(failures=(_BODY, FailureRecord(-1, "transition", "no clear move")))
    asked = []
    out = policy.long_reach_pass(standard, [0, 1], lambda only: PlanDraft(),
                                 lambda ws: asked.append(ws) or {})
    assert asked == [] and out.record.deviations[-1].item == "burr"
