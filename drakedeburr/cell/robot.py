"""The ABB IRB1600-10/1.2 model: names, limits and where its file is.

The model itself is ``models/robots/irb1600_10_120.sdf`` (written by us, see its header and
docs/cell.md). These constants restate what that file holds so code and tests can name joints
and limits without parsing; ``tests/test_robot_model.py`` checks both agree.

Sources and assumptions:
    * joint origins, axes, position limits: ros-industrial/abb irb1600_6_12 (the 1.2 m arm), as
      recorded in extdata/kinematics/robot_kinematics_reference.json.
    * velocity limits 180/180/185/385/400/460 deg/s: the 10 kg variant (irb1600_10_145 URDF).
      Combining them with the 1.2 m geometry for a 10/1.2 is an INFERENCE, not a sourced fact.
    * acceleration limits: ASSUMED (ABB publishes none; the controller's dynamic model limits
      acceleration by torque). Chosen so each axis reaches its top speed in about 0.3 s
      (axes 1-3: 10 rad/s^2, axes 4-5: 20 rad/s^2, axis 6: 25 rad/s^2), a conservative figure
      for a 10 kg payload at full reach. Drake parses them from ``<drake:acceleration>``.
"""

from __future__ import annotations

import numpy as np

from drakedeburr.units import rad_from_deg

__all__ = [
    "ROBOT_MODEL_URL",
    "ROBOT_MODEL_RELPATH",
    "ROBOT_MODEL_NAME",
    "JOINT_NAMES",
    "BASE_FRAME_NAME",
    "FLANGE_FRAME_NAME",
    "POSITION_LOWER",
    "POSITION_UPPER",
    "VELOCITY_LIMITS",
    "ACCELERATION_LIMITS",
]

ROBOT_MODEL_RELPATH = "robots/irb1600_10_120.sdf"
ROBOT_MODEL_URL = f"package://drakedeburr/{ROBOT_MODEL_RELPATH}"
#: model instance name the scenarios give the robot (``load_cell`` looks for it)
ROBOT_MODEL_NAME = "irb1600"
#: joint order = ABB axes 1..6 = the order of ``drakedeburr.post.opw.fk_opw``
JOINT_NAMES: tuple[str, ...] = tuple(f"joint_{i}" for i in range(1, 7))
BASE_FRAME_NAME = "base"
#: ABB tool0: +Z out of the flange; at q = 0 at (0.815, 0, 0.9615) with +Z along +X_base
FLANGE_FRAME_NAME = "flange"

#: (6,) [rad]
POSITION_LOWER = np.array([-np.pi, -1.0995, -4.1015, -3.4906, -2.0071, -6.9813])
POSITION_UPPER = np.array([np.pi, 1.9198, 0.9599, 3.4906, 2.0071, 6.9813])
#: (6,) [rad/s], symmetric
VELOCITY_LIMITS = rad_from_deg(np.array([180.0, 180.0, 185.0, 385.0, 400.0, 460.0]))
#: (6,) [rad/s^2], symmetric, ASSUMED (see module docstring)
ACCELERATION_LIMITS = np.array([10.0, 10.0, 10.0, 20.0, 20.0, 25.0])
