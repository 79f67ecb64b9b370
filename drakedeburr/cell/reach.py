"""Reachability survey: can the robot put the cutting point on every point of the hub face?

Used to choose (and to test) the fixture pose of the tool-in-hand cell and the stand pose of the
workpiece-in-hand cell. For each target point p_HQ on the hub face and each tool axis direction
a_H (both in the hub frame H) it solves a Drake InverseKinematics problem

    p_TQ = 0 (cutting point on the target),  angle(+Z_T, a_H) <= axis_tolerance,
    q within the joint limits shrunk by ``joint_margin``, |q_5| >= ``wrist_margin``,
    optional: every unfiltered geometry pair >= ``min_distance``, except the hub against the
    burr body (head, shank, collet): the survey puts the cutting point on the face plane, where
    the shank necessarily passes within ~3 mm of a solid face; at a real window edge the axis
    sits over the opening,

from several seeds, and re-checks each solution by forward kinematics. The same formulation
serves both modes because it constrains T relative to H.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drakedeburr.cell.station import Cell
from drakedeburr.frames.vectors import angle_between

__all__ = ["ReachTarget", "ReachOptions", "ReachResult", "ReachSurvey", "face_targets",
           "survey_reach", "WRIST_MARGIN"]


@dataclass(frozen=True)
class ReachTarget:
    """One target: a point on the hub face and a tool axis, in the hub frame H.

    Attributes:
        p_HQ: (3,) target point [m].
        a_H: (3,) unit tool axis direction +Z_T wanted at the target (points into the face).
    """

    p_HQ: np.ndarray
    a_H: np.ndarray


#: [rad] smallest |J5| a reachable target keeps (J5 = 0 is the wrist singularity): the mount
#: study's, and the planner's IK, seeds, cone probe and home (drakedeburr.plan.kinematics)
WRIST_MARGIN = 0.25


@dataclass(frozen=True)
class ReachOptions:
    """The survey's constraints and effort.

    Attributes:
        joint_margin: distance kept from every position limit [rad].
        wrist_margin: minimum |q_5| (J5 = 0 is the wrist singularity) [rad].
        min_distance: minimum clearance [m] between unfiltered geometry pairs, the burr
            head/hub pair excepted; None skips collision constraints.
        axis_tolerance: cone half-angle around a_H [rad] (small, non-zero: see DESIGN.md).
        position_tolerance: box half-width on p_TQ [m].
        seeds: number of initial guesses tried per target (home, wrist flips, random).
    """

    joint_margin: float = float(np.radians(10.0))
    wrist_margin: float = WRIST_MARGIN
    min_distance: float | None = 0.005
    axis_tolerance: float = 0.01
    position_tolerance: float = 1e-6
    seeds: int = 6


@dataclass(frozen=True)
class ReachResult:
    """Outcome for one target.

    Attributes:
        target: the target.
        success: a solution was found and passed the FK re-check.
        q: (6,) joints [rad] (NaN when not found).
        position_error: |p_TQ| from FK [m].
        axis_error: angle between +Z_T and a_H from FK [rad].
        clearance: smallest signed distance at q over the pairs the survey checks [m].
    """

    target: ReachTarget
    success: bool
    q: np.ndarray
    position_error: float
    axis_error: float
    clearance: float


@dataclass(frozen=True)
class ReachSurvey:
    """All results; ``failed`` lists the indices of targets without a solution."""

    results: tuple[ReachResult, ...]

    @property
    def failed(self) -> list[int]:
        return [i for i, r in enumerate(self.results) if not r.success]

    @property
    def all_reached(self) -> bool:
        return not self.failed

    @property
    def min_wrist(self) -> float:
        """Smallest |q_5| over the solutions [rad]."""
        return float(min((abs(r.q[4]) for r in self.results if r.success), default=np.nan))


def face_targets(
    radius: float, *, rings: int = 2, per_ring: int = 8, tilt: float = 0.5, tilts: int = 4
) -> list[ReachTarget]:
    """Targets on a disc of the face z_H = 0: centre plus ``rings`` rings up to ``radius``.

    Each point gets the axis -Z_H and ``tilts`` axes tilted by ``tilt`` [rad] from it at evenly
    spaced azimuths.
    """
    points = [np.zeros(3)]
    for k in range(1, rings + 1):
        r = radius * k / rings
        for phi in np.linspace(0.0, 2 * np.pi, per_ring, endpoint=False):
            points.append(np.array([r * np.cos(phi), r * np.sin(phi), 0.0]))
    axes = [np.array([0.0, 0.0, -1.0])]
    for b in np.linspace(0.0, 2 * np.pi, tilts, endpoint=False):
        axes.append(np.array([np.sin(tilt) * np.cos(b), np.sin(tilt) * np.sin(b), -np.cos(tilt)]))
    return [ReachTarget(p, a) for p in points for a in axes]


def survey_reach(
    cell: Cell,
    targets: list[ReachTarget],
    options: ReachOptions = ReachOptions(),
    progress: Callable[[int, int, str], None] | None = None,
) -> ReachSurvey:
    """Solve IK for every target (see module docstring). Failing targets are reported, not raised.

    Args:
        cell: the cell.
        targets: from :func:`face_targets` or your own.
        options: margins, clearance, tolerances and seeds (:class:`ReachOptions`).
        progress: optional callback (done, total, label).
    """
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

    plant = cell.plant
    context = cell.create_context()
    sg_context = cell.scene_graph.GetMyMutableContextFromRoot(context)
    inspector = cell.scene_graph.model_inspector()
    burr_frames = {inspector.GetFrameId(g) for g in cell.burr_head_ids}
    burr_body_ids = [g for g in cell.burr_head_ids | cell.robot_ids | cell.environment_ids
                     if inspector.GetFrameId(g) in burr_frames]
    cell.scene_graph.collision_filter_manager(sg_context).Apply(
        CollisionFilterDeclaration().ExcludeBetween(
            GeometrySet(burr_body_ids), GeometrySet(list(cell.hub_ids))))
    plant_context = plant.GetMyMutableContextFromRoot(context)
    wrist_margin, min_distance = options.wrist_margin, options.min_distance
    axis_tolerance, position_tolerance = options.axis_tolerance, options.position_tolerance
    seeds = options.seeds

    lo = np.asarray(cell.q_lower) + options.joint_margin
    hi = np.asarray(cell.q_upper) - options.joint_margin
    rng = np.random.default_rng(0)
    seed_list = [np.asarray(cell.q_home, float)]
    flips = ((0, 0, 0, np.pi, 0, np.pi), (0, 0, 0, np.pi / 2, 0, 0), (0, 0, 0, -np.pi / 2, 0, 0))
    for flip in flips:
        seed_list.append(np.clip(cell.q_home + np.asarray(flip), lo, hi))
    while len(seed_list) < seeds:
        seed_list.append(rng.uniform(0.5 * lo, 0.5 * hi))
    seed_list = seed_list[:seeds]

    results = []
    for i, target in enumerate(targets):
        prev = results[-1].q if results and results[-1].success else None
        found = _solve_target(cell, plant_context, target, ([prev] if prev is not None else [])
                              + seed_list, (lo, hi), options)
        if found is None:
            results.append(ReachResult(target, False, np.full(6, np.nan), np.nan, np.nan, np.nan))
        else:
            a_H = np.asarray(target.a_H, float) / np.linalg.norm(target.a_H)
            X_HT = cell.X_HT(found)
            pos_err = float(np.linalg.norm(X_HT.inverse().multiply(target.p_HQ)))
            z_T = X_HT.rotation().matrix()[:, 2]
            axis_err = float(angle_between(z_T, a_H))
            clearance = _clearance(cell, context, found)
            ok = (pos_err <= 10 * position_tolerance and axis_err <= 1.01 * axis_tolerance + 1e-6
                  and np.all(found >= lo - 1e-9) and np.all(found <= hi + 1e-9)
                  and abs(found[4]) >= wrist_margin - 1e-9
                  and (min_distance is None or clearance >= min_distance - 1e-4))
            results.append(ReachResult(target, bool(ok), found, pos_err, axis_err, clearance))
        if progress is not None:
            progress(i + 1, len(targets), "reach")
    return ReachSurvey(tuple(results))


def _solve_target(cell: Cell, plant_context, target: ReachTarget, seeds: list,
                  bounds: tuple[np.ndarray, np.ndarray], options: ReachOptions
                  ) -> np.ndarray | None:
    """Joints reaching one target within the joint ``bounds`` (lo, hi) from the first seed (and
    J5 sign) that solves, or None."""
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import SnoptSolver, Solve

    plant = cell.plant
    lo, hi = bounds
    wrist_margin, min_distance = options.wrist_margin, options.min_distance
    axis_tolerance, position_tolerance = options.axis_tolerance, options.position_tolerance
    a_H = np.asarray(target.a_H, float) / np.linalg.norm(target.a_H)
    for seed in seeds:
        for sign in (1.0, -1.0):
            ik = InverseKinematics(plant, plant_context, with_joint_limits=False)
            ik.AddPositionConstraint(
                cell.hub_frame, target.p_HQ, cell.tool_frame,
                -position_tolerance * np.ones(3), position_tolerance * np.ones(3))
            ik.AddAngleBetweenVectorsConstraint(
                cell.hub_frame, a_H, cell.tool_frame, [0.0, 0.0, 1.0], 0.0, axis_tolerance)
            if min_distance is not None:
                ik.AddMinimumDistanceLowerBoundConstraint(min_distance, 0.05)
            prog = ik.get_mutable_prog()
            q = ik.q()
            lo_i, hi_i = lo.copy(), hi.copy()
            if sign > 0:
                lo_i[4] = max(lo_i[4], wrist_margin)
            else:
                hi_i[4] = min(hi_i[4], -wrist_margin)
            prog.AddBoundingBoxConstraint(lo_i, hi_i, q)
            start = np.clip(seed, lo_i, hi_i)
            prog.AddQuadraticErrorCost(0.05 * np.eye(6), start, q)
            prog.SetInitialGuess(q, start)
            solver = SnoptSolver()
            result = solver.Solve(prog) if solver.available() else Solve(prog)
            if result.is_success():
                return result.GetSolution(q)
    return None


def _clearance(cell: Cell, context, q: np.ndarray) -> float:
    """Smallest signed distance [m] at q with the survey's filters (held in ``context``)."""
    plant_context = cell.plant.GetMyMutableContextFromRoot(context)
    cell.plant.SetPositions(plant_context, q)
    query = cell.scene_graph.get_query_output_port().Eval(
        cell.scene_graph.GetMyContextFromRoot(context))
    pairs = query.ComputeSignedDistancePairwiseClosestPoints(1.0)
    return float(min((p.distance for p in pairs), default=1.0))
