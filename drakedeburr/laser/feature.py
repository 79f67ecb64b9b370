"""Larger contours cut by the robot: "Feature" settings -> tool poses (source 004 §3.1).

Like ROBOGUIDE's Feature function: travel angle, work angle, point spacing and the user frame
of the part plane turn a contour into robot tool poses. The beam (tool +z) points into the
plate (-z of the plane frame P) and is then tilted by the travel angle about the tool y axis
(positive leans the beam forward along the travel direction) and by the work angle about the
tool x axis (= the travel direction). The TCP speed profile comes from TOPP-RA on the
Cartesian contour under the programmed speed and TCP acceleration limits, and sets the laser
command like the tool-alone case.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.laser.power import PowerMap
from drakedeburr.laser.shapes import Contour, ShapeBase, build_contour
from drakedeburr.laser.timing import AxisLimits, time_path

__all__ = ["FeatureSettings", "LaserTargets", "plan_contour", "feature_orientations"]


@dataclass(frozen=True)
class FeatureSettings:
    """Robot contour settings.

    Attributes:
        travel_angle: beam lean along the travel direction [rad].
        work_angle: beam lean sideways (about the travel direction) [rad].
        point_spacing: distance between targets along the contour [m].
        speed: programmed cutting speed [m/s].
        acceleration: TCP acceleration limit per plane axis [m/s^2] (robot, small contours).
    """

    travel_angle: float = 0.0
    work_angle: float = 0.0
    point_spacing: float = 2e-3
    speed: float = 0.10
    acceleration: float = 3.0

    def __post_init__(self) -> None:
        for name in ("point_spacing", "speed", "acceleration"):
            if not getattr(self, name) > 0:
                raise InputError(f"FeatureSettings.{name} must be > 0, got "
                                 f"{getattr(self, name)!r}")
        for name in ("travel_angle", "work_angle"):
            if not abs(getattr(self, name)) < np.pi / 2:
                raise InputError(f"FeatureSettings.{name} must be within +-90 deg, got "
                                 f"{getattr(self, name)!r} rad")


@dataclass(frozen=True, eq=False)
class LaserTargets:
    """Robot tool poses for a laser contour (what a post writer takes).

    Attributes:
        name: shape kind.
        p_WT: (N, 3) TCP positions in the world / user frame W [m].
        R_WT: (N, 3, 3) tool orientations in W (tool +z = beam direction).
        t: (N,) time at which each target is passed [s].
        speed: (N,) TCP speed at the targets [m/s].
        command: (N,) laser analogue command [V].
        is_cut: (N,) False on the lead-in.
        contour: the sampled contour (plane frame P).
        power: the speed -> command map used.
    """

    name: str
    p_WT: np.ndarray
    R_WT: np.ndarray
    t: np.ndarray
    speed: np.ndarray
    command: np.ndarray
    is_cut: np.ndarray
    contour: Contour
    power: PowerMap

    def __len__(self) -> int:
        return len(self.t)


def feature_orientations(R_WP: np.ndarray, t_P: np.ndarray,
                         settings: FeatureSettings) -> np.ndarray:
    """Tool orientations (N, 3, 3) in W for in-plane tangents t_P (N, 2) of plane P."""
    t_W = np.einsum("ij,nj->ni", R_WP[:, :2], t_P)
    t_W /= np.linalg.norm(t_W, axis=1, keepdims=True)
    z_W = np.tile(-R_WP[:, 2], (len(t_W), 1))
    y_W = np.cross(z_W, t_W)
    R_base = np.stack([t_W, y_W, z_W], axis=2)  # columns x, y, z
    a, b = settings.travel_angle, settings.work_angle
    Ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    # +travel leans the beam forward: tool z gets a +x component
    return R_base @ (Ry @ Rx)


def plan_contour(shape: ShapeBase, X_WP: np.ndarray | None = None,
                 settings: FeatureSettings | None = None,
                 power: PowerMap | None = None) -> LaserTargets:
    """Tool poses and laser commands for a contour cut by the robot.

    Args:
        shape: the contour (sizes in metres) in the part plane P.
        X_WP: (4, 4) pose of the plane frame P in W (user frame); identity if None.
        settings: Feature settings.
        power: speed -> command map (its nominal speed should be the programmed speed).

    Returns:
        LaserTargets.
    """
    settings = settings or FeatureSettings()
    power = power or PowerMap(nominal_speed=settings.speed)
    X = np.eye(4) if X_WP is None else np.asarray(X_WP, dtype=float)
    contour = build_contour(shape, settings.point_spacing)
    R_WP, p_WP = X[:3, :3], X[:3, 3]
    p_WT = p_WP + np.einsum("ij,nj->ni", R_WP[:, :2], contour.p_P)
    R_WT = feature_orientations(R_WP, contour.t_P, settings)
    limits = AxisLimits(velocity=(1e3, 1e3), acceleration=(settings.acceleration,) * 2,
                        feed=settings.speed, feed_acceleration=settings.acceleration)
    timed = time_path(contour.s, contour.p_P, contour.corner, limits)
    _, _, sd = timed.sample(timed.knot_t)
    command, _ = power.command(sd)
    return LaserTargets(name=shape.kind, p_WT=p_WT, R_WT=R_WT, t=timed.knot_t, speed=sd,
                        command=command, is_cut=contour.is_cut, contour=contour, power=power)
