"""The milder recipes reuse the first pass's CL points (plan.relax.window_ladder with ``cl``,
plan.relax.oriented, plan.relax.first_cl_paths, plan.planner.cell_passes): the path stage
reads only the edge, so each tilt box's targets from the first pass's ClPath equal those the
full path + orientation chain (plan.tool_paths.tool_path) makes for that box, array for array.
"""

from __future__ import annotations

import functools
from types import SimpleNamespace

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.plan.relax import first_cl_paths, plan_ladder, window_ladder
from drakedeburr.plan.results import WindowPlan, WindowStatus
from drakedeburr.plan.tool_paths import tool_path
from drakedeburr.plan.types import FailureRecord
from drakedeburr.plan.window_targets import WindowTargets

ARRAYS = ("p_HC", "n_H", "t_H", "retract_H", "cone_retract_H")


@functools.cache
def _edge():
    from drakedeburr.hub import load_hub

    return next(w for w in load_hub("h5_split").windows if w.kind == "large")


def _failing(wt) -> WindowPlan:
    """Every box fails, so the whole ladder is made (what a refused window's ladder does)."""
    return WindowPlan(wt.window_index, WindowStatus.IK_FAILED,
                      failures=[FailureRecord(window=wt.window_index, kind="window",
                                              reason="stand-in")])


def test_each_box_from_the_first_pass_cl_equals_the_full_chain():
    edge, params = _edge(), ProcessParameters()
    first = WindowTargets.from_tool_path(tool_path(edge, params))
    cls = first_cl_paths([first])
    assert set(cls) == {edge.index}
    anew = window_ladder(edge, params, _failing)
    reused = window_ladder(edge, params, _failing, cls[edge.index])
    assert len(anew) == len(reused) >= 2
    for (box_a, wt_a, _), (box_b, wt_b, _) in zip(anew, reused, strict=True):
        assert box_a == box_b
        assert (wt_a is None) == (wt_b is None)
        if wt_a is None:
            continue
        assert len(wt_a) == len(wt_b)
        for name in ARRAYS:
            np.testing.assert_array_equal(getattr(wt_a, name), getattr(wt_b, name), name)
        assert wt_a.cone_half_angle == wt_b.cone_half_angle
        # and the reused box is not the recipe's own: the orientation did read the box
        assert not np.array_equal(wt_b.retract_H, first.retract_H)
        # geometric truth: the tool axes are unit vectors inside the box's enclosing cone
        # about the cone axis
        np.testing.assert_allclose(np.linalg.norm(wt_b.retract_H, axis=1), 1.0, atol=1e-9)
        cosang = np.einsum("ij,ij->i", wt_b.retract_H, wt_b.cone_retract_H) / np.linalg.norm(
            wt_b.cone_retract_H, axis=1)
        assert np.all(np.arccos(np.clip(cosang, -1, 1)) <= wt_b.cone_half_angle + 1e-6)


def test_plan_ladder_takes_the_cl_and_the_old_item_form(monkeypatch):
    edge, params = _edge(), ProcessParameters()
    cl = first_cl_paths([WindowTargets.from_tool_path(tool_path(edge, params))])[edge.index]
    seen = []

    def fake_plan_window(ctx, wt, mode):
        seen.append(len(wt))
        return _failing(wt)

    monkeypatch.setattr("drakedeburr.plan.window.plan_window", fake_plan_window)
    with_cl = plan_ladder(SimpleNamespace(), (edge, params, cl))
    without = plan_ladder(SimpleNamespace(), (edge, params))
    assert [b for b, _, _ in with_cl] == [b for b, _, _ in without]
    assert seen[:len(with_cl)] == seen[len(with_cl):]


def test_targets_without_a_tool_path_give_no_cl():
    assert first_cl_paths([SimpleNamespace(window_index=3, tool_path=None)]) == {}
