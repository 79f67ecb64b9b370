"""drakedeburr.cell: the Drake deburring cell (robot, tools, fixtures, hub) from a scenario.

``load_cell(scenario, hub)`` returns a :class:`Cell`; tool-in-hand and workpiece-in-hand cells
are the same code with different frames. Tool geometry (the burr) is defined once in
:mod:`drakedeburr.cell.tools`.
"""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "reach": ("ReachOptions", "ReachResult", "ReachSurvey", "ReachTarget", "face_targets",
              "survey_reach"),
    "station": ("Cell", "load_cell", "resolve_hub_sdf"),
    "tools": ("BURR", "FLOATING_SPINDLE", "SPINDLE_STAND", "BurrGeometry"),
})
