"""drakedeburr.cell: the Drake deburring cell (robot, tools, fixtures, hub) from a scenario.

``load_cell(scenario, hub)`` returns a :class:`Cell`; tool-in-hand and workpiece-in-hand cells
are the same code with different frames. Tool geometry (the burr) is defined once in
:mod:`drakedeburr.cell.tools`.
"""

from drakedeburr.cell.reach import ReachResult, ReachSurvey, ReachTarget, face_targets, survey_reach
from drakedeburr.cell.station import Cell, load_cell, resolve_hub_sdf
from drakedeburr.cell.tools import BURR, FLOATING_SPINDLE, SPINDLE_STAND, BurrGeometry

__all__ = [
    "Cell",
    "load_cell",
    "resolve_hub_sdf",
    "BurrGeometry",
    "BURR",
    "FLOATING_SPINDLE",
    "SPINDLE_STAND",
    "ReachTarget",
    "ReachResult",
    "ReachSurvey",
    "face_targets",
    "survey_reach",
]
