"""The burr choice of the hub-level policy (plan.relax.choose_tool / better_cut / cut_tally):
the long-reach plan is kept only when it cuts the hub better, compared as a cell engineer
compares two programs: one whose moves off the cut miss the clearance is not run; else what is
cut (no window left wholly uncut that the other cut in part, no less edge) before the count of
failing windows. Synthetic plans (PlanDraft with per-window figures and failure records)."""

from __future__ import annotations

import pytest

from drakedeburr.plan.relax import (
    EDGE_TIE,
    LONG_REACH,
    MOVE_KINDS,
    better_cut,
    choose_tool,
    cut_tally,
)
from drakedeburr.plan.results import PlanDraft, PlanRecord
from drakedeburr.plan.types import FailureRecord

LOOP_MM = 450.0  # every synthetic window's loop


def _window(w: int, cut_mm: float) -> dict:
    """One window's figures: cut whole (``cut_mm`` = the loop) or in part (a partial record,
    its planned stretches' closed polylines: twice the edge they cut, as the planner adds
    them up)."""
    if cut_mm >= LOOP_MM:
        return {"window": w, "edge_length_m": 1e-3 * LOOP_MM, "partial": None}
    return {"window": w, "edge_length_m": 2e-3 * cut_mm,
            "partial": {"loop_mm": LOOP_MM, "cut_mm": cut_mm}}


def _draft(cut: dict, failures=(), tool=None) -> PlanDraft:
    """A hub plan cutting ``cut`` (window -> mm; a window not in it: not planned) with these
    failure records, plus the partial record of each window cut in part."""
    recs = [FailureRecord(w, "window", f"cut {mm} of {LOOP_MM} mm")
            for w, mm in cut.items() if mm < LOOP_MM]
    return PlanDraft(failures=(*recs, *failures),
                     record=PlanRecord(tool=tool, figures={"windows": [
                         _window(w, mm) for w, mm in sorted(cut.items())]}))


def _uncut(w: int) -> FailureRecord:
    return FailureRecord(w, "window", "every tool axis of the cone puts the collet in the part")


def _move(w: int, kind: str = "transition") -> FailureRecord:
    return FailureRecord(w, kind, "no collision-free joint move found (clearance 1.95 mm, kto)",
                         value=1.95e-3, limit=2e-3, unit="m")


# audibot's numbers: the standard burr cuts all ten windows in part, the long-reach burr
# cuts none of window 0 (main, 4fe65ba)
STANDARD = {0: 130.9, 1: 336.8, 2: 135.4, 3: 273.7, 4: 97.0, 5: 380.2, 6: 276.0, 7: 368.0,
            8: 268.3, 9: 240.4}
LONG = {w: mm + 20.0 for w, mm in STANDARD.items() if w != 0}


def test_the_tally_reads_the_cut_edge_and_the_moves():
    t = cut_tally(_draft(STANDARD, (_move(8, "retract"),)))
    assert set(t.cut_m) == set(range(10))
    assert t.edge_m == pytest.approx(1e-3 * sum(STANDARD.values()))  # partial: cut_mm
    assert t.cut_m[8] == pytest.approx(0.2683) and t.failing == 10 and not t.runs
    whole = cut_tally(_draft({0: LOOP_MM, 1: 100.0}))
    assert whole.cut_m[0] == pytest.approx(1e-3 * LOOP_MM) and whole.runs and whole.failing == 1
    assert MOVE_KINDS >= {"approach", "retract", "transition", "home"}
    assert "window" not in MOVE_KINDS and "relaxation" not in MOVE_KINDS


def test_a_window_left_wholly_uncut_loses_though_fewer_windows_fail():
    """The long-reach plan cuts more edge in total but none of window 0, and the standard
    plan's failing move is repaired: 10 windows failing both (each cut in part, window 0
    uncut): the standard burr is kept."""
    std = _draft(STANDARD)
    alt = _draft(LONG, (_uncut(0),), tool=LONG_REACH)
    assert cut_tally(alt).edge_m > cut_tally(std).edge_m
    assert not better_cut(cut_tally(alt), cut_tally(std))
    kept = choose_tool(std, alt)
    assert kept.record.tool is None and kept.record.deviations == ()
    note = kept.failures[-1]
    assert note.kind == "relaxation" and "in 9 window(s)" in note.reason


def test_the_old_count_would_have_changed_the_burr_over_a_move_in_one_window():
    """Main's case: the move between window 8's runs failed (attributed to window -1: 11
    failing entries against 10). A move under the clearance is a program not run, so the
    plan whose moves keep it wins, whatever it cuts: that is why the move is repaired."""
    std = _draft(STANDARD, (_move(-1),))
    alt = _draft(LONG, (_uncut(0),), tool=LONG_REACH)
    assert better_cut(cut_tally(alt), cut_tally(std))
    kept = choose_tool(std, alt)
    assert kept.record.tool == LONG_REACH
    dev = kept.record.deviations[-1]
    assert dev.item == "burr" and "under the clearance" in dev.reason
    # both programs with a move under the clearance: what they cut decides
    alt_bad = _draft(LONG, (_uncut(0), _move(3, "approach")), tool=LONG_REACH)
    assert not better_cut(cut_tally(alt_bad), cut_tally(std))


@pytest.mark.parametrize("alt_cut, kept", [
    ({w: mm + 2 * EDGE_TIE * 1e3 for w, mm in STANDARD.items()}, "long_reach"),  # more edge
    (dict(STANDARD), "standard"),  # the same cut, the same failing windows: a tie
    ({**STANDARD, 4: LOOP_MM}, "long_reach"),  # window 4 whole: fewer fail
    ({**STANDARD, 4: LOOP_MM, 5: 10.0}, "standard"),  # fewer fail, but less edge
    ({w: LOOP_MM for w in range(9)}, "standard"),  # 9 whole windows, window 9 wholly uncut
])
def test_more_edge_or_fewer_failing_windows_wins_only_without_losing_a_window(alt_cut, kept):
    std = _draft(STANDARD)
    alt = _draft(alt_cut, tuple(_uncut(w) for w in range(10) if w not in alt_cut),
                 tool=LONG_REACH)
    got = choose_tool(std, alt)
    assert ("long_reach" if got.record.tool == LONG_REACH else "standard") == kept


def test_without_figures_the_failing_windows_decide_as_before():
    """Stand-in drafts without per-window figures: nothing counted as cut on either side,
    so fewer failing windows wins and a tie keeps the standard burr."""
    std = PlanDraft(failures=(_uncut(0), _uncut(1)))
    assert better_cut(cut_tally(PlanDraft(failures=(_uncut(1),))), cut_tally(std))
    assert not better_cut(cut_tally(PlanDraft(failures=(_uncut(2), _uncut(3)))),
                          cut_tally(std))


def test_the_failing_windows_first_keep_the_standard_burr_when_cut_no_better():
    """policy.long_reach_pass: the standard burr cuts windows 0-2 whole and 3, 4 in part;
    the long-reach burr, tried on windows 3 and 4 first, cuts window 4 whole but none of
    window 3 (fewer failing windows there, the old rule planned the hub again): it cannot
    cut the hub better, the standard plan is kept without planning the hub again. Cutting
    both whole, the hub is planned with it."""
    from drakedeburr.plan.policy import long_reach_pass

    std = _draft({0: LOOP_MM, 1: LOOP_MM, 2: LOOP_MM, 3: 200.0, 4: 100.0})
    made = []

    def plan_long_reach(only, first):
        made.append(only)
        return first if only is not None else _draft(
            {w: LOOP_MM for w in range(5)}, tool=LONG_REACH)

    worse = _draft({4: LOOP_MM}, (_uncut(3),), tool=LONG_REACH)
    kept = long_reach_pass(std, range(5), lambda only: plan_long_reach(only, worse))
    assert made == [{3, 4}] and kept.record.tool is None
    assert "cut them no better" in kept.failures[-1].reason
    made.clear()
    whole = _draft({3: LOOP_MM, 4: LOOP_MM}, tool=LONG_REACH)
    kept = long_reach_pass(std, range(5), lambda only: plan_long_reach(only, whole))
    assert made == [{3, 4}, None] and kept.record.tool == LONG_REACH
