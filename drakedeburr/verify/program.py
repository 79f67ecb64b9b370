"""The Cartesian program read against the sampled trajectory, as a controller executes it.

Linear moves between consecutive targets (position linear, orientation slerped) for every
target whose motion is "linear"; both faces must agree both ways: each sample against the
program's path (which move it lies on, how far), and the program's own points against the
trajectory's path. The orientation a sample is compared with is the program's at the share of
the move travelled between passing its targets (:mod:`drakedeburr.plan.program_reading`: the
projection stands still in a corner zone while the tool turns on).
"""

from __future__ import annotations

import numpy as np

from drakedeburr.plan.program_reading import (
    moves_in_order,
    passing_fractions,
    rot_angle,
    slerp_pairs,
)
from drakedeburr.verify.geometry import point_segment
from drakedeburr.verify.refs import target_motion

__all__ = ["read_program"]


def _segment_reading(targets, ks: list[int], idx: np.ndarray, samples, out: dict) -> None:
    """Fill ``out``'s per-sample arrays for the samples ``idx`` of one segment whose linear
    moves end at targets ``ks``."""
    p = samples.p_HT[idx]
    P0 = np.array([targets[k - 1].X_HT[:3, 3] for k in ks])
    P1 = np.array([targets[k].X_HT[:3, 3] for k in ks])
    d, m, f = moves_in_order(p, P0, P1)
    ka = np.asarray(ks)
    out["path_dev"][idx] = d
    out["move"][idx] = ka[m]
    out["fraction"][idx] = f
    if len(idx) >= 2 and np.all(np.diff(ka) == 1):
        chain = np.arange(ka[0] - 1, ka[-1] + 1)
        m_o, f_o = passing_fractions(p, np.array([targets[k].X_HT[:3, 3] for k in chain]))
        k_o = ka[m_o]
    else:  # not one chain of targets: read by the projection
        k_o, f_o = ka[m], f
    R_prog = slerp_pairs(np.array([targets[k - 1].X_HT[:3, :3] for k in k_o]),
                         np.array([targets[k].X_HT[:3, :3] for k in k_o]), f_o)
    out["orient_dev"][idx] = rot_angle(R_prog, samples.X_HT[idx, :3, :3])


def _program_points(targets, ks: list[int], step: float) -> np.ndarray:
    """Points of the program's linear moves ending at ``ks``, every ``step`` or finer."""
    pts = []
    for k in ks:
        A, B = targets[k - 1].X_HT[:3, 3], targets[k].X_HT[:3, 3]
        n = max(1, int(np.ceil(np.linalg.norm(B - A) / step)))
        pts.append(A + np.outer(np.arange(n + 1) / n, B - A))
    return np.concatenate(pts)


def read_program(plan, samples, tol):
    """:class:`drakedeburr.verify.types.ProgramReading` of the plan's program."""
    from drakedeburr.verify.types import ProgramReading

    targets = plan.targets
    n = len(samples)
    out = {"move": np.full(n, -1), "fraction": np.full(n, np.nan),
           "path_dev": np.full(n, np.nan), "orient_dev": np.full(n, np.nan)}
    worst, worst_at = 0.0, None
    for si, seg in enumerate(plan.segments):
        a, b = seg.target_range
        if a < 1 or b > len(targets) or b <= a:
            continue
        ks = [k for k in range(a, b) if target_motion(targets[k]) == "linear"]
        if not ks:
            continue
        idx = np.flatnonzero(samples.segment == si)
        _segment_reading(targets, ks, idx, samples, out)
        if len(idx) < 2:
            continue
        pts = _program_points(targets, ks, tol.dense_step)
        p = samples.p_HT
        dd, jj, _ = point_segment(pts, p[idx[:-1]], p[idx[1:]])
        j = int(np.argmax(dd))
        if dd[j] > worst:
            worst, worst_at = float(dd[j]), int(idx[int(jj[j])])
    return ProgramReading(move=out["move"], fraction=out["fraction"], path_dev=out["path_dev"],
                          orient_dev=out["orient_dev"], program_to_path=worst,
                          program_worst=worst_at)
