"""drakedeburr.post: CL/APT reader and CL -> robot program (through drakedeburr.robots and
drakedeburr.programs), virtual TCP for workpiece-in-hand, cell calibration from touched points."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "calibration": (
        "CalibrationFit", "ScaleCompensation", "calibrated_pose", "fit_machined_contour",
        "fit_touch_points",
    ),
    "cl_post": (
        "PostOutput", "PostResult", "PostSettings", "PostSummary", "pose_from_mm_deg",
        "post_cl_file",
        "program_from_cl",
    ),
    "cl_reader": (
        "ClMove", "ClParseError", "ClProgram", "ClReadOptions", "ClToolPath", "ClWarning",
        "ClWordCount",
        "iter_cl_moves", "parse_cl_text", "read_cl",
    ),
    "tool_axis": ("ToolAxisOptions", "ToolAxisPathResult", "path_travel", "solve_tool_axis_path",
                  "tool_frames"),
    "virtual_tcp": (
        "contour_frames", "offset_contour", "part_contour_at_virtual", "virtual_tcp_poses",
    ),
    "virtual_tcp_post": (
        "VirtualTcpSetup", "post_cl_file_virtual_tcp", "solve_virtual_tcp",
        "virtual_tcp_program_from_cl", "virtual_tcp_setup",
    ),
})
