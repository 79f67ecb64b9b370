"""The tracked reading of the samples: each class's exact smallest distance at every sample
with few narrow-phase queries, and what the clearance certificate needs.

Every pair of :class:`~drakedeburr.verify.pair_scene.PairScene` has a *key*: its last reading
plus its track's cumulative displacement then (:mod:`drakedeburr.verify.motion_bounds`, the
first-order bound summed over the samples in between), so ``key - C[track, i]`` is a lower
bound of its distance at sample ``i``. Pairs that came near are kept per track in a heap by
key; all others are covered by one *far* key per track: the smallest bound of their distance
from the track geometry's ball to their box (in the track's reference frame), refreshed, with
the pairs that could come near read into the heap, when the far key could fall below what
the sample reads. At each sample, per class:

1. the pairs whose bound is below the smallest distance read so far (at most the query
   distance) are read in order of bound: the class minimum is then exact (what the dense
   reference reads, tested bit for bit);
2. for clearance and self, also every pair whose bound is below ``level + delta + 2 e`` of
   its track on the two adjacent intervals, ``level`` the certificate's target for the
   smallest distance read so far (:func:`resolution_target`, never above the final target):
   every pair left unread is then certified above the target over both intervals without more
   reading (:mod:`drakedeburr.verify.certificate`).

The samples are read in *parts* of ~2000 (:func:`part_bounds`, a function of the sample count
alone), neighbours sharing one sample; each part starts its own tracking, so the parts are
independent tasks: this process reads them from the front while the machine's other cores
(:func:`drakedeburr.pool.map_tasks`, workers that build the same cell) read them from
the back, and the result is the same on one core or many. Where two parts share a sample, the
class minimum is exact in both, and the bounds kept are the smaller of the two (each valid).
Fresh heaps also read fewer pairs than one long run (86.7k against 102k readings on the
default hub's plan): pairs that came near once no longer stay in a track's heap.

A reading higher than the pair's last reading plus the displacement since is not possible for
the true distance: it is the narrow phase's overestimate (GJK converges from above; Drake's
cylinder/convex distances were seen up to ~1 mm high), and the key keeps the allowed value.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from drakedeburr.verify.motion_bounds import (
    accel_weights,
    chord_bound,
    rate_bounds,
    relative_pose,
)
from drakedeburr.verify.pair_scene import CLEARANCE, SELF, PairScene, checked_scene, warm_scene

__all__ = ["Sweep", "sweep", "track_motion", "class_limits", "resolution_target"]

#: a refresh reads the pairs whose box bound is within the track's threshold + this [m]; a
#: speed setting (larger: fewer refreshes, more pairs read), not a tolerance
_NEAR_MARGIN = 0.02


def class_limits(tol) -> dict[int, float]:
    """The certified classes and their limits [m]: clearance >= min_clearance, self > 0."""
    return {CLEARANCE: float(tol.min_clearance), SELF: 0.0}


def resolution_target(level: float, limit: float, tol) -> float:
    """What the certificate's bounds must reach when ``level`` [m] is the smallest distance
    read (at most the query distance): ``level`` less the larger of
    ``Tolerances.certificate_gap`` and ``certificate_share`` of its margin above ``limit``,
    but never below ``limit`` while ``level`` is at or above it: a plan whose smallest
    reading lies within the gap above the limit is refined until its bound reaches the limit
    (else a clearance read at 2.0001 mm was certified at 2.0001 - 0.01 mm and failed the
    2 mm check it meets: an unseen hub, session 9). Non-decreasing in ``level``."""
    target = level - max(float(tol.certificate_gap),
                         float(tol.certificate_share) * (level - limit))
    return max(target, float(limit)) if level >= limit else target


@dataclass(frozen=True, eq=False)
class _Part:
    """A part's reading: what :class:`Sweep` holds but the samples and their poses, over the
    part's samples (indices local to it)."""

    best: np.ndarray
    best_pair: np.ndarray
    level: np.ndarray
    lower: np.ndarray
    delta: np.ndarray
    e: np.ndarray
    rec_sample: np.ndarray
    rec_pair: np.ndarray
    rec_value: np.ndarray
    posed: int
    refreshes: int


@dataclass(frozen=True, eq=False)
class Sweep(_Part):
    """What the tracked sweep read, for the certificate.

    Attributes:
        t: (N,) sample times [s]; q: (N, nq) joints [rad]; X: (N, n_bodies, 4, 4) body poses
            (numpy kinematic tree).
        best: (3, N) class minima within the query distance [m] (inf: none); best_pair: (3, N)
            their pairs (-1 none).
        level: (3, N) per certified class the level step 2 read below (+ the track's pad) at
            each sample [m] (-inf for the burr class).
        lower: (T, N) lower bound of each track's smallest distance at each sample [m], exact
            where below what step 2 reads.
        delta, e: (T, N - 1) each track's displacement and path-deviation bounds per interval.
        rec_sample, rec_pair, rec_value: every reading (sample, pair, distance [m]).
        posed: samples the scene was posed at; refreshes: track refreshes.
    """

    t: np.ndarray
    q: np.ndarray
    X: np.ndarray


def track_motion(scene: PairScene, traj, t: np.ndarray, X: np.ndarray):
    """delta, e (T, N - 1) [m] of every track over every sample interval."""
    tracks, n = scene.tracks, len(t)
    h = np.diff(t)
    qd, qdd = rate_bounds(traj, t[:-1], h)
    delta, e = np.zeros((len(tracks), n - 1)), np.zeros((len(tracks), n - 1))
    rel, weights = {}, {}
    for k in range(len(tracks)):
        key = (int(tracks.ref[k]), int(tracks.link[k]))
        if key not in rel:
            rel[key] = relative_pose(X, *key)
        R, p = rel[key]
        delta[k] = chord_bound(R[:-1], p[:-1], R[1:], p[1:], tracks.c[k], tracks.rho[k])
        seq = tuple(tracks.seq[k])
        if seq not in weights:
            weights[seq] = accel_weights(qd, qdd, tracks.seq[k])
        e[k] = weights[seq] @ tracks.reach[k]
    return delta, e * (0.125 * h ** 2 * (1.0 + 1e-9))


class _Reader:
    """The sweep's state (module docstring): per track a heap of (key, pair) and a far key."""

    def __init__(self, scene: PairScene, q: np.ndarray, X: np.ndarray, C: np.ndarray,
                 qd: float) -> None:
        self.scene, self.q, self.X, self.C, self.qd = scene, q, X, C, qd
        self.in_heap = np.zeros(len(scene.track), bool)
        self.heaps: list[list] = [[] for _ in range(len(scene.tracks))]
        self.far = np.full(len(scene.tracks), -np.inf)
        self.top = np.full(len(scene.tracks), -np.inf)
        self.stamp = [-1] * len(scene.track)
        self.last_d = [np.inf] * len(scene.track)
        self.last_C = [0.0] * len(scene.track)
        self.track = scene.track.tolist()
        self.cls = scene.cls.tolist()
        self.at, self.posed, self.refreshes = -1, 0, 0
        self.cur = [np.inf] * 3
        self.cur_k = [-1] * 3
        self.bodies: list[int] = []
        self.cls_t: list[int] = []
        self.rec: list[tuple[int, int, float]] = []  # (sample, pair, distance) in read order

    def _visit(self, i: int) -> None:
        if self.at != i:
            self.scene.set_configuration(self.q[i], self.bodies)
            self.at, self.posed = i, self.posed + 1

    def _note(self, i: int, p: int, d: float, Ci: float) -> float:
        """Record a reading; update the sample's class minimum; -> the pair's new key."""
        self.stamp[p] = i
        self.rec.append((i, p, d))
        c = self.cls[p]
        if d <= self.qd and d < self.cur[c]:
            self.cur[c], self.cur_k[c] = d, self.track[p]
        allowed = min(d, self.last_d[p] + Ci - self.last_C[p])
        self.last_d[p], self.last_C[p] = allowed, Ci
        return allowed + Ci

    def start(self, i: int, due: list) -> None:
        """A new sample, whose reads touch only the tracks ``due``."""
        self.cur = [np.inf] * 3
        self.cur_k = [-1] * 3
        tb = self.scene.track_bodies
        self.bodies = sorted({b for k in due for b in tb[k]})

    def refresh(self, k: int, i: int, reach: float) -> None:
        """Bound track ``k``'s pairs outside its heap at sample ``i`` by their boxes: read
        those that could be within ``reach`` [m] into the heap, keep the rest's smallest bound
        as the track's far key."""
        sc, tr = self.scene, self.scene.tracks
        self.refreshes += 1
        pairs = sc.track_pairs[k]
        out = pairs[~self.in_heap[pairs]]
        if not len(out):
            self.far[k] = np.inf
        else:
            X = self.X[i]
            ref, link = int(tr.ref[k]), int(tr.link[k])
            c_W = X[link, :3, :3] @ tr.c[k] + X[link, :3, 3]
            c_R = X[ref, :3, :3].T @ (c_W - X[ref, :3, 3])
            gap = np.maximum(sc.box_lo[out] - c_R, 0.0) + np.maximum(c_R - sc.box_hi[out], 0.0)
            lb = np.sqrt(np.einsum("ij,ij->i", gap, gap)) - tr.rho[k]
            near = lb < reach
            Ci = float(self.C[k, i])
            heap = self.heaps[k]
            for p in out[near].tolist():
                self._visit(i)
                heapq.heappush(heap, (self._note(i, p, self.scene.distance(p), Ci), p))
            self.in_heap[out[near]] = True
            self.far[k] = float(lb[~near].min()) + Ci if (~near).any() else np.inf
        heap = self.heaps[k]
        self.top[k] = min(heap[0][0], self.far[k]) if heap else self.far[k]

    def drain(self, k: int, i: int, below: float, shrink: bool = False) -> None:
        """Read every pair of track ``k`` whose bound at sample ``i`` is below ``below``
        (once per sample; with ``shrink``, ``below`` drops to each smaller distance read, so
        only what can still be the minimum is read)."""
        heap, Ci, stash, stamp = self.heaps[k], float(self.C[k, i]), [], self.stamp
        pop, distance, note = heapq.heappop, self.scene.distance, self._note
        while heap and heap[0][0] - Ci < below:
            key, p = pop(heap)
            if stamp[p] == i:
                stash.append((key, p))
                continue
            if self.at != i:
                self._visit(i)
            d = distance(p)
            stash.append((note(i, p, d, Ci), p))
            if shrink and d < below:
                below = d
        if len(stash) == 1:
            heapq.heappush(heap, stash[0])
        else:
            for item in stash:
                heapq.heappush(heap, item)
        self.top[k] = min(heap[0][0], self.far[k]) if heap else self.far[k]


class _Agenda:
    """When each track next needs a look: at sample i' only if its bound could fall below
    what the sample reads, ``top - C[k, i'] < max(U(i'), level) + pad[k, i']`` where U, the
    class minimum at i', is at most the query distance and at most the class minimum last
    read plus how far that pair's track has moved since. Running maxima
    of the left-hand terms make each look-up a binary search; a look taken early is harmless
    (the track is read only where needed), never late."""

    def __init__(self, C, pad, cls: list, qd: float, n: int) -> None:
        self.C, self.pad, self.cls, self.qd, self.n = C, pad, cls, qd, n
        self.level = [-np.inf] * 3  # per class: what step 2 reads below (+ pad), at most qd
        self.cap = np.maximum.accumulate(C + pad, axis=1)
        self._pair: dict[tuple[int, int], np.ndarray] = {}
        self.heap = [(0, k) for k in range(len(C))]
        self.at = [0] * len(C)

    def schedule(self, k: int, i: int, top: float, best: tuple) -> None:
        """After a look at track ``k`` at sample ``i`` (its top key now ``top``), given the
        last class minimum read (distance, sample, track)."""
        d, i_b, kb = best
        C, pad, j = self.C, self.pad, i + 1
        level = max(d, self.level[self.cls[k]]) - C[kb, i_b] if kb >= 0 else np.inf
        if j < self.n and top - C[k, j] < self.qd + pad[k, j] and (
                kb < 0 or C[k, j] + pad[k, j] + C[kb, j] > top - level):
            nxt = j  # due at the next sample already: no search
        else:
            nxt = int(self.cap[k].searchsorted(top - self.qd, side="right"))
            if kb >= 0:
                M = self._pair.get((k, kb))
                if M is None:
                    M = self._pair[(k, kb)] = np.maximum.accumulate(C[k] + pad[k] + C[kb])
                nxt = max(nxt, int(M.searchsorted(top - level, side="right")))
            nxt = max(nxt, j)
        if nxt < self.n:
            self.at[k] = nxt
            heapq.heappush(self.heap, (nxt, k))

    def next(self):
        """The next sample with tracks due and those tracks (None, [] when done)."""
        heap = self.heap
        while heap:
            i = heap[0][0]
            due = []
            while heap and heap[0][0] == i:
                _, k = heapq.heappop(heap)
                if self.at[k] == i:
                    due.append(k)
            if due:
                return i, due
        return None, []


def _read_sample(reader: _Reader, i: int, due: list, qd: float, level: list,
                 pad_i: np.ndarray) -> None:
    """Steps 1 and 2 of the module docstring at sample ``i`` over the tracks ``due`` there
    (every other track is bounded above what the sample reads)."""
    C, top, cur, cls_t = reader.C, reader.top, reader.cur, reader.cls_t
    due.sort(key=lambda k: top[k] - C[k, i])
    first = np.nextafter(qd, np.inf)
    for k in due:
        below = min(first, cur[cls_t[k]])
        if top[k] - C[k, i] < below:
            reader.drain(k, i, below, shrink=True)
    for k in due:
        theta = level[cls_t[k]] + pad_i[k]
        if top[k] - C[k, i] < theta:
            reader.drain(k, i, float(theta))


def _lower(tracks_n: int, n: int, hist: list, C: np.ndarray) -> np.ndarray:
    """(T, N) each track's lower bound at each sample from the history of its top key."""
    lower = np.empty((tracks_n, n))
    by_track: list[list] = [[] for _ in range(tracks_n)]
    for i, k, top in hist:
        by_track[k].append((i, top))
    for k, h in enumerate(by_track):
        at = np.array([i for i, _ in h], int)
        val = np.array([v for _, v in h])
        lower[k] = val[np.searchsorted(at, np.arange(n), side="right") - 1] - C[k]
    return lower


def _class_minima(rec_i, rec_p, rec_d, cls: np.ndarray, n: int, qd: float):
    """(3, N) smallest reading per class and sample within ``qd`` and its pair (the first
    read among equals), from the readings in read order."""
    best, best_pair = np.full((3, n), np.inf), np.full((3, n), -1)
    i, p, d = np.asarray(rec_i, int), np.asarray(rec_p, int), np.asarray(rec_d, float)
    keep = d <= qd
    i, p, d = i[keep], p[keep], d[keep]
    c = cls[p]
    order = np.lexsort((np.arange(len(d)), d, i, c))
    i, p, d, c = i[order], p[order], d[order], c[order]
    first = np.ones(len(d), bool)
    first[1:] = (i[1:] != i[:-1]) | (c[1:] != c[:-1])
    best[c[first], i[first]], best_pair[c[first], i[first]] = d[first], p[first]
    return best, best_pair


#: samples per part of the sweep (module docstring); a speed setting, not a tolerance
_PART_SAMPLES = 2000


def part_bounds(n: int) -> list[tuple[int, int]]:
    """The parts of ``n`` samples: (first, last) sample of each, neighbours sharing one; a
    function of ``n`` alone, so the same on any machine and any number of processes."""
    k = max(1, int(round((n - 1) / _PART_SAMPLES)))
    b = np.linspace(0, max(n - 1, 0), k + 1).round().astype(int)
    return [(int(b[j]), int(b[j + 1])) for j in range(k)]


def sweep(scene: PairScene, traj, t: np.ndarray, q: np.ndarray, tol, progress=None,
          workers: int | None = None) -> Sweep:
    """The tracked reading of every sample (module docstring), part by part.

    Args:
        scene: the cell's pairs. traj: the joint trajectory; t (N,) [s], q (N, nq) [rad]: the
        samples on it. tol: the tolerances. progress: optional callback (done, total).
        workers: processes (:func:`drakedeburr.pool.worker_count`; None: the cores);
        the parts are the same whatever the count, and so is the result.
    """
    from drakedeburr.cell.fingerprint import geometry_digest
    from drakedeburr.pool import map_tasks

    scene.use_tolerances(tol)  # readings held to rigorous bounds (cell.narrowphase)
    parts, n = part_bounds(len(t)), len(t)
    recipe = scene.cell.recipe
    read = [0]

    def finished(k: int, part: _Part) -> _Part:
        read[0] += parts[k][1] - parts[k][0] + (k == 0)
        if progress is not None:
            progress(read[0], n)
        return part

    def here(k: int) -> _Part:
        a, b = parts[k]
        return finished(k, _sweep_part(scene, traj, t[a:b + 1], q[a:b + 1], tol))

    def remote(k: int) -> tuple:
        a, b = parts[k]
        return _part_in_worker, (dict(recipe), geometry_digest(scene.cell), scene.digest(),
                                 traj, t[a:b + 1], q[a:b + 1], tol)

    def done(k: int, value) -> _Part:
        part, tally = value
        scene.tally.merge(tally)
        return finished(k, part)

    use_pool = recipe is not None and len(parts) > 1
    results = map_tasks(len(parts), here, remote if use_pool else None, workers, done,
                        name=lambda k: f"distance sweep, samples {parts[k][0]}-{parts[k][1]}")
    return _merge(scene, t, q, parts, results)


def warm_workers(cell, n_samples: int, workers: int | None = None) -> None:
    """Have the pool's idle workers build ``cell``'s pair scene now (from its recorded
    ``Cell.recipe``), so that they are ready when the sweep of ``n_samples`` hands them parts;
    nothing when that sweep is one part or the cell cannot be built again."""
    recipe = cell.recipe
    if recipe is not None and len(part_bounds(n_samples)) > 1:
        from drakedeburr.cell.fingerprint import geometry_digest
        from drakedeburr.pool import warm_pool

        warm_pool(warm_scene, (dict(recipe), geometry_digest(cell)), workers)


def warm_workers_for_plan(plan, workers: int | None = None) -> None:
    """Have the pool's idle workers start building the cell ``plan`` was made in and its pair
    scene now, before this process has built that cell (a worker's start-up, ~2.5 s, then
    overlaps this process's cell, sampling and program reading instead of the sweep). Each
    part a worker reads later is still checked against this process's cell
    (:func:`_part_in_worker`)."""
    from drakedeburr.cell.recipe import plan_cell_args
    from drakedeburr.pool import warm_pool

    warm_pool(warm_scene, (plan_cell_args(plan), None), workers)


def _part_in_worker(recipe: dict, fingerprint: str, digest: str, traj, t: np.ndarray,
                    q: np.ndarray, tol):
    """A pool worker's task: one part read in the same cell -> (_Part, its reading tally)."""
    scene = checked_scene(recipe, fingerprint, digest, tol)
    return _sweep_part(scene, traj, t, q, tol), scene.tally


def _merge(scene: PairScene, t: np.ndarray, q: np.ndarray, parts: list, res: list) -> Sweep:
    """One :class:`Sweep` of the parts. At a sample two parts share, the class minimum (exact
    in both) is the earlier part's unless the later read smaller; the bounds (``lower``,
    ``level``) are the smaller of the two, each valid."""
    n, T = len(t), len(scene.tracks)
    best, best_pair = np.full((3, n), np.inf), np.full((3, n), -1)
    level, lower = np.full((3, n), np.inf), np.full((T, n), np.inf)
    delta, e = np.zeros((T, max(n - 1, 0))), np.zeros((T, max(n - 1, 0)))
    for (a, b), r in zip(parts, res, strict=True):
        s = slice(a, b + 1)
        smaller = r.best < best[:, s]
        best[:, s] = np.where(smaller, r.best, best[:, s])
        best_pair[:, s] = np.where(smaller, r.best_pair, best_pair[:, s])
        level[:, s] = np.minimum(level[:, s], r.level)
        lower[:, s] = np.minimum(lower[:, s], r.lower)
        delta[:, a:b], e[:, a:b] = r.delta, r.e
    return Sweep(t=t, q=q, X=scene.tree.body_poses(q), best=best, best_pair=best_pair,
                 level=level, lower=lower, delta=delta, e=e,
                 rec_sample=np.concatenate([r.rec_sample + a for (a, _), r in zip(
                     parts, res, strict=True)]),
                 rec_pair=np.concatenate([r.rec_pair for r in res]),
                 rec_value=np.concatenate([r.rec_value for r in res]),
                 posed=sum(r.posed for r in res), refreshes=sum(r.refreshes for r in res))


def _sweep_part(scene: PairScene, traj, t: np.ndarray, q: np.ndarray, tol) -> _Part:
    """The tracked reading of the samples of one part (module docstring; the scene's
    tolerances already set)."""
    tracks, n, T = scene.tracks, len(t), len(scene.tracks)
    X = scene.tree.body_poses(q)
    delta, e = track_motion(scene, traj, t, X)
    C = np.zeros((T, n))
    C[:, 1:] = np.cumsum(delta, axis=1)
    limits = class_limits(tol)
    qd = float(tol.query_distance)
    pad = np.zeros((T, n))
    pad[:, 1:] = delta + 2.0 * e
    pad[:, :-1] = np.maximum(pad[:, :-1], pad[:, 1:])
    pad[~np.isin(tracks.cls, list(limits))] = 0.0  # the burr class is not certified
    cls_t = tracks.cls.tolist()
    when = _Agenda(C, pad, cls_t, qd, n)
    pad_T = pad.T.copy()
    reader = _Reader(scene, q, X, C, qd)
    reader.cls_t = cls_t
    hist: list[tuple[int, int, float]] = []
    last = [(np.inf, 0, -1)] * 3  # per class the last minimum read: (distance, sample, track)
    low = dict.fromkeys(limits, np.inf)  # per certified class the smallest distance read
    levels: list[tuple[int, int, float]] = []
    for c, lim in limits.items():
        when.level[c] = resolution_target(qd, lim, tol)
        levels.append((0, c, when.level[c]))
    while True:
        i, due = when.next()
        if i is None:
            break
        reader.start(i, due)
        for k in due:
            if reader.far[k] - C[k, i] < qd + pad_T[i, k]:
                reader.refresh(k, i, float(qd + pad_T[i, k]) + _NEAR_MARGIN)
        _read_sample(reader, i, due, qd, when.level, pad_T[i])
        for c in range(3):
            if reader.cur_k[c] >= 0:
                last[c] = (reader.cur[c], i, reader.cur_k[c])
                if c in low and reader.cur[c] < low[c]:
                    low[c] = reader.cur[c]
                    when.level[c] = resolution_target(min(low[c], qd), limits[c], tol)
                    levels.append((i + 1, c, when.level[c]))
        for k in due:
            top = float(reader.top[k])
            hist.append((i, k, top))
            when.schedule(k, i, top, last[reader.cls_t[k]])
    rec = np.array(reader.rec, float).reshape(-1, 3)
    rec_i, rec_p = rec[:, 0].astype(int), rec[:, 1].astype(int)
    best, best_pair = _class_minima(rec_i, rec_p, rec[:, 2], scene.cls, n, qd)
    level = np.full((3, n), -np.inf)
    for i, c, v in levels:
        level[c, i:] = v
    return _Part(best=best, best_pair=best_pair, level=level, lower=_lower(T, n, hist, C),
                 delta=delta, e=e, rec_sample=rec_i, rec_pair=rec_p, rec_value=rec[:, 2],
                 posed=reader.posed, refreshes=reader.refreshes)
