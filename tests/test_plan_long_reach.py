"""The long-reach retry of plan_hub (planner._long_reach): the windows the standard burr left
failing are planned first with the long-reach burr (placed for the whole hub); the whole hub
is planned again only when that cuts one of them, or when a move between windows failed.
Control flow with stand-in plans; that a window's plan does not depend on the others is
tests/test_plan_parallel.py's."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from drakedeburr.plan import planner
from drakedeburr.plan.types import FailureRecord


@dataclass(frozen=True)
class _Plan:
    failures: tuple
    meta: dict = field(default_factory=dict)
    run: dict = field(default_factory=lambda: {"timings": {}})
    label: str = ""


def _fail(w: int, reason: str = "blocked") -> FailureRecord:
    return FailureRecord(window=w, kind="ik", reason=reason,
                         where={"pair": ("spindle::body/spindle::spindle_body", "hub::hub/hub::p")})


@pytest.fixture
def calls(monkeypatch):
    """Replace the cell build and the per-cell planning; record each call's ``only``."""
    from drakedeburr.cell import station

    made: list = []
    outcomes: dict = {}

    def plan_in_cell(cell, hub_model, wts, config, options, progress, only=None):
        made.append(None if only is None else sorted(only))
        return outcomes["first" if only is not None else "full"]

    monkeypatch.setattr(station, "load_cell", lambda *a, **k: "long-reach cell")
    monkeypatch.setattr(planner, "_plan_in_cell", plan_in_cell)
    return made, outcomes


class _Config:
    scenario, hub, robot = "tool_in_hand", "hub", None


def _run(standard, wts=(0, 1, 2, 3)):
    class _Wt:
        def __init__(self, w):
            self.window_index = w

    return planner._long_reach(standard, None, [_Wt(w) for w in wts], _Config(), None, None)


def test_failing_windows_first_and_no_full_pass_when_they_still_fail(calls):
    made, outcomes = calls
    standard = _Plan(failures=(_fail(2),), label="standard")
    outcomes["first"] = _Plan(failures=(_fail(2, "position/cone not met"),))
    kept = _run(standard)
    assert made == [[2]]  # the other windows not planned again
    assert kept.label == "standard"
    note = kept.failures[-1]
    assert note.window == 2 and note.kind == "relaxation"
    assert "tried on window(s) [2] first" in note.reason
    assert note.reason.endswith("here: position/cone not met")


def test_the_hub_planned_again_when_the_long_reach_burr_cuts_a_failing_window(calls):
    made, outcomes = calls
    standard = _Plan(failures=(_fail(1), _fail(2)), label="standard")
    outcomes["first"] = _Plan(failures=(_fail(2),))  # window 1 cut
    outcomes["full"] = _Plan(failures=(_fail(2),), label="long reach")
    chosen = _run(standard)
    assert made == [[1, 2], None]
    assert chosen.label == "long reach"  # fewer windows failing
    assert chosen.meta["recipe_deviations"][-1]["item"] == "burr"


def test_a_failed_move_between_windows_plans_the_hub_again(calls):
    made, outcomes = calls
    standard = _Plan(failures=(_fail(2),), label="standard")
    outcomes["first"] = _Plan(failures=(
        _fail(2), FailureRecord(window=-1, kind="transition", reason="no clear move")))
    outcomes["full"] = _Plan(failures=(_fail(2),), label="long reach")
    kept = _run(standard)
    assert made == [[2], None]
    assert kept.label == "standard"  # a tie keeps the standard burr
    assert "was tried for the hub" in kept.failures[-1].reason


def test_a_standard_plan_failing_between_windows_or_everywhere_goes_straight_to_the_hub(calls):
    made, outcomes = calls
    outcomes["full"] = _Plan(failures=(), label="long reach")
    between = _Plan(failures=(_fail(-1), _fail(2)), label="standard")
    assert _run(between).label == "long reach" and made == [None]
    made.clear()
    everywhere = _Plan(failures=tuple(_fail(w) for w in range(4)), label="standard")
    assert _run(everywhere).label == "long reach" and made == [None]
