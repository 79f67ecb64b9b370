"""drakedeburr.laser: FANUC robot laser cutting with a five-bar "Cutting Tool" (SPEC.md §S4).

* :mod:`~drakedeburr.laser.kinematics` - five-bar FK (eqs. 1-9), IK, Jacobian, singularities
* :mod:`~drakedeburr.laser.model` - Drake SDF model (closed loop) for Meshcat / the flange
* :mod:`~drakedeburr.laser.shapes` - circle, semicircle, rectangle, slot, keyhole, hexagon,
  polyline contours at a point spacing
* :mod:`~drakedeburr.laser.timing` - TOPP-RA timing under axis and feed limits
* :mod:`~drakedeburr.laser.hole` - holes by the tool alone (servo trajectory)
* :mod:`~drakedeburr.laser.feature` - larger contours by the robot ("Feature" settings)
* :mod:`~drakedeburr.laser.power` - TCP speed -> analogue laser command
* :mod:`~drakedeburr.laser.itp` - hole programs in whole interpolation periods (8 ms)
* :mod:`~drakedeburr.laser.robot_job` - plate frame (UFRAME), the arm's IK and CONFIG, one
  job for a part's holes and contour
* :mod:`~drakedeburr.laser.fanuc_ls` - FANUC .ls programs with the analogue output
"""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "feature": ("FeatureSettings", "LaserTargets", "plan_contour"),
    "hole": ("HoleProgram", "ServoLimits", "plan_hole"),
    "itp": ("ControllerTiming", "ItpSegments"),
    "robot_job": ("LaserCell", "LaserJob", "LaserProcess", "plan_job"),
    "kinematics": (
        "FiveBarGeometry", "check_reach", "forward_kinematics", "inverse_kinematics", "jacobian",
        "singularity_measures",
    ),
    "power": ("PowerMap", "PowerProfile"),
    "shapes": (
        "SHAPE_KINDS", "Circle", "Contour", "Hexagon", "Keyhole", "Polyline", "Rectangle",
        "Semicircle", "Slot", "build_contour",
    ),
})
