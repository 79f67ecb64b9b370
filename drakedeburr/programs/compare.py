"""Compare a program read back from its files with the program that should be there.

``compare_programs(expected, actual)`` takes the :class:`RobotProgram` a plan (or CL file)
gives and the :class:`ReadProgram` a reader returned, and lists every difference as a
:class:`Discrepancy` naming file, line, move and item (pose, configuration, speed, zone, move
type, move order, move count, tool, work object, load, mode). Values are compared the way the
format holds them (:mod:`drakedeburr.programs.common`: e.g. LS speeds in whole mm/sec, LS
zones as CNT), so a program written by us compares equal to its plan, and an edited speed,
zone, pose or configuration, or two swapped moves, are named with their line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.programs.common import (
    joint_percent,
    ls_cnts,
    speed_written,
    zone_from_cnt,
    zone_written,
)
from drakedeburr.programs.program import JOINT, RobotProgram
from drakedeburr.programs.read_types import ReadMove, ReadProgram
from drakedeburr.robots import configuration_of
from drakedeburr.units import mm_from_m

__all__ = ["CompareTolerances", "Discrepancy", "compare_programs", "expected_values"]

_CONTROLLER = {"rapid": "abb", "krl": "kuka", "ls": "fanuc"}


@dataclass(frozen=True)
class CompareTolerances:
    """How far a value read back may be from the expected one (beyond the format's own
    resolution, which is applied to the expected value first).

    Attributes:
        position: [m]. orientation: [rad]. speed: [m/s]. zone: [m]. mass: [kg]. cog: [m].
    """

    position: float = 1e-6
    orientation: float = 1e-6
    speed: float = 1e-6
    zone: float = 1e-6
    mass: float = 1e-3
    cog: float = 1e-6


@dataclass(frozen=True)
class Discrepancy:
    """One difference between the expected and the actual program.

    Attributes:
        file: the file holding the line. line: 1-based line (0: the program as a whole).
        item: "pose", "configuration", "speed", "joint speed", "zone", "move type",
            "move order", "move count", "tool", "work object", "load" or "mode".
        expected, got: the values, as text with units.
        move: 1-based move number, or None.
    """

    file: str
    line: int
    item: str
    expected: str
    got: str
    move: int | None = None

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        move = f" move {self.move}" if self.move is not None else ""
        return f"{where}:{move} {self.item}: expected {self.expected}, got {self.got}"


@dataclass(frozen=True, eq=False)
class _Expected:
    move_type: str
    X_OT: np.ndarray
    configuration: object
    speed: float | None
    joint_percent: int | None
    zone: float


def expected_values(program: RobotProgram, fmt: str) -> list[_Expected]:
    """Per move, the values ``fmt`` holds for ``program`` (the writers' quantisation)."""
    out = []
    cnts = ls_cnts(program) if fmt == "ls" else None
    for i, m in enumerate(program.moves):
        joint_pct = fmt != "rapid" and m.move_type == JOINT
        out.append(_Expected(
            move_type=m.move_type, X_OT=program.X_OT(i),
            configuration=configuration_of(program.kinematics, m.q, _CONTROLLER[fmt]),
            speed=None if joint_pct else speed_written(fmt, m.speed),
            joint_percent=joint_percent(program.joint_fraction(i)) if joint_pct else None,
            zone=zone_from_cnt(int(cnts[i])) if cnts is not None else zone_written(fmt, m.zone)))
    return out


def _pose_error(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    dp = float(np.linalg.norm(A[:3, 3] - B[:3, 3]))
    R = A[:3, :3].T @ B[:3, :3]
    s = 0.5 * np.linalg.norm([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return dp, float(np.arctan2(s, 0.5 * (np.trace(R) - 1.0)))


def _pose_text(X: np.ndarray) -> str:
    x, y, z = mm_from_m(X[:3, 3])
    return f"({x:.3f}, {y:.3f}, {z:.3f}) mm"


def _same_pose(A, B, tol: CompareTolerances) -> bool:
    dp, da = _pose_error(A, B)
    return dp <= tol.position and da <= tol.orientation


def _frames(expected: RobotProgram, actual: ReadProgram, tol: CompareTolerances) -> list:
    out = []
    file = actual.files[0]
    if expected.stationary_tool != actual.stationary_tool:
        out.append(Discrepancy(file, 0, "mode",
                               "stationary tool" if expected.stationary_tool else "tool in hand",
                               "stationary tool" if actual.stationary_tool else "tool in hand"))
    X_RO = np.linalg.solve(expected.X_BR, expected.X_WO)
    for item, X_exp, X_got in (("tool", expected.X_FT, actual.X_FT),
                               ("work object", X_RO, actual.X_RO)):
        f, line = actual.frame_lines.get(item, (file, 0))
        if X_got is None:
            out.append(Discrepancy(f, line, item, _pose_text(X_exp), "not stated"))
        elif not _same_pose(X_exp, X_got, tol):
            dp, da = _pose_error(X_exp, X_got)
            out.append(Discrepancy(f, line, item, _pose_text(X_exp),
                                   f"{_pose_text(X_got)} ({dp * 1e3:.3f} mm, "
                                   f"{np.degrees(da):.4f} deg off)"))
    m = expected.tool_mass + expected.workpiece_mass
    cog = (expected.tool_mass * np.asarray(expected.tool_cog, float)
           + expected.workpiece_mass * np.asarray(expected.workpiece_cog, float)) / m
    f, line = actual.frame_lines.get("load", (file, 0))
    if actual.load_mass is None or actual.load_cog is None:
        out.append(Discrepancy(f, line, "load", f"{m:.3f} kg", "not stated"))
    elif abs(actual.load_mass - m) > tol.mass or np.abs(actual.load_cog - cog).max() > tol.cog:
        out.append(Discrepancy(f, line, "load", f"{m:.3f} kg at {np.round(mm_from_m(cog), 3)} mm",
                               f"{actual.load_mass:.3f} kg at "
                               f"{np.round(mm_from_m(actual.load_cog), 3)} mm"))
    return out


def _move(i: int, e: _Expected, a: ReadMove, tol: CompareTolerances, others: list) -> list:
    out = []
    n = i + 1
    if e.move_type != a.move_type:
        out.append(Discrepancy(a.file, a.line, "move type", e.move_type, a.move_type, n))
    if not _same_pose(e.X_OT, a.X_OT, tol):
        match = [j for j, o in enumerate(others) if j != i and _same_pose(o.X_OT, a.X_OT, tol)]
        if match:
            out.append(Discrepancy(a.file, a.line, "move order", f"target of move {n}",
                                   f"the target of move {match[0] + 1} ({a.name})", n))
            return out
        dp, da = _pose_error(e.X_OT, a.X_OT)
        line = a.target_line if dp > tol.position or not a.orientation_line else \
            a.orientation_line
        out.append(Discrepancy(a.target_file, line, "pose", _pose_text(e.X_OT),
                               f"{_pose_text(a.X_OT)} ({dp * 1e3:.3f} mm, "
                               f"{np.degrees(da):.4f} deg off)", n))
    if e.configuration != a.configuration:
        out.append(Discrepancy(a.target_file, a.config_line or a.target_line, "configuration",
                               str(e.configuration), str(a.configuration), n))
    if e.joint_percent is not None or a.joint_percent is not None:
        if e.joint_percent != a.joint_percent:
            out.append(Discrepancy(a.file, a.speed_line, "joint speed", f"{e.joint_percent} %",
                                   f"{a.joint_percent} %", n))
    elif a.speed is None or abs(a.speed - e.speed) > tol.speed:
        got = "none" if a.speed is None else f"{mm_from_m(a.speed):.3f} mm/s"
        out.append(Discrepancy(a.file, a.speed_line, "speed", f"{mm_from_m(e.speed):.3f} mm/s",
                               got, n))
    if abs(a.zone - e.zone) > tol.zone:
        out.append(Discrepancy(a.file, a.zone_line, "zone", f"{mm_from_m(e.zone):.3f} mm",
                               f"{mm_from_m(a.zone):.3f} mm", n))
    return out


def compare_programs(expected: RobotProgram, actual: ReadProgram,
                     tolerances: CompareTolerances | None = None) -> list[Discrepancy]:
    """Every difference between the program that should be there and the one read.

    Args:
        expected: the program as built from the plan (or CL file).
        actual: what a reader returned (:func:`drakedeburr.programs.read_program`).
        tolerances: beyond the format's resolution (default :class:`CompareTolerances`).

    Returns:
        Discrepancies in file order (empty: the program is the expected one).
    """
    tol = tolerances or CompareTolerances()
    exp = expected_values(expected, actual.format)
    out = _frames(expected, actual, tol)
    if len(exp) != len(actual.moves):
        last = actual.moves[-1] if actual.moves else None
        out.append(Discrepancy(actual.files[0], last.line if last else 0, "move count",
                               str(len(exp)), str(len(actual.moves))))
    for i, (e, a) in enumerate(zip(exp, actual.moves, strict=False)):
        out += _move(i, e, a, tol, exp)
    return out
