"""The records of a sampled plan (built by :func:`drakedeburr.verify.sampling.sample_plan`, read by
every check): :class:`Samples`, :class:`ProgramReading`, :class:`Distances`,
:class:`CutGeometry`, :class:`JointLimits` and the :class:`SampledPlan` holding them. Kept apart
from the builders so that each stage (``program``, ``distances``, ``cut_geometry``) imports
the record it fills without importing the module that calls it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.config import Config
from drakedeburr.verify.kinematics import VerifyKinematics

__all__ = ["KIND_CODE", "Samples", "ProgramReading", "Distances", "CutGeometry", "JointLimits",
           "SampledPlan"]


#: integer code of each segment kind in :attr:`Samples.kind`
KIND_CODE = {"home": 0, "transition": 1, "approach": 2, "cut": 3, "retract": 4}


@dataclass(frozen=True, eq=False)
class Samples:
    """The trajectory at N sample times.

    Attributes:
        t: (N,) times [s]; segment: (N,) index of the plan segment of each sample.
        q, qd: (N, 6) joints [rad] and joint velocities [rad/s].
        X_HT: (N, 4, 4) tool pose in the hub frame [m]; p_HT: (N, 3) its position.
        X_WF: (N, 4, 4) flange pose in world (analytic) [m].
        speed: (N,) speed of T relative to H [m/s] (central difference, 1 us).
        path_acceleration: (N,) its rate of change along the path, (dp/dt . d2p/dt2) / speed
            [m/s^2] (second differences over 10 us; at rest |d2p/dt2|).
        kind: (N,) :data:`KIND_CODE` of the segment; window: (N,) its window (-1 none).
    """

    t: np.ndarray
    segment: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    X_HT: np.ndarray
    p_HT: np.ndarray
    X_WF: np.ndarray
    speed: np.ndarray
    path_acceleration: np.ndarray
    kind: np.ndarray
    window: np.ndarray

    def __len__(self) -> int:
        return len(self.t)


@dataclass(frozen=True, eq=False)
class ProgramReading:
    """The samples read against the program's linear moves.

    Attributes:
        move: (N,) index of the target the linear move of each sample ends at (-1: none).
        fraction: (N,) share of that move (NaN off linear moves).
        path_dev: (N,) distance of T from the program's path [m] (NaN off linear moves).
        orient_dev: (N,) angle between executed and programmed orientation [rad].
        program_to_path: largest distance of the program's own points from the trajectory's
            path [m]; program_worst: the sample nearest that point (or None).
    """

    move: np.ndarray
    fraction: np.ndarray
    path_dev: np.ndarray
    orient_dev: np.ndarray
    program_to_path: float
    program_worst: int | None


@dataclass(frozen=True, eq=False)
class Distances:
    """Per sample: smallest signed distance of each class [m] (inf: nothing within the query
    distance) and its pair; |det J| of the flange Jacobian; largest Drake-vs-analytic FK
    difference [m] and which evaluations it covers (``fk_scope``); the continuous clearance
    certificate (:class:`drakedeburr.verify.certificate.ClearanceCertificate`, None from the
    dense reference method)."""

    clearance: np.ndarray
    clearance_pair: tuple
    self_distance: np.ndarray
    self_pair: tuple
    burr: np.ndarray
    burr_pair: tuple
    manipulability: np.ndarray
    fk_difference: float
    fk_scope: str = ""
    certificate: object = None


@dataclass(frozen=True, eq=False)
class CutGeometry:
    """Per sample on a cut (NaN elsewhere): executed contact point in H ``contact`` (N, 3) [m],
    its distance to the true edge ``edge_dev`` [m], the edge point's depth in the burr cone
    ``engagement`` [m], ``theta_A``/``theta_B`` [rad], margins to the cone and to the theta box
    [rad], tool travel along the cut ``s_cut`` [m]. Per window: ``coverage`` (largest gap of
    the true edge from the contact path [m], edge point index) and the cone figures."""

    contact: np.ndarray
    edge_dev: np.ndarray
    engagement: np.ndarray
    theta_A: np.ndarray
    theta_B: np.ndarray
    cone_margin: np.ndarray
    box_margin: np.ndarray
    s_cut: np.ndarray
    coverage: dict
    cone_per_window: dict


@dataclass(frozen=True)
class JointLimits:
    """The cell's joint limits: position (6,) [rad], |velocity| (6,) [rad/s], |acceleration|
    (6,) [rad/s^2], and the home configuration (6,) [rad]."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    home: np.ndarray

    @classmethod
    def of_cell(cls, cell) -> JointLimits:
        return cls(np.asarray(cell.q_lower, float), np.asarray(cell.q_upper, float),
                   np.maximum(np.abs(cell.v_lower), np.abs(cell.v_upper)),
                   np.maximum(np.abs(cell.a_lower), np.abs(cell.a_upper)),
                   np.asarray(cell.q_home, float))


@dataclass(frozen=True, eq=False)
class SampledPlan:
    """A plan, its cell and hub, and everything sampled from them (module docstring).

    Attributes:
        plan: the plan. config: the run's configuration (recipe, tolerances).
        cell: the freshly loaded cell; kin: the verifier's kinematics of it; limits: its joints.
        hub_model: the hub's ground truth; expected_windows: windows the plan must cut.
        edge_of: window -> ground-truth WindowEdge; cut_windows: windows the plan cuts.
        refs: window -> :class:`WindowRef` (None: nothing to check the cut against).
        X_HT_targets: (M, 4, 4) FK of every target's joints.
    """

    plan: object
    config: Config
    cell: object
    kin: VerifyKinematics
    limits: JointLimits
    hub_model: object
    expected_windows: list
    edge_of: dict
    cut_windows: list
    refs: dict
    X_HT_targets: np.ndarray
    samples: Samples
    program: ProgramReading
    distances: Distances
    cut: CutGeometry
    _memo: dict = field(default_factory=dict, repr=False)

    def memo(self, key: str, compute: Callable[[], object]):
        """A figure several checks read, computed once (``compute()``) and kept."""
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]

    @property
    def targets(self) -> tuple:
        return self.plan.targets

    @property
    def segments(self) -> tuple:
        return tuple(self.plan.segments)

    def samples_of(self, window: int, kind: str = "cut") -> np.ndarray:
        """Indices of the samples of ``window``'s segments of ``kind``."""
        s = self.samples
        return np.flatnonzero((s.window == window) & (s.kind == KIND_CODE[kind]))

    def depth_of_cut(self, window: int) -> float:
        """The recipe's depth of cut of a window [m] (0 for a window the hub does not have)."""
        edge = self.edge_of.get(window)
        return 0.0 if edge is None else self.config.process.depth_of_cut(edge.kind)

    def where(self, i) -> dict:
        """Worst-location fields of sample ``i``: its window, time and the target its move ends
        at (the linear move it lies on, else its segment's last target)."""
        i = int(i)
        seg = self.segments[self.samples.segment[i]]
        k = int(self.program.move[i])
        k = k if k >= 0 else seg.target_range[1] - 1
        return {"window": int(seg.window_index), "time": float(self.samples.t[i]),
                "target_index": int(min(max(k, 0), len(self.targets) - 1))}

    def where_time(self, t: float) -> dict:
        """Worst-location fields of trajectory time ``t`` [s]."""
        for seg in self.segments:
            if seg.t_range[0] - 1e-12 <= t <= seg.t_range[1] + 1e-12:
                return {"window": int(seg.window_index), "time": float(t),
                        "target_index": int(min(seg.target_range[1] - 1,
                                                len(self.targets) - 1))}
        return {"time": float(t)}
