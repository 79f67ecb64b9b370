"""Seeds of the window IK (:mod:`drakedeburr.plan.ik`): the analytic OPW IK swept over the
spin for a window's first target, the previous solution re-posed on the next target, the axis
in the cone with the most clearance, and the cone probe that tells a target no pose in the cone
can reach from one the solver missed."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.cell.narrowphase import READING_GAP
from drakedeburr.frames.vectors import angle_between, perpendicular_basis
from drakedeburr.plan.kinematics import (
    JOINT_WEIGHTS,
    WRIST_MARGIN,
    CellKinematics,
    ClearanceChecker,
)
from drakedeburr.plan.targets import X_HT_from_axis, cross

if TYPE_CHECKING:
    from drakedeburr.plan.ik import IkOptions

__all__ = ["IkTarget", "ProbeSettings", "ConeProbe", "seed_by_spin", "cone_clearance_probe",
           "analytic_seed", "analytic_accept", "clearance_seed", "unreachable", "recheck",
           "reach_shortfall"]


@dataclass(frozen=True, eq=False)
class IkTarget:
    """One CL target of the window IK, in H: the constrained point ``p_HT`` (on the burr axis,
    ``lift`` from T toward the tip, see :func:`drakedeburr.plan.ik.solve_window_ik`) [m], the
    cone axis, the preferred axis (both (3,) tip -> spindle) and the feed tangent (3,)."""

    p_HT: np.ndarray
    cone_retract_H: np.ndarray
    pref_retract_H: np.ndarray
    t_H: np.ndarray


@dataclass(frozen=True)
class ProbeSettings:
    """How :func:`cone_clearance_probe` searches a cone.

    Attributes:
        bound: the clearance a pose must have [m] (the IK's ``min_distance_floor``).
        lift: the constrained point's distance from T toward the tip [m].
        min_wrist: smallest |J5| of a pose [rad].
        rings: rings of axes, as shares of the cone's half-angle (0: the cone axis alone).
        ring_axes: axes on each ring; spins: spins about each axis.
        per_axis: poses of an axis queried at most.
    """

    bound: float
    lift: float = 0.0
    min_wrist: float = WRIST_MARGIN
    rings: tuple[float, ...] = (0.0, 0.33, 0.66, 0.98)
    ring_axes: int = 16
    spins: int = 24
    per_axis: int = 24


@dataclass(frozen=True, eq=False)
class ConeProbe:
    """What :func:`cone_clearance_probe` found at a target.

    Attributes:
        feasible: a pose with the bound's clearance was found.
        best_clearance: the largest clearance read [m] (-inf: no pose read).
        pair: the closest pair (geometry names) at the best pose (``("", "")``: none).
        q: (6,) the best pose found [rad], or None.
        queries: distance queries and contact tests made.
        axis_bound: the largest reading of the spin-invariant pairs over the axes, an upper
            bound on every pose of its axis [m] (-inf where no axis had a pose).
    """

    feasible: bool
    best_clearance: float
    pair: tuple[str, str]
    q: np.ndarray | None
    queries: int
    axis_bound: float


def seed_by_spin(kin: CellKinematics, checker: ClearanceChecker | None, p_HT: np.ndarray,
                 retract_H: np.ndarray, t_H: np.ndarray, q_ref: np.ndarray,
                 options: IkOptions, count: int = 1) -> np.ndarray | None:
    """Best joint vector for one target over a sweep of spins and all IK branches.

    Score: same branch as ``q_ref`` first, then weighted distance to ``q_ref``; candidates with
    |J5| < ``min_wrist``, outside the limits or in collision are dropped.

    Args:
        p_HT: (3,) tool point [m]; retract_H: (3,) preferred axis; t_H: (3,) feed tangent.
        q_ref: (6,) reference joints (e.g. home or the previous window's end) [rad].

        count: > 1 returns a list of up to ``count`` distinct seeds (J4/J6 differing by more
            than 0.5 rad), best first, for window-level retries.

    Returns:
        (6,) joints [rad], or None when no spin/branch reaches (a list when count > 1).
    """
    spins = np.linspace(-np.pi, np.pi, options.spin_samples, endpoint=False)
    k = len(spins)
    X_HT = X_HT_from_axis(np.repeat(p_HT[None], k, 0), np.repeat(retract_H[None], k, 0),
                          np.repeat(t_H[None], len(spins), 0), spins)
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X_HT))
    b_ref = kin.branch_of(q_ref)
    cands, scores = [], []
    w = np.array([2.0, 2.0, 1.5, 0.5, 0.5, 0.5])
    centre = np.concatenate([q_ref[:3], 0.5 * (kin.q_lower + kin.q_upper)[3:]])
    for k in range(q_all.shape[0]):
        for b in range(8):
            q = q_all[k, b]
            if np.any(np.isnan(q)):
                continue
            # turns of J4/J6 nearest the middle of their range (a window winds the wrist by up
            # to ~100 deg: start it centred), the arm nearest q_ref
            q = centre + np.mod(q - centre + np.pi, 2 * np.pi) - np.pi
            if not kin.within_limits(q) or abs(q[4]) < options.min_wrist:
                continue
            score = (float(w[:3] @ np.abs(q - q_ref)[:3]) + float(w[3:] @ np.abs(q - centre)[3:])
                     + (0.0 if np.all(branches[b] == b_ref) else 100.0))
            cands.append(q)
            scores.append(score)
    if not cands:
        return None if count == 1 else []
    ranked = np.argsort(scores)
    if checker is None and count == 1:
        return cands[ranked[0]]
    # the IK's distance constraint can tilt the axis inside the cone: a seed needs clearance
    # from the arm and cell, not the full bound at the burr (that depends on the axis only)
    picked: list[np.ndarray] = []
    best, best_d = None, -np.inf
    for j in ranked[:max(12, 6 * count)]:
        if any(np.max(np.abs(cands[j][[3, 5]] - p[[3, 5]])) < 0.5 for p in picked):
            continue
        d = np.inf if checker is None else checker.distance(cands[j], options.min_distance)
        if d >= options.min_distance:
            picked.append(cands[j])
            if len(picked) >= count:
                break
        elif d > best_d + 1e-4:
            best, best_d = cands[j], d
    if count > 1:
        return picked or ([best] if best is not None and best_d > 0.0 else [])
    if picked:
        return picked[0]
    return best if best_d > 0.0 else None


def analytic_seed(kin: CellKinematics, X_prev: np.ndarray, p_HT: np.ndarray,
                   retract_H: np.ndarray, q_prev: np.ndarray,
                   weights: tuple[float, ...] = JOINT_WEIGHTS,
                   spin_span: float = 0.5, spin_samples: int = 21) -> np.ndarray:
    """Seed that already meets position and preferred axis exactly, with the spin about the
    axis that minimises the program's own joint cost ``sum w_j (q_j - q_prev_j)^2``: spins
    within ``spin_span`` of the previous pose's X_T projected normal to the new axis, solved
    by the analytic IK on the previous configuration's branch. Falls back to ``q_prev``."""
    z = -retract_H / np.linalg.norm(retract_H)
    x = X_prev[:3, 0] - (X_prev[:3, 0] @ z) * z
    if np.linalg.norm(x) < 1e-6:
        return q_prev
    x /= np.linalg.norm(x)
    y = cross(z, x)
    psi = np.linspace(-spin_span, spin_span, spin_samples)
    X = np.repeat(np.eye(4)[None], spin_samples, axis=0)
    X[:, :3, 0] = np.cos(psi)[:, None] * x + np.sin(psi)[:, None] * y
    X[:, :3, 1] = -np.sin(psi)[:, None] * x + np.cos(psi)[:, None] * y
    X[:, :3, 2] = z
    X[:, :3, 3] = p_HT
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    match = np.flatnonzero(np.all(branches == kin.branch_of(q_prev)[None], axis=1))
    if match.size == 0:
        return q_prev
    cand = q_all[:, match[0]]
    cand = q_prev + np.mod(cand - q_prev + np.pi, 2 * np.pi) - np.pi  # no 2 pi turns
    good = ~np.any(np.isnan(cand), axis=1) & kin.within_limits(cand)
    good &= np.max(np.abs(cand - q_prev), axis=1) <= 0.6
    if not good.any():
        return q_prev
    cost = np.where(good, np.sum(np.asarray(weights) * (cand - q_prev) ** 2, axis=1), np.inf)
    return cand[int(np.argmin(cost))]


def cone_ring(c: np.ndarray, angle: float, count: int) -> list[np.ndarray]:
    """``count`` unit axes at ``angle`` from the unit axis ``c``, evenly around it."""
    e1, e2, _ = perpendicular_basis(c).T
    return [np.cos(angle) * c + np.sin(angle) * (np.cos(f) * e1 + np.sin(f) * e2)
            for f in np.linspace(0.0, 2 * np.pi, count, endpoint=False)]


#: axes on the ring :func:`clearance_seed` tries around the cone axis
SEED_RING = 12


def clearance_seed(kin: CellKinematics, checker: ClearanceChecker, X_prev: np.ndarray,
                   target: IkTarget, half_angle: float, q_prev: np.ndarray, reach: float,
                   lift: float = 0.0) -> np.ndarray | None:
    """Analytic seed at the axis of most clearance among the preferred axis, the cone axis and
    :data:`SEED_RING` axes at 0.8 of the cone half-angle around it (None if none is
    reachable). ``target.p_HT`` is the constrained point (``lift`` below T on the axis, see
    solve_window_ik); ``reach``: how far the distance query looks [m]."""
    c = target.cone_retract_H / np.linalg.norm(target.cone_retract_H)
    axes = [target.pref_retract_H, c] + cone_ring(c, 0.8 * half_angle, SEED_RING)
    best, best_d = None, -np.inf
    for a in axes:
        q = analytic_seed(kin, X_prev, target.p_HT + lift * a, a, q_prev)
        if q is q_prev:
            continue
        d = checker.distance(q, reach)
        if d > best_d:
            best, best_d = q, d
    return best


def analytic_accept(kin: CellKinematics, checker: ClearanceChecker, q: np.ndarray,
                    anchor: np.ndarray, target: IkTarget, half: float, options: IkOptions,
                    lift: float):
    """The analytic warm start as the target's solution when it meets every constraint of the
    Drake program: position and cone (re-checked by FK), joint limits, the trust region about
    the previous target, the wrist branch and margin, and the clearance bound (the distance
    read as far as the program's constraint looks: ``min_distance + influence_distance``).
    Returns ``(X_HT, clearance)`` or None (then the Drake program runs)."""
    if q is anchor or np.max(np.abs(q - anchor)) > options.trust_region:
        return None
    if abs(q[4]) < options.min_wrist or np.sign(q[4]) != np.sign(anchor[4]):
        return None
    good, _, _, X = recheck(kin, q, target.p_HT, target.cone_retract_H, half, options, lift)
    if not good:
        return None
    dist = checker.distance(q, options.min_distance + options.influence_distance)
    if dist < options.min_distance:
        return None
    return X, dist


def _probe_candidates(kin: CellKinematics, p_HQ: np.ndarray, axes: list, t_H: np.ndarray,
                      q_ref: np.ndarray, settings: ProbeSettings) -> list[np.ndarray]:
    """Per axis: the analytic IK's admissible joints over ``settings.spins`` spins and every
    branch (the reference configuration's branch first; J4/J6 turned into the limits where a
    turn fits, |J5| >= ``min_wrist``), thinned to about ``per_axis`` (one batched IK for all
    axes). ``p_HQ``: the constrained point (``settings.lift`` below T on the axis)."""
    spins, lift = settings.spins, settings.lift
    psi = np.linspace(-np.pi, np.pi, spins, endpoint=False)
    A = np.repeat(np.asarray(axes, float), spins, axis=0)
    X = X_HT_from_axis(p_HQ[None] + lift * A, A, np.repeat(t_H[None], len(A), 0),
                       np.tile(psi, len(axes)))
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    b_ref = kin.branch_of(q_ref)
    order = np.argsort([0 if np.all(b == b_ref) else 1 for b in branches], kind="stable")
    out = []
    for k in range(len(axes)):
        q = q_all[k * spins:(k + 1) * spins][:, order].transpose(1, 0, 2).reshape(-1, 6)
        q = q[~np.any(np.isnan(q), axis=1)]
        for j in (3, 5):
            q[q[:, j] < kin.q_lower[j], j] += 2 * np.pi
            q[q[:, j] > kin.q_upper[j], j] -= 2 * np.pi
        q = q[kin.within_limits(q) & (np.abs(q[:, 4]) >= settings.min_wrist)]
        out.append(q[:: max(1, len(q) // settings.per_axis)])
    return out


#: a probe's best pose at most this short of the bound is a near miss, not unreachable [m]
NEAR_MISS = 0.2e-3


def cone_clearance_probe(kin: CellKinematics, checker: ClearanceChecker, target: IkTarget,
                         half_angle: float, q_ref: np.ndarray,
                         settings: ProbeSettings) -> ConeProbe:
    """Is there any admissible pose at a target? A sampled search of the whole cone.

    Axes: the preferred and the cone axis, then ``ring_axes`` axes on each ring of ``rings`` x
    half-angle (``settings``); for each, ``spins`` spins about it and every analytic IK branch
    (J4/J6 turned into the limits where a turn fits, |J5| >= ``min_wrist``), up to ``per_axis``
    of them queried for signed distance. Stops at the first pose with the ``bound``'s
    clearance. The axes are searched best first: one pose of each is queried (in the order
    above), then the remaining poses axis by axis in the order of that first clearance (the
    burr shank's clearance, which the spin does not change, mostly decides: a clear pose is
    usually found on the first axes searched, where the axes in their listed order found it
    only near the rim). A pose in contact (85 % of the poses of a blocked target on a deep-dish
    hub) is not read by the signed distances (2-3 ms): the first pose of each axis is ranked by
    its deepest penetration (:meth:`ClearanceChecker.ranked_distance`), later poses are
    rejected by the contact test alone (0.2 ms). Every pose with positive clearance is read in
    full, so the verdict and, where a clear pose exists, the best pose are the same. An axis
    whose first pose puts a spin-invariant pair (the spindle body, collet or shank against the
    hub: :meth:`ClearanceChecker.spin_invariant`) more than ``NEAR_MISS`` short of the bound is
    not searched further: that pair is as short at each of its poses (the tool and hub keep
    their relative pose up to a turn about the burr axis), so no pose of it meets the bound or
    decides between a near miss and an unreachable target. The verdict, and the best pose
    whenever it is a near miss or clear, are those of the full search; an unreachable target's
    best clearance is the best of the axes searched (on a blocked deep-dish target, ~95 % of
    the poses are on such axes).

    Used when the IK fails at a target, to tell an unreachable target (no axis in the cone
    clears the cell: the tool or the theta box has to change) from a solver failure (a pose
    exists; the returned one seeds the retry). The search is sampled, so only a best pose more
    than 0.2 mm short of the bound ends the target's retries and labels it unreachable; nearer
    misses go on to the distance-constrained retries, which can still find the bound.

    The result depends on ``q_ref`` only through its analytic branch (searched first), so it
    is kept per checker under the target, that branch, the cell's frames and the search's
    settings: the same target probed again (another start seed, the other spin rule, the full
    pass after a fail-fast one) is answered from the memo with the identical result.

    A near miss (the best within ``NEAR_MISS`` of the bound) is searched on between the
    sampled axes (:func:`_refine_near_miss`).

    Args:
        target: the target (``target.p_HT`` the constrained point, ``settings.lift`` below T).
        half_angle: the cone's half-angle [rad]; q_ref: (6,) the configuration whose branch is
            searched first [rad].
        settings: the bound, lift, wrist margin and how finely the cone is sampled.

    Returns:
        :class:`ConeProbe` (a fresh copy of its ``q``).
    """
    out = checker.memo_probe(_probe_key(kin, q_ref, target, half_angle, settings),
                             lambda: _probe(kin, checker, q_ref, target, half_angle, settings))
    return replace(out, q=None if out.q is None else out.q.copy())


def _probe_key(kin: CellKinematics, q_ref: np.ndarray, target: IkTarget, half_angle: float,
               settings: ProbeSettings) -> bytes:
    """What :func:`cone_clearance_probe`'s result depends on, as bytes."""
    arrays = (kin.branch_of(q_ref), kin.X_FT, kin.X_WH, kin.X_FH, kin.X_WT, kin.X_WB,
              kin.q_lower, kin.q_upper, target.p_HT, target.cone_retract_H, half_angle,
              target.pref_retract_H, target.t_H)
    return b"".join(np.asarray(a, float).tobytes() for a in arrays) + repr(settings).encode()


class _Search:
    """One cone probe's search: what it reads with, the best pose read so far and the count of
    queries (the state :func:`_probe` and :func:`_refine_near_miss` share)."""

    def __init__(self, kin: CellKinematics, checker: ClearanceChecker, q_ref: np.ndarray,
                 target: IkTarget, settings: ProbeSettings) -> None:
        self.kin, self.checker, self.q_ref = kin, checker, q_ref
        self.target, self.settings = target, settings
        self.feasible, self.best_clearance, self.q = False, -np.inf, None
        self.queries, self.axis_bound = 0, -np.inf

    def candidates(self, axes: list) -> list[np.ndarray]:
        return _probe_candidates(self.kin, self.target.p_HT, axes, self.target.t_H, self.q_ref,
                                 self.settings)

    def query(self, qq: np.ndarray) -> tuple[float, float]:
        """One pose read in full: (its clearance, the bound of its axis's spin-invariant
        pairs), the best kept."""
        bound = self.settings.bound
        d, upper = self.checker.axis_reading(qq, bound + 1e-3)
        self.queries += 1
        if d > self.best_clearance:
            self.best_clearance, self.q = float(d), qq.copy()
        self.feasible = self.feasible or d >= bound
        return d, upper

    def result(self) -> ConeProbe:
        pair = ("", "")
        if self.q is not None:
            pair = self.checker.min_distance(self.q, self.settings.bound + 1e-3)[1]
        return ConeProbe(feasible=bool(self.feasible), best_clearance=self.best_clearance,
                         pair=pair, q=self.q, queries=self.queries, axis_bound=self.axis_bound)


def _probe(kin: CellKinematics, checker: ClearanceChecker, q_ref: np.ndarray, target: IkTarget,
           half_angle: float, settings: ProbeSettings) -> ConeProbe:
    """:func:`cone_clearance_probe`, searched."""
    bound = settings.bound
    c = target.cone_retract_H / np.linalg.norm(target.cone_retract_H)
    axes = [target.pref_retract_H / np.linalg.norm(target.pref_retract_H), c]
    for ring in settings.rings:
        if ring > 0:
            axes += cone_ring(c, ring * half_angle, settings.ring_axes)
    search = _Search(kin, checker, q_ref, target, settings)
    cands = search.candidates(axes)
    first, dead = np.full(len(axes), -np.inf), np.zeros(len(axes), bool)
    uppers = np.full(len(axes), -np.inf)
    for k, q in enumerate(cands):
        if len(q):
            first[k], uppers[k] = search.query(q[0])
            # a spin-invariant pair (ClearanceChecker.spin_invariant) short of the near-miss
            # line at the first pose is as short at every pose of the axis: none can meet the
            # bound nor make the best a near miss, so the axis is not searched further
            dead[k] = uppers[k] < bound - NEAR_MISS - READING_GAP
            if search.feasible:
                break
    if not search.feasible:
        for k in np.argsort(-first, kind="stable"):
            if dead[k]:
                continue
            for qq in cands[k][1:]:
                if checker.collides(qq):  # fails the bound; most poses of a blocked target
                    search.queries += 1
                    continue
                if search.query(qq)[0] >= bound:
                    break
            if search.feasible:
                break
    search.axis_bound = float(uppers.max())
    if not search.feasible and search.best_clearance >= bound - NEAR_MISS:
        _refine_near_miss(search, c, half_angle, [axes[k] for k in np.argsort(
            -uppers, kind="stable")[:3] if np.isfinite(uppers[k])])
    return search.result()


#: a near miss's compass search over the axes: first step and the step it stops below, as
#: shares of the cone's radius in the tangent plane; at most this many axes per start
_REFINE_STEPS = (0.25, 0.01)
_REFINE_EVALS = 48


def _refine_near_miss(search: _Search, c: np.ndarray, half_angle: float, starts: list) -> None:
    """A near miss searched on between the sampled axes: from each of ``starts`` (the sampled
    axes whose spin-invariant pairs stand farthest off), a compass search in the tangent plane
    of the cone (unit axis ``c``), kept inside the cone, for the axis whose spin-invariant
    pairs stand farthest off. Those pairs' distance depends on the axis alone (every spin,
    every branch), so it bounds every pose of the axis: ``search.axis_bound`` becomes the
    largest found. Where it reaches the bound, that axis's poses are read in full
    (``search.query``: a clear one makes the probe feasible). Hand-written: a two-parameter
    search whose every step is one analytic IK and one distance query of the cell; scipy's
    optimisers would need a smooth objective, which a distance over convex pieces is not."""
    checker, bound = search.checker, search.settings.bound
    e1, e2, _ = perpendicular_basis(c).T
    radius = np.tan(half_angle)

    def axis(xy):
        a = c + xy[0] * e1 + xy[1] * e2
        return a / np.linalg.norm(a)

    def poses(xy):
        return search.candidates([axis(xy)])[0]

    def upper(xy) -> float:
        q = poses(xy)
        if not len(q):
            return -np.inf
        search.queries += 1
        return checker.axis_reading(q[0], bound + 1e-3)[1]

    for a in starts:
        xy = np.array([a @ e1, a @ e2]) / max(float(a @ c), 1e-9)
        value, step, evals = upper(xy), _REFINE_STEPS[0] * radius, 1
        while step > _REFINE_STEPS[1] * radius and value < bound and evals < _REFINE_EVALS:
            for d in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                cand = xy + d
                n = np.linalg.norm(cand)
                cand = cand * (radius / n) if n > radius else cand
                v = upper(cand)
                evals += 1
                if v > value:
                    xy, value = cand, v
                    break
            else:
                step *= 0.5
        search.axis_bound = max(search.axis_bound, float(value))
        if value >= bound:
            for qq in poses(xy):
                if not checker.collides(qq) and search.query(qq)[0] >= bound:
                    return


def unreachable(probe: ConeProbe, options: IkOptions) -> bool:
    """The probe's best pose is more than ``NEAR_MISS`` short of the bound (the sampled search
    may miss a pose within that; the retries may still find it), or a near miss whose search
    between the axes kept the spin-invariant pairs under the bound on every axis it read."""
    return not probe.feasible and (
        probe.best_clearance < options.min_distance_floor - NEAR_MISS
        or probe.axis_bound < options.min_distance_floor)


def recheck(kin: CellKinematics, q: np.ndarray, p_HT: np.ndarray, cone_retract_H: np.ndarray,
             half_angle: float, options: IkOptions,
             lift: float = 0.0) -> tuple[bool, float, float, np.ndarray]:
    """Independent check of a solution with the analytic FK: (ok, position error, cone angle)."""
    X = kin.X_HT_from_q(q)
    err = float(np.linalg.norm(X[:3, 3] + lift * X[:3, 2] - p_HT))
    ang = float(angle_between(-X[:3, 2], cone_retract_H))
    ok = (err <= 10 * options.position_tolerance and ang <= half_angle + 1e-6
          and bool(kin.within_limits(q)))
    return ok, err, ang, X


def reach_shortfall(kin: CellKinematics, p_HT: np.ndarray, retract_H: np.ndarray,
                    t_H: np.ndarray, spins: int = 72) -> float:
    """How far [m] the wrist centre of the best spin lies outside the arm's reach for one
    target (<= 0: within reach): the OPW wrist centre C = p_F - c4 z_F, at the distance
    d = |(sqrt(x^2 + y^2 - b^2) - a1, z - c1)| from the shoulder, against the annulus
    |c2 - l3| <= d <= c2 + l3 (l3 = sqrt(a2^2 + c3^2), the forearm). For the report: an
    unreachable target says by how much."""
    o = kin.robot.opw
    s = np.linspace(-np.pi, np.pi, spins, endpoint=False)
    X_HT = X_HT_from_axis(np.repeat(p_HT[None], spins, 0), np.repeat(retract_H[None], spins, 0),
                          np.repeat(t_H[None], spins, 0), s)
    X_BF = np.linalg.inv(kin.X_WB) @ kin.X_WF_from_X_HT(X_HT)
    c = X_BF[:, :3, 3] - o.c4 * X_BF[:, :3, 2]
    n = np.sqrt(np.maximum(c[:, 0] ** 2 + c[:, 1] ** 2 - o.b ** 2, 0.0)) - o.a1
    d = np.hypot(n, c[:, 2] - o.c1)
    l3 = np.hypot(o.a2, o.c3)
    out = np.maximum(d - (o.c2 + l3), abs(o.c2 - l3) - d)
    return float(out.min())
