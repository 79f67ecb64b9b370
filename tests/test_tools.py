"""Tool models: generated files are current; frame T matches the burr geometry."""

import math

import numpy as np
import pytest
import trimesh
from pydrake.geometry import Role, SceneGraph
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

import drakedeburr.cell.tools as mut
from drakedeburr.resources import add_package_to, model_path


def test_committed_tool_models_are_generated_from_the_dataclasses():
    for name, text in mut.tool_model_texts().items():
        assert model_path(f"tools/{name}").read_text() == text, (
            f"models/tools/{name} is stale: run `python -m drakedeburr.cell`")


def test_write_tool_models(tmp_path):
    paths = mut.write_tool_models(tmp_path)
    assert sorted(p.name for p in paths) == sorted(mut.tool_model_texts())


def test_burr_geometry_derived_numbers():
    b = mut.BURR
    assert b.cone_half_angle == pytest.approx(math.pi / 4)
    assert b.head_length == pytest.approx(b.head_radius)  # 90 deg cone
    assert b.apex_offset == pytest.approx(b.contact_radius)
    assert b.flank_radius(0.0) == pytest.approx(b.contact_radius)
    assert b.flank_radius(b.apex_offset) == pytest.approx(0.0)
    assert np.isnan(b.flank_radius(b.apex_offset + 1e-3))
    assert b.z_tool_tip < b.z_apex


def test_burr_geometry_validates():
    with pytest.raises(ValueError, match="contact_radius"):
        mut.BurrGeometry(contact_radius=0.01)
    with pytest.raises(ValueError, match="cone_half_angle"):
        mut.BurrGeometry(cone_half_angle=2.0)


def _tool_plant(relative):
    plant = MultibodyPlant(0.0)
    scene_graph = SceneGraph()
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (model,) = parser.AddModels(str(model_path(relative)))
    plant.Finalize()
    return plant, scene_graph, model


@pytest.mark.parametrize("relative,base", [("tools/floating_spindle.sdf", "spindle"),
                                           ("tools/spindle_stand.sdf", "stand")])
def test_tool_frame_convention_against_burr_mesh(relative, base):
    """+Z_T points from the spindle body to the tip; the flank radius at T is contact_radius."""
    plant, scene_graph, model = _tool_plant(relative)
    context = plant.CreateDefaultContext()
    M = plant.GetBodyByName(base, model).body_frame()
    X_MT = plant.GetFrameByName("tool_tip", model).CalcPose(context, M)
    X_MA = plant.GetFrameByName("burr_apex", model).CalcPose(context, M)
    z_T = X_MT.rotation().matrix()[:, 2]
    b = mut.BURR
    # apex ahead of T along +Z_T by apex_offset, same orientation
    np.testing.assert_allclose(X_MA.translation() - X_MT.translation(), b.apex_offset * z_T,
                               atol=1e-12)
    inspector = scene_graph.model_inspector()
    burr = plant.GetBodyByName("burr", model)
    by_name = {inspector.GetName(g).split("::")[-1]: g
               for g in plant.GetCollisionGeometriesForBody(burr)}
    by_name.update({inspector.GetName(g).split("::")[-1]: g
                    for g in plant.GetCollisionGeometriesForBody(plant.GetBodyByName(base, model))})
    # spindle body centre lies behind T on the axis: (p_T - p_C) is along +Z_T
    X_BC = inspector.GetPoseInFrame(by_name["spindle_body"])
    X_MB = plant.GetBodyByName(base, model).body_frame().CalcPose(context, M)
    p_MC = X_MB.multiply(X_BC.translation())
    d = X_MT.translation() - p_MC
    assert np.linalg.norm(np.cross(d, z_T)) <= 1e-12 and d @ z_T > 0.1
    # the cone mesh, expressed in T: apex at +apex_offset, radius(z) = flank_radius(z)
    mesh = trimesh.load(model_path("tools/burr_head.obj"), force="mesh")
    X_BurrHead = inspector.GetPoseInFrame(by_name["burr_head"])
    X_MBurr = burr.body_frame().CalcPose(context, M)
    X_TG = X_MT.inverse().multiply(X_MBurr).multiply(X_BurrHead)
    v_T = X_TG.multiply(np.asarray(mesh.vertices).T).T
    radius = np.hypot(v_T[:, 0], v_T[:, 1])
    apex = np.argmax(v_T[:, 2])
    np.testing.assert_allclose(v_T[apex], [0, 0, b.apex_offset], atol=1e-9)
    rim = radius > 1e-9
    np.testing.assert_allclose(radius[rim], b.head_radius, atol=1e-9)
    np.testing.assert_allclose(radius[rim], b.flank_radius(v_T[rim, 2]), atol=1e-9)
    assert mesh.is_watertight and mesh.is_convex
    # the cutting head is its own collision geometry (so the planner can filter it)
    assert {"burr_head", "burr_shank", "spindle_body"} <= set(by_name)
    assert inspector.GetProximityProperties(by_name["burr_head"]) is not None
    assert Role.kProximity in (Role.kProximity,)


def test_floating_spindle_mount_angle():
    plant, _, model = _tool_plant("tools/floating_spindle.sdf")
    context = plant.CreateDefaultContext()
    M = plant.GetBodyByName("spindle", model).body_frame()  # = flange frame F when welded
    X_FT = plant.GetFrameByName("tool_tip", model).CalcPose(context, M)
    z_T = X_FT.rotation().matrix()[:, 2]
    assert math.degrees(math.acos(z_T[2])) == pytest.approx(45.0, abs=1e-9)
    np.testing.assert_allclose(X_FT.translation(), mut.FLOATING_SPINDLE.p_FT, atol=1e-9)
    np.testing.assert_allclose(mut.X_FS_floating()[:3, 2], z_T, atol=1e-12)
