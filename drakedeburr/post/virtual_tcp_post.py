"""CL file -> the paper's virtual-TCP program (SPEC.md S0, seed 000): no controller option.

The robot holds the part, the spindle stands still at the virtual TCP O (``X_BO`` in the robot
base B), the part's CL frame P sits at ``X_FP`` on the flange F. The paper's program uses
only an ordinary TCP:

- **reference pose**: the pose of the part at which its CL frame P lies at ``X_OP`` in O
  (the paper makes them coincide up to the tool-axis flip). The robot's ordinary TCP is set
  so that at the reference pose it coincides with O: ``X_FT = X_FP X_OP^-1`` (the UTOOL /
  tooldata / $TOOL the program writes). The robot never needs to go to the reference pose.
- **virtual points** (translation mode, eqs. 1-6 with the full mirror): every CL point
  p_i (tool centre, in P) is mapped to the TCP target ``X_OV_i = [I, -X_OP p_i]`` in O; the
  user frame (UFRAME / wobjdata / $BASE) of the program is O itself, so the targets written
  are the mirrored CL points. With the TCP on V_i the part has only translated from the
  reference pose and its point p_i lies on O (the CL point on the tool centre).

The part keeps its reference orientation, so the CL tool axis must be the same at every
point (a 3-axis contour); varying axes are refused with the line named (use the
stationary-tool program, ``--workpiece-in-hand`` without ``--virtual-tcp``). The reference
orientation brings the CL axis (tip -> spindle) onto -Z of O, like the stationary-tool post
(the CL tool frame C with Z_C = -axis onto O); its spin about the axis is free and chosen for
reach and least joint travel (:func:`virtual_tcp_setup`) unless ``X_OP`` is given. The CL
points are tool-centre points: no radius offset is applied here (part contours are offset by
:func:`drakedeburr.post.virtual_tcp.offset_contour` before CAM / path generation).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drakedeburr.errors import InputError
from drakedeburr.post.cl_post import (
    PostOutput,
    PostResult,
    PostSettings,
    PostSummary,
    file_notes,
    part_file,
    program_moves,
    unreachable_flag,
)
from drakedeburr.post.cl_reader import ClProgram, ClReadOptions, read_cl
from drakedeburr.post.tool_axis import READY_POSE, ToolAxisPathResult
from drakedeburr.programs.program import RobotProgram, zones_within_half_moves
from drakedeburr.robots import RobotKinematics, solve_path, travel_weights

__all__ = ["VirtualTcpSetup", "virtual_tcp_setup", "solve_virtual_tcp",
           "virtual_tcp_program_from_cl", "post_cl_file_virtual_tcp", "SPIN_CANDIDATES"]

#: spins about the tool axis tried for the reference orientation (when X_OP is not given)
SPIN_CANDIDATES = 24
_AXIS_TOL = 1e-9  # CL axes closer than this (unit vectors) count as the same axis
_SPIN_SAMPLE = 200  # CL points used to rank the spins (the whole path is solved after)


@dataclass(frozen=True)
class VirtualTcpSetup:
    """The frames of a virtual-TCP program (module docstring). Arrays (4, 4) [m].

    Attributes:
        X_BO: the virtual TCP (fixed spindle tool point) in the robot base.
        X_FP: the part's CL frame in the flange frame.
        X_OP: the part's CL frame in O at the reference pose.
    """

    X_BO: np.ndarray
    X_FP: np.ndarray
    X_OP: np.ndarray

    @property
    def X_FT(self) -> np.ndarray:
        """The ordinary TCP in the flange frame (what the program's tool data says)."""
        return self.X_FP @ np.linalg.inv(self.X_OP)

    @property
    def X_BF_reference(self) -> np.ndarray:
        """The flange at the reference pose (the TCP on O)."""
        return self.X_BO @ self.X_OP @ np.linalg.inv(self.X_FP)

    def virtual_points(self, p_P: np.ndarray) -> np.ndarray:
        """(N, 4, 4) TCP targets X_BV in B for CL points p_P (N, 3) in P [m]."""
        p_O = np.asarray(p_P, float) @ self.X_OP[:3, :3].T + self.X_OP[:3, 3]
        X_OV = np.tile(np.eye(4), (p_O.shape[0], 1, 1))
        X_OV[:, :3, 3] = -p_O  # the mirror image of the point in O (eq. 4, z mirrored too)
        return self.X_BO[None] @ X_OV


def _common_axis(cl: ClProgram) -> np.ndarray:
    axis = np.asarray(cl.axis_C, float)
    dev = np.linalg.norm(axis - axis[0], axis=1)
    bad = np.flatnonzero(dev > _AXIS_TOL)
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"{cl.source}:{int(cl.lines[i])}: the tool axis changes ({axis[i].round(6)} after "
            f"{axis[0].round(6)}): a virtual-TCP program keeps the part's orientation, so every "
            "CL point needs the same axis; use --workpiece-in-hand without --virtual-tcp")
    return axis[0] / np.linalg.norm(axis[0])


def reference_rotation(axis_P: np.ndarray, spin: float) -> np.ndarray:
    """(3, 3) R_OP taking the CL axis (in P) onto -Z_O, turned by ``spin`` about Z_O [rad]."""
    a = np.asarray(axis_P, float) / np.linalg.norm(axis_P)
    align, _ = Rotation.align_vectors([[0.0, 0.0, -1.0]], [a])  # shortest turn a -> -z
    if abs(a[2] - 1.0) < 1e-12:  # a = +z: the shortest turn is undefined, flip about x
        align = Rotation.from_euler("x", np.pi)
    return (Rotation.from_euler("z", spin) * align).as_matrix()


def _solve(robot: RobotKinematics, setup: VirtualTcpSetup, p_P: np.ndarray,
           q_start: np.ndarray):
    X_BV = setup.virtual_points(p_P)
    X_BF = X_BV @ np.linalg.inv(setup.X_FT)[None]
    return X_BV, solve_path(robot, X_BF, q_start=q_start)


def virtual_tcp_setup(robot: RobotKinematics, X_BO: np.ndarray, X_FP: np.ndarray,
                      p_P: np.ndarray, axis_P: np.ndarray, X_OP: np.ndarray | None = None,
                      q_start: np.ndarray | None = None) -> VirtualTcpSetup:
    """The frames for CL points ``p_P`` with the common axis ``axis_P`` (both in P).

    With ``X_OP`` None the reference orientation (:func:`reference_rotation`) is tried at
    :data:`SPIN_CANDIDATES` spins about the tool axis on up to 200 of the points; the spin
    that reaches the most points, then with the least weighted joint travel, is kept. The
    reference origin is O (the paper: virtual TCP, tool and part frames coincide).
    """
    X_BO, X_FP = np.asarray(X_BO, float), np.asarray(X_FP, float)
    q0 = READY_POSE if q_start is None else np.asarray(q_start, float)
    if X_OP is not None:
        X_OP = np.asarray(X_OP, float)
        a_O = X_OP[:3, :3] @ (np.asarray(axis_P, float) / np.linalg.norm(axis_P))
        if np.linalg.norm(a_O - [0.0, 0.0, -1.0]) > 1e-6:
            raise InputError(f"--reference: it turns the CL tool axis to {a_O.round(4)} in the "
                             "spindle's frame; the axis (tip -> spindle) must lie on -Z of "
                             "the spindle's TCP")
        return VirtualTcpSetup(X_BO, X_FP, X_OP)
    p_P = np.asarray(p_P, float)
    sample = p_P[np.unique(np.linspace(0, len(p_P) - 1, min(len(p_P), _SPIN_SAMPLE)).astype(int))]
    w = travel_weights(robot.opw)
    best = None
    for spin in np.linspace(-np.pi, np.pi, SPIN_CANDIDATES, endpoint=False):
        X = np.eye(4)
        X[:3, :3] = reference_rotation(axis_P, spin)
        setup = VirtualTcpSetup(X_BO, X_FP, X)
        _, res = _solve(robot, setup, sample, q0)
        q = res.q[res.reachable]
        travel = float(np.sum(np.abs(np.diff(np.vstack([q0, q]), axis=0)) * w)) if len(q) else 0.0
        key = (-int(res.reachable.sum()), len(res.configuration_changes), travel)
        if best is None or key < best[0]:
            best = (key, setup)
    return best[1]


def solve_virtual_tcp(cl: ClProgram, s: PostSettings, X_OP: np.ndarray | None = None
                      ) -> tuple[VirtualTcpSetup, ToolAxisPathResult]:
    """Frames and joints of the virtual-TCP program of ``cl``. ``s.X_WO`` is the spindle's
    TCP O in the base (required), ``s.X_FT`` the part's CL frame in the flange (None: the
    flange frame)."""
    if len(cl) == 0:
        raise InputError(f"{cl.source}: no moves in the CL file")
    if s.X_WO is None:
        raise InputError("virtual TCP: give the stationary spindle's TCP in the robot base "
                         "(--tool)")
    X_FP = np.eye(4) if s.X_FT is None else np.asarray(s.X_FT, float)
    axis = _common_axis(cl)
    q0 = READY_POSE if s.q_start is None else np.asarray(s.q_start, float)
    setup = virtual_tcp_setup(s.robot, s.X_WO, X_FP, cl.p_C, axis, X_OP, q0)
    X_BV, res = _solve(s.robot, setup, cl.p_C, q0)
    n = len(cl)
    return setup, ToolAxisPathResult(
        q=res.q, X_WT=X_BV, spin=np.zeros(n), reachable=res.reachable, failed=res.failed,
        configuration_changes=res.configuration_changes, mode="virtual_tcp")


def _notes(cl: ClProgram, setup: VirtualTcpSetup, changes) -> tuple[str, ...]:
    from drakedeburr.units import mm_from_m

    Xr = setup.X_BF_reference
    return tuple(["virtual TCP program (source 000, translation mode): no RTCP / "
                  "external-TCP option used",
                  "TCP = the virtual TCP O (the spindle) as carried by the flange at the "
                  "reference pose; user frame = O; targets = the CL points mirrored in O",
                  "reference flange pose in the robot base [mm]: "
                  + ", ".join(f"{v:.3f}" for v in mm_from_m(Xr[:3, 3])),
                  ] + file_notes(cl, "fixed (the part only translates)", changes)[1:])


def virtual_tcp_program_from_cl(cl: ClProgram, name: str, s: PostSettings,
                                X_OP: np.ndarray | None = None) -> PostResult:
    """The virtual-TCP program of a read CL file (module docstring); unreachable points as
    :func:`~drakedeburr.post.cl_post.program_from_cl` handles them."""
    setup, res = solve_virtual_tcp(cl, s, X_OP)
    bad = tuple(sorted({int(cl.lines[i]) for i in res.failed}))
    changes = tuple(sorted({int(cl.lines[i]) for i in res.configuration_changes}))
    notes = _notes(cl, setup, changes)
    keep = np.flatnonzero(res.reachable)
    if (bad and not s.force) or keep.size == 0:
        return PostResult(None, bad, changes, res, notes)
    flag, reason = unreachable_flag(bad)
    # zones within half of the adjacent moves (the controller would shrink larger ones)
    program = zones_within_half_moves(RobotProgram(
        name=name, moves=tuple(program_moves(cl, res, keep, s, int(keep[-1]))),
        X_FT=setup.X_FT, X_WO=setup.X_BO, robot=s.robot, source=Path(cl.source).name,
        flag=flag, flag_reason=reason, notes=notes, tool_name="tVirtual",
        wobj_name="wobjVirtual"))
    return PostResult(program, bad, changes, res, notes)


def post_cl_file_virtual_tcp(
    cl_path: str | Path, output: PostOutput, settings: PostSettings,
    read: ClReadOptions | None = None,
    progress: Callable[[int, int, str], None] | None = None, X_OP: np.ndarray | None = None,
) -> PostSummary:
    """:func:`~drakedeburr.post.cl_post.post_cl_file` writing the virtual-TCP program."""
    from drakedeburr.programs.writers import write_program

    max_moves, name = output.checked_max_moves(), output.name
    read = read or ClReadOptions()
    cl = read_cl(cl_path, read.units, read.arc_tolerance, read.require_end, read.cutcom,
                 progress)
    result = virtual_tcp_program_from_cl(cl, name, settings, X_OP)
    prog = result.program
    if prog is None:
        return PostSummary((), 0, result.unreachable_lines, result.configuration_change_lines,
                           result.notes, cl)
    moves = prog.moves
    parts = [moves[a:a + max_moves] for a in range(0, len(moves), max_moves)]
    files: list[Path] = []
    for k, part in enumerate(parts):
        extra = (f"part {k + 1} of {len(parts)}",) if len(parts) > 1 else ()
        piece = RobotProgram(
            name=name if len(parts) == 1 else f"{name[:20]}_{k + 1:03d}", moves=tuple(part),
            X_FT=prog.X_FT, X_WO=prog.X_WO, robot=prog.robot, source=prog.source,
            flag=prog.flag, flag_reason=prog.flag_reason, notes=prog.notes + extra,
            tool_name=prog.tool_name, wobj_name=prog.wobj_name)
        files += write_program(piece, part_file(Path(output.path), k, len(parts)), output.fmt)
        if progress is not None:
            progress(k + 1, len(parts), "write")
    return PostSummary(tuple(files), len(moves), result.unreachable_lines,
                       result.configuration_change_lines, result.notes, cl)
