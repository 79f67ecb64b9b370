"""Recipe relaxation: a window the default recipe cannot cut is planned again with a milder
one, and the deviation is recorded (``plan.meta["recipe_deviations"]``) and shown in the report.

What is relaxed, in order, for a window whose plan leaves failure records:

1. the tool tilt: the large windows' (theta_A, theta_B) box of the source (0.26-0.44 rad) is
   meant for a flat face; on a dished or rising face the spindle body leans into the face
   beyond the opening (the bundled deep-dish hub needed exactly this, by hand). The window is
   oriented again with the small windows' box (0.09-0.26 rad), then with 0-0.15 rad;
2. nothing else is tried automatically: a slower feed does not make a motion feasible (the
   timing already slows wherever a limit binds), and the cell has one burr model (a smaller
   burr would need its tool model and depth of cut). Both stay the recipe's to change.

Each variant is planned for the window alone; the first that plans without a failure record
is kept and the hub is planned again with it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

from drakedeburr.config import OrientationBounds

__all__ = ["Deviation", "TILT_STEPS", "relaxed_targets"]

log = logging.getLogger(__name__)

#: tilt boxes tried in turn, milder each step [rad]
TILT_STEPS = (OrientationBounds(0.09, 0.26), OrientationBounds(0.0, 0.15))


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


def relaxed_targets(edge, params, failed_reason: str, plan_one):
    """A window's targets under the first milder recipe that ``plan_one(wt)`` (a plan of the
    window alone) plans without failure records, and the deviation ((None, None) when none
    does), and what was tried: (recipe item, the first failure it left) per variant.

    Args:
        edge: the hub's WindowEdge. params: the recipe's ProcessParameters.
        failed_reason: why the default failed (for the record).
        plan_one: callable WindowTargets -> Plan.
    """
    from drakedeburr.plan.planner import _tool_path
    from drakedeburr.plan.window_targets import WindowTargets

    default = params.bounds(edge.kind)
    tried = []
    for box in TILT_STEPS:
        if box.theta_max >= default.theta_max and box.theta_min >= default.theta_min:
            continue  # not milder than the recipe's own box
        p = replace(params, bounds_large=box, bounds_small=box)
        wt = WindowTargets.from_tool_path(_tool_path(edge, p))
        trial = plan_one(wt)
        log.info("window %d: relaxed to %s: %d failure records", edge.index, _box(box),
                 len(trial.failures))
        if not trial.failures:
            return wt, Deviation(edge.index, "tool tilt", _box(default), _box(box),
                                 f"the recipe's box failed: {failed_reason}"), tried
        tried.append((_box(box), str(trial.failures[0])))
    return None, None, tried
