"""drakedeburr.post: CL/APT reader and CL -> robot program (through drakedeburr.robots and
drakedeburr.programs), virtual TCP for workpiece-in-hand, cell calibration from touched points."""

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

__all__ = [
    "CalibrationFit", "calibrated_pose", "fit_touch_points", "scale_about",
    "PostResult", "PostSettings", "PostSummary", "pose_from_mm_deg", "post_cl_file",
    "program_from_cl",
    "ClMove", "ClParseError", "ClProgram", "ClToolPath", "ClWarning", "ClWordCount",
    "iter_cl_moves", "parse_cl_text",
    "read_cl",
    "ToolAxisPathResult", "path_travel", "solve_tool_axis_path", "tool_frames",
    "contour_frames", "offset_contour", "part_contour_at_virtual", "virtual_tcp_poses",
]
