"""Drake model of the five-bar Cutting Tool, for Meshcat display and mounting on a flange.

The SDF (generated from :class:`FiveBarGeometry`, the default shipped as
``models/tools/five_bar_cutting_tool.sdf``) is an open tree: base -> crank_1 (``servo_1``)
-> link_1 (``passive_3``) and base -> crank_2 (``servo_2``) -> link_2 (``passive_4``); the
loop is closed at the head J5 by a ``drake:ball_constraint`` between link_1 and link_2
(active in a discrete SAP plant). The servos are actuated (effort limit 20 N m, assumed);
the passive joints have effort 0, so Drake adds no actuator for them. For display the four
joint angles are set from the closed-form kinematics (:func:`joint_positions`), so the
loop is closed exactly.

Frames: ``cutting_tool_base`` = C of :mod:`drakedeburr.laser.kinematics` (origin at servo
axis J1, linkage in the x-y plane, beam along +z); ``laser_tcp`` is on link_1 at J5, offset
``nozzle_length`` along +z (the cutting point).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drakedeburr._io import round_numbers
from drakedeburr.laser.kinematics import FiveBarGeometry, forward_kinematics

__all__ = ["five_bar_sdf", "joint_positions", "add_cutting_tool", "set_tool_positions",
           "JOINT_NAMES", "DEFAULT_SDF",
           "NOZZLE_LENGTH"]

DEFAULT_SDF = "tools/five_bar_cutting_tool.sdf"
NOZZLE_LENGTH = 0.080  # [m] J5 plane to the cutting point (focus), along +z of C
_THICK = 0.006  # [m] link plate thickness (display only)


def _box_link(name: str, length: float, direction: int, z: float, color: str,
              y0: float, extra: str = "") -> str:
    """A link body whose own frame sits at its proximal joint (at y = ``y0`` of the model
    frame when all joint angles are zero); it extends along ``direction`` * y."""
    cy = 0.5 * direction * length
    return f"""
    <link name="{name}"><pose>0 {y0} 0 0 0 0</pose>
      <inertial><pose>0 {cy} {z} 0 0 0</pose><mass>0.1</mass>
        <inertia><ixx>1e-5</ixx><iyy>1e-5</iyy><izz>1e-5</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
      <visual name="plate"><pose>0 {cy} {z} 0 0 0</pose>
        <geometry><box><size>0.010 {length} {_THICK}</size></box></geometry>
        <material><diffuse>{color}</diffuse></material></visual>{extra}
    </link>"""


def _joint(name: str, parent: str, child: str, effort: float) -> str:
    """A revolute joint about z at the child's frame; effort 0 = passive (no actuator)."""
    return f"""
    <joint name="{name}" type="revolute">
      <parent>{parent}</parent><child>{child}</child>
      <axis><xyz>0 0 1</xyz><limit><effort>{effort}</effort></limit></axis>
    </joint>"""


def five_bar_sdf(g: FiveBarGeometry | None = None, nozzle_length: float = NOZZLE_LENGTH) -> str:
    """SDF text of the Cutting Tool for geometry ``g`` (lengths in metres)."""
    g = g or FiveBarGeometry()
    z1, z2 = 0.5 * _THICK, 1.5 * _THICK  # cranks / links in two layers
    head = f"""
      <visual name="laser_head"><pose>0 {g.l3} {0.5 * nozzle_length} 0 0 0</pose>
        <geometry><cylinder><radius>0.012</radius><length>{nozzle_length}</length></cylinder>
        </geometry><material><diffuse>0.85 0.2 0.1 1</diffuse></material></visual>"""
    return round_numbers(f"""<?xml version="1.0"?>
<!-- Five-bar Cutting Tool (drakedeburr.laser.model.five_bar_sdf; source 004 Fig. 3).
     L0={g.l0} L1={g.l1} L2={g.l2} L3={g.l3} L4={g.l4} m. Generated, do not edit. -->
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
  <model name="cutting_tool">
    <link name="cutting_tool_base">
      <inertial><mass>2.0</mass>
        <inertia><ixx>1e-3</ixx><iyy>1e-3</iyy><izz>1e-3</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
      <visual name="housing"><pose>-0.030 {0.5 * g.l0} {-0.025} 0 0 0</pose>
        <geometry><box><size>0.050 {g.l0 + 0.060} 0.050</size></box></geometry>
        <material><diffuse>0.9 0.8 0.1 1</diffuse></material></visual>
    </link>{_box_link("crank_1", g.l1, -1, z1, "0.3 0.3 0.3 1", 0.0)}{
        _box_link("crank_2", g.l2, -1, z1, "0.3 0.3 0.3 1", g.l0)}{
        _box_link("link_1", g.l3, +1, z2, "0.6 0.6 0.7 1", -g.l1, head)}{
        _box_link("link_2", g.l4, -1, z2 + _THICK, "0.6 0.6 0.7 1", g.l0 - g.l2)}
{_joint("servo_1", "cutting_tool_base", "crank_1", 20)}{
        _joint("servo_2", "cutting_tool_base", "crank_2", 20)}{
        _joint("passive_3", "crank_1", "link_1", 0)}{
        _joint("passive_4", "crank_2", "link_2", 0)}
    <frame name="laser_tcp" attached_to="link_1">
      <pose relative_to="link_1">0 {g.l3} {nozzle_length} 0 0 0</pose>
    </frame>
    <drake:ball_constraint>
      <drake:ball_constraint_body_A>link_1</drake:ball_constraint_body_A>
      <drake:ball_constraint_body_B>link_2</drake:ball_constraint_body_B>
      <drake:ball_constraint_p_AP>0 {g.l3} 0</drake:ball_constraint_p_AP>
      <drake:ball_constraint_p_BQ>0 {-g.l4} 0</drake:ball_constraint_p_BQ>
    </drake:ball_constraint>
  </model>
</sdf>
""")


def joint_positions(g: FiveBarGeometry, q: np.ndarray) -> np.ndarray:
    """Model joint angles (servo_1, servo_2, passive_3, passive_4) [rad] for servo angles q.

    Args:
        q: (2,) or (N, 2) servo angles [rad].

    Returns:
        (4,) or (N, 4) joint angles; link_1 points along its +y (world angle -theta3),
        link_2 along its -y (world angle theta4).
    """
    q = np.asarray(q, dtype=float)
    st = forward_kinematics(g, np.atleast_2d(q))
    th1, th2 = st.q[:, 0], st.q[:, 1]
    out = np.stack([th1, th2, -st.theta3 - th1, st.theta4 - th2], axis=1)
    return out[0] if q.ndim == 1 else out


def add_cutting_tool(plant, g: FiveBarGeometry | None = None, parent_frame=None, X_PC=None,
                     sdf_path: str | Path | None = None):
    """Add the Cutting Tool to ``plant`` and weld its base C to ``parent_frame``.

    Args:
        plant: a MultibodyPlant before Finalize().
        g: geometry (generates the SDF); ignored when ``sdf_path`` is given.
        parent_frame: frame to weld to (e.g. the robot's ``flange``); world if None.
        X_PC: RigidTransform of C in the parent frame; identity if None.
        sdf_path: load this SDF file instead of generating one.

    Returns:
        the ModelInstanceIndex of the tool.
    """
    from pydrake.math import RigidTransform
    from pydrake.multibody.parsing import Parser

    parser = Parser(plant)
    parser.SetAutoRenaming(True)
    if sdf_path is not None:
        (model,) = parser.AddModels(str(sdf_path))
    else:
        (model,) = parser.AddModelsFromString(five_bar_sdf(g), "sdf")
    parent = parent_frame if parent_frame is not None else plant.world_frame()
    plant.WeldFrames(parent, plant.GetFrameByName("cutting_tool_base", model),
                     X_PC if X_PC is not None else RigidTransform())
    return model


JOINT_NAMES = ("servo_1", "servo_2", "passive_3", "passive_4")


def set_tool_positions(plant, context, model, g: FiveBarGeometry, q: np.ndarray) -> None:
    """Set the tool's four joints in ``context`` from servo angles q (2,) [rad]."""
    for name, angle in zip(JOINT_NAMES, joint_positions(g, q), strict=True):
        plant.GetJointByName(name, model).set_angle(context, float(angle))
