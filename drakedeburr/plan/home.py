"""The home a hub is planned from: the cell's own home where this hub leaves it clear, else the
nearest clear configuration to it, recorded as a recipe deviation.

A cell's home (:class:`drakedeburr.robots.CellMount`) was chosen with a stand-in hub
(:mod:`drakedeburr.cell.mounts`). A hub much larger or deeper than that one may touch the arm
there: seen on a 21 in hub held in the gripper, where at the home (J5 = 1.83 rad) the hub's rim
reaches into the robot's own forearm (-0.88 mm), so no move out of home can be clear.

Where the home's clearance (every pair, the burr head included: nothing cuts at home) is below
:data:`HOME_CLEARANCE` (the mount study's home margin), the home is moved to the configuration
nearest to it (joint travel weighted by :data:`drakedeburr.plan.kinematics.JOINT_WEIGHTS`, as
the placement search weighs it) that keeps that clearance, the joints :data:`JOINT_MARGIN`
inside their limits and the wrist :data:`drakedeburr.plan.kinematics.WRIST_MARGIN` off its
singularity on the home's own side. Drake's ``InverseKinematics``-style program (SNOPT, a
``MinimumDistanceLowerBoundConstraint``) from a fixed list of starts, every answer re-read by
the clearance checker; deterministic. The plan records the home it used
(``plan.meta["q_home"]``) and the deviation; the program starts and ends there and the verifier
builds the cell with it (:func:`drakedeburr.cell.station.load_plan_cell`).
"""

from __future__ import annotations

import logging

import numpy as np

from drakedeburr.plan.kinematics import JOINT_WEIGHTS, WRIST_MARGIN
from drakedeburr.plan.relax import Deviation

__all__ = ["HOME_CLEARANCE", "JOINT_MARGIN", "clear_home"]

log = logging.getLogger(__name__)

HOME_CLEARANCE = 5e-3  # [m] as the mount study's home (cell.mounts)
JOINT_MARGIN = np.radians(10.0)  # [rad] inside each joint limit, as the mount study
_WEIGHTS = np.asarray(JOINT_WEIGHTS)  # joint travel weighed as the placement search does
# starts: the home, the wrist unbent by steps (a held hub swings off the forearm), the upper
# arm raised / lowered; fixed, so the answer is the same on any machine
_STARTS = ((0.0, 0.0, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, -0.3, 0.0),
           (0.0, 0.0, 0.0, 0.0, -0.6, 0.0), (0.0, -0.2, 0.2, 0.0, 0.0, 0.0),
           (0.0, 0.2, -0.2, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.3, 0.0))


def _deg(q: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.1f}" for v in np.degrees(q)) + ") deg"


def _bounds(cell, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lo = np.asarray(cell.q_lower, float) + JOINT_MARGIN
    hi = np.asarray(cell.q_upper, float) - JOINT_MARGIN
    if q0[4] >= 0:  # the wrist stays on the home's side of J5 = 0
        lo[4] = max(lo[4], WRIST_MARGIN)
    else:
        hi[4] = min(hi[4], -WRIST_MARGIN)
    return lo, hi


def _nearest(checker, q0: np.ndarray, start: np.ndarray, lo, hi) -> np.ndarray | None:
    """The clear configuration SNOPT finds nearest to ``q0`` from ``start`` (None: none)."""
    from pydrake.solvers import MathematicalProgram, SnoptSolver

    prog = MathematicalProgram()
    q = prog.NewContinuousVariables(6, "q")
    prog.AddQuadraticErrorCost(np.diag(_WEIGHTS), q0, q)
    prog.AddBoundingBoxConstraint(lo, hi, q)
    # 1 mm above the bound: the constraint's smoothing reads a little high near it
    prog.AddConstraint(checker.distance_constraint(HOME_CLEARANCE + 1e-3, 0.05), q)
    result = SnoptSolver().Solve(prog, np.clip(start, lo, hi), None)
    if not result.is_success():
        return None
    return np.asarray(result.GetSolution(q), float)


def clear_home(cell, checker) -> tuple[np.ndarray, Deviation | None]:
    """The home to plan this hub from, and the deviation when it is not the cell's.

    Args:
        cell: the cell with the hub where it will sit (after the placement search).
        checker: a :class:`drakedeburr.plan.kinematics.ClearanceChecker` of ``cell`` that
            counts the burr head (``filter_burr_contact=False``).

    Returns:
        (q_home (6,) [rad], None) where the cell's home is clear by :data:`HOME_CLEARANCE`;
        else (the nearest clear configuration, its Deviation); the cell's home and None when
        no clear configuration is found (the moves out of home then fail with their reasons).
    """
    q0 = np.asarray(cell.q_home, float)
    d0, (a, b) = checker.min_distance(q0, 2 * HOME_CLEARANCE)
    if d0 >= HOME_CLEARANCE:
        return q0, None
    lo, hi = _bounds(cell, q0)
    best, best_cost = None, np.inf
    for step in _STARTS:
        q = _nearest(checker, q0, q0 + np.asarray(step), lo, hi)
        if q is None or np.any(q < lo - 1e-9) or np.any(q > hi + 1e-9):
            continue
        if checker.distance(q, 2 * HOME_CLEARANCE) < HOME_CLEARANCE:  # re-read, not trusted
            continue
        cost = float(_WEIGHTS @ (q - q0) ** 2)
        if cost < best_cost - 1e-12:
            best, best_cost = q, cost
    if best is None:
        log.warning("home: the cell's home is %.1f mm from %s / %s with this hub and no clear "
                    "configuration was found near it", 1e3 * d0, a, b)
        return q0, None
    log.warning("home: the cell's home is %.1f mm from %s / %s with this hub (%.0f mm asked); "
                "planned from %s instead", 1e3 * d0, a, b, 1e3 * HOME_CLEARANCE, _deg(best))
    return best, Deviation(
        window=-1, item="home", default=_deg(q0), used=_deg(best),
        reason=f"the cell's home is {1e3 * d0:.2f} mm from {a} / {b} with this hub; the "
               f"nearest configuration {1e3 * HOME_CLEARANCE:.0f} mm clear")
