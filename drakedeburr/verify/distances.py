"""Signed distances at every sample, the Drake-plant FK cross-check and the manipulability ->
:class:`drakedeburr.verify.types.Distances`, with the continuous clearance certificate.

Per sample, the smallest signed distance of each class (clearance, self, burr: see
:mod:`drakedeburr.verify.pair_scene`) within ``Tolerances.query_distance`` (``inf`` if none)
and its pair. Two implementations give the same values (tested):

* ``"tracked"`` (default): the pairs of :class:`~drakedeburr.verify.pair_scene.PairScene` are
  read one by one, each only when it could matter (:mod:`drakedeburr.verify.sweep`: a pair
  last read at distance ``d`` is at least ``d`` minus how far its track has moved since), and
  the continuous clearance certificate is built on those readings
  (:mod:`drakedeburr.verify.certificate`). Far from everything nothing is read.
* ``"dense"``: the previous implementation, the cell's
  ``ComputeSignedDistancePairwiseClosestPoints`` at every sample (plus a Drake FK and
  Jacobian per sample); kept as the reference and the benchmarks' baseline. It computes no
  certificate.

The burr-head/hub pair is the process contact: measured (class ``burr``, its own check) but
not part of the clearance or its certificate.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from drakedeburr.verify.pair_scene import BURR, CLEARANCE, SELF, PairScene, pair_scene_of

__all__ = ["DistanceProbe", "PairDistances", "pair_scene_of", "measure_samples"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PairDistances:
    """Smallest signed distance per class at one configuration ([m]; ``inf`` if none within
    the query distance) and the pair's geometry names."""

    clearance: float
    clearance_pair: tuple[str, str]
    self_distance: float
    self_pair: tuple[str, str]
    burr: float
    burr_pair: tuple[str, str]


class DistanceProbe:
    """The cell's own broad-phase distance query at one configuration (the reference).

    Args:
        cell: the cell. query_distance: pairs farther apart are not reported [m].
        tolerances: how readings are certified (default: the default tolerances).
    """

    def __init__(self, cell, query_distance: float, tolerances=None) -> None:
        from drakedeburr.config import default_tolerances

        self.cell = cell
        self.query_distance = float(query_distance)
        self.context = cell.diagram.CreateDefaultContext()
        self.plant_context = cell.plant.GetMyMutableContextFromRoot(self.context)
        self.sg_context = cell.scene_graph.GetMyContextFromRoot(self.context)
        self.port = cell.scene_graph.get_query_output_port()
        self.scene = pair_scene_of(cell)
        self.scene.use_tolerances(tolerances or default_tolerances())
        self._index = {g.get_value(): n for n, g in enumerate(self.scene.ids)}
        self._pair_of = {(int(a), int(b)): p
                         for p, (a, b) in enumerate(zip(self.scene.a, self.scene.b, strict=True))}

    def measure(self, q: np.ndarray) -> PairDistances:
        """Smallest distance per class at joints ``q`` [rad]."""
        self.cell.plant.SetPositions(self.plant_context, q)
        query = self.port.Eval(self.sg_context)
        best = {CLEARANCE: (np.inf, None), SELF: (np.inf, None), BURR: (np.inf, None)}
        for r in query.ComputeSignedDistancePairwiseClosestPoints(self.query_distance):
            ia, ib = self._index[r.id_A.get_value()], self._index[r.id_B.get_value()]
            p = self._pair_of.get((min(ia, ib), max(ia, ib)))
            if p is None:
                continue  # filtered in the cell (fixed-fixed pairs are filtered there too)
            c = int(self.scene.cls[p])
            d = float(r.distance)
            if c != BURR and d > 0.0:  # held to a rigorous bound, as the tracked sweep's
                X_A, X_B = (query.GetPoseInWorld(g).GetAsMatrix4() for g in (r.id_A, r.id_B))
                n_BA = np.asarray(r.nhat_BA_W)
                if ia != self.scene.a[p]:  # the scene's pair is (b, a) here
                    X_A, X_B, n_BA = X_B, X_A, -n_BA
                d = self.scene.certify(p, d, n_BA, X_A, X_B)
            if d < best[c][0]:
                best[c] = (d, p)

        def named(c):
            d, p = best[c]
            return d, (("", "") if p is None else self.scene.pair_names(p))

        (c, cp), (sd, sp), (b, bp) = named(CLEARANCE), named(SELF), named(BURR)
        return PairDistances(c, cp, sd, sp, b, bp)


def _fk_difference(cell, scene: PairScene, samples, X: np.ndarray, extra: list[int],
                   every: int) -> tuple[float, int]:
    """Largest element difference of the flange pose in world and the tool pose in the hub:
    the plant's model (numpy tree, every sample) and Drake's own evaluation (every
    ``every``-th sample and ``extra``) vs the analytic OPW poses of ``samples``."""
    tree = scene.tree
    fb, hb, tb = (int(f.body().index()) for f in (cell.flange_frame, cell.hub_frame,
                                                    cell.tool_frame))
    X_BF, X_BH, X_BT = (f.GetFixedPoseInBodyFrame().GetAsMatrix4()
                        for f in (cell.flange_frame, cell.hub_frame, cell.tool_frame))
    X_WF = X[:, fb] @ X_BF
    X_HT = np.linalg.inv(X[:, hb] @ X_BH) @ (X[:, tb] @ X_BT)
    diff = max(float(np.abs(X_WF - samples.X_WF).max(initial=0.0)),
               float(np.abs(X_HT - samples.X_HT).max(initial=0.0)))
    subset = sorted(set(range(0, len(samples), every)) | {i for i in extra if i >= 0})
    plant, pc = cell.plant, scene.plant_context
    for i in subset:
        plant.SetPositions(pc, samples.q[i])
        X_WF_d = cell.flange_frame.CalcPoseInWorld(pc).GetAsMatrix4()
        X_HT_d = cell.tool_frame.CalcPose(pc, cell.hub_frame).GetAsMatrix4()
        diff = max(diff, float(np.abs(X_WF_d - samples.X_WF[i]).max()),
                   float(np.abs(X_HT_d - samples.X_HT[i]).max()))
    del tree
    return diff, len(subset)


def _measure_dense(cell, samples, tol, progress=None):
    """The previous implementation: one broad-phase query, one Drake FK and Jacobian per
    sample (no certificate)."""
    from pydrake.multibody.tree import JacobianWrtVariable

    from drakedeburr.verify.types import Distances

    probe = DistanceProbe(cell, tol.query_distance, tol)
    plant, pc = cell.plant, probe.plant_context
    n = len(samples)
    out = {k: np.full(n, np.inf) for k in ("clearance", "self_distance", "burr")}
    pairs = {k: [("", "")] * n for k in out}
    manip = np.full(n, np.nan)
    fk_diff = 0.0
    for i in range(n):
        d = probe.measure(samples.q[i])  # sets the positions in probe's context
        X_WF_d = cell.flange_frame.CalcPoseInWorld(pc).GetAsMatrix4()
        X_HT_d = cell.tool_frame.CalcPose(pc, cell.hub_frame).GetAsMatrix4()
        fk_diff = max(fk_diff, float(np.abs(X_WF_d - samples.X_WF[i]).max()),
                      float(np.abs(X_HT_d - samples.X_HT[i]).max()))
        J = plant.CalcJacobianSpatialVelocity(pc, JacobianWrtVariable.kQDot, cell.flange_frame,
                                              np.zeros(3), plant.world_frame(),
                                              plant.world_frame())
        manip[i] = abs(float(np.linalg.det(J)))
        for k, (v, pr) in {"clearance": (d.clearance, d.clearance_pair),
                           "self_distance": (d.self_distance, d.self_pair),
                           "burr": (d.burr, d.burr_pair)}.items():
            out[k][i], pairs[k][i] = v, pr
        if progress is not None and (i % max(1, n // 50) == 0 or i == n - 1):
            progress(i + 1, n)
    return Distances(clearance=out["clearance"], clearance_pair=tuple(pairs["clearance"]),
                     self_distance=out["self_distance"], self_pair=tuple(pairs["self_distance"]),
                     burr=out["burr"], burr_pair=tuple(pairs["burr"]), manipulability=manip,
                     fk_difference=fk_diff, fk_scope=f"Drake at all {n} samples",
                     certificate=None)


def measure_samples(cell, samples, tol, progress=None, n_segments: int = 1, *,
                    trajectory=None, method: str = "tracked", alongside=None):
    """Distances, the FK cross-check, the manipulability and the clearance certificate of the
    samples -> :class:`drakedeburr.verify.types.Distances` (module docstring).

    Args:
        cell: the freshly loaded cell. samples: :class:`~drakedeburr.verify.types.Samples`.
        tol: the tolerances (query distance, limits, certificate resolution).
        progress: optional callback (done, total, label), reported as the second half of
            ``2 * n_segments`` steps (the first half is the sampling).
        trajectory: the plan's joint trajectory (needed by ``"tracked"``).
        method: ``"tracked"`` (default) or ``"dense"`` (module docstring).
        alongside: optional work of the caller's that needs no distance, run here after the
            sweep, while a running pool worker makes the certificate (else before it).
    """
    from drakedeburr.verify.certificate import certify_alongside
    from drakedeburr.verify.types import Distances

    def step(done, total, label="distances"):
        if progress is not None:
            progress(n_segments + int(n_segments * done / total), 2 * n_segments, label)

    if method == "dense":
        if alongside is not None:
            alongside()
        return _measure_dense(cell, samples, tol, step)
    if method != "tracked":
        raise ValueError(f"method must be 'tracked' or 'dense', got {method!r}")
    if trajectory is None:
        raise ValueError("the tracked method needs the trajectory")
    from drakedeburr.verify.sweep import sweep as run_sweep

    scene = pair_scene_of(cell)
    sweep = run_sweep(scene, trajectory, samples.t, samples.q, tol, step)
    certificate = certify_alongside(scene, trajectory, sweep, tol, alongside)
    fb = cell.flange_frame
    manip = scene.tree.jacobian_det(sweep.X, int(fb.body().index()),
                                    fb.GetFixedPoseInBodyFrame().translation())
    finite = [np.where(np.isfinite(b), b, np.inf) for b in sweep.best]
    worst = [int(np.argmin(b)) if np.isfinite(b).any() else -1 for b in finite]
    every = 25
    fk_diff, n_drake = _fk_difference(cell, scene, samples, sweep.X, worst, every)

    def named(c):
        return tuple(scene.pair_names(p) if p >= 0 else ("", "") for p in sweep.best_pair[c])

    log.debug("distances: %d samples, scene posed at %d, %d pair readings, %d broad-phase "
              "refreshes", len(samples), sweep.posed, len(sweep.rec_pair), sweep.refreshes)
    return Distances(
        clearance=sweep.best[CLEARANCE], clearance_pair=named(CLEARANCE),
        self_distance=sweep.best[SELF], self_pair=named(SELF), burr=sweep.best[BURR],
        burr_pair=named(BURR), manipulability=manip, fk_difference=fk_diff,
        fk_scope=(f"the plant's joint frames and axes in numpy at all {len(samples)} samples, "
                  f"Drake's own evaluation at {n_drake} (every {every}th and the smallest "
                  "clearance/self/burr distances)"),
        certificate=certificate)
