"""The plan sampled once: :class:`~drakedeburr.verify.types.SampledPlan`, what every check of the
verifier reads (the records are in :mod:`drakedeburr.verify.types`).

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

import numpy as np

from drakedeburr.config import Config
from drakedeburr.errors import InputError
from drakedeburr.verify.kinematics import VerifyKinematics
from drakedeburr.verify.refs import LINEAR_KINDS, WindowRef, tool_paths_of, window_ref
from drakedeburr.verify.types import (
    KIND_CODE,
    JointLimits,
    SampledPlan,
    Samples,
)

__all__ = ["sample_plan", "sample_times", "validate_plan", "path_acceleration"]

Progress = Callable[[int, int, str], None] | None


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
