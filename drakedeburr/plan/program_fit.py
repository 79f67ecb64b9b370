"""The program of a window's executed cut: its targets are the CL targets' tool points with the
smooth orientation there, plus via targets on the executed cut where the program (linear
moves, slerped orientation, as a controller runs it) would stray from it; where it still strays
(moves too short for a via) the executed orientation is pulled onto the program's.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from drakedeburr.frames.vectors import angle_between
from drakedeburr.plan.cut import between_samples_error, cone_of_cut
from drakedeburr.plan.kinematics import DISTANCE_SLACK
from drakedeburr.plan.options import PlanContext
from drakedeburr.plan.program_reading import (
    moves_in_order,
    program_orientation_error,
    program_orientations,
    rot_angle,
    slerp_pairs,
)
from drakedeburr.plan.results import ExecutedCut, ProgramFit, WindowStatus
from drakedeburr.plan.types import FailureRecord

__all__ = ["fit_program", "via_samples", "add_vias", "conform_to_program"]

log = logging.getLogger(__name__)


def fit_program(ctx: PlanContext, wt, tr, order: np.ndarray, refine: bool) -> ProgramFit:
    """Step 4 of a window pass: the program of the tracked cut ``tr`` (module docstring),
    :class:`ProgramFit` with its :class:`ExecutedCut`, with ``finer`` (``refine`` and the
    trajectory would stray from the program between the samples,
    :func:`drakedeburr.plan.cut.between_samples_error`), or with status
    ``WindowStatus.PROGRAM_FAILED`` (a program target is unreachable; recorded)."""
    records: list[FailureRecord] = []
    w, kin, tol = wt.window_index, ctx.kin, ctx.config.tolerances
    cp, cut, dist = tr.cp, tr.cut, tr.dist
    fillets: list = []
    if ctx.options.fillets is not None:
        from drakedeburr.plan.fillets import repair_fillets

        cp, cut, dist, fillets = repair_fillets(ctx, cp, cut, dist, cone_of_cut(wt, order, cp),
                                                wt.cone_half_angle, w)
    cp, via = add_vias(cp, ctx.program_orientation, ctx.options.via_rounds, w,
                       tol_position=ctx.program_position)
    cut = replace(cut, target_index=cp.target_index)
    if ctx.options.conform_program:
        cp, cut, dist = conform_to_program(ctx, cp, cut, dist, w, cone_of_cut(wt, order, cp, via),
                                           wt.cone_half_angle)
    q_targets = np.array([kin.track(kin.X_WF_from_X_HT(cp.X_target[j][None]),
                                    cut.q[cp.target_index[j]])[0][0]
                          for j in range(len(cp.X_target))])
    bad = np.flatnonzero(np.any(~np.isfinite(q_targets), axis=1))
    cl_of = np.full(len(via), -1)
    cl_of[~via] = order
    for j in bad:
        records.append(FailureRecord(window=w, kind="program", point=int(cl_of[j]),
                                     reason="program target unreachable with the smoothed "
                                            "orientation"))
    if bad.size:
        return ProgramFit(status=WindowStatus.PROGRAM_FAILED, failures=tuple(records))
    if refine:
        err, out_of_cone, dev = between_samples_error(
            kin, cut, cp, (cp.X_target[~via, :3, 3], wt.cone_retract_H[order],
                           wt.cone_half_angle))
        if err > 0.8 * tol.orientation_match or out_of_cone > 0.0 or dev > ctx.program_position:
            return ProgramFit(status=WindowStatus.OK, finer=True)
    stray = program_orientation_error(cp.X_HT, cp.X_target)[0]
    if stray.max() > tol.orientation_match:
        k = int(np.argmax(stray))
        records.append(FailureRecord(
            window=w, kind="program", value=float(stray[k]), limit=tol.orientation_match,
            unit="rad", where=dict(sample=k),
            tried=(f"{int(via.sum())} via targets", "orientation pulled onto the program"),
            reason=f"program orientation strays {1e3 * stray[k]:.1f} mrad from the executed cut "
                   f"(via targets: {int(via.sum())})"))
    return ProgramFit(status=WindowStatus.OK, failures=tuple(records), executed=ExecutedCut(
        cp=cp, cut=cut, dist=dist, q_targets=q_targets, via=via, fillets=tuple(fillets)))


def via_samples(X: np.ndarray, X_targets: np.ndarray, target_index: np.ndarray,
                tol: float, tol_position: float = np.inf) -> np.ndarray:
    """Dense samples to make via targets: on each move of the program whose orientation strays
    more than ``tol`` from the executed poses ``X`` (read as the verifier reads it,
    :func:`drakedeburr.plan.program_reading.program_orientation_error`), the sample where it
    strays most; on each other move whose line the executed tool point leaves by more than
    ``tol_position`` (:func:`drakedeburr.plan.program_reading.moves_in_order`, the verifier's
    ``path_deviation`` reading), the sample farthest from it (sorted; never a target's own
    sample)."""
    err, move = program_orientation_error(X, X_targets)
    err[np.asarray(target_index)] = 0.0
    out = _worst_per_move(err, move, tol)
    if np.isfinite(tol_position):
        P = X_targets[:, :3, 3]
        d, move_p, _ = moves_in_order(X[:, :3, 3], P[:-1], P[1:])
        d[np.asarray(target_index)] = 0.0
        split = set(move[out].tolist()) if out else set()
        out += [k for k in _worst_per_move(d, move_p, tol_position)
                if int(move_p[k]) not in split]
    return np.asarray(sorted(set(out)), int)


def _worst_per_move(err: np.ndarray, move: np.ndarray, tol: float) -> list[int]:
    """Per move with a sample above ``tol``: its worst sample in the middle half of the move
    (a move of >= 3 samples: a via next to a target, or on a move shorter than the sampling,
    only shortens moves below what the reading resolves)."""
    out = []
    for k in np.unique(move[err > tol]):
        on = np.flatnonzero(move == k)
        mid = on[len(on) // 4:len(on) - len(on) // 4]
        if len(on) >= 3 and len(mid):
            out.append(int(mid[np.argmax(err[mid])]))
    return out


def add_vias(cp, tol: float, rounds: int, window: int, zone_quantum: float = 0.05e-3,
             tol_position: float = np.inf):
    """The cut program with via targets: executed poses (position and orientation of a dense
    sample of the cut) made targets where the program's orientation strays more than ``tol``
    or its moves leave the executed tool point by more than ``tol_position``
    (:func:`via_samples`), for up to ``rounds`` rounds. The executed cut is not changed: a via
    lies on it, so the program only gains a vertex on the path it already runs. Its zone: 45 %
    of the shorter of its two moves, rounded down to ``zone_quantum`` (at least that; a zone
    of 0 would be a stop). Returns (CutPath with the vias, via mask per target)."""
    via = np.zeros(len(cp.target_index), bool)
    for k in range(rounds):
        add = via_samples(cp.X_HT, cp.X_target, cp.target_index, tol, tol_position)
        if add.size == 0:
            break
        at = np.searchsorted(cp.target_index, add)
        ti = np.insert(cp.target_index, at, add)
        Xt = np.insert(cp.X_target, at, cp.X_HT[add], axis=0)
        via = np.insert(via, at, True)
        zone = np.insert(cp.zone, at, 0.0)
        P = Xt[:, :3, 3]
        for j in np.flatnonzero(via & (zone == 0.0)):
            leg = 0.45 * min(np.linalg.norm(P[j] - P[j - 1]), np.linalg.norm(P[j + 1] - P[j]))
            zone[j] = max(zone_quantum, np.floor(leg / zone_quantum) * zone_quantum)
        cp = replace(cp, target_index=ti, X_target=Xt, zone=zone)
        log.debug("window %d: %d via targets where the program strays more than %.1f mrad or "
                  "%.3f mm (round %d)", window, len(add), 1e3 * tol, 1e3 * tol_position, k + 1)
    return cp, via


def _pulled(cp, tol: float, ramp: float):
    """The executed orientation pulled onto the program's where it strays more than ``tol``
    (fading back over ``ramp`` of travel): (poses, changed samples, samples of offending moves,
    largest stray) or None when nothing strays."""
    R_prog, move = program_orientations(cp.X_HT, cp.X_target)
    err = rot_angle(R_prog, cp.X_HT[:, :3, :3])
    err[cp.target_index] = 0.0
    if err.max() <= tol:
        return None
    on = np.isin(move, np.unique(move[err > tol]))
    gap = np.abs(cp.s[:, None] - cp.s[on][None]).min(axis=1)
    wgt = np.clip(1.0 - gap / ramp, 0.0, 1.0)
    ch = np.flatnonzero(wgt > 0)
    X = cp.X_HT.copy()
    X[ch, :3, :3] = slerp_pairs(cp.X_HT[ch, :3, :3], R_prog[ch], wgt[ch])
    return X, ch, on, float(err.max())


#: travel over which the pulled orientation fades back to the smooth one [m]
CONFORM_RAMP = 1.5e-3
#: how far inside its cone the pulled tool axis stays [rad]
CONFORM_CONE_MARGIN = 1e-3


def conform_to_program(ctx: PlanContext, cp, cut, dist, window: int, cone_axis: np.ndarray,
                       half_angle: float):
    """Where the program's orientation still strays more than ``ctx.program_orientation``
    after the vias (moves too short for a via: a tight corner of a small window, 0.25-0.5 mm
    moves over which the smooth executed orientation turns unevenly), the executed orientation
    is pulled onto the program's (each move's slerp, as a controller runs it) there, fading
    back to the smooth one over ``CONFORM_RAMP`` of travel either side. The targets keep their poses
    (the program is unchanged); the joints are re-tracked and the change is kept only if they
    stay reachable, without jumps and at least as clear of the hub as the smooth cut was (or
    the clearance bound), and only if the tool axis stays ``CONFORM_CONE_MARGIN`` inside its cone
    (``cone_axis`` per dense sample, tip -> spindle) or no farther out than the smooth cut's:
    near a tight corner the chord of a slerp can cut across the turning cone. Returns
    (CutPath, DensePath, distances), changed or not."""
    ramp, cone_margin = CONFORM_RAMP, CONFORM_CONE_MARGIN
    pulled = _pulled(cp, ctx.program_orientation, ramp)
    if pulled is None:
        return cp, cut, dist
    X, ch, on, err_max = pulled
    c = np.asarray(cone_axis, float)[ch]
    before = angle_between(c, -cp.X_HT[ch, :3, 2])
    after = angle_between(c, -X[ch, :3, 2])
    if np.any(after > np.maximum(half_angle - cone_margin, before)):
        log.debug("window %d: the program's orientation leaves the tool axis' cone (by %.2f mrad); "
                 "keeping the smooth cut", window, 1e3 * float(np.max(after - half_angle)))
        return cp, cut, dist
    q, ok = ctx.kin.track(ctx.kin.X_WF_from_X_HT(X), cut.q[0])
    jumps = np.max(np.abs(np.diff(q, axis=0)), axis=1) if len(q) > 1 else np.zeros(0)
    if not (np.all(ok) and np.all(jumps <= ctx.options.max_joint_jump)):
        log.debug("window %d: the program's orientation at %d samples leaves the joints' reach; "
                 "keeping the smooth cut", window, int(on.sum()))
        return cp, cut, dist
    d_new = dist.copy()
    d_new[ch] = ctx.checker.min_distances_along(q[ch], ctx.min_clearance + 1e-3)
    floor = np.minimum(dist[ch] - DISTANCE_SLACK, ctx.cut_clearance)
    if np.any(d_new[ch] < floor):
        log.debug("window %d: the program's orientation at %d samples costs clearance (%.2f mm); "
                 "keeping the smooth cut", window, int(on.sum()), 1e3 * d_new[ch].min())
        return cp, cut, dist
    log.debug("window %d: executed orientation pulled onto the program's on %d samples "
             "(strayed up to %.1f mrad)", window, int(on.sum()), 1e3 * err_max)
    return replace(cp, X_HT=X), replace(cut, X_HT=X, q=q, ok=ok), d_new
