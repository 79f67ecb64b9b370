"""The robot program the writers turn into RAPID, KRL or FANUC LS.

Frames (DESIGN.md): W world = robot base; F flange (ABB tool0); T tool (TCP at the burr's
cutting point, +Z spindle -> tip); O work object (user frame) in W. Every move carries the
TCP pose X_WT and the planned joints; the writers express the pose in the work object
(X_OT = X_WO^-1 X_WT) and derive the vendor configuration data from the joints.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.post.opw import fk_opw
from drakedeburr.post.opw_ik import IRB1600_10_120_ROBOT, RobotKinematics

__all__ = ["ProgramMove", "RobotProgram", "LINEAR", "JOINT", "check_pose"]

LINEAR = "linear"
JOINT = "joint"


def check_pose(X: np.ndarray, what: str, tol: float = 1e-6) -> np.ndarray:
    """Validate a (4, 4) rigid transform; returns it as a float array.

    Raises:
        InputError: wrong shape, non-finite, or rotation part not orthonormal (right-handed).
    """
    X = np.asarray(X, float)
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise InputError(f"{what}: expected a finite (4, 4) transform, got shape {X.shape}")
    R = X[:3, :3]
    if (np.abs(R.T @ R - np.eye(3)).max() > tol or np.linalg.det(R) < 0
            or np.abs(X[3] - [0, 0, 0, 1]).max() > tol):
        raise InputError(f"{what}: not a rigid transform (rotation not orthonormal)")
    return X


@dataclass(frozen=True, eq=False)
class ProgramMove:
    """One robot motion.

    Attributes:
        X_WT: (4, 4) TCP pose in the robot base / world [m].
        q: (6,) planned joints in the robot's convention [rad]; the configuration data
            written to the program are derived from them.
        move_type: ``"linear"`` (MoveL / LIN / L) or ``"joint"`` (MoveJ / PTP / J).
        speed: TCP speed [m/s] (linear moves; joint moves use it as a cap where the format
            allows, else full joint speed).
        zone: corner zone radius [m]; 0 = stop point (fine).
        comment: short text written before the move.
        source_line: e.g. the CL line number the move came from (for messages), or None.
    """

    X_WT: np.ndarray
    q: np.ndarray
    move_type: str = LINEAR
    speed: float = 0.150
    zone: float = 0.0
    comment: str = ""
    source_line: int | None = None


@dataclass(frozen=True, eq=False)
class RobotProgram:
    """A complete program: tool, work object, moves and header information.

    Attributes:
        name: program/module name (letters, digits, underscore; starts with a letter).
        moves: the motions, in order.
        X_FT: (4, 4) tool (TCP) in the flange frame [m] (ABB tooldata tframe, KUKA $TOOL).
        X_WO: (4, 4) work object in the robot base [m] (ABB wobjdata uframe, KUKA $BASE,
            FANUC user frame).
        robot: kinematics used to check and to derive configuration data.
        tool_name / wobj_name: names used in the program.
        tool_mass: [kg]; tool_cog: (3,) centre of gravity in the flange frame [m].
        source: where the data came from (e.g. the CL file name).
        flag: prominent header warning, e.g. ``"FORCED"`` or ``"UNVERIFIED"`` ("" = none).
        flag_reason: one line explaining the flag.
        notes: further header comment lines.
    """

    name: str
    moves: tuple[ProgramMove, ...]
    X_FT: np.ndarray = field(default_factory=lambda: np.eye(4))
    X_WO: np.ndarray = field(default_factory=lambda: np.eye(4))
    robot: RobotKinematics = IRB1600_10_120_ROBOT
    tool_name: str = "tBurr"
    wobj_name: str = "wobjHub"
    tool_mass: float = 2.0
    tool_cog: tuple[float, float, float] = (0.0, 0.0, 0.08)
    source: str = ""
    flag: str = ""
    flag_reason: str = ""
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        import re

        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,23}", self.name):
            raise InputError(f"program name {self.name!r}: letters, digits, '_', start with a "
                             "letter, at most 24 characters")
        for label in (self.tool_name, self.wobj_name):
            if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,23}", label):
                raise InputError(f"data name {label!r}: letters, digits, '_'")
        object.__setattr__(self, "X_FT", check_pose(self.X_FT, "X_FT (tool)"))
        object.__setattr__(self, "X_WO", check_pose(self.X_WO, "X_WO (work object)"))
        object.__setattr__(self, "moves", tuple(self.moves))
        if not self.moves:
            raise InputError("a program needs at least one move")
        if not self.tool_mass > 0:
            raise InputError(f"tool_mass must be > 0 kg, got {self.tool_mass}")
        for i, m in enumerate(self.moves):
            check_pose(m.X_WT, f"move {i + 1} X_WT")
            q = np.asarray(m.q, float)
            if q.shape != (6,) or not np.all(np.isfinite(q)):
                raise InputError(f"move {i + 1}: q must be 6 finite joint values [rad]")
            if m.move_type not in (LINEAR, JOINT):
                raise InputError(f"move {i + 1}: move_type {m.move_type!r} (linear|joint)")
            if not (np.isfinite(m.speed) and m.speed > 0):
                raise InputError(f"move {i + 1}: speed must be > 0 m/s, got {m.speed}")
            if not (np.isfinite(m.zone) and m.zone >= 0):
                raise InputError(f"move {i + 1}: zone must be >= 0 m, got {m.zone}")

    @classmethod
    def from_poses(
        cls,
        name: str,
        X_WT: Sequence[np.ndarray] | np.ndarray,
        q: Sequence[np.ndarray] | np.ndarray,
        speed: float | Sequence[float] = 0.150,
        zone: float | Sequence[float] = 0.0,
        move_type: str | Sequence[str] = LINEAR,
        comments: Sequence[str] | None = None,
        source_lines: Sequence[int | None] | None = None,
        **kwargs,
    ) -> RobotProgram:
        """Build a program from arrays: X_WT (N, 4, 4) [m], q (N, 6) [rad], per-move or
        scalar speed [m/s], zone [m] and move type; other fields by keyword."""
        X_WT = np.asarray(X_WT, float).reshape(-1, 4, 4)
        q = np.asarray(q, float).reshape(-1, 6)
        n = X_WT.shape[0]
        if q.shape[0] != n:
            raise InputError(f"{n} poses but {q.shape[0]} joint vectors")

        def per(v, i):
            return v if isinstance(v, (int, float, str)) else v[i]

        moves = tuple(
            ProgramMove(X_WT=X_WT[i], q=q[i], move_type=per(move_type, i),
                        speed=float(per(speed, i)), zone=float(per(zone, i)),
                        comment=comments[i] if comments else "",
                        source_line=source_lines[i] if source_lines else None)
            for i in range(n))
        return cls(name=name, moves=moves, **kwargs)

    def X_OT(self, i: int) -> np.ndarray:
        """(4, 4) TCP pose of move i in the work object frame [m]."""
        return np.linalg.solve(self.X_WO, self.moves[i].X_WT)

    def consistency_error(self) -> np.ndarray:
        """(N,) distance [m] between FK(q) * X_FT and X_WT per move (position part) plus
        orientation error [rad]; the writers refuse programs where it exceeds 1e-6."""
        out = np.zeros(len(self.moves))
        for i, m in enumerate(self.moves):
            X = fk_opw(self.robot.opw, m.q) @ self.X_FT
            dp = np.linalg.norm(X[:3, 3] - m.X_WT[:3, 3])
            c = (np.trace(X[:3, :3].T @ m.X_WT[:3, :3]) - 1.0) / 2.0
            out[i] = dp + float(np.arccos(np.clip(c, -1.0, 1.0)))
        return out
