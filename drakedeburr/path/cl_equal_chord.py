"""The ``equal_chord_height`` CL planner (the classic baseline of :mod:`cl_planning`) and the
sample counts every planner uses to measure a segment's chord height on the spline.

March along the curve, each next point as far as the true chord height allows (delta_max);
no length cap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.path.edge_curve import EdgeCurve

if TYPE_CHECKING:
    from drakedeburr.path.cl_planning import PlannerParams

__all__ = ["SAMPLED_MARGIN", "plan_equal_chord_height", "samples_for", "sample_count"]

# relative safety margin between the sampled chord height used while planning and the refined
# one reported by the metrics (sampling underestimates a smooth maximum by < 5e-4 relative)
SAMPLED_MARGIN = 5e-3


def samples_for(curve: EdgeCurve, u0, u1, s0=None) -> int:
    """Samples per segment so that the sampled max is within ~1e-3 of the true one: one per
    0.25 mm of the longest arc, 48..600 (s0: arc length to u0 if known)."""
    return sample_count(float(np.max(curve.arc_length(u0, u1, s0=s0))))


def sample_count(arc: float) -> int:
    return int(np.clip(arc / 0.25e-3, 48, 600))


def plan_equal_chord_height(curve: EdgeCurve, params: PlannerParams) -> np.ndarray:
    """CL parameters of the equal-chord-height march (module doc), u in [0, 1)."""
    target = params.delta_max * (1.0 - SAMPLED_MARGIN)
    L = curve.length
    s, out = 0.0, [0.0]
    # a step can never exceed the length of the rest of the loop
    while True:
        rest = L - s
        ch = _ChordHeightFrom(curve, s)
        # grow a bracket geometrically (steps 1, 2, 4, ... mm below the rest of the loop, all
        # measured in one call together with the rest itself), then shrink it with guesses
        # from the model h ~ step^2 (safeguarded inside the bracket); stop within 0.2 % of
        # the target
        steps = [min(rest, 1e-3)]
        while steps[-1] * 2.0 < rest:
            steps.append(steps[-1] * 2.0)
        if steps[-1] >= rest:
            steps = []
        h_all = ch.many(np.array([rest, *steps]))
        if h_all[0] <= target and ch(rest, refine=True) <= params.delta_max:
            break
        lo, hi, h_lo, h_hi = 0.0, rest, 0.0, np.inf
        for step, h in zip(steps, h_all[1:], strict=True):
            if h > target:
                hi, h_hi = step, h
                break
            lo, h_lo = step, h
        for _ in range(40):
            if h_lo >= 0.998 * target or hi - lo < 1e-7:
                break
            guess = hi * np.sqrt(target / h_hi) if np.isfinite(h_hi) else 0.5 * (lo + hi)
            width = hi - lo
            guess = float(np.clip(guess, lo + 0.05 * width, hi - 0.05 * width))
            h = ch(guess)
            if h > target:
                hi, h_hi = guess, h
            else:
                lo, h_lo = guess, h
        # the search used sampled chord heights; confirm the step with the refined one
        while lo > 1e-6 and ch(lo, refine=True) > params.delta_max:
            lo *= 0.995
        s += lo
        out.append(s)
    return curve.u_from_arc(np.array(out))


class _ChordHeightFrom:
    """Chord height of the arc from arc length s to s + step, for many steps from one s (the
    start parameter is found once, not once per trial step)."""

    def __init__(self, curve: EdgeCurve, s: float):
        self.curve, self.s = curve, s
        self.u0 = curve.u_from_arc(s)
        self.s0 = curve.arc_length(np.mod(self.u0, 1.0))

    def __call__(self, step: float, refine: bool = False) -> float:
        curve, s, u0 = self.curve, self.s, self.u0
        u1 = curve.u_from_arc(s + step)
        if s + step >= curve.length - 1e-12 or u1 <= u0:
            u1 = u1 + 1.0
        return float(curve.chord_height(u0, u1, samples=samples_for(curve, u0, u1, self.s0),
                                        refine=refine)[0])

    def many(self, steps: np.ndarray) -> np.ndarray:
        """Sampled chord heights (refine=False) for several steps at once, (K,): the values of
        K calls (each arc keeps its own sample count; shorter sample rows are padded with
        their last sample, t = 1, which does not change a maximum)."""
        curve, s, u0 = self.curve, self.s, self.u0
        steps = np.asarray(steps, float)
        if len(steps) == 0:
            return np.zeros(0)
        u1 = curve.u_from_arc(s + steps)
        u1 = np.where((s + steps >= curve.length - 1e-12) | (u1 <= u0), u1 + 1.0, u1)
        # _samples_for per arc, the arcs measured in one call (elementwise: the same values)
        arcs = curve.arc_length(u0, u1, s0=self.s0)
        counts = [sample_count(float(a)) for a in arcs]
        t = np.ones((len(steps), max(counts) + 1))
        for k, c in enumerate(counts):
            t[k, : c + 1] = np.linspace(0.0, 1.0, c + 1)
        return curve.chord_height_at(u0, u1, t)
