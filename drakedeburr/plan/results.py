"""Typed results inside the planner: what a window's planning returns and its figures.

:class:`WindowPlan` carries a :class:`WindowStatus` (in the spirit of toppra's return codes):
a window is either planned (its stretches and :class:`WindowStats` are there; failure records
may still say where it missed a bound) or skipped with the status naming the stage that could
not be done. Failure records are :class:`drakedeburr.plan.types.FailureRecord`.

A hub's assembled plan, while the hub-level policy (:mod:`drakedeburr.plan.policy`) still
chooses, is a :class:`PlanDraft`: its motion, failure records and :class:`PlanRecord` (what
``Plan.meta`` and ``Plan.run`` are built from, once, by :meth:`PlanDraft.plan`).
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.plan.timing import TimedPath
from drakedeburr.plan.types import FailureRecord, Plan

__all__ = ["WindowStatus", "Stretch", "ExecutedCut", "WindowStats", "WindowPlan", "PlanStats",
           "CutTargets", "IkStep", "ProgramFit", "CutStep", "Deviation", "PlanRecord",
           "PlanMotion", "PlanDraft"]


class WindowStatus(enum.Enum):
    """Outcome of planning one window."""

    OK = "ok"  # planned, no failure record
    DEGRADED = "degraded"  # planned, with failure records (a bound missed somewhere)
    IK_FAILED = "ik_failed"  # too few CL targets reached: skipped
    MOTION_FAILED = "motion_failed"  # the executed cut leaves the configuration: skipped
    PROGRAM_FAILED = "program_failed"  # a program target unreachable: skipped
    APPROACH_FAILED = "approach_failed"  # approach or retract unreachable: skipped
    # failed under the recipe at an IK target or with its executed cut under the clearance,
    # the rest not planned (RunMode.FAIL_FAST: relaxation comes next, and the window is
    # planned in full if none is kept)
    ABANDONED = "abandoned"

    @property
    def planned(self) -> bool:
        return self in (WindowStatus.OK, WindowStatus.DEGRADED)


@dataclass
class Stretch:
    """A timed stretch of the plan and the program targets it ends at."""

    kind: str
    window_index: int
    timed: TimedPath
    targets: list


@dataclass(frozen=True, eq=False)
class ExecutedCut:
    """A window's executed cut and its program.

    Attributes:
        cp: the :class:`drakedeburr.plan.cut_path.CutPath` (dense poses, program targets
            ``X_target`` with their zones, ``target_index`` into the dense samples).
        cut: the :class:`drakedeburr.plan.interpolate.DensePath` tracked by the analytic IK.
        dist: (N,) clearance of every dense sample [m].
        q_targets: (T, 6) joints at the program's targets [rad].
        via: (T,) True where a target is a via (on the executed path, between CL targets).
        fillets: the fillet repair's report of each slow stretch
            (:func:`drakedeburr.plan.fillets.repair_fillets`).
    """

    cp: object
    cut: object
    dist: np.ndarray
    q_targets: np.ndarray
    via: np.ndarray
    fillets: tuple = ()


@dataclass(frozen=True, eq=False)
class CutTargets:
    """Step 1 of a window pass (:func:`drakedeburr.plan.window.plan_window_pass`): the IK's
    targets. ``loop``: (L,) CL index of each target in solving order (a closed window ends on
    a second copy of CL 0); ``p_HQ``: (L, 3) centre of the cutting circle at each [m], in H;
    ``lift``: how far below T on the axis that centre lies [m]."""

    loop: np.ndarray
    p_HQ: np.ndarray
    lift: float


@dataclass(frozen=True, eq=False)
class IkStep:
    """Step 2 of a window pass: the window's IK from its best start configuration.

    Attributes:
        status: OK / DEGRADED (go on, DEGRADED with failure records), IK_FAILED or ABANDONED
            (the window stops here).
        wik: the :class:`drakedeburr.plan.ik.WindowIk` kept.
        good: rows of ``wik`` that met every constraint; order: (G,) their CL indices.
        failures: the IK's records (CL indices), plus the window's own when it stops.
        seconds: time the IK took [s]; starts: start configurations tried.
    """

    status: WindowStatus
    wik: object
    good: np.ndarray
    order: np.ndarray
    failures: tuple[FailureRecord, ...]
    seconds: float
    starts: int

    @property
    def X_ik(self) -> np.ndarray:
        """(G, 4, 4) the IK's tool poses in H at the reached targets."""
        return self.wik.X_HT[self.good]


@dataclass(frozen=True, eq=False)
class ProgramFit:
    """Step 4 of a window pass (:func:`drakedeburr.plan.program_fit.fit_program`): the program
    of a tracked cut. ``executed``: the cut and its program (None unless ``status`` is OK);
    ``status``: OK or PROGRAM_FAILED; ``finer``: the trajectory would stray from the program
    between the samples, so the cut is to be sampled again at half the step (``executed`` is
    None); ``failures``: the program's records."""

    status: WindowStatus
    executed: ExecutedCut | None = None
    finer: bool = False
    failures: tuple[FailureRecord, ...] = ()


@dataclass(frozen=True, eq=False)
class CutStep:
    """Steps 3-4 of a window pass (:func:`drakedeburr.plan.window.execute_cut`): the tracked cut
    and its program at the finest sampling needed. ``status``: OK / DEGRADED (go on),
    MOTION_FAILED, PROGRAM_FAILED or ABANDONED (stop); ``failures``: the tracking's and the
    program's records; ``seconds``: time taken [s]."""

    status: WindowStatus
    executed: ExecutedCut | None
    failures: tuple[FailureRecord, ...]
    seconds: float


@dataclass(frozen=True)
class WindowStats:
    """Figures of one planned window (``plan.meta["windows"]`` holds them as mappings): a pure
    function of the inputs (the run's timings are in ``plan.run``, not here).

    Lengths [m], angles [deg] where the name says so, else SI; ``ik``: the IK's counters.
    ``speed_in_band_bound``: the planner's figure of the share of the cut that could be in the
    feed band (the fillet repair's: the share with every slow stretch where the feed can be
    held cut at the feed, the others as timed; None without the repair); ``fillets``: the
    repair's report of each slow stretch; ``chamfer_relief``: see
    :mod:`drakedeburr.plan.burr_depth`.
    """

    window: int
    kind: str
    cl_points: int
    reached: int
    edge_length_m: float
    tool_travel_m: float
    dense_samples: int
    cut_seconds: float
    j4_range_deg: float
    j5_range_deg: float
    j6_range_deg: float
    min_abs_j5_deg: float
    min_clearance_m: float
    axis_in_theta_box_fraction: float | None
    cone_half_angle_rad: float
    speed_in_band_fraction: float
    ik: dict
    joint_fit_deviation_m: float
    orientation_smoothing_rad: float
    via_targets: int
    least_axis_acceleration_radps2: float
    q_ik_rad: list
    q_smoothed_rad: list
    cl_order: list
    transition_method: str = ""
    spin_rule: str = ""
    speed_in_band_bound: float | None = None
    fillets: list = field(default_factory=list)
    #: tool points moved out where the burr would reach too deep into the hub (a rounded or
    #: acute edge, :mod:`drakedeburr.plan.burr_depth`): None when the recipe's held everywhere
    chamfer_relief: dict | None = None
    #: a partial window (:mod:`drakedeburr.plan.partial`): loop length, cut share, the cut
    #: and the uncut stretches (CL ranges, mm) and why; None when the loop is cut whole
    partial: dict | None = None

    def to_dict(self) -> dict:
        out = dataclasses.asdict(self)
        if out["partial"] is None:  # a whole window: its record as before partial windows
            del out["partial"]
        return out


@dataclass
class WindowPlan:
    """One window's planning result.

    Attributes:
        window: the window; status: the outcome.
        stretches: approach, cut and retract (empty unless planned).
        stats: the window's figures (None unless planned).
        q_start: (6,) joints where the approach starts [rad] (None unless planned).
        failures: what could not be done.
    """

    window: int
    status: WindowStatus
    stretches: list[Stretch] = field(default_factory=list)
    stats: WindowStats | None = None
    q_start: np.ndarray | None = None
    failures: list[FailureRecord] = field(default_factory=list)
    seconds: dict = field(default_factory=dict)

    @classmethod
    def skipped(cls, window: int, status: WindowStatus,
                failures: list[FailureRecord]) -> WindowPlan:
        return cls(window=window, status=status, failures=list(failures))


@dataclass(frozen=True)
class PlanStats:
    """Timings of a planning run [s] (``plan.run["timings"]``; not part of the plan's content).
    A stage the run did not go through (no placement search, no long-reach retry) is None and
    left out of the record."""

    total_seconds: float
    transition_seconds: float
    targets_seconds: float = 0.0
    placement_seconds: float | None = None
    standard_burr_seconds: float | None = None
    long_reach_seconds: float | None = None

    def to_dict(self) -> dict:
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None}


@dataclass(frozen=True)
class Deviation:
    """One departure from the recipe for one window: what, from what to what, and why
    (``plan.meta["recipe_deviations"]`` holds :meth:`record` of each)."""

    window: int  # -1: the whole hub
    item: str
    default: str
    used: str
    reason: str

    def record(self) -> dict:
        return {"window": self.window, "item": self.item, "default": self.default,
                "used": self.used, "reason": self.reason}


@dataclass(frozen=True, eq=False)
class PlanRecord:
    """Everything a plan records beside its motion, collected while it is planned and turned
    into ``Plan.meta`` (:meth:`meta`) and ``Plan.run`` (:meth:`run`) once, when the Plan is
    made (:meth:`PlanDraft.plan`).

    Attributes:
        config, options: the run's configuration and planner options (JSON-ready records).
        robot: the arm's reference; tool, tool_title: the burr when not the standard one.
        X_FT, X_FH, X_WT, X_WB: (4, 4) the cell's frames (tool on flange, hub on flange, tool
            in world, robot base in world) [m].
        contact_radius_m, contact_lift_m: the burr contact geometry [m].
        figures: the assembled plan's figures (per-window statistics, cycle and cut times).
        deviations: departures from the recipe, in the order they are recorded: the home, the
            tool points moved out of the material, the milder tilts, the burr.
        q_home: (6,) the home planned from when it is not the cell's [rad].
        hub_pose, placement: (4, 4) the hub pose the placement search chose and its record.
        timings: the run's timings; window_seconds: per planned window its stage timings.
    """

    config: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    robot: str | None = None
    tool: str | None = None
    tool_title: str | None = None
    X_FT: np.ndarray | None = None
    X_FH: np.ndarray | None = None
    X_WT: np.ndarray | None = None
    X_WB: np.ndarray | None = None
    contact_radius_m: float | None = None
    contact_lift_m: float | None = None
    figures: dict = field(default_factory=dict)
    deviations: tuple[Deviation, ...] = ()
    q_home: np.ndarray | None = None
    hub_pose: np.ndarray | None = None
    placement: dict | None = None
    timings: PlanStats = PlanStats(0.0, 0.0)
    window_seconds: tuple[dict, ...] = ()

    def meta(self) -> dict:
        """``Plan.meta``: what the plan was made with and its figures (part of its content)."""
        return dict(
            version=1, planner="drakedeburr.plan", config=self.config,
            contact_radius_m=self.contact_radius_m, contact_lift_m=self.contact_lift_m,
            X_FT=_listed(self.X_FT), X_FH=_listed(self.X_FH), X_WT=_listed(self.X_WT),
            robot=self.robot, X_WB=_listed(self.X_WB), **self.figures, options=self.options,
            **({"tool": self.tool, "tool_title": self.tool_title} if self.tool else {}),
            **({"recipe_deviations": [d.record() for d in self.deviations]}
               if self.deviations else {}),
            **({"q_home": self.q_home.tolist()} if self.q_home is not None else {}),
            **({"hub_pose": self.hub_pose.tolist(), "placement": self.placement}
               if self.hub_pose is not None else {}))

    def run(self) -> dict:
        """``Plan.run``: how the run went (timings [s]; not part of the plan's content)."""
        return {"timings": self.timings.to_dict(), "windows": list(self.window_seconds)}


def _listed(X: np.ndarray | None) -> list | None:
    return None if X is None else np.asarray(X).tolist()


@dataclass(frozen=True, eq=False)
class PlanMotion:
    """The motion of an assembled plan: the :class:`drakedeburr.plan.types.Plan` fields other
    than its failures and records."""

    scenario: str
    hub: str
    mode: str
    X_WH: np.ndarray
    targets: tuple
    segments: tuple
    trajectory: object
    tool_path: object = None


@dataclass(frozen=True, eq=False)
class PlanDraft:
    """A hub's plan while the hub-level policy (:mod:`drakedeburr.plan.policy`) still works on
    it: its motion, its failure records and its :class:`PlanRecord`. The policy makes new
    drafts (never edits one); :meth:`plan` makes the Plan, once, at the end."""

    failures: tuple[FailureRecord, ...] = ()
    record: PlanRecord = PlanRecord()
    motion: PlanMotion | None = None

    def with_deviations(self, front: tuple = (), back: tuple = ()) -> PlanDraft:
        """The draft with ``front`` recorded before its deviations and ``back`` after."""
        devs = (*front, *self.record.deviations, *back)
        return dataclasses.replace(self, record=dataclasses.replace(self.record,
                                                                    deviations=devs))

    def with_record(self, **changes) -> PlanDraft:
        """The draft with those :class:`PlanRecord` fields replaced."""
        return dataclasses.replace(self, record=dataclasses.replace(self.record, **changes))

    def with_timings(self, **seconds: float) -> PlanDraft:
        """The draft with those :class:`PlanStats` timings set [s]."""
        return self.with_record(timings=dataclasses.replace(self.record.timings, **seconds))

    def plan(self) -> Plan:
        """The Plan: its motion, failures, and ``meta`` / ``run`` built from the record."""
        m = self.motion
        return Plan(scenario=m.scenario, hub=m.hub, mode=m.mode, X_WH=m.X_WH, targets=m.targets,
                    segments=m.segments, trajectory=m.trajectory, tool_path=m.tool_path,
                    failures=tuple(self.failures), meta=self.record.meta(), run=self.record.run())
