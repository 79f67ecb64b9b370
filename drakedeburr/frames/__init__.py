"""drakedeburr.frames: inner-side normals and local frames at CL points (source §2.1-2.2)."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "local_frames": (
        "R_HL_from_normals", "R_LT_from_angles", "angles_from_axis", "angles_from_zT_H",
        "axis_from_angles", "zT_H_from_angles",
    ),
    "normals": ("NormalEstimate", "inner_normals_from_cloud", "inner_normals_from_mesh"),
})
