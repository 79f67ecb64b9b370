"""The executed cut of a window: a smooth path through its CL targets' tool points
(:mod:`drakedeburr.plan.cut_path`: corners blended within ``blend_deviation`` of the linear
program, the smoothest axis inside the cones), the spin about the axis chosen by dynamic
programming (:mod:`drakedeburr.plan.spin`), tracked by the analytic IK on the window's
configuration every ``dense_step`` of travel and checked for clearance and joint jumps.

Where samples come too close to the hub the IK's (clearance-checked) axis is pinned around
them and the blends tightened; where the program's moves are shorter than the sampling, or the
axis would leave its cone between the samples, the cut is sampled again at half the step
(:func:`between_samples_error`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from drakedeburr.frames.vectors import angle_between
from drakedeburr.plan.cut_path import AxisSmoothing, CutPathOptions, cut_path
from drakedeburr.plan.interpolate import DensePath
from drakedeburr.plan.options import PlanContext
from drakedeburr.plan.program_reading import (
    cone_axes_on_moves,
    moves_in_order,
    program_orientation_error,
)
from drakedeburr.plan.results import IkStep
from drakedeburr.plan.spin import SpinSearch, optimize_spin, spin_frames
from drakedeburr.plan.timing import joint_spline
from drakedeburr.plan.types import FailureRecord

__all__ = ["track_cut", "cone_of_cut", "between_samples_error", "clearance_records",
           "motion_records"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class _Try:
    """One try of the executed cut at one sampling step."""

    cp: object  # CutPath
    cut: DensePath
    dist: np.ndarray
    spin_mode: str
    records: tuple[FailureRecord, ...] = ()  # the tracking's: joint jumps, clearance


def clearance_records(window: int, checker, cut, dist: np.ndarray,
                      bound: float) -> list[FailureRecord]:
    """One failure record per stretch of the executed cut under the clearance bound
    (:attr:`PlanContext.cut_clearance`): where it starts and ends (sample index and tool
    travel), its least clearance and the closest pair."""
    low = dist < bound
    out = []
    k = 0
    while k < len(low):
        if not low[k]:
            k += 1
            continue
        end = k
        while end + 1 < len(low) and low[end + 1]:
            end += 1
        j = k + int(np.argmin(dist[k:end + 1]))
        d, pair = checker.min_distance(cut.q[j], bound + 1e-3)
        out.append(FailureRecord(
            window=window, kind="dense", value=float(d), limit=float(bound), unit="m",
            where=dict(sample=int(j), samples=[int(k), int(end)],
                       s_range_mm=[float(cut.s[k] * 1e3), float(cut.s[end] * 1e3)],
                       pair=list(pair)),
            reason=f"clearance {d * 1e3:.3f} mm on the executed motion over "
                   f"{cut.s[k] * 1e3:.1f}-{cut.s[end] * 1e3:.1f} mm of the cut "
                   f"({end - k + 1} samples; {pair[0]} vs {pair[1]}), under the planning "
                   f"bound {bound * 1e3:.4f} mm"))
        k = end + 1
    return out


def motion_records(window: int, cut, max_jump: float) -> list[FailureRecord]:
    """Failure records of joint jumps between dense samples and unreachable samples."""
    out = []
    jumps = np.max(np.abs(np.diff(cut.q, axis=0)), axis=1)
    for k in np.flatnonzero(~(jumps <= max_jump)):
        out.append(FailureRecord(window=window, kind="dense", value=float(jumps[k]),
                                 limit=max_jump, unit="rad", where=dict(sample=int(k)),
                                 reason=f"joint jump {float(jumps[k]):.3g} rad between dense "
                                        "samples"))
    for k in np.flatnonzero(~cut.ok):
        out.append(FailureRecord(window=window, kind="dense", where=dict(sample=int(k)),
                                 reason="dense sample unreachable on the window's "
                                        "configuration"))
    return out


def between_samples_error(kin, cut, cp, cone: tuple | None = None
                          ) -> tuple[float, float, float]:
    """How far the executed cut strays *between* the dense samples, where the timed trajectory
    runs on the joint spline through them (:func:`drakedeburr.plan.timing.joint_spline`): read
    at the quarter points of every interval together with the samples, as the verifier reads
    the trajectory.

    Returns:
        (largest angle [rad] between the program's orientation and the executed one, largest
        angle [rad] by which the tool axis leaves its cone there: ``cone`` = (CL target points
        (K, 3), their cone axes (K, 3) tip -> spindle, half-angle), read on the moves as the
        verifier does; -inf without ``cone``; largest distance [m] of the tool point from the
        program's moves, read as the verifier's ``path_deviation``).

    Design notes: where the program's moves are shorter than the sampling and turn the tool,
    the spline cannot follow its orientation kinks (h5_split's tight corners: 0.1-0.37 mm moves
    turning 25-50 mrad read 11 mrad off the program at 0.25 mm sampling, 6.6 mrad at 0.125 mm).
    Where the wrist turns fast while the tool point barely moves (a near stop), the spline's
    tool point leaves the line between two samples (0.059 mm between two samples 0.23 mm apart
    on a relaxed window of a catalogue hub). The cone reading is a guard: where a cut left the
    verifier's cone at a corner (0.16 rad of cone turn between two CL points), the spline
    between the samples stayed inside; the cause was the reading of the cone itself
    (:data:`drakedeburr.plan.cut_path.PIN_MARGIN`).
    """
    sp = joint_spline(cut.s, cut.q)
    ds = np.diff(cut.s)
    s_all = np.sort(np.concatenate([cut.s] + [cut.s[:-1] + f * ds for f in (0.25, 0.5, 0.75)]))
    X = kin.X_HT_from_q(sp(s_all))
    err = float(program_orientation_error(X, cp.X_target)[0].max())
    P = cp.X_target[:, :3, 3]
    dev = float(moves_in_order(X[:, :3, 3], P[:-1], P[1:])[0].max())
    if cone is None:
        return err, -np.inf, dev
    P, C, half = cone
    c = cone_axes_on_moves(X[:, :3, 3], P, C)
    return err, float(np.max(angle_between(c, -X[:, :3, 2])) - half), dev


def _spin(ctx: PlanContext, cp, q0: np.ndarray, step: float, spin_mode: str, w: int):
    """The cut path with its spin: searched (:func:`optimize_spin`) or the IK's, smoothed.
    Returns (CutPath, spin mode used)."""
    opt = ctx.options
    if spin_mode == "search" and opt.spin_search:
        # the spin program keeps its travel resolution (every 2nd sample at the base step)
        # when the cut is sampled more finely
        search = SpinSearch(wrist_margin=opt.ik.min_wrist, band=opt.spin_band,
                            stride=max(1, round(2 * opt.dense_step / step)))
        X_spin, stats = optimize_spin(ctx.kin, cp.X_HT, cp.s, q0, search, psi_ref=cp.psi_ik)
        if stats["ok"]:
            X_tg = cp.X_target.copy()
            X_tg[:, :3, :3] = X_spin[cp.target_index, :3, :3]
            return replace(cp, X_HT=X_spin, X_target=X_tg), spin_mode
        log.debug("window %d: spin search failed (%s); using the IK's spin", w, stats["reason"])
        spin_mode = "ik"
    # the IK's own spin (clearance-checked at the targets), smoothed
    X_sp = cp.X_HT.copy()
    X_sp[:, :3, :3] = spin_frames(cp.X_HT[:, :3, :3], cp.psi_ik)
    X_tg = cp.X_target.copy()
    X_tg[:, :3, :3] = X_sp[cp.target_index, :3, :3]
    return replace(cp, X_HT=X_sp, X_target=X_tg), spin_mode


def track_cut(ctx: PlanContext, wt, ik: IkStep, step: float) -> _Try:
    """Step 3 of a window pass (:func:`drakedeburr.plan.window.execute_cut`): track the
    executed cut at sampling ``step``; where samples come too close to the hub, pin the axis
    and tighten the blends around them and try again (up to 6 times). Its records (joint
    jumps, clearance) are in ``_Try.records``."""
    opt, kin, w = ctx.options, ctx.kin, wt.window_index
    wik, good, order, X_ik = ik.wik, ik.good, ik.order, ik.X_ik
    records: list[FailureRecord] = []
    pin = None
    spin_mode = "search"
    dev = np.full(len(order), opt.blend_deviation)
    q0 = wik.q[good[0]]
    for attempt in range(6):
        dist = None
        shape = CutPathOptions(step=step, spin_sigma=opt.spin_sigma,
                               axes=AxisSmoothing(margin=opt.axis_margin))
        cp = cut_path(X_ik, wt.cone_retract_H[order], wt.cone_half_angle, shape, pin=pin,
                      deviation=dev)
        cp, spin_mode = _spin(ctx, cp, q0, step, spin_mode, w)
        q_d, ok_d = kin.track(kin.X_WF_from_X_HT(cp.X_HT), q0)
        cut = DensePath(X_HT=cp.X_HT, s=cp.s, target_index=cp.target_index, q=q_d, ok=ok_d)
        jumps = np.max(np.abs(np.diff(cut.q, axis=0)), axis=1)
        if not (np.all(cut.ok) and np.all(jumps <= opt.max_joint_jump)):
            if spin_mode != "ik":
                log.debug("window %d: searched spin leaves the limits or jumps; using the IK's "
                         "spin", w)
                spin_mode = "ik"
                continue
            break
        dist = ctx.checker.min_distances_along(cut.q, ctx.min_clearance + 1e-3)
        low = dist < ctx.cut_clearance
        if not low.any():
            break
        if dist.min() < ctx.min_clearance - 0.5e-3 and spin_mode != "ik":
            # far below the bound: the spin put the spindle body into the hub (pinning the
            # axis cannot fix that); fall back to the IK's spin
            log.debug("window %d: %.2f mm clearance with the searched spin; using the IK's spin",
                     w, dist.min() * 1e3)
            spin_mode = "ik"
            continue
        pin, dev = _pin_and_tighten(cp, low, step, pin, dev, len(order))
        log.debug("window %d: %d samples under the clearance; pinning the axis and tightening "
                 "the blends around them (attempt %d)", w, int(low.sum()), attempt + 1)
    records += motion_records(w, cut, opt.max_joint_jump)
    if not np.all(cut.ok):
        dist = np.full(len(cut.s), np.nan)
    else:
        if dist is None:  # left the loop before measuring this cut (joint jumps)
            dist = ctx.checker.min_distances_along(cut.q, ctx.min_clearance + 1e-3)
        records += clearance_records(w, ctx.checker, cut, dist, ctx.cut_clearance)
    return _Try(cp=cp, cut=cut, dist=dist, spin_mode=spin_mode, records=tuple(records))


def _pin_and_tighten(cp, low: np.ndarray, step: float, pin, dev: np.ndarray, n: int):
    """Keep the IK's (clearance-checked) axis within 3 mm of the samples that came too close,
    and round the corners there less (a blend cuts the corner by up to its deviation)."""
    near = np.convolve(low.astype(float), np.ones(2 * int(3e-3 / step) + 1), mode="same") > 0
    margin = 3e-3
    new_iv = np.column_stack([cp.s[low] - margin, cp.s[low] + margin])
    pin = new_iv if pin is None else np.vstack([pin, new_iv])
    tight = np.unique(np.searchsorted(cp.s[cp.target_index], cp.s[near]))
    tight = np.clip(np.concatenate([tight - 1, tight]), 0, n - 1)
    dev = dev.copy()
    dev[tight] *= 0.25
    return pin, dev


def cone_of_cut(wt, order: np.ndarray, cp, via: np.ndarray | None = None) -> np.ndarray:
    """The cone axis at every dense sample of the cut, read on the moves between the CL
    targets as the verifier reads it (:func:`program_reading.cone_axes_on_moves`)."""
    P = cp.X_target[:, :3, 3] if via is None else cp.X_target[~via, :3, 3]
    return cone_axes_on_moves(cp.X_HT[:, :3, 3], P, wt.cone_retract_H[order])
