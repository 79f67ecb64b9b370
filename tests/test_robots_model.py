"""The arm model layout (robots/model.py) and the hand-written IRB1600-10/1.2 model against the
reference kinematics and the OPW forward map (the other arms: tests/test_robots_arms.py)."""

import json

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

import drakedeburr.robots.model as mut
from drakedeburr.resources import add_package_to, model_path, models_dir, resolve_package_url
from drakedeburr.robots import IRB1600, IRB1600_10_120, fk_opw

IRB1600_FILE = resolve_package_url(IRB1600.model_url)


def _robot_plant():
    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (robot,) = parser.AddModels(str(IRB1600_FILE))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(mut.BASE_FRAME_NAME, robot))
    plant.Finalize()
    return plant, robot


@pytest.mark.parametrize(
    "relative",
    sorted(str(p.relative_to(models_dir()))
           for sub in ("robots", "tools", "fixtures") for p in (models_dir() / sub).glob("*.sdf")),
)
def test_every_model_file_parses(relative):
    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    models = parser.AddModels(str(model_path(relative)))
    assert models
    plant.Finalize()
    assert plant.num_bodies() > 1


def test_joint_order_and_limits_match_reference(extdata):
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    joints = ref["urdf_joints"]["ABB_IRB1600_6_12"]["joints"]
    plant, robot = _robot_plant()
    assert plant.num_positions() == 6
    for i, name in enumerate(mut.JOINT_NAMES):
        joint = plant.GetJointByName(name, robot)
        assert joint.position_start() == i
        np.testing.assert_allclose(joint.revolute_axis(), joints[i]["axis"], atol=0)
        assert joint.position_lower_limits()[0] == pytest.approx(joints[i]["lower_rad"], abs=1e-12)
        assert joint.position_upper_limits()[0] == pytest.approx(joints[i]["upper_rad"], abs=1e-12)
    np.testing.assert_allclose(plant.GetPositionLowerLimits(), IRB1600.q_lower, atol=1e-12)
    np.testing.assert_allclose(plant.GetPositionUpperLimits(), IRB1600.q_upper, atol=1e-12)
    # 10 kg variant speeds (an inference, see the model header)
    np.testing.assert_allclose(np.degrees(plant.GetVelocityUpperLimits()),
                               [180, 180, 185, 385, 400, 460], atol=1e-9)
    np.testing.assert_allclose(plant.GetVelocityLowerLimits(), -IRB1600.v_max)
    np.testing.assert_allclose(plant.GetAccelerationUpperLimits(), IRB1600.a_max)
    np.testing.assert_allclose(plant.GetAccelerationLowerLimits(), -IRB1600.a_max)


def test_joint_origins_match_reference_chain(extdata):
    """Joint i's axis passes through the cumulative origin sum of the reference URDF at q = 0."""
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    joints = ref["urdf_joints"]["ABB_IRB1600_6_12"]["joints"]
    plant, robot = _robot_plant()
    context = plant.CreateDefaultContext()
    p = np.zeros(3)
    for i, name in enumerate(mut.JOINT_NAMES):
        p = p + np.asarray(joints[i]["origin_xyz_m"])
        X_WJ = plant.GetJointByName(name, robot).frame_on_child().CalcPoseInWorld(context)
        np.testing.assert_allclose(X_WJ.translation(), p, atol=1e-12)


def test_flange_at_zero_is_tool0():
    plant, robot = _robot_plant()
    context = plant.CreateDefaultContext()
    X_WF = plant.GetFrameByName(mut.FLANGE_FRAME_NAME, robot).CalcPoseInWorld(context)
    np.testing.assert_allclose(X_WF.translation(), [0.815, 0.0, 0.9615], atol=1e-12)
    np.testing.assert_allclose(X_WF.rotation().matrix()[:, 2], [1.0, 0.0, 0.0], atol=1e-12)


def test_fk_equals_opw_at_random_configurations():
    plant, robot = _robot_plant()
    context = plant.CreateDefaultContext()
    flange = plant.GetFrameByName(mut.FLANGE_FRAME_NAME, robot)
    rng = np.random.default_rng(0)
    qs = rng.uniform(plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits(), (150, 6))
    X_opw = fk_opw(IRB1600_10_120, qs)
    worst_p = worst_R = 0.0
    for q, X_ref in zip(qs, X_opw, strict=True):
        plant.SetPositions(context, q)
        X = flange.CalcPoseInWorld(context).GetAsMatrix4()
        worst_p = max(worst_p, np.linalg.norm(X[:3, 3] - X_ref[:3, 3]))
        worst_R = max(worst_R, np.abs(X[:3, :3] - X_ref[:3, :3]).max())
    assert worst_p <= 1e-9
    assert worst_R <= 1e-9


def test_links_have_collision_geometry_and_plausible_mass():
    plant = MultibodyPlant(0.0)
    from pydrake.geometry import SceneGraph

    scene_graph = SceneGraph()
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (robot,) = parser.AddModels(str(IRB1600_FILE))
    plant.Finalize()
    total = 0.0
    for index in plant.GetBodyIndices(robot):
        body = plant.get_body(index)
        if body.name() == "world":
            continue
        assert plant.GetCollisionGeometriesForBody(body), body.name()
        assert body.default_mass() > 0
        total += body.default_mass()
    assert 150.0 < total < 300.0  # catalogue: about 250 kg


def test_read_model_limits_of_every_registered_arm():
    from drakedeburr.robots import ROBOTS

    for spec in ROBOTS.values():
        lim = mut.read_model_limits(resolve_package_url(spec.model_url))
        np.testing.assert_allclose(lim.q_lower, spec.q_lower, atol=1e-12, err_msg=spec.name)
        np.testing.assert_allclose(lim.q_upper, spec.q_upper, atol=1e-12, err_msg=spec.name)
        np.testing.assert_allclose(lim.v_max, spec.v_max, atol=1e-12, err_msg=spec.name)
        np.testing.assert_allclose(lim.a_max, spec.a_max, atol=1e-12, err_msg=spec.name)
