"""plan.window.tool_refusal: the pre-check's cone search is made once per tool scene and
window targets in a process (the policy's passes ask it again with the same inputs: first
pass, milder recipes, report-only pass); a change of any input it reads searches again, and a
reused search gives the very record a fresh one gives."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

import drakedeburr.plan.window as mut
from drakedeburr.resources import hub_names


def test_the_search_is_reused_for_the_same_targets_only(monkeypatch):
    if not hub_names():
        pytest.skip("no bundled hub models")
    import drakedeburr.plan.clearance as clearance
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import default_tolerances
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.planner import window_targets_for_hub

    cell = load_cell("tool_in_hand", DEFAULT_HUB)
    wt = window_targets_for_hub(load_hub(DEFAULT_HUB), source="toolpath", windows=[0])[0]
    ctx = PlanContext(cell=cell, kin=cell_kinematics(cell), checker=ClearanceChecker(cell),
                      free_checker=None,
                      config=SimpleNamespace(tolerances=default_tolerances()),
                      options=PlanOptions())
    real, calls = clearance.tool_axis_clearance, []

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(clearance, "tool_axis_clearance", counted)
    # a cone so wide and a bound so large that some targets are refused: a record to compare
    wide = replace(ctx, config=SimpleNamespace(tolerances=replace(
        default_tolerances(), min_clearance=0.008)))
    first = mut.tool_refusal(wide, wt)
    again = mut.tool_refusal(wide, wt)
    assert len(calls) == 1
    assert first is not None and again == first and again.where == first.where
    moved = replace(wt, cone_half_angle=0.5 * wt.cone_half_angle)
    mut.tool_refusal(wide, moved)
    mut.tool_refusal(ctx, wt)  # another bound
    assert len(calls) == 3
    fresh = ClearanceChecker(cell)  # another scene: searched again, the same record
    assert mut.tool_refusal(replace(wide, checker=fresh), wt) == first and len(calls) == 4
    assert np.array_equal(first.where["blocked_points"], again.where["blocked_points"])
