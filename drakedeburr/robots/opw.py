"""OPW kinematics (Brandstoetter, Angerer, Hofbaur 2014): orthoparallel arm + spherical wrist.

The parameters a1, a2, b, c1..c4 describe the arm; ``offsets`` and ``sign_corrections`` map the
robot's joint values to the model's: ``q_opw = q_robot * sign - offset``. The end frame is
the robot's flange in the vendor convention (ABB ``tool0``: +Z out of the flange).

This module holds the parameter type and the forward map; the analytic inverse lives beside it
(:mod:`drakedeburr.robots.opw_ik`), the arms' values in :mod:`drakedeburr.robots.arms`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["OpwParameters", "fk_opw"]


@dataclass(frozen=True)
class OpwParameters:
    """OPW geometry [m] and joint map [rad]. See module docstring."""

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets: tuple[float, float, float, float, float, float] = (0.0,) * 6
    sign_corrections: tuple[int, int, int, int, int, int] = (1,) * 6
    name: str = ""

    def q_opw_from_robot(self, q_robot: np.ndarray) -> np.ndarray:
        return np.asarray(q_robot, float) * np.asarray(self.sign_corrections) - np.asarray(
            self.offsets
        )

    def q_robot_from_opw(self, q_opw: np.ndarray) -> np.ndarray:
        return (np.asarray(q_opw, float) + np.asarray(self.offsets)) * np.asarray(
            self.sign_corrections
        )

    @classmethod
    def from_mapping(cls, data: dict, name: str = "") -> OpwParameters:
        """From a mapping with keys a1..c4, offsets, sign_corrections (reference JSON style)."""
        return cls(
            a1=float(data["a1"]), a2=float(data["a2"]), b=float(data["b"]),
            c1=float(data["c1"]), c2=float(data["c2"]), c3=float(data["c3"]),
            c4=float(data["c4"]),
            offsets=tuple(float(v) for v in data.get("offsets", (0.0,) * 6)),
            sign_corrections=tuple(int(v) for v in data.get("sign_corrections", (1,) * 6)),
            name=name,
        )


def fk_opw(params: OpwParameters, q_robot: np.ndarray) -> np.ndarray:
    """Flange pose for robot joints.

    Args:
        params: the robot's OPW parameters.
        q_robot: (6,) or (N, 6) joint values in the robot's convention [rad].

    Returns:
        (4, 4) or (N, 4, 4) homogeneous transform X_BF, flange F in robot base B [m].
    """
    q_robot = np.asarray(q_robot, float)
    single = q_robot.ndim == 1
    q = params.q_opw_from_robot(np.atleast_2d(q_robot))
    q0, q1, q2, q3, q4, q5 = q.T
    psi3 = np.arctan2(params.a2, params.c3)
    k = np.hypot(params.a2, params.c3)
    cx1 = params.c2 * np.sin(q1) + k * np.sin(q1 + q2 + psi3) + params.a1
    cy1 = params.b
    cz1 = params.c2 * np.cos(q1) + k * np.cos(q1 + q2 + psi3)
    c0 = np.stack(
        [cx1 * np.cos(q0) - cy1 * np.sin(q0), cx1 * np.sin(q0) + cy1 * np.cos(q0),
         cz1 + params.c1], axis=-1)
    s1, c1 = np.sin(q0), np.cos(q0)
    s2, c2 = np.sin(q1 + q2), np.cos(q1 + q2)
    s3, c3 = np.sin(q3), np.cos(q3)
    s4, c4 = np.sin(q4), np.cos(q4)
    s5, c5 = np.sin(q5), np.cos(q5)
    zero = np.zeros_like(s1)
    R_0c = np.stack([
        np.stack([c1 * c2, -s1, c1 * s2], -1),
        np.stack([s1 * c2, c1, s1 * s2], -1),
        np.stack([-s2, zero, c2], -1)], -2)
    R_ce = np.stack([
        np.stack([c3 * c4 * c5 - s3 * s5, -c3 * c4 * s5 - s3 * c5, c3 * s4], -1),
        np.stack([s3 * c4 * c5 + c3 * s5, -s3 * c4 * s5 + c3 * c5, s3 * s4], -1),
        np.stack([-s4 * c5, s4 * s5, c4], -1)], -2)
    R = R_0c @ R_ce
    X = np.zeros((q.shape[0], 4, 4))
    X[:, :3, :3] = R
    X[:, :3, 3] = c0 + params.c4 * R[:, :, 2]
    X[:, 3, 3] = 1.0
    return X[0] if single else X
