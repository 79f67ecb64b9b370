"""drakedeburr.plan stage: cone-constrained IK, the executed motion, smoothing, timing, Plan."""

from drakedeburr.plan.ik import IkOptions, WindowIk, solve_window_ik
from drakedeburr.plan.io import load_plan, save_plan, write_joint_csv
from drakedeburr.plan.kinematics import CellKinematics, ClearanceChecker, cell_kinematics
from drakedeburr.plan.planner import PlanOptions, plan_hub, plan_windows, window_targets_for_hub
from drakedeburr.plan.targets import (
    X_HT_from_axis,
    burr_contact_radius,
    contact_geometry,
    edge_point_from_tool_pose,
    tool_point_H,
)
from drakedeburr.plan.timing import TimingLimits, time_path
from drakedeburr.plan.types import CartesianTarget, JointTrajectory, Plan, PlanSegment
from drakedeburr.plan.window_targets import WindowTargets

__all__ = [
    "CartesianTarget", "JointTrajectory", "Plan", "PlanSegment",
    "PlanOptions", "plan_hub", "plan_windows", "window_targets_for_hub", "WindowTargets",
    "IkOptions", "WindowIk", "solve_window_ik",
    "CellKinematics", "ClearanceChecker", "cell_kinematics",
    "tool_point_H", "edge_point_from_tool_pose", "X_HT_from_axis", "burr_contact_radius",
    "contact_geometry",
    "TimingLimits", "time_path",
    "save_plan", "load_plan", "write_joint_csv",
]
