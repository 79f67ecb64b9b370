"""ToolPath: the orientation stage's output, consumed by the planning stage."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from pydrake.math import RigidTransform

from drakedeburr.config import OrientationBounds
from drakedeburr.frames.local_frames import R_LT_from_angles, angles_from_zT_H
from drakedeburr.hub.types import WindowKind
from drakedeburr.path.types import ClPath

__all__ = ["ToolPath"]


@dataclass(frozen=True, eq=False)
class ToolPath:
    """Tool positions and axes along one window edge, with the freedom the planner may use.

    Everything per point is stored in the hub frame H; the world view follows ``X_WH`` (the
    registered hub pose), so re-targeting to a new hub pose is :meth:`with_hub_pose`.

    Tool-axis convention: ``zT_H`` is DESIGN.md's tool ``+Z_T``, the unit vector along the
    burr from the spindle toward the tip (into the material side); a CAM/APT (i, j, k) vector
    is ``-axis`` (:attr:`ijk_H`). The spin about the axis is free; :attr:`R_HT` gives one
    (X_T = the local N turned with the tool) as a preference.

    Attributes:
        window_index: window number (0-based, as WindowEdge.index / ClPath.window_index).
        kind: "large" or "small".
        cl_path: the ClPath the points came from.
        X_WH: hub pose in world used for the world-frame views.
        p_HC: (M, 3) CL points (burr cutting point) in H [m].
        R_HL: (M, 3, 3) right-handed local frames [N_new, T, -B] in H (frames.local_frames).
        zT_H: (M, 3) chosen unit tool axes +Z_T in H (spindle -> tip).
        theta_A: (M,) work/tilt angle [rad] of zT_H in its local frame.
        theta_B: (M,) lead/travel angle [rad].
        bounds: the box [theta_min, theta_max] both angles must stay in.
        cone_zT_H: (M, 3) axis at the box centre (the planner's preferred axis if it
            prefers the middle of the admissible set rather than ``zT_H``).
        cone_half_angle: [rad] half-angle of the largest cone about ``cone_zT_H`` inside the
            box: any axis within it satisfies the bounds (use for the IK cone constraint).
        cone_outer_half_angle: [rad] half-angle of the smallest cone about ``cone_zT_H``
            containing the whole box (a permissive cone).
        depth_of_cut: [m] from ProcessParameters for this window kind.
        model: "axis" or "paper"; solver: "exact" or "pso".
        objective: model objective of the returned angles.
        success: the solver met its optimality/feasibility checks.
        solve_seconds: wall time of the solve [s].
        stats: angle_statistics(...) plus solver info.
        message: human-readable outcome.
    """

    window_index: int
    kind: WindowKind
    cl_path: ClPath
    X_WH: RigidTransform
    p_HC: np.ndarray
    R_HL: np.ndarray
    zT_H: np.ndarray
    theta_A: np.ndarray
    theta_B: np.ndarray
    bounds: OrientationBounds
    cone_zT_H: np.ndarray
    cone_half_angle: float
    cone_outer_half_angle: float
    depth_of_cut: float
    model: str
    solver: str
    objective: float
    success: bool
    solve_seconds: float
    stats: dict = field(default_factory=dict)
    message: str = ""

    def __len__(self) -> int:
        return len(self.p_HC)

    @property
    def ijk_H(self) -> np.ndarray:
        """(M, 3) CAM/APT tool-axis vectors (tip -> spindle) in H: ``-zT_H``."""
        return -self.zT_H

    @property
    def R_HT(self) -> np.ndarray:
        """(M, 3, 3) preferred tool orientations in H: R_HL @ R_y(-theta_A) @ R_x(theta_B)."""
        return np.einsum("mij,mjk->mik", self.R_HL, R_LT_from_angles(self.theta_A, self.theta_B))

    @property
    def R_WT(self) -> np.ndarray:
        """(M, 3, 3) preferred tool orientations in world."""
        return np.einsum("ij,mjk->mik", self.X_WH.rotation().matrix(), self.R_HT)

    @property
    def p_WC(self) -> np.ndarray:
        """(M, 3) CL points in world [m]."""
        return self.X_WH.multiply(self.p_HC.T).T

    @property
    def axis_W(self) -> np.ndarray:
        """(M, 3) tool axes +Z_T (spindle -> tip) in world."""
        return (self.X_WH.rotation().matrix() @ self.zT_H.T).T

    @property
    def cone_axis_W(self) -> np.ndarray:
        """(M, 3) cone axes in world."""
        return (self.X_WH.rotation().matrix() @ self.cone_zT_H.T).T

    @property
    def R_WL(self) -> np.ndarray:
        """(M, 3, 3) local frames in world."""
        return np.einsum("ij,mjk->mik", self.X_WH.rotation().matrix(), self.R_HL)

    def admissible(self, axis_W: np.ndarray, tol: float = 1e-9) -> np.ndarray:
        """(M,) bool: does the world-frame tool axis +Z_T (M, 3) keep both angles in
        the box at each point? The exact test behind the cone approximations."""
        zT_H = (self.X_WH.rotation().matrix().T @ np.asarray(axis_W, float).T).T
        a, b = angles_from_zT_H(self.R_HL, zT_H)
        lo, hi = self.bounds.theta_min - tol, self.bounds.theta_max + tol
        return (a >= lo) & (a <= hi) & (b >= lo) & (b <= hi)

    def with_hub_pose(self, X_WH: RigidTransform) -> ToolPath:
        """The same tool path re-targeted to another hub pose (e.g. a registered one)."""
        return replace(self, X_WH=RigidTransform(X_WH))
