"""The continuous clearance certificate: a lower bound of the clearance (and of the robot's
distance to itself) over the whole trajectory, not only at the samples.

Between two consecutive samples a distance can fall only as far as some point of the
geometry moves relative to the other geometry (:mod:`drakedeburr.verify.motion_bounds`: the
displacement of each geometry's bounding ball from the poses at both ends, and the deviation
from that chord bounded by the joints' rates on the trajectory's own polynomial pieces times
the links' reach). From the distances at both ends of an interval this gives a lower bound
over the interval for every pair; the certificate of a class is the smallest such bound.

The tracked sweep (:mod:`drakedeburr.verify.sweep`) reads at each sample the pairs that
could come within ``level + delta + 2 e`` of their track, ``level`` the target for the
smallest distance read so far, so every pair it leaves unread is certified above the target
without more work. Where a bound falls
below the *target* (the smallest distance read, at most the query distance, less the larger
of ``Tolerances.certificate_gap`` and ``certificate_share`` of its margin above the limit, but
not below the limit while that reading is above it: :func:`resolution_target`),
the interval is refined: the pairs read at its ends are read at its
midpoint (the trajectory evaluated there), and each half is bounded again, until every pair
is above the target or the interval is shorter than ``Tolerances.certificate_floor``
(reported: its bound and that it could not be refined further). A reading found between the
samples below the limit is a real violation the samples missed (the *witness*).

The certified minimum is therefore at most every distance read (samples and refinement) and,
where refinement converged, within that resolution of the smallest distance read. The
burr head/hub pair (the process contact) is not part of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.verify.motion_bounds import (
    interval_lower_bound,
    rate_bounds,
    track_interval_bounds,
)
from drakedeburr.verify.pair_scene import CLEARANCE, SELF, checked_scene
from drakedeburr.verify.sweep import class_limits, resolution_target

__all__ = ["ClassCertificate", "ClearanceCertificate", "certify", "certify_alongside", "METHOD"]

METHOD = ("Lipschitz bound per pair: ball displacement from FK at both ends of each interval + "
          "h^2/8 x point acceleration bound (exact joint-rate bounds of the trajectory's "
          "polynomial pieces x link reach), bisection where below target")


@dataclass(frozen=True)
class ClassCertificate:
    """The certificate of one distance class.

    Attributes:
        limit: the class's limit [m] (clearance >= min_clearance, self > 0).
        certified: lower bound of the class's distance over the whole trajectory [m].
        interval: (t0, t1) [s] of the interval holding that bound; pair: its geometry pair.
        sampled: smallest distance at the samples [m] (inf: none within the query distance).
        observed: smallest distance read anywhere, samples and refinement [m];
            observed_time [s], observed_pair: where.
        unresolved: pair bounds left at the floor below the target; unresolved_below_limit:
            those below the limit.
    """

    limit: float
    certified: float
    interval: tuple[float, float]
    pair: tuple[str, str]
    sampled: float
    observed: float
    observed_time: float
    observed_pair: tuple[str, str]
    unresolved: int
    unresolved_below_limit: int

    @property
    def passed(self) -> bool:
        ok = self.certified >= self.limit if self.limit > 0 else self.certified > self.limit
        return bool(ok)


@dataclass(frozen=True)
class ClearanceCertificate:
    """Certificates of the clearance and self classes, the method and the resolution used
    (``gap`` [m] or ``share`` of the margin, ``floor`` [s]); the sweep's pair readings and the
    samples it posed the scene at; the refinement's intervals, pair readings and deepest
    bisection."""

    clearance: ClassCertificate
    self_distance: ClassCertificate
    method: str
    gap: float
    share: float
    floor: float
    sweep_readings: int
    samples_posed: int
    refined: int
    refine_readings: int
    depth: int


class _Refiner:
    """Bisection of the intervals whose bound is below the target (module docstring)."""

    def __init__(self, scene, traj, sweep, tol, limits: dict) -> None:
        self.scene, self.traj, self.sweep = scene, traj, sweep
        self.qd = float(tol.query_distance)
        self.gap, self.floor = float(tol.certificate_gap), float(tol.certificate_floor)
        self.share = float(tol.certificate_share)
        self.limits, self.tol = limits, tol
        self.readings = 0
        self.observed = {}  # class -> (value, time, pair)
        for c in (CLEARANCE, SELF):
            b = sweep.best[c]
            i = int(np.argmin(b))
            self.observed[c] = (float(b[i]), float(sweep.t[i]), int(sweep.best_pair[c, i]))

    def target(self, c: int) -> float:
        """What every bound of class ``c`` must reach: the smallest distance read (at most the
        query distance) less the resolution (module docstring)."""
        return resolution_target(min(self.observed[c][0], self.qd), self.limits[c], self.tol)

    def note(self, d: float, t: float, p: int) -> None:
        c = int(self.scene.cls[p])
        if d <= self.qd and d < self.observed[c][0]:
            self.observed[c] = (float(d), float(t), int(p))

    def read_at(self, q: np.ndarray, t: float, pairs: np.ndarray) -> np.ndarray:
        """Read ``pairs`` at joints ``q`` (time ``t``)."""
        self.scene.set_configuration(q)
        d = np.array([self.scene.distance(int(p)) for p in pairs])
        self.readings += len(pairs)
        for v, p in zip(d, pairs, strict=True):
            self.note(float(v), t, int(p))
        return d

    def bounds(self, ta, tb, item, pairs, d_a, d_b) -> np.ndarray:
        """Per entry (item index into ``ta``/``tb``, pair, distances at both ends) the lower
        bound over the item's interval [m]."""
        h = tb - ta
        X_a = self.scene.tree.body_poses(self.traj.value(ta))
        X_b = self.scene.tree.body_poses(self.traj.value(tb))
        qd, qdd = rate_bounds(self.traj, ta, h)
        delta, e = track_interval_bounds(self.scene.tracks, self.scene.track[pairs], X_a[item],
                                         X_b[item], qd[item], qdd[item], h[item])
        return interval_lower_bound(d_a, d_b, delta, e)


def _start_items(ref: _Refiner, fail: np.ndarray):
    """The pairs of the failing (track, interval)s read at either end of their interval, with
    the missing end readings taken -> (intervals (M,), entries: item, pair, d_a, d_b)."""
    sw, scene = ref.sweep, ref.scene
    tracks_fail = {}
    for k, m in zip(*fail, strict=True):
        tracks_fail.setdefault(int(m), set()).add(int(k))
    order = np.argsort(sw.rec_sample, kind="stable")
    rs, rp, rv = sw.rec_sample[order], sw.rec_pair[order], sw.rec_value[order]
    cut = np.searchsorted(rs, np.arange(len(sw.t) + 1))
    at = {}  # sample -> {pair: value}

    def readings(i):
        if i not in at:
            at[i] = dict(zip(rp[cut[i]:cut[i + 1]].tolist(), rv[cut[i]:cut[i + 1]].tolist(),
                             strict=True))
        return at[i]

    intervals, item, pair = sorted(tracks_fail), [], []
    for n, m in enumerate(intervals):
        ks = tracks_fail[m]
        ps = sorted(p for p in set(readings(m)) | set(readings(m + 1))
                    if int(scene.track[p]) in ks)
        item += [n] * len(ps)
        pair += ps
    item, pair = np.array(item, int), np.array(pair, int)
    d = np.empty((2, len(pair)))
    for end in (0, 1):
        missing: dict[int, list[int]] = {}
        for j, (n, p) in enumerate(zip(item, pair, strict=True)):
            i = intervals[n] + end
            v = readings(i).get(int(p))
            if v is None:
                missing.setdefault(i, []).append(j)
            else:
                d[end, j] = v
        for i, js in missing.items():
            d[end, js] = ref.read_at(sw.q[i], float(sw.t[i]), pair[js])
    return np.array(intervals, int), item, pair, d[0], d[1]


#: deepest bisection of one sample interval (a guard; the floor ends it first)
_MAX_DEPTH = 40


class _Tally:
    """Per class: the smallest final bound and where, and the unresolved counts."""

    def __init__(self, limits: dict) -> None:
        self.limits = limits
        self.best = {c: (np.inf, (np.nan, np.nan), ("", "")) for c in limits}
        self.unresolved = dict.fromkeys(limits, 0)
        self.below = dict.fromkeys(limits, 0)

    def add(self, c: int, values: np.ndarray, t0: np.ndarray, t1: np.ndarray, name) -> None:
        if len(values):
            j = int(np.argmin(values))
            if values[j] < self.best[c][0]:
                self.best[c] = (float(values[j]), (float(t0[j]), float(t1[j])), name(j))


def _refine(ref: _Refiner, fail, tally: _Tally) -> tuple[int, int]:
    """Bisect the failing (track, interval)s until certified or at the floor -> (intervals
    refined, deepest level)."""
    scene, t = ref.scene, ref.sweep.t
    intervals, item, pair, d_a, d_b = _start_items(ref, fail)
    ta, tb = t[intervals], t[intervals + 1]
    depth = 0
    while len(pair):
        bnd = ref.bounds(ta, tb, item, pair, d_a, d_b)
        cls = scene.cls[pair]
        target = np.array([ref.target(c) if c in tally.limits else -np.inf for c in range(3)])
        ok = bnd >= target[cls]
        h = (tb - ta)[item]
        floor = (0.5 * h < ref.floor) | (depth >= _MAX_DEPTH)
        done = ok | floor
        for c in tally.limits:
            m = done & (cls == c)
            tally.add(c, bnd[m], ta[item[m]], tb[item[m]],
                      lambda j, sel=pair[m]: scene.pair_names(int(sel[j])))
            stuck = m & ~ok
            tally.unresolved[c] += int(stuck.sum())
            tally.below[c] += int((stuck & (bnd < tally.limits[c])).sum())
        keep = ~done
        if not keep.any():
            break
        item, pair, d_a, d_b = item[keep], pair[keep], d_a[keep], d_b[keep]
        split, item = np.unique(item, return_inverse=True)
        tm = 0.5 * (ta[split] + tb[split])
        q_m = ref.traj.value(tm)
        d_m = np.empty(len(pair))
        order = np.argsort(item, kind="stable")
        cut = np.searchsorted(item[order], np.arange(len(split) + 1))
        for n in range(len(split)):
            js = order[cut[n]:cut[n + 1]]
            d_m[js] = ref.read_at(q_m[n], float(tm[n]), pair[js])
        ta = np.concatenate([ta[split], tm])
        tb = np.concatenate([tm, tb[split]])
        item = np.concatenate([item, item + len(split)])
        pair = np.concatenate([pair, pair])
        d_a, d_b = np.concatenate([d_a, d_m]), np.concatenate([d_m, d_b])
        depth += 1
    return len(intervals), depth


def _unread_bounds(sw, tracks) -> np.ndarray:
    """(T, N - 1) bound over each interval of the pairs of each track the sweep left unread at
    both ends: they were at least their class's ``level`` + the track's pad there."""
    pad = np.zeros(sw.lower.shape)
    pad[:, 1:] = sw.delta + 2.0 * sw.e
    pad[:, :-1] = np.maximum(pad[:, :-1], pad[:, 1:])
    theta = sw.level[tracks.cls] + pad
    return interval_lower_bound(theta[:, :-1], theta[:, 1:], sw.delta, sw.e)


def certify(scene, traj, sweep, tol) -> ClearanceCertificate:
    """The certificate of a tracked sweep (module docstring).

    Args:
        scene: the cell's :class:`~drakedeburr.verify.pair_scene.PairScene`.
        traj: the plan's joint trajectory. sweep: :class:`~drakedeburr.verify.sweep.Sweep`.
        tol: the tolerances (limits, query distance, ``certificate_gap``/``_floor``).
    """
    limits = class_limits(tol)
    ref = _Refiner(scene, traj, sweep, tol, limits)
    tracks, t = scene.tracks, sweep.t
    B = interval_lower_bound(sweep.lower[:, :-1], sweep.lower[:, 1:], sweep.delta, sweep.e)
    U = _unread_bounds(sweep, tracks)
    target = np.array([ref.target(c) if c in limits else -np.inf for c in tracks.cls])
    fail = B < target[:, None]
    tally = _Tally(limits)
    for c in limits:
        rows = np.flatnonzero(tracks.cls == c)
        for k in rows:
            b = np.where(fail[k], U[k], B[k])
            geom = scene.names[scene.track_geometry[k]]
            tally.add(c, b, t[:-1], t[1:], lambda j, g=geom: (g, "(track bound)"))
    refined, depth = _refine(ref, np.nonzero(fail), tally)
    out = {}
    for c, lim in limits.items():
        value, interval, pair = tally.best[c]
        obs, t_obs, p_obs = ref.observed[c]
        sampled = float(np.min(sweep.best[c]))
        out[c] = ClassCertificate(
            limit=lim, certified=value, interval=interval, pair=pair, sampled=sampled,
            observed=obs, observed_time=t_obs,
            observed_pair=scene.pair_names(p_obs) if p_obs >= 0 else ("", ""),
            unresolved=tally.unresolved[c], unresolved_below_limit=tally.below[c])
    return ClearanceCertificate(clearance=out[CLEARANCE], self_distance=out[SELF],
                                method=_method(scene), gap=ref.gap,
                                share=ref.share, floor=ref.floor,
                                sweep_readings=len(sweep.rec_pair), samples_posed=sweep.posed,
                                refined=refined, refine_readings=ref.readings, depth=depth)


def _method(scene) -> str:
    return f"{METHOD}; {scene.tally.summary()}"


def certify_alongside(scene, traj, sweep, tol, alongside=None,
                      workers: int | None = None) -> ClearanceCertificate:
    """:func:`certify`, made on a running pool worker (the sweep's: it holds the same pair
    scene, checked by its digest; ``workers`` as :func:`drakedeburr.pool.map_tasks`)
    while this process runs ``alongside()``; without a worker, ``alongside()`` then
    :func:`certify` here. The same certificate either way: the worker's
    readings are added to this scene's tally before the method is written."""
    from dataclasses import replace

    from drakedeburr.cell.fingerprint import geometry_digest
    from drakedeburr.pool import map_tasks, running_workers

    recipe = scene.cell.recipe
    if alongside is None or recipe is None or not running_workers():
        if alongside is not None:
            alongside()
        return certify(scene, traj, sweep, tol)
    def here(k: int):
        return alongside() if k == 0 else certify(scene, traj, sweep, tol)

    def remote(k: int):
        if k == 0:
            return None
        lean = replace(sweep, X=np.empty((0,)))  # the poses (~30 MB): certify reads none
        return certify_in_worker, (dict(recipe), geometry_digest(scene.cell), scene.digest(),
                                   traj, lean, tol)

    def done(k: int, value):
        cert, tally = value
        scene.tally.merge(tally)
        return replace(cert, method=_method(scene))

    return map_tasks(2, here, remote, workers, done,
                     name=lambda k: "the clearance certificate" if k else "alongside")[1]


def certify_in_worker(recipe: dict, fingerprint: str, digest: str, traj, sweep, tol):
    """A pool worker's task: the certificate of a sweep (:func:`certify`) in the same cell
    -> (certificate, its reading tally)."""
    scene = checked_scene(recipe, fingerprint, digest, tol)
    return certify(scene, traj, sweep, tol), scene.tally
