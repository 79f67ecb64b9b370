"""Burr variants (cell.tools.TOOL_VARIANTS): the long-reach burr moves the spindle body back
along the burr axis and nothing else; cells, plans, fingerprints and programs carry the
variant; on a deep dish it clears targets the standard burr's spindle body cannot."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from drakedeburr.cell.station import load_cell
from drakedeburr.cell.tools import DEFAULT_TOOL, TOOL_VARIANTS, tool_variant
from drakedeburr.errors import InputError

EXTRA = TOOL_VARIANTS["long_reach"].burr.stick_out - TOOL_VARIANTS["standard"].burr.stick_out


@functools.cache
def _cell(scenario: str, tool: str | None):
    return load_cell(scenario, "h5_deepdish", tool=tool)


def _pose(cell, frame_name: str, q):
    ctx = cell.plant.CreateDefaultContext()
    cell.plant.SetPositions(ctx, q)
    return cell.plant.GetFrameByName(frame_name).CalcPoseInWorld(ctx).GetAsMatrix4()


def _geometry_in_T(cell, name: str, q) -> np.ndarray:
    """Pose of a named collision geometry of the tool model in T, from the scene graph."""
    ctx = cell.create_context(q)
    sg_ctx = cell.scene_graph.GetMyContextFromRoot(ctx)
    query = cell.scene_graph.get_query_output_port().Eval(sg_ctx)
    inspector = query.inspector()
    gid = next(g for g in inspector.GetAllGeometryIds() if inspector.GetName(g).endswith(name))
    X_WG = query.GetPoseInWorld(gid).GetAsMatrix4()
    return np.linalg.inv(_pose(cell, "tool_tip", q)) @ X_WG


def test_variants_share_the_head_and_differ_in_stick_out():
    std, lr = tool_variant(None), tool_variant("long_reach")
    assert std.name == DEFAULT_TOOL and tool_variant("standard") is std
    assert EXTRA == pytest.approx(50e-3)
    for f in ("cone_half_angle", "head_diameter", "contact_radius", "shank_diameter"):
        assert getattr(lr.burr, f) == getattr(std.burr, f)
    assert lr.burr.z_tool_tip - std.burr.z_tool_tip == pytest.approx(EXTRA)
    with pytest.raises(ValueError, match="unknown tool"):
        tool_variant("bogus")


@pytest.mark.parametrize("scenario", ["tool_in_hand", "workpiece_in_hand"])
def test_long_reach_moves_the_tool_body_back_along_the_axis(scenario):
    std, lr = _cell(scenario, None), _cell(scenario, "long_reach")
    assert (std.tool, lr.tool) == ("standard", "long_reach")
    q = std.q_home
    X_std, X_lr = _pose(std, "tool_tip", q), _pose(lr, "tool_tip", q)
    # T keeps its orientation and moves EXTRA along its own +Z (out of the spindle)
    np.testing.assert_allclose(X_lr[:3, :3], X_std[:3, :3], atol=1e-12)
    np.testing.assert_allclose(X_lr[:3, 3] - X_std[:3, 3], EXTRA * X_std[:3, 2], atol=1e-12)
    # seen from T, the spindle body is EXTRA further back, the head where it was
    for name, shift in (("spindle_body", -EXTRA), ("burr_head", 0.0)):
        G_std, G_lr = _geometry_in_T(std, name, q), _geometry_in_T(lr, name, q)
        np.testing.assert_allclose(G_lr[:3, 3] - G_std[:3, 3], [0, 0, shift], atol=1e-12)
    assert lr.flange_loads().tool_mass == std.flange_loads().tool_mass


def test_a_variant_needs_the_bundled_spindle(tmp_path):
    from drakedeburr.resources import model_path

    with pytest.raises(InputError, match="unknown tool 'bogus'"):
        load_cell("tool_in_hand", "h5_straight", tool="bogus")
    # a user scenario carrying its own tool model: no variant of it exists
    own = tmp_path / "spindle.sdf"
    own.write_text(model_path("tools/floating_spindle.sdf").read_text())
    text = model_path("scenarios/tool_in_hand.yaml").read_text().replace(
        "package://drakedeburr/tools/floating_spindle.sdf", own.as_uri())
    scenario = tmp_path / "cell.yaml"
    scenario.write_text(text)
    assert load_cell(scenario, "h5_straight").tool is None
    with pytest.raises(InputError, match="no bundled spindle model"):
        load_cell(scenario, "h5_straight", tool="long_reach")


def test_the_cell_fingerprint_names_the_variant():
    from drakedeburr.cell.fingerprint import cell_fingerprint

    base = cell_fingerprint("tool_in_hand", "h5_straight", None)
    assert cell_fingerprint("tool_in_hand", "h5_straight", None, "standard") == base
    assert cell_fingerprint("tool_in_hand", "h5_straight", None, "long_reach") != base


def test_on_a_deep_dish_the_long_reach_clears_what_the_spindle_body_blocks():
    """h5_deepdish window 4 at the source's tilt box: the standard burr's spindle body meets
    the dish at a stretch of targets whatever the axis in the cone and the spin; with the
    long-reach burr every target has a pose, re-checked here by FK and Drake's distance."""
    from drakedeburr.config import ProcessParameters
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.ik import IkOptions
    from drakedeburr.plan.ik_seeds import IkTarget, _probe
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    wt = window_targets_for_hub(load_hub("h5_deepdish"), source="toolpath", windows=[4],
                                params=ProcessParameters())[0]
    r_c, lift = contact_geometry(PlanOptions().contact_radius)
    p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    opt = IkOptions()
    blocked = {}
    for tool in ("standard", "long_reach"):
        cell = _cell("tool_in_hand", tool)
        kin, checker = cell_kinematics(cell), ClearanceChecker(cell)
        for i in range(0, len(wt), 2):
            r = _probe(kin, checker, cell.q_home, IkTarget(
                p_HQ[i], wt.cone_retract_H[i], wt.retract_H[i], wt.t_H[i]), wt.cone_half_angle,
                opt.probe_settings(lift))
            if not r.feasible:
                blocked.setdefault(tool, []).append((i, r.pair))
                continue
            if tool == "standard":
                continue
            # independent re-check of the long-reach pose: the tool point on its target, the
            # axis in the cone, Drake's signed distance above the limit
            X_HT = np.linalg.inv(_pose(cell, "hub", r.q)) @ _pose(cell, "tool_tip", r.q)
            p_HT = X_HT[:3, 3] + lift * X_HT[:3, 2]
            assert np.linalg.norm(p_HT - p_HQ[i]) < 1e-6
            cos = float(-X_HT[:3, 2] @ wt.cone_retract_H[i])
            assert cos >= np.cos(wt.cone_half_angle) - 1e-6
            assert cell.min_distance(r.q)[0] >= opt.min_distance_floor - 1e-6
    std_blocked = blocked.get("standard", [])
    assert len(std_blocked) >= 3, std_blocked
    assert all("spindle_body" in " ".join(pair) for _, pair in std_blocked)
    assert "long_reach" not in blocked, blocked.get("long_reach")
