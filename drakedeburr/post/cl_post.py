"""CL file -> robot program: the post-processor of SPEC.md S1.

CL points (tool tip + CAM tool axis) are taken in the work object O (the robot base when no
work object is given), the free spin about the tool axis is resolved
(:mod:`drakedeburr.post.tool_axis`), joints come from the analytic IK with configuration
continuity, and a :class:`~drakedeburr.post.program.RobotProgram` is built. Points the robot
cannot reach are reported with their CL line numbers; they are left out of the program only
when the caller forces it, and the program header then says FORCED.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.post.cl_reader import ClProgram
from drakedeburr.post.tool_axis import ToolAxisPathResult, solve_tool_axis_path
from drakedeburr.programs.program import JOINT, LINEAR, ProgramMove, RobotProgram
from drakedeburr.robots import IRB1600_10_120_ROBOT, RobotKinematics
from drakedeburr.units import m_from_mm, rad_from_deg

__all__ = ["PostResult", "program_from_cl", "pose_from_mm_deg", "ROBOTS"]

log = logging.getLogger(__name__)

ROBOTS: dict[str, RobotKinematics] = {"irb1600": IRB1600_10_120_ROBOT}


def pose_from_mm_deg(values: tuple[float, ...] | list[float], what: str = "pose") -> np.ndarray:
    """(4, 4) transform from (x, y, z [mm], rx, ry, rz [deg]), R = Rz(rz) Ry(ry) Rx(rx).

    This is the fixed-axis XYZ convention of KUKA (A=rz, B=ry, C=rx) and FANUC (W, P, R).
    """
    from scipy.spatial.transform import Rotation

    v = [float(x) for x in values]
    if len(v) != 6 or not np.all(np.isfinite(v)):
        raise InputError(f"{what}: expected 6 finite numbers x,y,z,rx,ry,rz (mm, deg), "
                         f"got {values!r}")
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("ZYX", rad_from_deg(np.array(v[5:2:-1]))).as_matrix()
    X[:3, 3] = m_from_mm(np.array(v[:3]))
    return X


@dataclass(frozen=True)
class PostResult:
    """Outcome of :func:`program_from_cl`.

    Attributes:
        program: the program (None when points are unreachable and ``force`` is False).
        unreachable_lines: CL line numbers of points the robot cannot reach.
        configuration_change_lines: CL lines where the arm configuration changes.
        joints: the IK result for every CL move (NaN rows where unreachable).
    """

    program: RobotProgram | None
    unreachable_lines: tuple[int, ...]
    configuration_change_lines: tuple[int, ...]
    joints: ToolAxisPathResult

    @property
    def ok(self) -> bool:
        return not self.unreachable_lines


def program_from_cl(
    cl: ClProgram,
    name: str,
    robot: RobotKinematics = IRB1600_10_120_ROBOT,
    X_WO: np.ndarray | None = None,
    X_FT: np.ndarray | None = None,
    spin_mode: str = "min_travel",
    zone: float = 1e-3,
    feed: float | None = None,
    rapid_speed: float | None = None,
    force: bool = False,
    process: ProcessParameters | None = None,
    q_start: np.ndarray | None = None,
    progress: Callable[[int, int, str], None] | None = None,
) -> PostResult:
    """Post-process a read CL file for a robot.

    Args:
        cl: the CL data (:func:`~drakedeburr.post.cl_reader.read_cl`).
        name: program name.
        robot: kinematics and limits.
        X_WO: (4, 4) work object (CL frame) in the robot base [m]; None = identity.
        X_FT: (4, 4) tool in the flange frame [m]; None = 0.2 m along the flange axis.
        spin_mode: "min_travel", "greedy" or "theta6_zero".
        zone: corner zone of feed moves [m] (the last move is always a stop point).
        feed: TCP speed of feed moves [m/s]; None = the CL file's FEDRAT, else
            ``process.grinding_speed``.
        rapid_speed: speed of RAPID moves (joint moves) [m/s]; None =
            ``process.window_switch_speed``.
        force: build the program even with unreachable points (they are left out and the
            header says FORCED).
        process: process parameters for the defaults.
        q_start: (6,) joints the robot starts from [rad] (default: tool_axis.READY_POSE);
            the first point's configuration is the one closest to it.
        progress: optional callback (done, total, label).
    """
    process = process or ProcessParameters()
    if not cl.moves:
        raise InputError(f"{cl.source}: no moves in the CL file")
    X_WO = np.eye(4) if X_WO is None else np.asarray(X_WO, float)
    if X_FT is None:
        X_FT = np.eye(4)
        X_FT[2, 3] = 0.2
    p_W = cl.p_C @ X_WO[:3, :3].T + X_WO[:3, 3]
    axis_W = cl.axis_C @ X_WO[:3, :3].T
    res = solve_tool_axis_path(robot, p_W, axis_W, X_FT, mode=spin_mode, q_start=q_start,
                               progress=progress)
    lines = cl.lines
    bad = tuple(sorted({int(lines[i]) for i in res.failed}))
    changes = tuple(sorted({int(lines[i]) for i in res.configuration_changes}))
    if bad and not force:
        log.warning("%d CL point(s) unreachable, first at line(s) %s", len(bad),
                    ", ".join(map(str, bad[:10])))
        return PostResult(None, bad, changes, res)
    moves = []
    keep = np.flatnonzero(res.reachable)
    rapid_speed = process.window_switch_speed if rapid_speed is None else rapid_speed
    for n_kept, i in enumerate(keep):
        m = cl.moves[i]
        v = feed if feed is not None else (m.feed if np.isfinite(m.feed) and m.feed > 0
                                           else process.grinding_speed)
        last = n_kept == len(keep) - 1
        moves.append(ProgramMove(
            X_WT=res.X_WT[i], q=res.q[i], move_type=JOINT if m.rapid else LINEAR,
            speed=rapid_speed if m.rapid else v, zone=0.0 if last or m.rapid else zone,
            comment=f"CL line {m.line}" if (m.rapid or n_kept == 0) else "",
            source_line=m.line))
    if not moves:
        return PostResult(None, bad, changes, res)
    notes = [f"spin about the tool axis: {spin_mode}"]
    if changes:
        notes.append("configuration changes at CL lines " + ", ".join(map(str, changes[:20])))
    program = RobotProgram(
        name=name, moves=tuple(moves), X_FT=X_FT, X_WO=X_WO, robot=robot,
        source=Path(cl.source).name,
        flag="FORCED" if bad else "UNVERIFIED",
        flag_reason=(f"{len(bad)} unreachable CL point(s) left out, lines "
                     + ", ".join(map(str, bad[:15])) if bad
                     else "joint limits checked; collisions NOT checked"),
        notes=tuple(notes))
    return PostResult(program, bad, changes, res)
