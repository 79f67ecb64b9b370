"""Meshcat scene of the Cutting Tool: the drawn TCP follows the planned cut."""

import numpy as np

import drakedeburr.laser.display as mut
from drakedeburr.laser import hole, shapes


def test_animation_tcp_follows_hole():
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    scene = mut.build_tool_scene(meshcat)
    prog = hole.plan_hole(shapes.Circle(diameter=0.008), spacing=0.5e-3)
    tcp = mut.animate_hole(scene, prog, meshcat, fps=500.0)
    r = np.linalg.norm(tcp[:, :2] - prog.geometry.p_CHome, axis=1)
    assert np.max(np.abs(r - 0.004)) < 0.1e-3
    assert meshcat.HasPath("/drakedeburr/laser_cut")


ROBOT_URDF = """<?xml version="1.0"?>
<robot name="toy_arm">
  <link name="base_link"/>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="flange"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="arm"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j_flange" type="fixed"><parent link="arm"/><child link="flange"/>
    <origin xyz="0.8 0 0" rpy="0 1.5707963267948966 0"/></joint>
</robot>
"""


def test_tool_on_a_robot_flange_reaches_the_hole(tmp_path):
    from pydrake.geometry import Meshcat
    from pydrake.math import RigidTransform, RollPitchYaw

    urdf = tmp_path / "toy.urdf"
    urdf.write_text(ROBOT_URDF)
    meshcat = Meshcat()
    scene = mut.build_tool_scene(meshcat, robot_model=urdf)
    plant = scene.plant
    ctx = plant.GetMyMutableContextFromRoot(scene.context)
    robot_q = np.array([0.4])
    g = scene.geometry
    from drakedeburr.laser.kinematics import inverse_kinematics

    q_home, _ = inverse_kinematics(g, g.p_CHome)
    scene.set_servo_angles(q_home[0], robot_q)
    X_WF = plant.GetFrameByName("flange", scene.robot).CalcPoseInWorld(ctx)
    X_WC = X_WF.multiply(mut.default_X_FC())
    # the TCP at home is where tool_base_pose_for_hole puts the hole
    X_WH = X_WC.multiply(RigidTransform([g.p_CHome[0], g.p_CHome[1], 0.080]))
    assert np.allclose(scene.tcp_in_world(), X_WH.translation(), atol=1e-12)
    X_WC2 = mut.tool_base_pose_for_hole(X_WH, g)
    assert X_WC2.IsNearlyEqualTo(X_WC, 1e-12)
    # a hole planned in H lands on the plate around H's origin
    X_WH_any = RigidTransform(RollPitchYaw(0.3, -0.2, 1.0), [0.7, 0.1, 0.2])
    X_WC_any = mut.tool_base_pose_for_hole(X_WH_any, g)
    prog = hole.plan_hole(shapes.Circle(diameter=0.006), spacing=0.5e-3)
    p_C = np.c_[prog.p_CJ5, np.full(len(prog.p_CJ5), 0.080)]
    p_H = X_WH_any.inverse().multiply(X_WC_any.multiply(p_C.T)).T
    assert np.allclose(p_H[:, 2], 0, atol=1e-12)
    assert np.allclose(np.linalg.norm(p_H[:, :2], axis=1), 0.003, atol=1e-12)


def test_tool_on_the_irb1600_flange_matches_analytic_fk():
    """The Cutting Tool on the real robot model: TCP = OPW FK(q) * X_FC * home point."""
    from pydrake.geometry import Meshcat
    from pydrake.math import RigidTransform

    from drakedeburr.laser.kinematics import inverse_kinematics
    from drakedeburr.resources import model_path
    from drakedeburr.robots import IRB1600_10_120, fk_opw

    meshcat = Meshcat()
    scene = mut.build_tool_scene(meshcat, robot_model=model_path("robots/irb1600_10_120.sdf"))
    g = scene.geometry
    q_servo, _ = inverse_kinematics(g, g.p_CHome)
    rng = np.random.default_rng(0)
    for _ in range(5):
        q_robot = rng.uniform(-1.0, 1.0, 6)
        scene.set_servo_angles(q_servo[0], q_robot)
        X_WF = RigidTransform(fk_opw(IRB1600_10_120, q_robot))
        X_WTcp = X_WF.multiply(mut.default_X_FC()).multiply(
            RigidTransform([g.p_CHome[0], g.p_CHome[1], 0.080]))
        assert np.allclose(scene.tcp_in_world(), X_WTcp.translation(), atol=1e-9)
