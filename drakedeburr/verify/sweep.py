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
2. for clearance and self, also every pair whose bound is below ``max(minimum, limit) +
   delta + 2 e`` of its track on the two adjacent intervals: every pair left unread is then
   certified above the minimum over both intervals (:mod:`drakedeburr.verify.certificate`).

A reading higher than the pair's last reading plus the displacement since is not possible for
the true distance: it is the narrow phase's overestimate (GJK converges from above; Drake's
cylinder/convex distances were seen up to ~1 mm high), and the key keeps the allowed value.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from drakedeburr.verify.motion_bounds import accel_bound, chord_bound, rate_bounds, relative_pose
from drakedeburr.verify.pair_scene import CLEARANCE, SELF, PairScene

__all__ = ["Sweep", "sweep", "track_motion", "class_limits"]

#: a refresh reads the pairs whose box bound is within the track's threshold + this [m]; a
#: speed setting (larger: fewer refreshes, more pairs read), not a tolerance
_NEAR_MARGIN = 0.02


def class_limits(tol) -> dict[int, float]:
    """The certified classes and their limits [m]: clearance >= min_clearance, self > 0."""
    return {CLEARANCE: float(tol.min_clearance), SELF: 0.0}


@dataclass(frozen=True, eq=False)
class Sweep:
    """What the tracked sweep read, for the certificate.

    Attributes:
        t: (N,) sample times [s]; q: (N, nq) joints [rad]; X: (N, n_bodies, 4, 4) body poses
            (numpy kinematic tree).
        best: (3, N) class minima within the query distance [m] (inf: none); best_pair: (3, N)
            their pairs (-1 none).
        lower: (T, N) lower bound of each track's smallest distance at each sample [m], exact
            where below what step 2 reads.
        delta, e: (T, N - 1) each track's displacement and path-deviation bounds per interval.
        rec_sample, rec_pair, rec_value: every reading (sample, pair, distance [m]).
        posed: samples the scene was posed at; refreshes: track refreshes.
    """

    t: np.ndarray
    q: np.ndarray
    X: np.ndarray
    best: np.ndarray
    best_pair: np.ndarray
    lower: np.ndarray
    delta: np.ndarray
    e: np.ndarray
    rec_sample: np.ndarray
    rec_pair: np.ndarray
    rec_value: np.ndarray
    posed: int
    refreshes: int


def track_motion(scene: PairScene, traj, t: np.ndarray, X: np.ndarray):
    """delta, e (T, N - 1) [m] of every track over every sample interval."""
    tracks, n = scene.tracks, len(t)
    h = np.diff(t)
    qd, qdd = rate_bounds(traj, t[:-1], h)
    delta, e = np.zeros((len(tracks), n - 1)), np.zeros((len(tracks), n - 1))
    rel = {}
    for k in range(len(tracks)):
        key = (int(tracks.ref[k]), int(tracks.link[k]))
        if key not in rel:
            rel[key] = relative_pose(X, *key)
        R, p = rel[key]
        delta[k] = chord_bound(R[:-1], p[:-1], R[1:], p[1:], tracks.c[k], tracks.rho[k])
        e[k] = 0.125 * h ** 2 * accel_bound(qd, qdd, tracks.seq[k], tracks.reach[k])
    return delta, e


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
        self.cur_p = [-1] * 3
        self.rec_i: list[int] = []
        self.rec_p: list[int] = []
        self.rec_d: list[float] = []

    def _visit(self, i: int) -> None:
        if self.at != i:
            self.scene.set_configuration(self.q[i])
            self.at, self.posed = i, self.posed + 1

    def _note(self, i: int, p: int, d: float, Ci: float) -> float:
        """Record a reading; update the sample's class minimum; -> the pair's new key."""
        self.stamp[p] = i
        self.rec_i.append(i)
        self.rec_p.append(p)
        self.rec_d.append(d)
        c = self.cls[p]
        if d <= self.qd and d < self.cur[c]:
            self.cur[c], self.cur_p[c] = d, p
        allowed = min(d, self.last_d[p] + Ci - self.last_C[p])
        self.last_d[p], self.last_C[p] = allowed, Ci
        return allowed + Ci

    def start(self, i: int) -> None:
        self.cur = [np.inf] * 3
        self.cur_p = [-1] * 3

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
        while heap and heap[0][0] - Ci < below:
            key, p = heapq.heappop(heap)
            if stamp[p] == i:
                stash.append((key, p))
                continue
            self._visit(i)
            d = self.scene.distance(p)
            stash.append((self._note(i, p, d, Ci), p))
            if shrink and d < below:
                below = d
        for item in stash:
            heapq.heappush(heap, item)
        self.top[k] = min(heap[0][0], self.far[k]) if heap else self.far[k]


def _read_sample(reader: _Reader, i: int, cand: np.ndarray, cls_t: list, qd: float,
                 limits: dict, pad_i: np.ndarray) -> None:
    """Steps 1 and 2 of the module docstring at sample ``i`` over the candidate tracks
    ``cand`` (ordered by bound)."""
    C, top, cur = reader.C, reader.top, reader.cur
    first = np.nextafter(qd, np.inf)
    for k in cand.tolist():
        c = cls_t[k]
        below = min(first, cur[c])
        if top[k] - C[k, i] < below:
            reader.drain(k, i, below, shrink=True)
    for k in cand.tolist():
        c = cls_t[k]
        if c in limits:
            theta = max(min(cur[c], qd), limits[c]) + pad_i[k]
            if top[k] - C[k, i] < theta:
                reader.drain(k, i, float(theta))


def sweep(scene: PairScene, traj, t: np.ndarray, q: np.ndarray, tol, progress=None) -> Sweep:
    """The tracked reading of every sample (module docstring).

    Args:
        scene: the cell's pairs. traj: the joint trajectory; t (N,) [s], q (N, nq) [rad]: the
        samples on it. tol: the tolerances. progress: optional callback (done, total).
    """
    tracks, n = scene.tracks, len(t)
    X = scene.tree.body_poses(q)
    delta, e = track_motion(scene, traj, t, X)
    C = np.zeros((len(tracks), n))
    C[:, 1:] = np.cumsum(delta, axis=1)
    pad_int = delta + 2.0 * e
    pad = np.zeros((len(tracks), n))
    pad[:, 1:] = pad_int
    pad[:, :-1] = np.maximum(pad[:, :-1], pad_int)
    limits = class_limits(tol)
    qd = float(tol.query_distance)
    certified = np.isin(tracks.cls, list(limits))
    lim_t = np.array([limits.get(int(c), qd) for c in tracks.cls])
    hi = (np.maximum(qd, lim_t)[:, None] + np.where(certified[:, None], pad, 0.0)).T.copy()
    C_T, pad_T = C.T.copy(), pad.T.copy()
    reader = _Reader(scene, q, X, C, qd)
    best, best_pair = np.full((3, n), np.inf), np.full((3, n), -1)
    lower = np.empty((n, len(tracks)))
    cls_t = tracks.cls.tolist()
    every = max(1, n // 50)
    for i in range(n):
        reader.start(i)
        for k in np.flatnonzero(reader.far - C_T[i] < hi[i]).tolist():
            reader.refresh(k, i, float(hi[i, k]) + _NEAR_MARGIN)
        lb = reader.top - C_T[i]
        cand = np.flatnonzero(lb < hi[i])
        if len(cand):
            _read_sample(reader, i, cand[np.argsort(lb[cand], kind="stable")], cls_t, qd,
                         limits, pad_T[i])
            lb = reader.top - C_T[i]
        best[:, i], best_pair[:, i] = reader.cur, reader.cur_p
        lower[i] = lb
        if progress is not None and (i % every == 0 or i == n - 1):
            progress(i + 1, n)
    return Sweep(t=t, q=q, X=X, best=best, best_pair=best_pair, lower=lower.T.copy(),
                 delta=delta, e=e, rec_sample=np.array(reader.rec_i, int),
                 rec_pair=np.array(reader.rec_p, int), rec_value=np.array(reader.rec_d),
                 posed=reader.posed, refreshes=reader.refreshes)
