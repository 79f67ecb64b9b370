"""drakedeburr.frames: inner-side normals and local frames at CL points (source §2.1-2.2)."""

from drakedeburr.frames.local_frames import (
    R_HL_from_normals,
    R_LT_from_angles,
    angles_from_axis,
    angles_from_zT_H,
    axis_from_angles,
    zT_H_from_angles,
)
from drakedeburr.frames.normals import (
    NormalEstimate,
    inner_normals_from_cloud,
    inner_normals_from_mesh,
)

__all__ = [
    "R_HL_from_normals",
    "axis_from_angles",
    "angles_from_axis",
    "zT_H_from_angles",
    "angles_from_zT_H",
    "R_LT_from_angles",
    "NormalEstimate",
    "inner_normals_from_cloud",
    "inner_normals_from_mesh",
]
