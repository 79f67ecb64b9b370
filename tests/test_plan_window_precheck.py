"""The tool pre-check searched point by point (plan.window.blocked_anywhere): one CL target's
cone search reads that target alone, so the targets searched one at a time give the whole
window's search (plan.clearance.tool_axis_clearance) array for array; a refusal names a
target the whole search proves blocked, with its clearance; a window none is proven at keeps
that search for plan.window.tool_refusal (not searched again)."""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from drakedeburr.plan import window
from drakedeburr.plan.clearance import tool_axis_clearance, tool_scene
from drakedeburr.plan.options import PlanOptions


@functools.cache
def _setup():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import load_config
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.planner import placed_cell
    from drakedeburr.plan.window_targets import WindowTargets

    config = load_config("tool_in_hand", "h5_straight")
    hub = load_hub("h5_straight")
    wt = WindowTargets.from_window_edge(hub.windows[0]).stretch(0, 10)
    cell = load_cell("tool_in_hand", "h5_straight")
    ctx = placed_cell(cell, hub, [wt], config, PlanOptions(placement=False, relax=False)).ctx
    return ctx, wt


def _full(ctx, wt):
    t = window.cut_targets(ctx, wt, np.zeros((len(wt), 3)))
    return tool_axis_clearance(tool_scene(ctx.checker), wt, t.p_HQ[:len(wt)], t.lift,
                               bound=ctx.min_clearance, margin=window.REFUSAL_MARGIN)


def test_a_clear_window_is_searched_whole_and_kept_for_the_refusal(monkeypatch):
    ctx, wt = _setup()
    assert window.blocked_anywhere(ctx, wt) is None
    full = _full(ctx, wt)
    assert not full.proven.any()
    t = window.cut_targets(ctx, wt, np.zeros((len(wt), 3)))
    key = window._search_key(wt, t.p_HQ[:len(wt)], t.lift, ctx.min_clearance)
    kept = window._SEARCHES[tool_scene(ctx.checker)][key]
    for name in ("best", "best_axis_H", "proven", "reads"):
        np.testing.assert_array_equal(getattr(kept, name), getattr(full, name), name)
    assert kept.part == full.part and kept.half_angle == full.half_angle
    # geometric truth: each target's best axis lies in its cone, and clears the bound
    cos = np.einsum("ij,ij->i", kept.best_axis_H, wt.cone_retract_H) / np.linalg.norm(
        wt.cone_retract_H, axis=1)
    assert np.all(np.arccos(np.clip(cos, -1, 1)) <= wt.cone_half_angle + 1e-9)
    assert np.all(kept.best >= ctx.min_clearance)
    # tool_refusal reads the kept search: not searched again
    monkeypatch.setattr("drakedeburr.plan.clearance.tool_axis_clearance",
                        lambda *a, **k: (_ for _ in ()).throw(AssertionError("searched")))
    assert window.tool_refusal(ctx, wt) is None


def test_the_first_proven_target_is_one_the_whole_search_proves():
    ctx, wt = _setup()
    # a clearance no axis keeps from the hub at the tool's contact: every target blocked
    far = replace(ctx, config=replace(ctx.config, tolerances=replace(
        ctx.config.tolerances, min_clearance=0.05)))
    full = _full(far, wt)
    assert full.proven.any()
    first = int(np.flatnonzero(full.proven)[-1])
    rec = window.blocked_anywhere(far, wt, first=[first])
    assert rec is not None and rec.point == first and rec.where["blocked_points"] == [first]
    assert rec.value == full.best[first] and rec.value < 0.05 - window.REFUSAL_MARGIN
    assert rec.where["pair"][0] == f"tool::{full.part[first]}"
    # in loop order: the first target the whole search proves
    rec = window.blocked_anywhere(far, wt)
    assert rec.point == int(np.flatnonzero(full.proven)[0])
