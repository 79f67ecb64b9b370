"""Where the hub sits, and which arm configuration cuts each window, chosen for the hub at hand.

A user's hub is not one the cells were laid out for. Before planning, the hub's pose on its
mount (``hub_mount``: the chuck of the tool-in-hand cell, the gripper of the workpiece-in-hand
cell) is chosen by a search:

* the seat: on a chuck (a ``fixture::chuck_top`` frame below the mount) the hub's rearmost
  point rests on the chuck top, whatever its depth (a deeper rim lifts the face);
* candidates: turns about the hub axis over one period of its windows (the windows repeat
  every 2 pi / spokes) and, on a chuck, offsets toward and away from the arm;
* each candidate is scored by the analytic IK of the arm (every branch, a ring of spins about
  the preferred tool axis) at CL targets spread over every window: a window counts when all its
  sampled targets are reached on one branch inside the joint limits with the wrist margin;
  then by the least joint-limit margin. The best few are built as cells and the clearance of
  their IK solutions checked (the signed distance of the cell, burr contact filtered).

The same analysis gives each window the branches it can be cut on; the branch sequence over the
hub is chosen by dynamic programming (no flip within a window, least joint travel between
windows) and handed to the planner as a reference configuration per window.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np

from drakedeburr.plan.kinematics import (
    JOINT_WEIGHTS,
    CellKinematics,
    ClearanceChecker,
    cell_kinematics,
)
from drakedeburr.plan.targets import X_HT_from_axis, contact_geometry, tool_point_H

__all__ = ["Placement", "PlacementSearch", "place_hub", "seat_offset"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Placement:
    """The chosen hub pose on its mount and the per-window branch references.

    Attributes:
        hub_pose: (4, 4) X_MH, the hub frame H in the ``hub_mount`` frame [m].
        turn: the turn about the hub axis [rad]; offset: the offset on the mount [m] (x).
        seat: the seat height correction [m] (z).
        windows_reached: windows whose sampled targets one branch reaches.
        margin: least joint-limit margin over the chosen branches [rad].
        clearance: least clearance of the sampled targets' solutions [m].
        q_refs: window -> (6,) a configuration on the window's chosen branch [rad].
        candidates: (turn, offset, windows reached, margin) of every candidate tried.
        cell: the cell built with the chosen hub pose (the search built it to check its
            clearance; the planner plans in it), or None.
    """

    hub_pose: np.ndarray
    turn: float
    offset: float
    seat: float
    windows_reached: int
    margin: float
    clearance: float
    q_refs: dict = field(default_factory=dict)
    candidates: tuple = ()
    cell: object = field(default=None, repr=False, compare=False)

    def record(self) -> dict:
        """JSON-ready record for ``plan.meta["placement"]``."""
        return {"turn_rad": self.turn, "offset_m": self.offset, "seat_m": self.seat,
                "windows_reached": self.windows_reached, "joint_margin_rad": self.margin,
                "clearance_m": self.clearance, "candidates": [list(c) for c in self.candidates]}


@dataclass(frozen=True)
class PlacementSearch:
    """How widely :func:`place_hub` searches.

    Attributes:
        per_window: CL targets sampled per window.
        turns: turns tried per window period.
        offsets: offsets tried on a chuck [m] (the nominal first: it wins ties).
        checked: best candidates whose clearance is checked in a built cell.
    """

    per_window: int = 16
    turns: int = 6
    offsets: tuple[float, ...] = (0.0, -0.05, 0.05)
    checked: int = 2


def seat_offset(cell, hub_model) -> float:
    """Height [m] to move H along the mount's z so the hub's rearmost point rests on the chuck
    top (0 without a ``chuck_top`` frame or in the workpiece-in-hand cell)."""
    plant = cell.plant
    if cell.mode != "tool" or not plant.HasFrameNamed("chuck_top"):
        return 0.0
    ctx = plant.CreateDefaultContext()
    chuck = plant.GetFrameByName("chuck_top").CalcPoseInWorld(ctx).GetAsMatrix4()
    X_WH = cell.hub_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
    rear = float(np.min(hub_model.vertices_H[:, 2]))  # <= 0: behind the face
    # H sits |rear| above the chuck top (the mount's z is the world's up in the chuck cell)
    return float(chuck[2, 3] - rear - X_WH[2, 3])


def _pose(turn: float, offset: float, seat: float) -> np.ndarray:
    c, s = np.cos(turn), np.sin(turn)
    X = np.eye(4)
    X[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    X[:3, 3] = [offset, 0.0, seat]
    return X


def _moved(kin: CellKinematics, X_MH: np.ndarray) -> CellKinematics:
    """The cell's kinematics with the hub at X_MH on its mount (the nominal mount = H0)."""
    if kin.mode == "tool":
        return replace(kin, X_WH=kin.X_WH @ X_MH)
    return replace(kin, X_FH=kin.X_FH @ X_MH)


def _sample_targets(wts, per_window: int, options) -> list[np.ndarray]:
    """Per window: (K, S, 4, 4) tool poses at K targets spread over its CL points, S spins."""
    r_c, lift = contact_geometry(options.contact_radius)
    spins = np.linspace(-np.pi, np.pi, 12, endpoint=False)
    out = []
    for wt in wts:
        idx = np.unique(np.linspace(0, len(wt) - 1, min(per_window, len(wt))).astype(int))
        p_HQ = tool_point_H(wt.p_HC[idx], wt.n_H[idx], wt.retract_H[idx], wt.depth_of_cut, r_c,
                            0.0)
        p_HT = p_HQ + lift * wt.retract_H[idx]
        X = np.stack([X_HT_from_axis(p_HT, wt.retract_H[idx], wt.t_H[idx], s) for s in spins],
                     axis=1)
        out.append(X)
    return out


def _window_branches(kin: CellKinematics, X_HT: np.ndarray, wrist: float):
    """For one window's (K, S, 4, 4) tool poses: per branch (8,) whether every target has a
    spin reaching it inside the limits with |J5| >= wrist, that branch's least limit margin,
    and one configuration of it (the first target's)."""
    K, S = X_HT.shape[:2]
    q, _ = kin.ik_all(kin.X_WF_from_X_HT(X_HT.reshape(-1, 4, 4)))
    q = q.reshape(K, S, 8, 6)
    lo, hi = kin.q_lower, kin.q_upper
    # J4 and J6 turn more than once: each solution's best 2 pi turn toward mid-range
    mid = 0.5 * (lo + hi)
    q = q + 2 * np.pi * np.round((mid - q) / (2 * np.pi)) * np.isin(np.arange(6), (3, 5))
    margin = np.min(np.minimum(q - lo, hi - q), axis=-1)  # (K, S, 8)
    good = np.isfinite(margin) & (margin >= 0) & (np.abs(q[..., 4]) >= wrist)
    margin = np.where(good, margin, -np.inf)
    best = margin.max(axis=1)  # (K, 8): the best spin per target and branch
    reach = np.all(best > -np.inf, axis=0)
    q_ref = np.full((8, 6), np.nan)
    for b in np.flatnonzero(reach):
        q_ref[b] = q[0, int(np.argmax(margin[0, :, b])), b]
    return reach, best.min(axis=0), q_ref


def _score(kin, samples, wrist):
    """(windows reached, least margin over them, per-window (reach, margin, q_ref))."""
    per = [_window_branches(kin, X, wrist) for X in samples]
    reached = [w for w in per if w[0].any()]
    margin = min((float(np.max(np.where(r, m, -np.inf))) for r, m, _ in reached),
                 default=-np.inf)
    return len(reached), margin, per


def branch_sequence(per: list, q_home: np.ndarray, weights: np.ndarray) -> dict[int, np.ndarray]:
    """The branch of each window (index into ``per``, in cutting order) that a dynamic
    programme over the windows picks: least weighted joint travel from home through the
    windows' reference configurations; windows no branch reaches get none."""
    order = [i for i, (reach, _, _) in enumerate(per) if reach.any()]
    if not order:
        return {}
    cost = {b: float(np.sum(weights * np.abs(per[order[0]][2][b] - q_home)))
            for b in np.flatnonzero(per[order[0]][0])}
    back: list[dict] = []
    for prev, cur in zip(order[:-1], order[1:], strict=True):
        new, arg = {}, {}
        for c in np.flatnonzero(per[cur][0]):
            steps = {b: cost[b] + float(np.sum(weights * np.abs(per[cur][2][c]
                                                                 - per[prev][2][b])))
                     for b in cost}
            arg[c] = min(steps, key=steps.get)
            new[c] = steps[arg[c]]
        back.append(arg)
        cost = new
    b = min(cost, key=cost.get)
    chosen = [b]
    for arg in reversed(back):
        b = arg[b]
        chosen.append(b)
    chosen.reverse()
    return {i: per[i][2][b] for i, b in zip(order, chosen, strict=True)}


def _clear_share(cell, kin: CellKinematics, samples, per, tol) -> tuple[float, float]:
    """Share of the sampled targets whose best reference solution clears the cell by
    ``tol.min_clearance``, and the least clearance found (the cell built with the candidate's
    hub pose)."""
    bound = float(tol.min_clearance)
    checker = ClearanceChecker(cell, tolerances=tol)
    n_ok, n, least = 0, 0, np.inf
    for X, (reach, _, _) in zip(samples, per, strict=True):
        if not reach.any():
            continue
        q, _ = kin.ik_all(kin.X_WF_from_X_HT(X[:, 0]))
        for qk in q:
            qk = qk[np.all(np.isfinite(qk), axis=1) & kin.within_limits(qk)]
            if not len(qk):
                continue
            d = max(checker.min_distance(qi, bound + 1e-3)[0] for qi in qk[:2])
            least = min(least, d)
            n_ok += d >= bound
            n += 1
    return (n_ok / n if n else 0.0), float(least)


def _may_win(cand: tuple, first: tuple, first_share: float) -> bool:
    """Whether a candidate ranked after ``first`` (by windows reached, then margin) can still
    be chosen over it once ``first``'s clearance share is known: only with as many windows
    reached and a larger share (the key compared below: windows, share to 0.01, margin)."""
    return cand[0] == first[0] and round(first_share, 2) < 1.0


def _candidate_clearance(recipe: dict, kin: CellKinematics, samples, per, tol):
    """A worker's task: :func:`_clear_share` of a candidate, its cell built from ``recipe``
    (kept as the worker's cell: a window planned in it later finds it built)."""
    from drakedeburr.plan.parallel import planning_cell

    return _clear_share(planning_cell(recipe)[0], kin, samples, per, tol)


def place_hub(cell, hub_model, wts, config, options, *,
              search: PlacementSearch = PlacementSearch()) -> Placement:
    """Search the hub's pose on its mount and the windows' branches (module docstring).

    Args:
        cell: the cell built with the hub at its nominal mount pose.
        hub_model: the hub; wts: its windows' targets, in cutting order.
        config: the run's configuration (tolerances: wrist margin, clearance).
        options: the planner's options (contact radius, IK wrist margin).
        search: how widely to search (targets per window, turns, offsets, cells built).
    """
    from drakedeburr.cell.recipe import cell_recipe
    from drakedeburr.cell.station import load_cell
    from drakedeburr.pool import map_calls

    kin0 = cell_kinematics(cell)
    seat = seat_offset(cell, hub_model)
    spec = hub_model.spec
    period = 2 * np.pi / (spec.spoke_count if spec is not None else max(len(wts), 1))
    turns = search.turns
    offs = search.offsets if cell.mode == "tool" else (0.0,)
    samples = _sample_targets(wts, search.per_window, options)
    wrist = max(options.ik.min_wrist, config.tolerances.wrist_margin)
    cands = []
    for k in range(turns):
        for off in offs:
            X = _pose(period * k / turns, off, seat)
            n, margin, per = _score(_moved(kin0, X), samples, wrist)
            cands.append((n, margin, -k, -abs(off), X, per, period * k / turns, off))
    cands.sort(key=lambda c: c[:4], reverse=True)
    top = cands[:search.checked]
    recipes = [cell_recipe(cell.scenario, cell.hub_sdf.parent, robot=cell.arm.ref,
                           tool=cell.tool, hub_pose=c[4]) for c in top]
    tol = config.tolerances
    built: dict[int, object] = {}
    shares: dict[int, tuple[float, float]] = {}

    def call(k: int) -> tuple:
        return _candidate_clearance, (recipes[k], _moved(kin0, top[k][4]), samples, top[k][5],
                                      tol)

    def here(k: int) -> tuple[float, float] | None:
        if k and 0 in shares and not _may_win(top[k], top[0], shares[0][0]):
            return None  # it cannot beat the first candidate: not built
        built[k] = load_cell(**recipes[k])
        shares[k] = _clear_share(built[k], _moved(kin0, top[k][4]), samples, top[k][5], tol)
        return shares[k]

    # the candidates are checked at once on the running workers (each the same reading
    # wherever it is made); the winner's cell is then this process's, built if a worker
    # read it
    read = map_calls(len(top), call, options.workers,
                     name=lambda k: f"placement candidate {k}", here=here)
    best, best_key = None, None
    for k, (n, margin, _, _, X, per, turn, off) in enumerate(top):
        if read[k] is None:
            continue
        share, least = read[k]
        key = (n, round(share, 2), margin)
        if best_key is None or key > best_key:
            best, best_key = (X, per, turn, off, n, margin, least, k), key
    X, per, turn, off, n, margin, least, k = best
    placed = built.get(k) or load_cell(**recipes[k])
    refs = branch_sequence(per, kin0.q_home, np.asarray(JOINT_WEIGHTS))
    log.info("hub placement: turn %.1f deg, offset %.0f mm, seat %.1f mm: %d of %d windows "
             "reachable on one branch (joint margin %.2f rad)", np.degrees(turn), 1e3 * off,
             1e3 * seat, n, len(wts), margin)
    return Placement(hub_pose=X, turn=float(turn), offset=float(off), seat=float(seat),
                     windows_reached=int(n), margin=float(margin), clearance=float(least),
                     q_refs={int(wts[i].window_index): q for i, q in refs.items()},
                     candidates=tuple((float(c[6]), float(c[7]), int(c[0]), float(c[1]))
                                      for c in cands), cell=placed)
