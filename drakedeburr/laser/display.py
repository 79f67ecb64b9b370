"""Meshcat display of the Cutting Tool (alone or on the robot flange) and of a cut.

``robot_model`` mounts the tool on a robot: the tool base C is welded to the robot's
``flange`` frame with ``X_FC`` (default: C origin 60 mm out along the flange z axis, beam
along flange z). The robot model (``models/robots/irb1600_10_120.sdf``) comes from the cell
stage; without it the tool is shown standalone at ``X_WC``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.laser.kinematics import FiveBarGeometry
from drakedeburr.laser.model import add_cutting_tool, set_tool_positions

__all__ = ["ToolScene", "build_tool_scene", "animate_hole", "default_X_FC",
           "tool_base_pose_for_hole"]


def default_X_FC():
    """Tool base C in the robot flange frame F: 60 mm along F's z, axes aligned."""
    from pydrake.math import RigidTransform

    return RigidTransform([0.0, 0.0, 0.060])


def tool_base_pose_for_hole(X_WH, g: FiveBarGeometry | None = None,
                            nozzle_length: float | None = None):
    """Pose X_WC of the tool base so that the TCP at the tool's home point is at the hole.

    Args:
        X_WH: RigidTransform of the hole frame H: origin at the hole's shape origin on the
            plate, +z along the beam (into the plate), x-y = the shape's x-y.
        g: tool geometry.
        nozzle_length: J5 plane to TCP [m] (default the model's).

    Returns:
        RigidTransform X_WC; the robot must hold the flange at X_WC * X_FC^-1.
    """
    from pydrake.math import RigidTransform

    from drakedeburr.laser.model import NOZZLE_LENGTH

    g = g or FiveBarGeometry()
    L = NOZZLE_LENGTH if nozzle_length is None else nozzle_length
    return X_WH.multiply(RigidTransform([-g.p_CHome[0], -g.p_CHome[1], -L]))


@dataclass
class ToolScene:
    """A built display diagram (mutable: it owns contexts)."""

    diagram: object
    plant: object
    tool: object
    robot: object | None
    visualizer: object
    context: object
    geometry: FiveBarGeometry

    def set_servo_angles(self, q: np.ndarray, robot_q: np.ndarray | None = None) -> None:
        """Pose the tool by servo angles q (2,) [rad] (and the robot joints) and publish."""
        plant_ctx = self.plant.GetMyMutableContextFromRoot(self.context)
        set_tool_positions(self.plant, plant_ctx, self.tool, self.geometry, q)
        if self.robot is not None and robot_q is not None:
            self.plant.SetPositions(plant_ctx, self.robot, robot_q)
        self.diagram.ForcedPublish(self.context)

    def tcp_in_world(self) -> np.ndarray:
        """(3,) laser TCP position in W [m] for the current pose."""
        ctx = self.plant.GetMyContextFromRoot(self.context)
        return self.plant.GetFrameByName("laser_tcp", self.tool).CalcPoseInWorld(ctx).translation()


def build_tool_scene(meshcat, geometry: FiveBarGeometry | None = None,
                     robot_model: str | Path | None = None, flange_frame: str = "flange",
                     X_FC=None, X_WC=None) -> ToolScene:
    """Diagram with the tool (optionally on a robot flange) drawn in ``meshcat``."""
    from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams, Role
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    from drakedeburr.resources import add_package_to

    g = geometry or FiveBarGeometry()
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    robot = None
    if robot_model is not None:
        parser = Parser(plant)
        add_package_to(parser.package_map())
        (robot,) = parser.AddModels(str(robot_model))
        # the model's root body (URDF base_link or SDF base)
        base = plant.get_body(plant.GetBodyIndices(robot)[0])
        plant.WeldFrames(plant.world_frame(), base.body_frame())
        parent = plant.GetFrameByName(flange_frame, robot)
        tool = add_cutting_tool(plant, g, parent, X_FC if X_FC is not None else default_X_FC())
    else:
        tool = add_cutting_tool(plant, g, None, X_WC)
    plant.Finalize()
    vis = MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat,
                                         MeshcatVisualizerParams(role=Role.kIllustration))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    return ToolScene(diagram=diagram, plant=plant, tool=tool, robot=robot, visualizer=vis,
                     context=context, geometry=g)


def animate_hole(scene: ToolScene, program, meshcat, fps: float = 200.0,
                 robot_q: np.ndarray | None = None) -> np.ndarray:
    """Record a Meshcat animation of a HoleProgram and draw the cut path.

    Returns:
        (M, 3) TCP positions in W along the animation [m] (from the Drake model).
    """
    from pydrake.geometry import Rgba

    t, q, _, _ = program.sample(1.0 / fps)
    scene.visualizer.StartRecording(False)
    tcp = np.empty((len(t), 3))
    for k, (tk, qk) in enumerate(zip(t, q, strict=True)):
        scene.context.SetTime(float(tk))
        scene.set_servo_angles(qk, robot_q)
        tcp[k] = scene.tcp_in_world()
    scene.visualizer.StopRecording()
    scene.visualizer.PublishRecording()
    meshcat.SetLine("/drakedeburr/laser_cut", tcp.T, 2.0, Rgba(0.9, 0.1, 0.1, 1))
    return tcp
