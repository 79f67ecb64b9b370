"""Data passed out of the planning stage (contract shared by plan/, verify/, post/, viz/).

A plan has two faces that must agree:
  * the Cartesian program a controller executes: targets joined by linear moves (MoveL / LIN /
    L) with the tool orientation interpolated between them, each with its speed and zone;
  * a dense timed joint trajectory that simulates that program (for Meshcat, verification and
    controllers that take joint streams).

Frames (DESIGN.md): W world = robot base frame B (z up); H hub frame; T tool frame (burr
cutting point, +Z spindle -> tip); F robot flange (ABB tool0). In the tool-in-hand cell T rides
on the flange and H is fixed; in the workpiece-in-hand cell H rides on the flange and T is
fixed (virtual TCP).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

__all__ = ["SegmentKind", "CartesianTarget", "PlanSegment", "JointTrajectory", "Plan",
           "FailureRecord", "CellFrames"]

SegmentKind = Literal["home", "approach", "cut", "retract", "transition"]


@dataclass(frozen=True, eq=False)
class CartesianTarget:
    """One target of the Cartesian program.

    Attributes:
        window_index: hub window the target belongs to, -1 for home/transition targets.
        segment: which kind of motion ends at this target.
        cl_index: index of the CL point in the window's ToolPath, -1 if none.
        X_HT: (4, 4) tool pose relative to the hub [m] (the process view).
        X_WF: (4, 4) flange pose in world = robot base [m] (what a controller moves).
        q: (6,) joint values of the robot at this target [rad] (ABB axis order).
        speed: TCP speed of the linear move that ends here [m/s] (relative speed of tool and
            hub in the workpiece-in-hand cell).
        zone: blending radius at this target [m] (0 = fine point).
        motion: how the controller reaches this target: "linear" (MoveL / LIN / L, tool point
            on a straight line, orientation slerped) or "joint" (MoveJ / PTP / J; the joint
            path between the targets is in ``Plan.trajectory``). Added by the planner.
        p_HC: (3,) the edge (CL) point this target cuts, in H [m], or None.
        n_H: (3,) unit inner normal at that edge point (out of the material), or None.
    """

    window_index: int
    segment: SegmentKind
    cl_index: int
    X_HT: np.ndarray
    X_WF: np.ndarray
    q: np.ndarray
    speed: float
    zone: float = 0.0
    motion: Literal["linear", "joint"] = "linear"
    p_HC: np.ndarray | None = None
    n_H: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class JointTrajectory:
    """Timed joint trajectory: between consecutive knots each joint is a polynomial in the time
    since the knot (exact to re-evaluate; the planner's pieces are the composition of its joint
    path with its timing, :func:`drakedeburr.plan.timing.compose`).

    Attributes:
        t: (K,) strictly increasing knot times [s], t[0] = 0.
        c: (D + 1, K - 1, 6) coefficients per piece, highest power first (scipy ``PPoly``
            layout) [rad, rad/s, ...].
    """

    t: np.ndarray
    c: np.ndarray

    @classmethod
    def from_hermite(cls, t: np.ndarray, q: np.ndarray, qd: np.ndarray) -> JointTrajectory:
        """The cubic Hermite spline through knots ``t`` (K,), positions ``q`` (K, 6) [rad] and
        velocities ``qd`` (K, 6) [rad/s]."""
        from scipy.interpolate import CubicHermiteSpline

        t = np.asarray(t, float)
        return cls(t=t, c=CubicHermiteSpline(t, np.asarray(q, float), np.asarray(qd, float),
                                             axis=0).c)

    @functools.cached_property
    def _pp(self):
        from scipy.interpolate import PPoly

        return PPoly(np.asarray(self.c, float), np.asarray(self.t, float))

    @property
    def q(self) -> np.ndarray:
        """(K, 6) joint positions at the knots [rad]."""
        return self._pp(self.t)

    @property
    def qd(self) -> np.ndarray:
        """(K, 6) joint velocities at the knots [rad/s]."""
        return self._pp(self.t, 1)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def value(self, t: np.ndarray | float) -> np.ndarray:
        """Joint positions at times ``t`` [s] -> (len(t), 6) (or (6,) for a scalar)."""
        return self._pp(t)

    def derivative(self, t: np.ndarray | float, order: int = 1) -> np.ndarray:
        return self._pp(t, order)


@dataclass(frozen=True, eq=False)
class PlanSegment:
    """A stretch of the plan: one motion kind, usually for one window.

    Attributes:
        window_index: -1 for home/transition segments.
        kind: motion kind.
        target_range: (first, last+1) indices into Plan.targets.
        t_range: (start, end) times in Plan.trajectory [s].
    """

    window_index: int
    kind: SegmentKind
    target_range: tuple[int, int]
    t_range: tuple[float, float]


@dataclass(frozen=True)
class FailureRecord:
    """Something the planner could not do, where, by how much, and what it tried.

    Attributes:
        window: the window (-1: a move between windows or home).
        kind: what failed: "ik" (a CL target), "window" (the window skipped), "dense" (the
            executed motion), "approach" / "retract", "program" (the program's targets),
            "transition" / "home" (joint moves).
        reason: one line for a human.
        point: CL point index in the window's ToolPath (-1: none).
        value, limit, unit: the measured figure and the bound it missed (SI unit), if any.
        where: location details (e.g. ``sample``, ``samples``, ``s_range_mm``, ``pair``).
        tried: what the planner tried before recording the failure.
    """

    window: int
    kind: str
    reason: str
    point: int = -1
    value: float | None = None
    limit: float | None = None
    unit: str = ""
    where: dict = field(default_factory=dict, hash=False, compare=False)
    tried: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return {"window": self.window, "kind": self.kind, "reason": self.reason,
                "point": self.point, "value": self.value, "limit": self.limit,
                "unit": self.unit, "where": dict(self.where), "tried": list(self.tried)}

    @classmethod
    def from_dict(cls, d: dict) -> FailureRecord:
        """From :meth:`to_dict`'s mapping (unknown keys go into ``where``)."""
        known = {"window", "kind", "reason", "point", "value", "limit", "unit", "where",
                 "tried"}
        where = dict(d.get("where") or {})
        where.update({k: v for k, v in d.items() if k not in known})
        return cls(window=int(d.get("window", -1)), kind=str(d.get("kind", "")),
                   reason=str(d.get("reason", "")), point=int(d.get("point", -1)),
                   value=d.get("value"), limit=d.get("limit"), unit=str(d.get("unit", "")),
                   where=where, tried=tuple(d.get("tried") or ()))

    def __str__(self) -> str:
        head = f"window {self.window}" if self.window >= 0 else "between windows"
        point = f", CL point {self.point}" if self.point >= 0 else ""
        return f"{head}{point} ({self.kind}): {self.reason}"


@dataclass(frozen=True, eq=False)
class Plan:
    """A complete deburring plan for one hub in one cell.

    Attributes:
        scenario: bundled scenario name or path the plan was made for.
        hub: bundled hub name or model path.
        mode: "tool" (tool in hand) or "workpiece" (workpiece in hand, virtual TCP).
        X_WH: (4, 4) hub pose in world used for planning (after registration if any).
        targets: the Cartesian program, in execution order.
        segments: stretches of the program/trajectory, in order.
        trajectory: the timed joint trajectory simulating the program.
        tool_path: the orientation stage's ToolPath per window this plan came from.
        failures: what could not be planned (empty when every point planned).
        meta: what the plan was made with and its figures (configuration, options, per-window
            statistics): a pure function of the inputs, part of the plan's content. The
            planner builds it once, with ``run``, from a
            :class:`drakedeburr.plan.results.PlanRecord`; nothing edits it afterwards.
        run: how this run went (timings [s]); not part of the plan's content (``run.json``).
    """

    scenario: str
    hub: str
    mode: Literal["tool", "workpiece"]
    X_WH: np.ndarray
    targets: tuple[CartesianTarget, ...]
    segments: tuple[PlanSegment, ...]
    trajectory: JointTrajectory
    tool_path: Any = None
    failures: tuple[FailureRecord, ...] = ()
    meta: dict = field(default_factory=dict)
    run: dict = field(default_factory=dict)

    @property
    def frames(self) -> CellFrames:
        """The cell's frames the plan was made in (read from its record, ``meta``)."""
        return CellFrames.from_meta(self.meta)


def _pose(v) -> np.ndarray | None:
    return None if v is None else np.asarray(v, float).reshape(4, 4)


@dataclass(frozen=True, eq=False)
class CellFrames:
    """The cell's frames of a plan (4x4 poses [m]; None where the cell has no such frame).

    Attributes:
        X_WB: the robot base in the world (identity for plans made before mounts existed).
        X_FT: the tool (burr tip frame) on the flange: tool in hand.
        X_FH: the hub on the flange (gripper): workpiece in hand.
        X_WT: the stationary tool in the world: workpiece in hand.
    """

    X_WB: np.ndarray
    X_FT: np.ndarray | None = None
    X_FH: np.ndarray | None = None
    X_WT: np.ndarray | None = None

    @classmethod
    def from_meta(cls, meta: dict) -> CellFrames:
        return cls(X_WB=_pose(meta.get("X_WB", np.eye(4))), X_FT=_pose(meta.get("X_FT")),
                   X_FH=_pose(meta.get("X_FH")), X_WT=_pose(meta.get("X_WT")))

    def carried(self, mode: str) -> tuple[np.ndarray, np.ndarray | None]:
        """(the frame the flange carries, the stationary tool in the world or None) of a plan
        ``mode``: the tool X_FT in "tool" mode, the hub X_FH and the tool X_WT in "workpiece"
        mode. Raises KeyError naming the frame the record lacks."""
        if mode == "tool":
            if self.X_FT is None:
                raise KeyError("X_FT")
            return self.X_FT, None
        for name in ("X_FH", "X_WT"):
            if getattr(self, name) is None:
                raise KeyError(name)
        return self.X_FH, self.X_WT


TOOL_PATH_ARRAYS = ("p_HC", "R_HL", "zT_H", "theta_A", "theta_B", "cone_zT_H")


@dataclass(frozen=True, eq=False)
class ToolPathRecord:
    """What a saved plan keeps of the orientation stage's ToolPath of one window (the reference
    verification checks the plan against). Same names and conventions as
    :class:`drakedeburr.orientation.ToolPath`.

    Attributes:
        window_index, kind: window number and "large"/"small".
        p_HC: (M, 3) CL points in H [m]; R_HL: (M, 3, 3) local frames [N_new, T, -B].
        zT_H: (M, 3) chosen axes +Z_T (spindle -> tip); theta_A, theta_B: (M,) [rad].
        cone_zT_H: (M, 3) box-centre axes +Z_T; bounds: the theta box.
        cone_half_angle / cone_outer_half_angle: inner / enclosing cone of the box [rad].
        depth_of_cut: [m].
    """

    window_index: int
    kind: str
    p_HC: np.ndarray
    R_HL: np.ndarray
    zT_H: np.ndarray
    theta_A: np.ndarray
    theta_B: np.ndarray
    cone_zT_H: np.ndarray
    bounds: object
    cone_half_angle: float
    cone_outer_half_angle: float
    depth_of_cut: float

    def __len__(self) -> int:
        return len(self.p_HC)
