"""CL file -> robot program: the post-processor of SPEC.md S1.

CL points (tool tip + CAM tool axis) are taken in the work object O (the robot base when no
work object is given), the free spin about the tool axis is resolved
(:mod:`drakedeburr.post.tool_axis`), joints come from the analytic IK with configuration
continuity, and a :class:`~drakedeburr.programs.program.RobotProgram` is built. Every tool path of
the file goes into the program in file order; its first move carries the path's name as a
comment and the header lists the paths, UNITS switches, expanded drilling cycles and the
words of the file that are not in the program. Rapids of the file are joint moves; the rapids
of an expanded drilling cycle are linear moves at rapid speed (the tool is in or right over
a hole).

Workpiece in hand (``stationary_tool``): the spindle stands still and the robot holds the part.
The CL points are then in the held part's frame O, ``X_WO`` is the spindle's TCP in the robot
base and ``X_FT`` is O in the flange frame (the frame the flange carries); the program is a
stationary-tool program (ABB robhold FALSE, KUKA external TCP, FANUC RTCP). Points the robot
cannot reach are reported with their CL line numbers; they are left
out of the program only when the caller forces it, and the header then says FORCED.

:func:`post_cl_file` is the streaming form the CLI uses: the file is read into arrays (about
90 bytes per move), the joints are solved in segments, and programs longer than
``max_moves`` are written as numbered parts, each built only while it is written, so memory
stays bounded for files of millions of lines. Progress goes to a callback; nothing is printed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError
from drakedeburr.post.cl_reader import ClProgram, ClReadOptions, read_cl
from drakedeburr.post.tool_axis import (
    ToolAxisOptions,
    ToolAxisPathResult,
    solve_tool_axis_path,
)
from drakedeburr.programs.program import (
    JOINT,
    LINEAR,
    IoAction,
    ProgramMove,
    RobotProgram,
    zones_within_half_moves,
)
from drakedeburr.robots import IRB1600_10_120_ROBOT, RobotKinematics
from drakedeburr.units import m_from_mm, rad_from_deg

__all__ = ["PostResult", "PostSettings", "PostSummary", "PostIO", "PostOutput", "program_from_cl",
           "post_cl_file", "pose_from_mm_deg", "robot_kinematics", "io_actions", "MAX_MOVES",
           "program_moves", "unreachable_flag", "part_file"]

log = logging.getLogger(__name__)

def robot_kinematics(name: str) -> RobotKinematics:
    """The analytic kinematics of a registered arm (``drakedeburr robots``)."""
    from drakedeburr.robots import get_robot

    return get_robot(name).kinematics
MAX_MOVES = 100_000  # moves per written program file; longer programs are split into parts
_NOTE_LINES = 40  # header lines listing tool paths / words at most


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
class PostIO:
    """Which controller outputs the CL file's SPINDL and COOLNT statements set (``--io``
    YAML with these fields). A port left None writes nothing for that function (the word is
    then listed as not applied, as without I/O settings).

    Attributes:
        spindle_do: DO number that runs the spindle (KRL ``$OUT[n]``, LS ``DO[n]``).
        spindle_do_name: its RAPID signal name (``SetDO doSpindle, 1;``).
        spindle_ccw_do: DO selecting counter-clockwise rotation (SPINDL/.., CCLW); None =
            the spindle turns one way only (CCLW is then refused).
        spindle_ccw_do_name: its RAPID signal name.
        spindle_ao: AO number of the speed command (KRL ``$ANOUT[n]``, LS ``AO[n]``).
        spindle_ao_name: its RAPID signal name (``SetAO aoSpindle, value;``).
        spindle_rpm_full_scale: spindle speed at the AO's full scale [1/min]; the AO value is
            rpm / this x the format's full scale (linear, 0 at standstill).
        ao_full_scale_rapid: RAPID logical value of the AO at full scale (e.g. 10 for a
            0-10 V output scaled in volts).
        ao_full_scale_krl: KRL ``$ANOUT`` at full scale (KSS: -1.0 .. 1.0, so 1.0).
        ao_full_scale_ls: FANUC AO value at full scale (counts of the analogue board, 4095
            for a 12-bit output).
        coolant_do: DO number that switches the coolant (COOLNT/ON, FLOOD, MIST ... OFF).
        coolant_do_name: its RAPID signal name.
    """

    spindle_do: int | None = None
    spindle_do_name: str = "doSpindle"
    spindle_ccw_do: int | None = None
    spindle_ccw_do_name: str = "doSpindleCcw"
    spindle_ao: int | None = None
    spindle_ao_name: str = "aoSpindle"
    spindle_rpm_full_scale: float = 24000.0
    ao_full_scale_rapid: float = 10.0
    ao_full_scale_krl: float = 1.0
    ao_full_scale_ls: float = 4095.0
    coolant_do: int | None = None
    coolant_do_name: str = "doCoolant"

    def __post_init__(self) -> None:
        for name in ("spindle_do", "spindle_ccw_do", "spindle_ao", "coolant_do"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
                raise InputError(f"I/O settings: {name} must be an output number >= 1, got "
                                 f"{v!r}")
        for name in ("spindle_rpm_full_scale", "ao_full_scale_rapid", "ao_full_scale_ls"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
                raise InputError(f"I/O settings: {name} must be > 0, got {v!r}")
        if not (isinstance(self.ao_full_scale_krl, (int, float))
                and 0 < self.ao_full_scale_krl <= 1.0):
            raise InputError(f"I/O settings: ao_full_scale_krl must be in (0, 1] ($ANOUT is "
                             f"-1.0 .. 1.0), got {self.ao_full_scale_krl!r}")
        dos = [p for p in (self.spindle_do, self.spindle_ccw_do, self.coolant_do) if p]
        if len(dos) != len(set(dos)):
            raise InputError(f"I/O settings: the spindle, direction and coolant DOs must "
                             f"differ, got {dos}")
        names = (self.spindle_do_name, self.spindle_ccw_do_name, self.spindle_ao_name,
                 self.coolant_do_name)
        for n in names:  # validated as IoAction names
            IoAction("do", 1, n, 0)

    @property
    def any(self) -> bool:
        return any(p is not None for p in (self.spindle_do, self.spindle_ao, self.coolant_do))

    @property
    def words(self) -> frozenset[str]:
        """The CL words these settings write."""
        out = set()
        if self.spindle_do is not None or self.spindle_ao is not None:
            out.add("SPINDL")
        if self.coolant_do is not None:
            out.add("COOLNT")
        return frozenset(out)


def io_actions(io: PostIO, word: str, value: float, line: int, source: str = "CL"
               ) -> tuple[IoAction, ...]:
    """The outputs a SPINDL (value = signed rpm, 0 = off) or COOLNT (1/0) statement sets.

    Raises:
        InputError: a speed above the AO's full scale, or CCLW without a direction output.
    """
    out: list[IoAction] = []
    why = f"{word} CL line {line}"
    if word == "COOLNT":
        if io.coolant_do is not None:
            out.append(IoAction("do", io.coolant_do, io.coolant_do_name, int(value > 0),
                                comment=why))
        return tuple(out)
    rpm = float(value)
    if np.isnan(rpm):  # SPINDL/ON before any speed
        if io.spindle_ao is not None:
            raise InputError(f"{source}:{line}: SPINDL/ON without a speed: the speed output "
                             "(spindle_ao) cannot be set")
        return () if io.spindle_do is None else (
            IoAction("do", io.spindle_do, io.spindle_do_name, 1, comment=why),)
    if rpm < 0 and io.spindle_ccw_do is None and (io.spindle_do or io.spindle_ao):
        raise InputError(f"{source}:{line}: SPINDL counter-clockwise (CCLW) but the I/O "
                         "settings have no spindle_ccw_do")
    if io.spindle_ccw_do is not None and rpm != 0:
        out.append(IoAction("do", io.spindle_ccw_do, io.spindle_ccw_do_name, int(rpm < 0),
                            comment=why))
    if io.spindle_ao is not None:
        if abs(rpm) > io.spindle_rpm_full_scale * (1 + 1e-12):
            raise InputError(f"{source}:{line}: SPINDL {abs(rpm):g} rpm is above the AO's full "
                             f"scale spindle_rpm_full_scale = {io.spindle_rpm_full_scale:g}")
        out.append(IoAction("ao", io.spindle_ao, io.spindle_ao_name,
                            abs(rpm) / io.spindle_rpm_full_scale,
                            (io.ao_full_scale_rapid, io.ao_full_scale_krl,
                             io.ao_full_scale_ls), comment=why))
    if io.spindle_do is not None:
        out.append(IoAction("do", io.spindle_do, io.spindle_do_name, int(rpm != 0),
                            comment=why))
    if rpm == 0:  # switch off first, then zero the speed command
        out.reverse()
    return tuple(out)


@dataclass(frozen=True)
class PostSettings:
    """How a CL file becomes robot motion (see :func:`program_from_cl` for each field).

    Attributes:
        robot: kinematics and limits.
        X_WO: (4, 4) the fixed frame in the robot base [m]: the work object (CL frame), or
            the spindle's TCP with ``stationary_tool``; None = identity (tool in hand only).
        X_FT: (4, 4) the frame the flange carries [m]: the tool, or the part's CL frame with
            ``stationary_tool``; None = 0.2 m along the flange axis (tool), the flange (part).
        spin_mode: "min_travel", "greedy" or "theta6_zero".
        zone: corner zone of feed moves [m].
        feed: TCP speed of feed moves [m/s]; None = the file's FEDRAT, else the process speed.
        rapid_speed: speed of rapid moves [m/s]; None = ``process.window_switch_speed``.
        force: write the reachable part when points are unreachable (flagged FORCED).
        q_start: (6,) joints the robot starts from [rad]; None = tool_axis.READY_POSE.
        process: process parameters for the defaults.
        stationary_tool: workpiece in hand (module docstring).
        io: the outputs SPINDL / COOLNT set (None: they are not written).
    """

    robot: RobotKinematics = IRB1600_10_120_ROBOT
    X_WO: np.ndarray | None = None
    X_FT: np.ndarray | None = None
    spin_mode: str = "min_travel"
    zone: float = 1e-3
    feed: float | None = None
    rapid_speed: float | None = None
    force: bool = False
    q_start: np.ndarray | None = None
    process: ProcessParameters | None = None
    stationary_tool: bool = False
    io: PostIO | None = None

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        if self.stationary_tool and self.X_WO is None:
            raise InputError("workpiece in hand: give the stationary spindle's TCP in the robot "
                             "base (--tool)")
        X_WO = np.eye(4) if self.X_WO is None else np.asarray(self.X_WO, float)
        if self.X_FT is None and self.stationary_tool:
            X_FT = np.eye(4)
        elif self.X_FT is None:
            X_FT = np.eye(4)
            X_FT[2, 3] = 0.2
        else:
            X_FT = np.asarray(self.X_FT, float)
        return X_WO, X_FT


@dataclass(frozen=True)
class PostResult:
    """Outcome of :func:`program_from_cl`.

    Attributes:
        program: the program (None when points are unreachable and ``force`` is False).
        unreachable_lines: CL line numbers of points the robot cannot reach.
        configuration_change_lines: CL lines where the arm configuration changes.
        joints: the IK result for every CL move (NaN rows where unreachable).
        notes: the header lines describing the file (paths, units, cycles, words not applied).
    """

    program: RobotProgram | None
    unreachable_lines: tuple[int, ...]
    configuration_change_lines: tuple[int, ...]
    joints: ToolAxisPathResult
    notes: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.unreachable_lines


def _solve(cl: ClProgram, s: PostSettings,
           progress: Callable[[int, int, str], None] | None) -> ToolAxisPathResult:
    if len(cl) == 0:
        raise InputError(f"{cl.source}: no moves in the CL file")
    X_WO, X_FT = s.frames()
    if s.stationary_tool:  # CL data stay in the held part's frame; the spindle is X_WO
        return solve_tool_axis_path(s.robot, cl.p_C, cl.axis_C, X_FT, s.spin_mode,
                                    ToolAxisOptions(q_start=s.q_start), progress, X_WS=X_WO)
    p_W = cl.p_C @ X_WO[:3, :3].T + X_WO[:3, 3]
    axis_W = cl.axis_C @ X_WO[:3, :3].T
    return solve_tool_axis_path(s.robot, p_W, axis_W, X_FT, s.spin_mode,
                                ToolAxisOptions(q_start=s.q_start), progress)


def file_notes(cl: ClProgram, spin_mode: str, change_lines: tuple[int, ...],
               io: PostIO | None = None) -> list[str]:
    """Header lines: the spin rule, tool paths, UNITS switches, cycles, words not applied
    (SPINDL / COOLNT are applied when ``io`` writes them)."""
    notes = [f"spin about the tool axis: {spin_mode}"]
    written = io.words if io is not None else frozenset()
    lines = [ln for ln in cl.summary()[1:]
             if not any(ln.startswith(f"not applied: {w} x") for w in written)]
    for w in sorted(written):
        n = sum(1 for e in cl.machine_events if e[1] == w)
        if n:
            notes.append(f"{w} x{n}: written to the outputs of the I/O settings")
    if len(lines) > _NOTE_LINES:
        lines = lines[:_NOTE_LINES] + [f"... {len(lines) - _NOTE_LINES} more lines"]
    notes += lines
    if cl.cycle.any():
        notes.append(f"{int(cl.cycle.sum())} moves from expanded drilling cycles (their "
                     "rapids are linear moves at rapid speed)")
    if change_lines:
        notes.append("configuration changes at CL lines " + ", ".join(map(str, change_lines[:20]))
                     + (" ..." if len(change_lines) > 20 else ""))
    return notes


def _io_before(cl: ClProgram, s: PostSettings, keep: np.ndarray
               ) -> tuple[dict[int, list[IoAction]], list[IoAction]]:
    """The outputs set before each kept move (index -> actions) and after the last one: an
    event before CL move k goes before the first kept move >= k."""
    before: dict[int, list[IoAction]] = {}
    end: list[IoAction] = []
    if s.io is None or not s.io.any or keep.size == 0:
        return before, end
    for line, word, value, n_before in cl.machine_events:
        acts = io_actions(s.io, word, value, line, Path(cl.source).name)
        j = int(np.searchsorted(keep, n_before))
        if j < keep.size:
            before.setdefault(int(keep[j]), []).extend(acts)
        else:
            end.extend(acts)
    return before, end


def program_moves(cl: ClProgram, res: ToolAxisPathResult, keep: np.ndarray, s: PostSettings,
                   last_index: int, io_before: dict[int, list[IoAction]] | None = None
                   ) -> list[ProgramMove]:
    """ProgramMoves of the CL moves ``keep`` (indices, increasing); the move ``last_index``
    ends the whole program (a stop point); ``io_before`` the outputs set before moves."""
    io_before = io_before or {}
    process = s.process or ProcessParameters()
    rapid_speed = process.window_switch_speed if s.rapid_speed is None else s.rapid_speed
    n_paths = len(cl.paths)
    moves = []
    prev_path = -1 if keep.size == 0 or keep[0] == 0 else int(cl.path[keep[0] - 1])
    for i in keep:
        i = int(i)
        rapid, line, path = bool(cl.rapid[i]), int(cl.lines[i]), int(cl.path[i])
        f = float(cl.feed[i])
        v = s.feed if s.feed is not None else (f if np.isfinite(f) and f > 0
                                               else process.grinding_speed)
        last = i == last_index
        comment = f"CL line {line}" if rapid or i == 0 else ""
        if path != prev_path and n_paths:
            comment = f"path {path + 1}/{n_paths} {cl.paths[path].name} (CL line {line})"
            comment = comment.replace("  ", " ")
        prev_path = path
        moves.append(ProgramMove(
            X_WT=res.X_WT[i], q=res.q[i],
            move_type=JOINT if rapid and not cl.cycle[i] else LINEAR,
            speed=rapid_speed if rapid else v,
            # holes: to full depth; a move before outputs switch: a stop point
            zone=0.0 if (last or rapid or cl.cycle[i] or _io_next(io_before, keep, i))
            else s.zone,
            comment=comment, source_line=line, io=tuple(io_before.get(i, ()))))
    return moves


def _io_next(io_before: dict, keep: np.ndarray, i: int) -> bool:
    """True when outputs switch before the kept move after ``i`` (so move i is a stop)."""
    if not io_before:
        return False
    j = int(np.searchsorted(keep, i)) + 1
    return j < keep.size and int(keep[j]) in io_before


def _names(s: PostSettings) -> dict:
    """Program fields that differ with workpiece in hand."""
    if not s.stationary_tool:
        return {}
    return dict(stationary_tool=True, tool_name="tSpindle", wobj_name="wobjPart")


def unreachable_flag(bad: tuple[int, ...]) -> tuple[str, str]:
    """The program's (flag, reason) when CL points ``bad`` (line numbers) were left out."""
    if bad:
        return "FORCED", (f"{len(bad)} unreachable CL point(s) left out, lines "
                          + ", ".join(map(str, bad[:15])))
    return "UNVERIFIED", "joint limits checked; collisions NOT checked"


def program_from_cl(
    cl: ClProgram,
    name: str,
    settings: PostSettings = PostSettings(),
    progress: Callable[[int, int, str], None] | None = None,
) -> PostResult:
    """Post-process a read CL file for a robot.

    Args:
        cl: the CL data (:func:`~drakedeburr.post.cl_reader.read_cl`).
        name: program name.
        settings: robot, frames, spin rule, zone, speeds, start joints, I/O and ``force``
            (:class:`PostSettings`): the last move is always a stop point; with ``force``
            the program is built even with unreachable points (they are left out and the
            header says FORCED); the first point's configuration is the one closest to
            ``q_start``.
        progress: optional callback (done, total, label).
    """
    s = settings
    res = _solve(cl, s, progress)
    bad = tuple(sorted({int(cl.lines[i]) for i in res.failed}))
    changes = tuple(sorted({int(cl.lines[i]) for i in res.configuration_changes}))
    notes = tuple(file_notes(cl, s.spin_mode, changes, s.io))
    if bad and not s.force:
        log.warning("%d CL point(s) unreachable, first at line(s) %s", len(bad),
                    ", ".join(map(str, bad[:10])))
        return PostResult(None, bad, changes, res, notes)
    keep = np.flatnonzero(res.reachable)
    if keep.size == 0:
        return PostResult(None, bad, changes, res, notes)
    X_WO_, X_FT_ = s.frames()
    flag, reason = unreachable_flag(bad)
    before, end = _io_before(cl, s, keep)
    program = zones_within_half_moves(RobotProgram(
        name=name, moves=tuple(program_moves(cl, res, keep, s, int(keep[-1]), before)),
        X_FT=X_FT_, X_WO=X_WO_, robot=s.robot, source=Path(cl.source).name, flag=flag,
        flag_reason=reason, notes=notes, io_end=tuple(end), **_names(s)))
    return PostResult(program, bad, changes, res, notes)


@dataclass(frozen=True)
class PostSummary:
    """Outcome of :func:`post_cl_file`.

    Attributes:
        files: the files written (none when points are unreachable and not forced).
        n_moves: moves written, over all parts.
        unreachable_lines: CL lines the robot cannot reach.
        configuration_change_lines: CL lines where the arm configuration changes.
        notes: the header lines describing the file.
        cl: the file as read (arrays, paths, words not applied, UNITS switches).
    """

    files: tuple[Path, ...]
    n_moves: int
    unreachable_lines: tuple[int, ...]
    configuration_change_lines: tuple[int, ...]
    notes: tuple[str, ...]
    cl: ClProgram


@dataclass(frozen=True)
class PostOutput:
    """The program :func:`post_cl_file` writes.

    Attributes:
        path: program file (.mod / .src / .ls); parts are ``out_001.ext``, ``out_002.ext``...
        fmt: 'rapid', 'krl' or 'ls'.
        name: program name (parts get ``_001`` ... appended, within 24 characters).
        max_moves: moves per written file; a longer program is written as numbered parts,
            each continuing where the previous ended.
    """

    path: str | Path
    fmt: str
    name: str
    max_moves: int = MAX_MOVES

    def checked_max_moves(self) -> int:
        """``max_moves``; InputError when below 1."""
        if self.max_moves < 1:
            raise InputError(f"max_moves must be >= 1, got {self.max_moves}")
        return self.max_moves


def part_file(out: Path, k: int, n_parts: int) -> Path:
    """The file of part ``k`` of ``n_parts`` (``out`` itself for one part, else ``_001`` ...)."""
    return out if n_parts == 1 else out.with_name(f"{out.stem}_{k + 1:03d}{out.suffix}")


def post_cl_file(
    cl_path: str | Path,
    output: PostOutput,
    settings: PostSettings = PostSettings(),
    read: ClReadOptions | None = None,
    progress: Callable[[int, int, str], None] | None = None,
) -> PostSummary:
    """Read a CL file, solve the joints and write the program (streaming, bounded memory).

    Args:
        cl_path: the CL/APT file.
        output: the program file, format, name and moves per file (:class:`PostOutput`).
        settings: see :class:`PostSettings`.
        read: how the CL file is read (:class:`~drakedeburr.post.cl_reader.ClReadOptions`;
            None = the defaults:
            units until a UNITS statement, cutter compensation refused or ignored).
        progress: callback (done, total, label) with labels 'read CL', 'spin + IK', 'write'.

    Raises:
        InputError: bad file or settings (named).
    """
    from drakedeburr.programs.writers import write_program

    max_moves, name = output.checked_max_moves(), output.name
    read = read or ClReadOptions()
    cl = read_cl(cl_path, read.units, read.arc_tolerance, read.require_end, read.cutcom,
                 progress)
    res = _solve(cl, settings, progress)
    bad = tuple(sorted({int(cl.lines[i]) for i in res.failed}))
    changes = tuple(sorted({int(cl.lines[i]) for i in res.configuration_changes}))
    notes = tuple(file_notes(cl, settings.spin_mode, changes, settings.io))
    keep = np.flatnonzero(res.reachable)
    if (bad and not settings.force) or keep.size == 0:
        return PostSummary((), 0, bad, changes, notes, cl)
    X_WO, X_FT = settings.frames()
    flag, reason = unreachable_flag(bad)
    parts = [keep[a:a + max_moves] for a in range(0, keep.size, max_moves)]
    before, end = _io_before(cl, settings, keep)
    # zones within half of the adjacent moves over the whole sequence (parts run on)
    every = zones_within_half_moves(RobotProgram(
        name="cl", moves=tuple(program_moves(cl, res, keep, settings, int(keep[-1]), before)),
        X_FT=X_FT, X_WO=X_WO, robot=settings.robot, io_end=tuple(end),
        **_names(settings))).moves
    files: list[Path] = []
    for k, part in enumerate(parts):
        extra = (f"part {k + 1} of {len(parts)}: CL lines {int(cl.lines[part[0]])}-"
                 f"{int(cl.lines[part[-1]])}",) if len(parts) > 1 else ()
        program = RobotProgram(
            name=name if len(parts) == 1 else f"{name[:20]}_{k + 1:03d}",
            moves=every[k * max_moves:k * max_moves + len(part)],
            X_FT=X_FT, X_WO=X_WO, robot=settings.robot, source=Path(cl.source).name,
            flag=flag, flag_reason=reason, notes=notes + extra,
            io_end=tuple(end) if k == len(parts) - 1 else (), **_names(settings))
        files += write_program(program, part_file(Path(output.path), k, len(parts)), output.fmt)
        del program
        if progress is not None:
            progress(k + 1, len(parts), "write")
    return PostSummary(tuple(files), int(keep.size), bad, changes, notes, cl)
