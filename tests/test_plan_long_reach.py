"""The long-reach retry of the hub-level policy (policy.long_reach_pass): the windows the
standard burr left failing are planned first with the long-reach burr (placed for the whole
hub); the whole hub is planned again only when that cuts one of them, or when a move between
windows failed. Control flow with typed stand-in plans (PlanDraft); that a window's plan does
not depend on the others is tests/test_plan_parallel.py's."""

from __future__ import annotations

import pytest

from drakedeburr.plan.policy import long_reach_pass
from drakedeburr.plan.relax import LONG_REACH
from drakedeburr.plan.results import PlanDraft, PlanRecord
from drakedeburr.plan.types import FailureRecord


def _plan(failures: tuple, label: str = "") -> PlanDraft:
    """A plan with these failure records; ``label`` "long reach" is one made in the
    long-reach cell (its record names the burr), else the standard burr's."""
    return PlanDraft(failures=failures,
                     record=PlanRecord(tool=LONG_REACH if label == "long reach" else None))


def _label(plan: PlanDraft) -> str:
    return "long reach" if plan.record.tool == LONG_REACH else "standard"


def _fail(w: int, reason: str = "blocked") -> FailureRecord:
    return FailureRecord(window=w, kind="ik", reason=reason,
                         where={"pair": ("spindle::body/spindle::spindle_body", "hub::hub/hub::p")})


@pytest.fixture
def calls():
    """The long-reach cell's plans: each call's ``only`` recorded, its outcome from the table."""
    return [], {}


def _run(calls, standard, wts=(0, 1, 2, 3)):
    made, outcomes = calls

    def plan_long_reach(only):
        made.append(None if only is None else sorted(only))
        return outcomes["first" if only is not None else "full"]

    return long_reach_pass(standard, list(wts), plan_long_reach)


def test_failing_windows_first_and_no_full_pass_when_they_still_fail(calls):
    made, outcomes = calls
    standard = _plan(failures=(_fail(2),), label="standard")
    outcomes["first"] = _plan(failures=(_fail(2, "position/cone not met"),))
    kept = _run(calls, standard)
    assert made == [[2]]  # the other windows not planned again
    assert _label(kept) == "standard"
    note = kept.failures[-1]
    assert note.window == 2 and note.kind == "relaxation"
    assert "tried on window(s) [2] first" in note.reason
    assert note.reason.endswith("here: position/cone not met")


def test_the_hub_planned_again_when_the_long_reach_burr_cuts_a_failing_window(calls):
    made, outcomes = calls
    standard = _plan(failures=(_fail(1), _fail(2)), label="standard")
    outcomes["first"] = _plan(failures=(_fail(2),))  # window 1 cut
    outcomes["full"] = _plan(failures=(_fail(2),), label="long reach")
    chosen = _run(calls, standard)
    assert made == [[1, 2], None]
    assert _label(chosen) == "long reach"  # fewer windows failing
    assert chosen.record.deviations[-1].item == "burr"


def test_a_failed_move_between_windows_plans_the_hub_again(calls):
    made, outcomes = calls
    standard = _plan(failures=(_fail(2),), label="standard")
    outcomes["first"] = _plan(failures=(
        _fail(2), FailureRecord(window=-1, kind="transition", reason="no clear move")))
    outcomes["full"] = _plan(failures=(_fail(2),), label="long reach")
    kept = _run(calls, standard)
    assert made == [[2], None]
    assert _label(kept) == "standard"  # a tie keeps the standard burr
    assert "was tried for the hub" in kept.failures[-1].reason


def test_a_standard_plan_failing_between_windows_or_everywhere_goes_straight_to_the_hub(calls):
    made, outcomes = calls
    outcomes["full"] = _plan(failures=(), label="long reach")
    between = _plan(failures=(_fail(-1), _fail(2)), label="standard")
    assert _label(_run(calls, between)) == "long reach" and made == [None]
    made.clear()
    everywhere = _plan(failures=tuple(_fail(w) for w in range(4)), label="standard")
    assert _label(_run(calls, everywhere)) == "long reach" and made == [None]
