"""drakedeburr.robots: the arm registry, a neutral room used by cell, plan, verify and post.

One :class:`RobotSpec` per arm, read from its arm file (YAML, :mod:`.arm_file`: OPW
parameters, joint limits, vendor joint conventions, payload ratings, Drake model, mounts in the
bundled cells), the OPW forward map and analytic inverse, the payload figures
(:mod:`.payload`) and the vendors' configuration data (ABB confdata, KUKA S/T, FANUC CONFIG).
"""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "arms": (
        "BUILTIN_ARMS", "DEFAULT_ROBOT", "IRB1600", "IRB1600_10_120", "IRB1600_10_120_ROBOT",
        "IRB2600", "KR20_R1810", "KR6_R700", "KR6_R700_SIXX", "LRMATE200IC", "LRMATE_200IC",
        "M10IA", "M20IA", "M710IC50", "M_10IA", "ROBOTS", "get_robot", "robot_for_model_url",
        "robot_names",
    ),
    "arm_file": ("SCHEMA", "arm_file_text", "is_arm_file", "load_arm"),
    "payload": ("CarriedLoad", "PayloadFigure", "carried_load", "payload_figures",
                "within_rating"),
    "configuration": (
        "abb_confdata", "configuration_of", "fanuc_config", "joints_from_configuration",
        "kuka_status_turn",
    ),
    "model": (
        "BASE_FRAME_NAME", "FLANGE_FRAME_NAME", "JOINT_NAMES", "ROBOT_MODEL_NAME", "ModelLimits",
        "read_model_limits",
    ),
    "opw": ("OpwParameters", "fk_opw"),
    "opw_ik": (
        "IkSolutions", "JointLimits", "JointPathResult", "RobotKinematics", "arm_branches",
        "ik_opw", "joint_candidates", "select_solution", "solve_path", "travel_weights",
    ),
    "spec": ("CONTROLLERS", "CellMount", "RobotSpec"),
})
