"""What every arm model of the registry has in common, and reading an arm model's limits.

The arm models are SDFormat files written by us under ``models/robots/`` (one per arm, see
:mod:`drakedeburr.robots.arms` and docs/cell.md). They share one layout so the cell, the planner
and the verifier never branch on the arm:

* joints ``joint_1`` .. ``joint_6`` = the controller's axes 1..6 in that order, each joint value
  in the *model* convention of :class:`~drakedeburr.robots.spec.RobotSpec` (equal to the
  controller's axis value except where the spec's joint map says otherwise: FANUC J3);
* frame ``base``: the robot's mounting face (floor side of the foot), z up, on axis 1;
* frame ``flange``: the vendor's flange frame (ABB tool0, KUKA $FLANGE, FANUC faceplate):
  +Z out of the flange; it equals the end frame of :func:`drakedeburr.robots.opw.fk_opw`;
* joint limits: ``<lower>``/``<upper>``, ``<velocity>`` and ``<drake:acceleration>``.

A scenario loads the arm as model instance ``robot`` (``ROBOT_MODEL_NAME``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "ROBOT_MODEL_NAME",
    "JOINT_NAMES",
    "BASE_FRAME_NAME",
    "FLANGE_FRAME_NAME",
    "ModelLimits",
    "read_model_limits",
]

#: model instance name the scenarios give the arm (``load_cell`` looks for it)
ROBOT_MODEL_NAME = "robot"
#: joint order = controller axes 1..6 = the order of ``drakedeburr.robots.opw.fk_opw``
JOINT_NAMES: tuple[str, ...] = tuple(f"joint_{i}" for i in range(1, 7))
BASE_FRAME_NAME = "base"
#: the vendor's flange frame, +Z out of the flange
FLANGE_FRAME_NAME = "flange"


@dataclass(frozen=True, eq=False)
class ModelLimits:
    """Joint limits as a Drake plant parses them from an arm model, (6,) each.

    Attributes:
        q_lower, q_upper: position limits [rad].
        v_max: symmetric velocity limits [rad/s].
        a_max: symmetric acceleration limits [rad/s^2].
    """

    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray


def read_model_limits(path: str | Path) -> ModelLimits:
    """Parse an arm model file alone (base welded to the world) and read its joint limits.

    Args:
        path: SDFormat/URDF file of an arm following the layout of this module.

    Returns:
        ModelLimits in joint order ``joint_1..joint_6``.
    """
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    (instance,) = Parser(plant).AddModels(str(path))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(BASE_FRAME_NAME, instance))
    plant.Finalize()
    for i, name in enumerate(JOINT_NAMES):
        if plant.GetJointByName(name, instance).position_start() != i:
            raise ValueError(f"{path}: joint {name} is not at position {i}")
    return ModelLimits(
        q_lower=plant.GetPositionLowerLimits(), q_upper=plant.GetPositionUpperLimits(),
        v_max=plant.GetVelocityUpperLimits(), a_max=plant.GetAccelerationUpperLimits())
