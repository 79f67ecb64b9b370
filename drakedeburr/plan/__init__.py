"""drakedeburr.plan stage: cone-constrained IK, the executed motion, smoothing, timing, Plan."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "ik": ("IkOptions", "WindowIk", "solve_window_ik"),
    "io": ("load_plan", "save_plan", "write_joint_csv"),
    "kinematics": ("CellKinematics", "ClearanceChecker", "cell_kinematics"),
    "planner": ("PlanOptions", "plan_hub", "plan_windows", "window_targets_for_hub"),
    "targets": (
        "X_HT_from_axis", "burr_contact_radius", "contact_geometry", "edge_point_from_tool_pose",
        "tool_point_H",
    ),
    "timing": ("TimingLimits", "time_path"),
    "types": ("CartesianTarget", "JointTrajectory", "Plan", "PlanSegment"),
    "window_targets": ("WindowTargets",),
})
