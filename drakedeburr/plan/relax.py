"""Recipe relaxation: a window the default recipe cannot cut is planned again with a milder
one, and the deviation is recorded (``plan.meta["recipe_deviations"]``) and shown in the report.

What is relaxed, in order, for a window whose plan leaves failure records:

1. the tool tilt: the large windows' (theta_A, theta_B) box of the source (0.26-0.44 rad) is
   meant for a flat face; on a dished or rising face the spindle body leans into the face
   beyond the opening (the bundled deep-dish hub needed exactly this, by hand). The window is
   oriented again with the small windows' box (0.09-0.26 rad), then with 0-0.15 rad, then with
   0-0.44 rad: every tilt of the source's two boxes and the milder ones, whose cone (about
   twice as wide) lets the IK lean the spindle where a narrow cone around any one tilt meets
   the dish (on an unseen 15 in hub with an 84 mm dish, no axis of the 0-0.15 rad cone kept
   the 80 mm spindle body 2 mm off the dish wall at some targets of every window; the whole
   range cut window 0 without a failure record);
2. nothing else is tried automatically: a slower feed does not make a motion feasible (the
   timing already slows wherever a limit binds), and the cell has one burr model (a smaller
   burr would need its tool model and depth of cut). Both stay the recipe's to change.

The variants of all failing windows are planned together, one round per tilt step (in
parallel where the planner has workers); a window keeps the first variant that plans without
a failure record. Windows are planned independently (the same plan whichever process plans
them), so the hub is not planned again: its plan is assembled anew (transitions, timing) from
the first pass's windows and the relaxed ones.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

from drakedeburr.config import OrientationBounds

__all__ = ["Deviation", "TILT_STEPS", "relax_windows"]

log = logging.getLogger(__name__)

#: tilt boxes tried in turn, milder each step [rad]
TILT_STEPS = (OrientationBounds(0.09, 0.26), OrientationBounds(0.0, 0.15),
              OrientationBounds(0.0, 0.44))


@dataclass(frozen=True)
class Deviation:
    """One departure from the recipe for one window: what, from what to what, and why."""

    window: int
    item: str
    default: str
    used: str
    reason: str

    def record(self) -> dict:
        return {"window": self.window, "item": self.item, "default": self.default,
                "used": self.used, "reason": self.reason}


def _box(b: OrientationBounds) -> str:
    return f"theta box {b.theta_min:.2f}-{b.theta_max:.2f} rad"


def relax_windows(edges, params, failed_reasons: dict, plan_many):
    """Milder recipes for several windows, one round per tilt step: each round plans the
    variant of every window still failing at once (``plan_many(list of WindowTargets)`` ->
    one result with ``failures`` per window, e.g. in parallel); a window keeps the first
    variant that plans without a failure record.

    Args:
        edges: the failing windows' WindowEdges. params: the recipe's ProcessParameters.
        failed_reasons: window -> why the default failed (for the record).
        plan_many: callable planning windows' targets.

    Returns:
        (accepted: window -> (WindowTargets, result, Deviation), tried: window -> [(recipe
        item, the first failure it left)] per variant that failed).
    """
    from drakedeburr.plan.planner import _tool_path
    from drakedeburr.plan.window_targets import WindowTargets

    pending = list(edges)
    accepted, tried = {}, {e.index: [] for e in edges}
    for box in TILT_STEPS:
        batch = []
        for edge in pending:
            default = params.bounds(edge.kind)
            if box.theta_max >= default.theta_max and box.theta_min >= default.theta_min:
                continue  # not milder than the recipe's own box
            p = replace(params, bounds_large=box, bounds_small=box)
            batch.append((edge, WindowTargets.from_tool_path(_tool_path(edge, p))))
        if not batch:
            continue
        results = plan_many([wt for _, wt in batch])
        for (edge, wt), res in zip(batch, results, strict=True):
            log.info("window %d: relaxed to %s: %d failure records", edge.index, _box(box),
                     len(res.failures))
            if not res.failures:
                accepted[edge.index] = (wt, res, Deviation(
                    edge.index, "tool tilt", _box(params.bounds(edge.kind)), _box(box),
                    f"the recipe's box failed: {failed_reasons.get(edge.index, '')}"))
                pending.remove(edge)
            else:
                tried[edge.index].append((_box(box), str(res.failures[0])))
    return accepted, tried
