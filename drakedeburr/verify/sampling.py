"""The plan sampled once: :class:`SampledPlan`, what every check of the verifier reads.

Built by :func:`sample_plan` from the plan alone (targets, segments, joint trajectory, tool
paths), a freshly loaded cell and the hub's ground truth, in stages that each produce one
frozen record:

* :class:`Samples` - the timed joint trajectory sampled every ``Tolerances.dense_step`` of tool
  travel (tool T relative to hub H) on approach/cut/retract, every ``joint_move_step`` on joint
  moves, and at least every ``time_step`` seconds and at every knot; poses by the verifier's
  own analytic kinematics (:mod:`drakedeburr.verify.kinematics`);
* :class:`ProgramReading` - the Cartesian program as a controller executes it (linear moves
  between consecutive targets, orientation slerped), read against the samples: which move each
  sample lies on and how far from it (:mod:`drakedeburr.verify.program`);
* :class:`Distances` - signed distances per sample from the scene graph, the continuous
  clearance certificate between the samples, the Drake-plant FK cross-check and the
  manipulability (:mod:`drakedeburr.verify.distances`);
* :class:`CutGeometry` - per cut sample the executed contact point, its distance to the true
  edge, the burr's engagement, theta_A/theta_B and the cone margin
  (:mod:`drakedeburr.verify.cut_geometry`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.config import Config
from drakedeburr.errors import InputError
from drakedeburr.verify.kinematics import VerifyKinematics
from drakedeburr.verify.refs import LINEAR_KINDS, WindowRef, tool_paths_of, window_ref

__all__ = ["KIND_CODE", "Samples", "ProgramReading", "Distances", "CutGeometry", "JointLimits",
           "SampledPlan", "sample_plan", "sample_times", "validate_plan",
           "path_acceleration"]

#: integer code of each segment kind in :attr:`Samples.kind`
KIND_CODE = {"home": 0, "transition": 1, "approach": 2, "cut": 3, "retract": 4}

Progress = Callable[[int, int, str], None] | None


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


def validate_plan(plan) -> None:
    """Raise InputError if the plan cannot be sampled (shapes, times, no targets)."""
    traj = plan.trajectory
    t, c = np.asarray(traj.t, float), np.asarray(traj.c, float)
    if t.ndim != 1 or len(t) < 2:
        raise InputError(f"plan for hub {plan.hub}: trajectory needs >= 2 knots, got {t.shape}")
    if c.ndim != 3 or c.shape[1:] != (len(t) - 1, 6) or len(c) < 1:
        raise InputError(f"plan for hub {plan.hub}: trajectory pieces must be (D + 1, "
                         f"{len(t) - 1}, 6), got {c.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(c))):
        raise InputError(f"plan for hub {plan.hub}: trajectory holds NaN/inf")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise InputError(f"plan for hub {plan.hub}: knot times not strictly increasing at knot "
                         f"{int(bad[0]) + 1}")
    if not plan.targets:
        raise InputError(f"plan for hub {plan.hub}: no targets")


def _segment_times(plan, kin: VerifyKinematics, seg, tol) -> np.ndarray:
    """Sample times of one segment: every ``dense_step`` (linear kinds) or ``joint_move_step``
    of tool travel, every ``time_step``, and every knot inside it."""
    traj = plan.trajectory
    t0, t1 = float(seg.t_range[0]), float(seg.t_range[1])
    if t1 <= t0:
        return np.array([t0])
    step = tol.dense_step if seg.kind in LINEAR_KINDS else tol.joint_move_step
    n = max(3, int(np.ceil((t1 - t0) / 2e-3)) + 1)
    for _ in range(6):
        tf = np.linspace(t0, t1, n)
        p = kin.X_HT(traj.value(tf))[:, :3, 3]
        ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
        if ds.max(initial=0.0) <= 0.5 * step:
            break
        n = 2 * n
    s_acc = np.concatenate([[0.0], np.cumsum(ds)])
    k_travel = np.arange(0.0, s_acc[-1], 0.95 * step)  # margin: chords of a fine grid
    t_travel = np.interp(k_travel, s_acc, tf)
    t_time = np.arange(t0, t1, tol.time_step)
    knots = traj.t[(traj.t > t0) & (traj.t < t1)]
    return np.unique(np.concatenate([[t0, t1], t_travel, t_time, knots]))


def path_acceleration(traj, kin, t: np.ndarray, p: np.ndarray, h: float = 1e-5
                       ) -> np.ndarray:
    """Tangential acceleration of T relative to H at times ``t`` [m/s^2] by central differences
    (one-sided at the trajectory's ends)."""
    t_end = float(traj.t[-1])
    t_hi = np.minimum(t + h, t_end)
    t_lo = np.maximum(t_hi - 2 * h, 0.0)
    t_mid = 0.5 * (t_hi + t_lo)
    p_hi = kin.X_HT(traj.value(t_hi))[:, :3, 3]
    p_lo = kin.X_HT(traj.value(t_lo))[:, :3, 3]
    p_mid = kin.X_HT(traj.value(t_mid))[:, :3, 3]
    v = (p_hi - p_lo) / (2 * h)
    a = (p_hi - 2 * p_mid + p_lo) / h ** 2
    speed = np.linalg.norm(v, axis=1)
    moving = speed > 1e-6
    return np.where(moving, np.einsum("ij,ij->i", v, a) / np.maximum(speed, 1e-12),
                    np.linalg.norm(a, axis=1))


def sample_times(plan, cell, tolerances) -> np.ndarray:
    """The times [s] the verifier samples ``plan`` at with ``tolerances`` (module docstring:
    every ``dense_step``/``joint_move_step`` of tool travel, every ``time_step``, every knot),
    in the order of :attr:`Samples.t`, without reading anything there."""
    kin = VerifyKinematics(cell)
    return np.concatenate([_segment_times(plan, kin, seg, tolerances) for seg in plan.segments])


def _samples(plan, kin: VerifyKinematics, tol, progress: Progress) -> Samples:
    segments = list(plan.segments)
    per_seg = []
    for si, seg in enumerate(segments):
        per_seg.append(_segment_times(plan, kin, seg, tol))
        if progress is not None:
            progress(si + 1, 2 * len(segments), f"sampling {seg.kind}")
    seg_index = np.concatenate([np.full(len(ts), i) for i, ts in enumerate(per_seg)]) \
        if per_seg else np.zeros(0, int)
    t = np.concatenate(per_seg) if per_seg else np.zeros(0)
    traj = plan.trajectory
    t_end = float(traj.t[-1])
    q = traj.value(t)
    X_HT = kin.X_HT(q)
    h = 1e-6
    t_hi, t_lo = np.clip(t + h, 0, t_end), np.clip(t - h, 0, t_end)
    speed = np.linalg.norm(kin.X_HT(traj.value(t_hi))[:, :3, 3]
                           - kin.X_HT(traj.value(t_lo))[:, :3, 3], axis=1) / (t_hi - t_lo)
    return Samples(t=t, segment=seg_index, q=q, qd=traj.derivative(t, 1), X_HT=X_HT,
                   p_HT=X_HT[:, :3, 3], X_WF=kin.X_WF(q), speed=speed,
                   path_acceleration=path_acceleration(traj, kin, t, X_HT[:, :3, 3]),
                   kind=np.array([KIND_CODE.get(segments[i].kind, -1) for i in seg_index], int),
                   window=np.array([segments[i].window_index for i in seg_index], int))


def _expected_windows(hub_model, expected_windows) -> list[int]:
    windows_hub = [w.index for w in hub_model.windows]
    if expected_windows is None:
        return windows_hub
    bad = [w for w in expected_windows if w not in windows_hub]
    if bad:
        raise InputError(f"hub {hub_model.name} has no window(s) {bad} (has {windows_hub})")
    return sorted(int(w) for w in expected_windows)


def sample_plan(plan, config: Config, *, cell=None, hub_model=None,
                expected_windows: list[int] | None = None,
                progress: Progress = None) -> SampledPlan:
    """Sample a plan for verification (module docstring).

    Args:
        plan: a :class:`drakedeburr.plan.types.Plan`.
        config: the run's configuration (its tolerances set the sampling).
        cell: an already loaded cell for the plan's scenario and hub (default: load afresh).
        hub_model: the hub's :class:`drakedeburr.hub.HubModel` (default: ``load_hub(plan.hub)``).
        expected_windows: windows the plan must cut (default: every window of the hub).
        progress: optional callback (done, total, label).

    Raises:
        InputError: the plan is malformed, or ``expected_windows`` names windows the hub lacks.
    """
    from drakedeburr.verify.cut_geometry import cut_geometry
    from drakedeburr.verify.distances import measure_samples
    from drakedeburr.verify.program import read_program
    from drakedeburr.verify.sweep import warm_workers

    validate_plan(plan)
    if cell is None:
        from drakedeburr.cell.station import load_plan_cell

        cell = load_plan_cell(plan)
    if hub_model is None:
        from drakedeburr.hub.model import load_hub

        hub_model = load_hub(plan.hub)
    windows = _expected_windows(hub_model, expected_windows)
    tol = config.tolerances
    kin = VerifyKinematics(cell)
    samples = _samples(plan, kin, tol, progress)
    warm_workers(cell, len(samples))  # parts of the distance sweep go to them
    edge_of = {w.index: w for w in hub_model.windows}
    cut_windows = sorted({s.window_index for s in plan.segments if s.kind == "cut"})
    tool_paths = tool_paths_of(plan)
    refs: dict[int, WindowRef | None] = {
        w: window_ref(w, plan.targets, tool_paths.get(w), edge_of.get(w), config.process)
        for w in cut_windows}
    read: dict = {}

    def program_and_cut() -> None:  # needs no distance: made while the certificate is
        read["program"] = program = read_program(plan, samples, tol)
        read["cut"] = cut_geometry(plan, samples, program, refs, edge_of, cut_windows, tol)

    distances = measure_samples(cell, samples, tol, progress, len(plan.segments),
                                trajectory=plan.trajectory, alongside=program_and_cut)
    program, cut = read["program"], read["cut"]
    return SampledPlan(
        plan=plan, config=config, cell=cell, kin=kin, limits=JointLimits.of_cell(cell),
        hub_model=hub_model, expected_windows=windows,
        edge_of=edge_of, cut_windows=cut_windows, refs=refs,
        X_HT_targets=kin.X_HT(np.array([t.q for t in plan.targets], float)),
        samples=samples, program=program, distances=distances, cut=cut)
