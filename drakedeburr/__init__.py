"""drakedeburr: plan and verify robot deburring paths for wheel-hub windows with Drake.

The public API is re-exported lazily (heavy libraries such as pydrake and open3d load only
when the name is first used).
"""

from __future__ import annotations

import importlib
import logging

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())

# public name -> module that defines it
_EXPORTS: dict[str, str] = {
    "ProcessParameters": "drakedeburr.config",
    "Tolerances": "drakedeburr.config",
    "InputError": "drakedeburr.errors",
    "VerificationFailed": "drakedeburr.errors",
    "HubSpec": "drakedeburr.hub",
    "HubModel": "drakedeburr.hub",
    "load_hub": "drakedeburr.hub",
    "generate_hub": "drakedeburr.hub",
    "simulate_scan": "drakedeburr.hub",
    "WindowEdge": "drakedeburr.hub",
    "ScanCloud": "drakedeburr.hub",
    "DEFAULT_HUB": "drakedeburr.hub",
    "load_hub_mesh": "drakedeburr.hub.mesh_io",
    "extract_window_edges": "drakedeburr.hub.extract",
    "register_hub": "drakedeburr.hub.registration",
    "RegistrationOptions": "drakedeburr.hub.registration",
    "RegistrationRefused": "drakedeburr.hub.registration",
    "ClPath": "drakedeburr.path",
    "EdgeCurve": "drakedeburr.path",
    "fit_edge_curve": "drakedeburr.path",
    "plan_cl": "drakedeburr.path",
    "PlannerParams": "drakedeburr.path",
    "cl_table": "drakedeburr.path",
    "R_HL_from_normals": "drakedeburr.frames",
    "axis_from_angles": "drakedeburr.frames",
    "angles_from_axis": "drakedeburr.frames",
    "inner_normals_from_cloud": "drakedeburr.frames",
    "inner_normals_from_mesh": "drakedeburr.frames",
    "ToolPath": "drakedeburr.orientation",
    "orient_window": "drakedeburr.orientation",
    "OrientOptions": "drakedeburr.orientation",
    "Cell": "drakedeburr.cell",
    "load_cell": "drakedeburr.cell",
    "BurrGeometry": "drakedeburr.cell",
    "BURR": "drakedeburr.cell",
    "read_cl": "drakedeburr.post",
    "program_from_cl": "drakedeburr.post",
    "RobotSpec": "drakedeburr.robots",
    "get_robot": "drakedeburr.robots",
    "robot_names": "drakedeburr.robots",
    "ik_opw": "drakedeburr.robots",
    "solve_path": "drakedeburr.robots",
    "RobotProgram": "drakedeburr.programs",
    "ProgramMove": "drakedeburr.programs",
    "write_program": "drakedeburr.programs",
    "read_program": "drakedeburr.programs",
    "compare_programs": "drakedeburr.programs",
    "virtual_tcp_poses": "drakedeburr.post",
    "fit_touch_points": "drakedeburr.post",
    "IRB1600_10_120": "drakedeburr.robots",
    "fk_opw": "drakedeburr.robots",
    "FiveBarGeometry": "drakedeburr.laser",
    "plan_hole": "drakedeburr.laser",
    "plan_contour": "drakedeburr.laser",
    "build_contour": "drakedeburr.laser",
    "get_meshcat": "drakedeburr.viz",
    "publish_cell": "drakedeburr.viz",
    "publish_edge_loops": "drakedeburr.viz",
    "write_static_html": "drakedeburr.viz",
    "plan_hub": "drakedeburr.plan",
    "PlanOptions": "drakedeburr.plan",
    "Plan": "drakedeburr.plan",
    "save_plan": "drakedeburr.plan",
    "load_plan": "drakedeburr.plan",
    "program_from_plan": "drakedeburr.programs",
    "verify_plan": "drakedeburr.verify",
    "VerificationReport": "drakedeburr.verify",
    "verify_all": "drakedeburr.verify",
    "write_report_json": "drakedeburr.verify",
    "write_report_html": "drakedeburr.verify",
    "run_demo": "drakedeburr.demo",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'drakedeburr' has no attribute {name!r}")
