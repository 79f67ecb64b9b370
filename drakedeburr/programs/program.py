"""A robot program as data: what the writers turn into RAPID, KRL or FANUC LS.

Frames. B is the robot's base frame (:mod:`drakedeburr.robots`: the mounting face on axis 1);
a program knows nothing of the cell, so the ``W`` in the field names below is B. F is the
flange (the vendor's flange frame). The program is written the way KUKA and FANUC store it:

* ``X_FT``: the frame carried on the flange: the TCP of the tool (tool in hand) or the work
  object held by the robot (``stationary_tool``: workpiece in hand);
* ``X_WO``: the fixed frame in B: the work object (tool in hand) or the stationary tool's TCP
  (workpiece in hand);
* each move's ``X_WT``: the pose of the flange-carried frame in B, ``X_WT = FK(q) X_FT``; what a
  controller stores for it is ``X_OT = X_WO^-1 X_WT`` (KUKA $POS in $BASE, FANUC P[] in
  UFRAME; ABB's robtarget is the TCP in the work object: X_OT, or X_OT^-1 with a stationary
  tool).

Loads: ``tool_mass``/``tool_cog`` is what is bolted to the flange (the spindle, or the gripper
of a workpiece-in-hand cell); ``workpiece_mass``/``workpiece_cog`` the workpiece held (only with
``stationary_tool``). Centres of gravity are in F [m].
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots import (
    IRB1600_10_120_ROBOT,
    ROBOTS,
    RobotKinematics,
    RobotSpec,
    fk_opw,
)

__all__ = ["ProgramMove", "RobotProgram", "MoveDetails", "IoAction", "LINEAR", "JOINT",
           "check_pose",
           "DEFAULT_JOINT_SPEED_FRACTION", "zones_within_half_moves"]

LINEAR = "linear"
JOINT = "joint"
#: joint moves without a planned speed run at this fraction of every axis' top speed
DEFAULT_JOINT_SPEED_FRACTION = 0.25
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,23}")
_PROGRAM_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,35}")


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


@dataclass(frozen=True)
class IoAction:
    """Set a digital or analogue output (RAPID ``SetDO``/``SetAO``, KRL ``$OUT[n]``/
    ``$ANOUT[n]``, FANUC ``DO[n]=ON``/``AO[n]=value``).

    Attributes:
        kind: "do" or "ao".
        port: the output's number (KRL, LS).
        name: the signal's name (RAPID; signals are named in the controller's I/O setup).
        value: DO: 0 or 1; AO: fraction of full scale, 0..1.
        full_scale: the AO value at full scale per format (RAPID logical value, KRL
            ``$ANOUT`` 1.0, LS counts).
        comment: why (e.g. "SPINDL CL line 13").
    """

    kind: str
    port: int
    name: str
    value: float
    full_scale: tuple[float, float, float] = (10.0, 1.0, 4095.0)
    comment: str = ""

    def __post_init__(self) -> None:
        if self.kind not in ("do", "ao"):
            raise InputError(f"I/O action kind {self.kind!r} (do|ao)")
        if not (isinstance(self.port, int) and self.port >= 1):
            raise InputError(f"I/O port must be an integer >= 1, got {self.port!r}")
        if not _NAME.fullmatch(self.name):
            raise InputError(f"I/O signal name {self.name!r}: letters, digits, '_', start with "
                             "a letter, at most 24 characters")
        ok = self.value in (0, 1) if self.kind == "do" else 0.0 <= self.value <= 1.0
        if not ok:
            raise InputError(f"I/O {self.kind} {self.name}: value {self.value!r} (DO 0/1, AO "
                             "0..1 of full scale)")

    def written(self, fmt: str) -> float:
        """The AO value as ``fmt`` writes it (LS: whole counts)."""
        k = ("rapid", "krl", "ls").index(fmt)
        v = self.value * self.full_scale[k]
        return float(round(v)) if fmt == "ls" else round(v, 6)


@dataclass(frozen=True, eq=False)
class ProgramMove:
    """One robot motion.

    Attributes:
        X_WT: (4, 4) pose of the flange-carried frame in the robot base [m] (module docstring).
        q: (6,) planned model joints [rad]; the configuration data written come from them.
        move_type: ``"linear"`` (MoveL / LIN / L) or ``"joint"`` (MoveJ / PTP / J).
        speed: TCP speed [m/s] (relative speed of tool and work object). Joint moves: the
            RAPID MoveJ speed; KRL/LS joint moves use ``joint_fraction``.
        zone: corner zone radius [m]; 0 = stop point (fine).
        comment: short text written before the move.
        source_line: e.g. the CL line number the move came from (for messages), or None.
        joint_fraction: joint moves: fraction (0, 1] of every axis' top speed (KRL
            BAS(#VEL_PTP), LS J %); None = the program's ``joint_speed_fraction``.
        io: outputs set before the move (spindle, coolant), in order.
    """

    X_WT: np.ndarray
    q: np.ndarray
    move_type: str = LINEAR
    speed: float = 0.150
    zone: float = 0.0
    comment: str = ""
    source_line: int | None = None
    joint_fraction: float | None = None
    io: tuple[IoAction, ...] = ()


@dataclass(frozen=True)
class MoveDetails:
    """Per-move columns of :meth:`RobotProgram.from_poses` beyond pose, speed, zone and type
    (each None, or one entry per move).

    Attributes:
        comments: the moves' comments ("" where none).
        source_lines: the input lines the moves come from (CL / plan), None where none.
        joint_fractions: a joint move's fraction of the axes' top speed (None: the
            program's ``joint_speed_fraction``).
    """

    comments: Sequence[str] | None = None
    source_lines: Sequence[int | None] | None = None
    joint_fractions: Sequence[float | None] | None = None


@dataclass(frozen=True, eq=False)
class RobotProgram:
    """A complete program: frames, loads, moves and header information.

    Attributes:
        name: program/module name (letters, digits, '_'; starts with a letter; <= 36 chars;
            RAPID <= 32).
            KRL and LS programs take the file's name when written (their controllers need it).
        moves: the motions, in order.
        X_FT: (4, 4) frame carried on the flange, in F [m] (module docstring).
        X_WO: (4, 4) fixed frame in the robot base B [m].
        robot: the arm (:class:`~drakedeburr.robots.RobotSpec`, or its kinematics).
        stationary_tool: workpiece in hand (ABB stationary tool + robot-held work object, KUKA
            external TCP, FANUC remote TCP).
        tool_name / wobj_name: data names in the program.
        tool_mass: [kg] and tool_cog: (3,) [m] in F of what is bolted to the flange.
        workpiece_mass, workpiece_cog: the held workpiece (stationary_tool only).
        load_source: where the loads come from (written in the header).
        joint_speed_fraction: default fraction of the axes' top speed for joint moves.
        source: where the data came from (e.g. the CL file or the plan).
        flag: prominent header warning, e.g. ``"FORCED"`` or ``"UNVERIFIED"`` ("" = none).
        flag_reason: one line explaining the flag.
        notes: further header comment lines.
        io_end: outputs set after the last move (e.g. spindle off at the end of the file).
    """

    name: str
    moves: tuple[ProgramMove, ...]
    X_FT: np.ndarray = field(default_factory=lambda: np.eye(4))
    X_WO: np.ndarray = field(default_factory=lambda: np.eye(4))
    robot: RobotSpec | RobotKinematics = IRB1600_10_120_ROBOT
    stationary_tool: bool = False
    tool_name: str = "tBurr"
    wobj_name: str = "wobjHub"
    tool_mass: float = 2.0
    tool_cog: tuple[float, float, float] = (0.0, 0.0, 0.08)
    workpiece_mass: float = 0.0
    workpiece_cog: tuple[float, float, float] = (0.0, 0.0, 0.0)
    load_source: str = "default values, not from a tool model"
    joint_speed_fraction: float = DEFAULT_JOINT_SPEED_FRACTION
    source: str = ""
    flag: str = ""
    flag_reason: str = ""
    notes: tuple[str, ...] = ()
    io_end: tuple[IoAction, ...] = ()

    def __post_init__(self) -> None:
        if not _PROGRAM_NAME.fullmatch(self.name):
            raise InputError(f"program name {self.name!r}: letters, digits, '_', start with a "
                             "letter, at most 36 characters")
        for label in (self.tool_name, self.wobj_name):
            if not _NAME.fullmatch(label):
                raise InputError(f"data name {label!r}: letters, digits, '_', start with a "
                                 "letter, at most 24 characters")
        object.__setattr__(self, "X_FT", check_pose(self.X_FT, "X_FT (flange-carried frame)"))
        object.__setattr__(self, "X_WO", check_pose(self.X_WO, "X_WO (fixed frame)"))
        object.__setattr__(self, "moves", tuple(self.moves))
        if not self.moves:
            raise InputError("a program needs at least one move")
        if not self.tool_mass > 0:
            raise InputError(f"tool_mass must be > 0 kg, got {self.tool_mass}")
        if not self.workpiece_mass >= 0 or (self.workpiece_mass > 0 and not self.stationary_tool):
            raise InputError("workpiece_mass: >= 0 kg, and only for a stationary-tool program")
        if not 0 < self.joint_speed_fraction <= 1:
            raise InputError(f"joint_speed_fraction must be in (0, 1], got "
                             f"{self.joint_speed_fraction}")
        for i, m in enumerate(self.moves):
            _check_move(i, m)

    # ------------------------------------------------------------------ the arm
    @property
    def kinematics(self) -> RobotKinematics:
        return self.robot.kinematics if isinstance(self.robot, RobotSpec) else self.robot

    @property
    def spec(self) -> RobotSpec | None:
        """The registered arm (None for an unregistered kinematics)."""
        if isinstance(self.robot, RobotSpec):
            return self.robot
        spec = ROBOTS.get(self.robot.name)
        if spec is not None and spec.opw == self.robot.opw:
            return spec
        from drakedeburr.robots.arm_file import loaded_spec_for

        return loaded_spec_for(self.robot)  # an arm file's (--robot FILE)

    @property
    def controller(self) -> str:
        return self.kinematics.controller

    @property
    def X_BR(self) -> np.ndarray:
        """(4, 4) the controller's robot frame (ABB base, KUKA $ROBROOT, FANUC world) in B."""
        spec = self.spec
        return np.eye(4) if spec is None else np.asarray(spec.X_BR)

    @classmethod
    def from_poses(
        cls,
        name: str,
        X_WT: Sequence[np.ndarray] | np.ndarray,
        q: Sequence[np.ndarray] | np.ndarray,
        speed: float | Sequence[float] = 0.150,
        zone: float | Sequence[float] = 0.0,
        move_type: str | Sequence[str] = LINEAR,
        details: MoveDetails = MoveDetails(),
        **kwargs,
    ) -> RobotProgram:
        """Build a program from arrays: X_WT (N, 4, 4) [m], q (N, 6) [rad], per-move or
        scalar speed [m/s], zone [m] and move type, per-move comments, source lines and
        joint fractions (:class:`MoveDetails`); other fields by keyword."""
        comments, source_lines = details.comments, details.source_lines
        joint_fractions = details.joint_fractions
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
                        source_line=source_lines[i] if source_lines else None,
                        joint_fraction=joint_fractions[i] if joint_fractions else None)
            for i in range(n))
        return cls(name=name, moves=moves, **kwargs)

    def X_OT(self, i: int) -> np.ndarray:
        """(4, 4) pose of move i's flange-carried frame in the fixed frame [m]."""
        return np.linalg.solve(self.X_WO, self.moves[i].X_WT)

    def joint_fraction(self, i: int) -> float:
        """Fraction of the axes' top speed for move i (joint moves)."""
        f = self.moves[i].joint_fraction
        return self.joint_speed_fraction if f is None else f

    def configuration(self, i: int):
        """The controller's configuration data of move i (ABB cf, KUKA (S, T), FANUC str)."""
        from drakedeburr.robots import configuration_of

        return configuration_of(self.kinematics, self.moves[i].q, self.controller)

    def path_points(self) -> np.ndarray:
        """(N, 3) the programmed TCP path [m] as the controller interpolates it: the TCP in the
        work object (tool in hand: X_OT's origin; stationary tool: the fixed TCP in the held
        work object, X_OT^-1's origin)."""
        X = np.array([self.X_OT(i) for i in range(len(self.moves))])
        if self.stationary_tool:
            X = np.linalg.inv(X)
        return X[:, :3, 3]

    def zone_limits(self) -> np.ndarray:
        """(N,) the largest zone radius [m] each move may carry so that no controller shrinks
        it: half the shorter of the move into its target and the move out of it (ABB zonedata
        and KUKA C_DIS are reduced to half the adjacent move; RAPID reference "zonedata",
        KSS "Approximate positioning"). The first move's start and the last move's successor
        are not in the program: only the move the program holds counts there."""
        p = self.path_points()
        d = np.linalg.norm(np.diff(p, axis=0), axis=1)
        out = np.zeros(len(p))
        if len(p) >= 2:
            out[0], out[-1] = 0.5 * d[0], 0.5 * d[-1]
        if len(p) > 2:
            out[1:-1] = 0.5 * np.minimum(d[:-1], d[1:])
        return out

    def consistency_error(self) -> np.ndarray:
        """(N,) distance [m] between FK(q) * X_FT and X_WT per move (position part) plus
        orientation error [rad]; the writers refuse programs where it exceeds 1e-6."""
        out = np.zeros(len(self.moves))
        for i, m in enumerate(self.moves):
            X = fk_opw(self.kinematics.opw, m.q) @ self.X_FT
            dp = np.linalg.norm(X[:3, 3] - m.X_WT[:3, 3])
            R = X[:3, :3].T @ m.X_WT[:3, :3]
            # rotation angle by atan2 (arccos of the trace loses ~1e-8 rad near 0)
            s = 0.5 * np.linalg.norm([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
            out[i] = dp + float(np.arctan2(s, 0.5 * (np.trace(R) - 1.0)))
        return out


def zones_within_half_moves(program: RobotProgram) -> RobotProgram:
    """The program with every zone reduced to :meth:`RobotProgram.zone_limits` (rounded down
    to 0.001 mm, the finest zone RAPID and KRL write), so the corner the controller makes is
    the one written."""
    from dataclasses import replace

    limits = np.floor(program.zone_limits() * 1e6 + 1e-6) / 1e6
    moves = tuple(m if m.zone <= lim else replace(m, zone=float(lim))
                  for m, lim in zip(program.moves, limits, strict=True))
    return replace(program, moves=moves)


def _check_move(i: int, m: ProgramMove) -> None:
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
    if m.joint_fraction is not None and not 0 < m.joint_fraction <= 1:
        raise InputError(f"move {i + 1}: joint_fraction must be in (0, 1], got "
                         f"{m.joint_fraction}")
