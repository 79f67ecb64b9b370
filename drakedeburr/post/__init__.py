"""drakedeburr.post: CL/APT reader, analytic OPW IK, program writers (RAPID, KRL, LS),
virtual TCP for workpiece-in-hand, cell calibration from touched points."""

from drakedeburr.post.calibration import (
    CalibrationFit,
    calibrated_pose,
    fit_touch_points,
    scale_about,
)
from drakedeburr.post.cl_post import (
    PostResult,
    PostSettings,
    PostSummary,
    pose_from_mm_deg,
    post_cl_file,
    program_from_cl,
)
from drakedeburr.post.cl_reader import (
    ClMove,
    ClParseError,
    ClProgram,
    ClToolPath,
    ClWarning,
    ClWordCount,
    iter_cl_moves,
    parse_cl_text,
    read_cl,
)
from drakedeburr.post.configuration import (
    abb_confdata,
    configuration_of,
    fanuc_config,
    joints_from_configuration,
    kuka_status_turn,
)
from drakedeburr.post.opw import IRB1600_10_120, OpwParameters, fk_opw
from drakedeburr.post.opw_ik import (
    IRB1600_10_120_ROBOT,
    IkSolutions,
    JointLimits,
    JointPathResult,
    RobotKinematics,
    ik_opw,
    select_solution,
    solve_path,
)
from drakedeburr.post.plan_program import program_from_plan
from drakedeburr.post.program import JOINT, LINEAR, ProgramMove, RobotProgram
from drakedeburr.post.tool_axis import (
    ToolAxisPathResult,
    path_travel,
    solve_tool_axis_path,
    tool_frames,
)
from drakedeburr.post.virtual_tcp import (
    contour_frames,
    offset_contour,
    part_contour_at_virtual,
    virtual_tcp_poses,
)
from drakedeburr.post.writers import format_krl, format_ls, format_rapid, write_program

__all__ = [
    "CalibrationFit", "calibrated_pose", "fit_touch_points", "scale_about",
    "PostResult", "PostSettings", "PostSummary", "pose_from_mm_deg", "post_cl_file",
    "program_from_cl",
    "ClMove", "ClParseError", "ClProgram", "ClToolPath", "ClWarning", "ClWordCount",
    "iter_cl_moves", "parse_cl_text",
    "read_cl",
    "abb_confdata", "configuration_of", "fanuc_config", "joints_from_configuration",
    "kuka_status_turn",
    "IRB1600_10_120", "OpwParameters", "fk_opw",
    "IRB1600_10_120_ROBOT", "IkSolutions", "JointLimits", "JointPathResult", "RobotKinematics",
    "ik_opw", "select_solution", "solve_path",
    "program_from_plan", "JOINT", "LINEAR", "ProgramMove", "RobotProgram",
    "ToolAxisPathResult", "path_travel", "solve_tool_axis_path", "tool_frames",
    "contour_frames", "offset_contour", "part_contour_at_virtual", "virtual_tcp_poses",
    "format_krl", "format_ls", "format_rapid", "write_program",
]
