"""drakedeburr.robots: the arm registry, a neutral room used by cell, plan, verify and post.

One :class:`RobotSpec` per arm (OPW parameters, joint limits, vendor joint conventions,
configuration data, Drake model, mounts in the bundled cells), the OPW forward map and
analytic inverse, and the vendors' configuration data (ABB confdata, KUKA S/T, FANUC CONFIG).
"""

from drakedeburr.robots.arms import (
    DEFAULT_ROBOT,
    IRB1600,
    IRB1600_10_120,
    IRB1600_10_120_ROBOT,
    KR6_R700,
    KR6_R700_SIXX,
    LRMATE200IC,
    LRMATE_200IC,
    M10IA,
    M_10IA,
    ROBOTS,
    get_robot,
    robot_for_model_url,
    robot_names,
)
from drakedeburr.robots.configuration import (
    abb_confdata,
    configuration_of,
    fanuc_config,
    joints_from_configuration,
    kuka_status_turn,
)
from drakedeburr.robots.model import (
    BASE_FRAME_NAME,
    FLANGE_FRAME_NAME,
    JOINT_NAMES,
    ROBOT_MODEL_NAME,
    ModelLimits,
    read_model_limits,
)
from drakedeburr.robots.opw import OpwParameters, fk_opw
from drakedeburr.robots.opw_ik import (
    IkSolutions,
    JointLimits,
    JointPathResult,
    RobotKinematics,
    arm_branches,
    ik_opw,
    joint_candidates,
    select_solution,
    solve_path,
    travel_weights,
)
from drakedeburr.robots.spec import CONTROLLERS, CellMount, RobotSpec

__all__ = [
    "RobotSpec", "CellMount", "CONTROLLERS",
    "ROBOTS", "DEFAULT_ROBOT", "robot_names", "get_robot", "robot_for_model_url",
    "IRB1600", "KR6_R700", "LRMATE200IC", "M10IA",
    "IRB1600_10_120", "KR6_R700_SIXX", "LRMATE_200IC", "M_10IA", "IRB1600_10_120_ROBOT",
    "OpwParameters", "fk_opw",
    "IkSolutions", "JointLimits", "JointPathResult", "RobotKinematics", "arm_branches", "ik_opw",
    "joint_candidates", "select_solution", "solve_path", "travel_weights",
    "abb_confdata", "configuration_of", "fanuc_config", "joints_from_configuration",
    "kuka_status_turn",
    "ROBOT_MODEL_NAME", "JOINT_NAMES", "BASE_FRAME_NAME", "FLANGE_FRAME_NAME", "ModelLimits",
    "read_model_limits",
]
