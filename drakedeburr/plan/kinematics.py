"""Cell kinematics for planning: the fixed transforms of a cell, analytic IK and clearance.

Both cells are one code path. What differs is which of the tool frame T and the hub frame H
rides on the flange F:

* tool-in-hand (``mode="tool"``): ``X_FT`` is fixed (spindle on the flange), ``X_WH`` is fixed
  (hub on the fixture); ``X_WF = X_WH X_HT X_FT^-1``.
* workpiece-in-hand (``mode="workpiece"``): ``X_FH`` is fixed (hub in the gripper), ``X_WT`` is
  fixed (spindle stand, the virtual TCP); ``X_WF = X_WT X_HT^-1 X_FH^-1``.

The planner thinks in the process pose ``X_HT`` (tool relative to hub); this module turns it
into flange poses and joints (analytic OPW IK from :mod:`drakedeburr.robots.opw_ik`, checked
against Drake's FK in the tests) and measures clearance with the burr-head/hub pair filtered.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drakedeburr.cell.narrowphase import ShapeSupport, certified_distance
from drakedeburr.cell.reach import WRIST_MARGIN as REACH_WRIST_MARGIN
from drakedeburr.frames.vectors import inverse_transform

#: cone probe results kept per checker (:meth:`ClearanceChecker.memo_probe`), at most this many
PROBE_MEMO_SIZE = 4096
#: :meth:`ClearanceChecker.pairs_within` answers kept per checker (the oldest dropped first):
#: the same configuration is read again by the policy's passes and the IK's retries (a
#: quarter of the audibot rim's reads), and a reading is a function of the configuration
PAIRS_MEMO_SIZE = 20000

__all__ = ["CellKinematics", "ClearanceChecker", "cell_kinematics", "resolve_level",
           "DISTANCE_SLACK", "NARROWPHASE_SLACK", "JOINT_WEIGHTS", "WRIST_MARGIN"]

#: (6,) weights of joint travel wherever the planner weighs it (the IK's ``q - q_prev`` cost,
#: the home search, the placement's branch sequence): the wrist joints cheaper
JOINT_WEIGHTS = (1.0, 1.0, 1.0, 0.3, 0.3, 0.3)

#: [rad] smallest |J5| the planner's IK, seeds, cone probe and home keep (J5 = 0 is the wrist
#: singularity): the mount study's own (:data:`drakedeburr.cell.reach.WRIST_MARGIN`), above the
#: verifier's ``Tolerances.wrist_margin``
WRIST_MARGIN = REACH_WRIST_MARGIN

# numerical slack of the clearance acceptance [m]: the IK's own bound ends exactly on 2 mm at a
# few fillet targets, and the signed-distance query of the mesh pieces is good to ~1e-7 m
DISTANCE_SLACK = 1e-6

#: how much farther than asked the cell's distance query looks [m], so that a pair Drake's
#: narrow phase reads too far is still certified: 1.3 mm seen on the default hub's plan, 3.9 mm
#: on an unseen random hub. No margin bounds FCL's error; the verifier, which reads pairs
#: without a cap, decides (docs/verify.md)
NARROWPHASE_SLACK = 5e-3


@dataclass(frozen=True, eq=False)
class CellKinematics:
    """Fixed transforms of a cell and the robot's analytic kinematics.

    Attributes:
        mode: "tool" or "workpiece".
        X_FT: (4, 4) tool in flange [m] (tool mode; identity placeholder otherwise).
        X_WH: (4, 4) hub in world [m] (tool mode; hub pose at ``q_home`` otherwise).
        X_FH: (4, 4) hub in flange [m] (workpiece mode).
        X_WT: (4, 4) tool in world [m] (workpiece mode; tool pose at ``q_home`` otherwise).
        robot: ``drakedeburr.robots.RobotKinematics`` of ``cell.arm`` with the cell's limits.
        q_lower, q_upper: (6,) joint limits [rad]; v_max, a_max: (6,) [rad/s], [rad/s^2].
        q_home: (6,) [rad].
        X_WB: (4, 4) robot base B in world [m] (the arm's mount; the OPW maps work in B).
    """

    mode: str
    X_FT: np.ndarray
    X_WH: np.ndarray
    X_FH: np.ndarray
    X_WT: np.ndarray
    robot: object
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    q_home: np.ndarray
    X_WB: np.ndarray = field(default_factory=lambda: np.eye(4))

    def X_WF_from_X_HT(self, X_HT: np.ndarray) -> np.ndarray:
        """(..., 4, 4) process poses -> (..., 4, 4) flange poses in world [m]."""
        X_HT = np.asarray(X_HT, float)
        if self.mode == "tool":
            return self.X_WH @ X_HT @ np.linalg.inv(self.X_FT)
        return self.X_WT @ inverse_transform(X_HT) @ np.linalg.inv(self.X_FH)

    def X_HT_from_X_WF(self, X_WF: np.ndarray) -> np.ndarray:
        """(..., 4, 4) flange poses -> (..., 4, 4) process poses X_HT [m]."""
        X_WF = np.asarray(X_WF, float)
        if self.mode == "tool":
            return np.linalg.inv(self.X_WH) @ X_WF @ self.X_FT
        return inverse_transform(X_WF @ self.X_FH) @ self.X_WT

    def fk_flange(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints [rad] -> (..., 4, 4) X_WF (analytic)."""
        from drakedeburr.robots.opw import fk_opw

        return self.X_WB @ fk_opw(self.robot.opw, np.asarray(q, float))

    def X_HT_from_q(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints -> (..., 4, 4) tool pose relative to the hub."""
        return self.X_HT_from_X_WF(self.fk_flange(q))

    def p_HT(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints -> (..., 3) tool point relative to the hub [m]."""
        return self.X_HT_from_q(q)[..., :3, 3]

    def X_WT_from_q(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints -> (..., 4, 4) tool pose in world."""
        if self.mode == "tool":
            return self.fk_flange(q) @ self.X_FT
        X = np.broadcast_to(self.X_WT, np.shape(q)[:-1] + (4, 4))
        return np.array(X)

    def X_WH_from_q(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints -> (..., 4, 4) hub pose in world."""
        if self.mode == "workpiece":
            return self.fk_flange(q) @ self.X_FH
        return np.array(np.broadcast_to(self.X_WH, np.shape(q)[:-1] + (4, 4)))

    def within_limits(self, q: np.ndarray, slack: float = 1e-9) -> np.ndarray:
        q = np.asarray(q, float)
        return np.all((q >= self.q_lower - slack) & (q <= self.q_upper + slack), axis=-1)

    def ik_all(self, X_WF: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All analytic IK branches of flange poses.

        Args:
            X_WF: (N, 4, 4) flange poses [m].

        Returns:
            q (N, 8, 6) [rad] wrapped to (-pi, pi] (NaN where unreachable) and branch signs
            (8, 3) (shoulder, elbow, wrist).
        """
        from drakedeburr.robots.opw_ik import ik_opw

        X_BF = inverse_transform(self.X_WB) @ np.asarray(X_WF, float).reshape(-1, 4, 4)
        sols = ik_opw(self.robot.opw, X_BF)
        return sols.q, sols.branch

    def branch_of(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) joints -> (..., 3) branch signs (shoulder, elbow, wrist)."""
        from drakedeburr.robots.opw_ik import arm_branches

        return arm_branches(self.robot.opw, q)

    def track(self, X_WF: np.ndarray, q_start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joints along a dense flange-pose sequence keeping ``q_start``'s branch.

        At each pose the solution of the same (shoulder, elbow, wrist) branch is taken and
        every joint is unwrapped by 2*pi toward the previous sample (no 2*pi jumps).

        Args:
            X_WF: (N, 4, 4) flange poses [m].
            q_start: (6,) joints of the robot just before the first pose [rad].

        Returns:
            q (N, 6) [rad] (NaN rows where the branch does not reach) and ok (N,) bool
            (reached, inside joint limits).
        """
        q_all, branches = self.ik_all(X_WF)
        b0 = self.branch_of(q_start)
        match = np.flatnonzero(np.all(branches == b0[None], axis=1))
        n = q_all.shape[0]
        q_out = np.full((n, 6), np.nan)
        ok = np.zeros(n, bool)
        q_prev = np.asarray(q_start, float)
        for i in range(n):
            cand = q_all[i, match]
            cand = cand[~np.any(np.isnan(cand), axis=1)]
            if cand.size == 0:
                continue
            # unwrap every joint toward the previous sample
            cand = q_prev + np.mod(cand - q_prev + np.pi, 2 * np.pi) - np.pi
            j = int(np.argmin(np.abs(cand - q_prev).sum(axis=1)))
            q_out[i] = cand[j]
            ok[i] = bool(self.within_limits(cand[j]))
            q_prev = cand[j]
        return q_out, ok


def cell_kinematics(cell) -> CellKinematics:
    """Fixed transforms of a loaded :class:`drakedeburr.cell.Cell` (read at ``q_home``)."""
    from drakedeburr.robots.opw_ik import JointLimits, RobotKinematics

    q = np.asarray(cell.q_home, float)
    X_WF = cell.X_WF(q).GetAsMatrix4()
    X_WT = cell.X_WT(q).GetAsMatrix4()
    X_WH = cell.X_WH(q).GetAsMatrix4()
    X_FW = np.linalg.inv(X_WF)
    robot = RobotKinematics(
        opw=cell.arm.opw,
        limits=JointLimits(lower=tuple(map(float, cell.q_lower)),
                           upper=tuple(map(float, cell.q_upper))),
        controller=cell.arm.controller, name=cell.arm.name)
    return CellKinematics(
        mode=cell.mode, X_FT=X_FW @ X_WT, X_WH=X_WH, X_FH=X_FW @ X_WH, X_WT=X_WT, robot=robot,
        q_lower=np.array(cell.q_lower), q_upper=np.array(cell.q_upper),
        v_max=np.minimum(-np.array(cell.v_lower), np.array(cell.v_upper)),
        a_max=np.minimum(-np.array(cell.a_lower), np.array(cell.a_upper)),
        q_home=q.copy(), X_WB=cell.X_WB().GetAsMatrix4())


def resolve_level(tolerances) -> float:
    """Where a clearance reading is solved exactly (:meth:`ClearanceChecker.reading`): the
    clearance bound plus ``Tolerances.narrowphase_resolve`` [m]."""
    return float(tolerances.min_clearance + tolerances.narrowphase_resolve)


def _spin_invariant_ids(checker: ClearanceChecker, tol: float = 1e-9) -> tuple[frozenset,
                                                                                frozenset]:
    """(tool geometries rotationally symmetric about the burr axis, geometries rigidly attached
    to the hub) of the checker's cell (:meth:`ClearanceChecker.spin_invariant`)."""
    from pydrake.geometry import Capsule, Cylinder, Sphere

    cell = checker.cell
    plant, query = cell.plant, checker.query_at(cell.q_home)

    def welded_ids(frame) -> set:
        return {g for b in plant.GetBodiesWeldedTo(frame.body())
                for g in plant.GetCollisionGeometriesForBody(b)}

    X_WT = cell.tool_frame.CalcPoseInWorld(checker.plant_context).GetAsMatrix4()
    o, z = X_WT[:3, 3], X_WT[:3, 2]
    sym = set()
    for g in welded_ids(cell.tool_frame):
        shape, X = query.inspector().GetShape(g), query.GetPoseInWorld(g).GetAsMatrix4()
        c = X[:3, 3] - o
        on_axis = bool(np.linalg.norm(c - (c @ z) * z) <= tol)
        coaxial = on_axis and bool(np.linalg.norm(np.cross(X[:3, 2], z)) <= tol)
        if (isinstance(shape, Sphere) and on_axis
                or isinstance(shape, (Cylinder, Capsule)) and coaxial):
            sym.add(g)
    return frozenset(sym), frozenset(welded_ids(cell.hub_frame))


@dataclass(eq=False)
class ClearanceChecker:
    """Signed distances of a cell with the burr-head/hub (process contact) pair filtered.

    Owns one diagram context whose scene-graph collision filters exclude the burr head against
    the hub (``SceneGraph.collision_filter_manager(context)``); every other pair counts. Used
    by the IK (its plant context carries the filter into MinimumDistanceLowerBoundConstraint)
    and by the dense checks. ``filter_burr_contact=False`` counts the burr head too: moves
    that do not cut (transitions, home) must keep it clear of the hub as well. Its readings are
    certified as the verifier's are (:meth:`reading`; ``tolerances``: the run's, default the
    default tolerances), so the planner and the verifier see the same distances.
    """

    cell: object
    filter_burr_contact: bool = True
    tolerances: object = None
    context: object = field(init=False)
    plant_context: object = field(init=False)
    _sg_context: object = field(init=False)
    #: what the planner's modules derive from this checker once and keep with it, each
    #: written by one owner: cone probe results (:meth:`memo_probe`, for
    #: :func:`drakedeburr.plan.ik_seeds.cone_clearance_probe`) and the counted body pairs of a
    #: motion bound (``clearance._counted``: ``(bound, pairs)``)
    probes: dict = field(init=False, default_factory=dict, repr=False)
    counted: tuple | None = field(init=False, default=None, repr=False)
    _read: dict = field(init=False, default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        c = self.cell
        self.context = c.diagram.CreateDefaultContext()
        self._sg_context = c.scene_graph.GetMyContextFromRoot(self.context)
        if self.filter_burr_contact:
            c.scene_graph.collision_filter_manager(self._sg_context).Apply(
                CollisionFilterDeclaration().ExcludeBetween(
                    GeometrySet(list(c.burr_head_ids)), GeometrySet(list(c.hub_ids))))
        self.plant_context = c.plant.GetMyMutableContextFromRoot(self.context)
        if self.tolerances is None:
            from drakedeburr.config import default_tolerances

            self.tolerances = default_tolerances()
        self.resolve_below = resolve_level(self.tolerances)
        self.solve_from = float(self.tolerances.min_clearance)
        self._supports: dict = {}

    def query_at(self, q: np.ndarray):
        """The scene graph's ``QueryObject`` with the robot at ``q`` (valid until the next
        call on this checker)."""
        self.cell.plant.SetPositions(self.plant_context, np.asarray(q, float))
        return self.cell.scene_graph.get_query_output_port().Eval(self._sg_context)

    def collides(self, q: np.ndarray) -> bool:
        """Whether any unfiltered pair is in contact at ``q`` (Drake's broadphase + contact
        test, ~10x cheaper than the signed distances: a pose in contact fails any clearance
        bound, whatever its depth)."""
        return bool(self.query_at(q).HasCollisions())

    def ranked_distance(self, q: np.ndarray, max_distance: float) -> float:
        """:meth:`distance` where the pose is clear of contact; in contact, minus the deepest
        penetration (Drake's contact query, ~0.7 ms with the contact test against 2-3 ms for
        the signed distances of a posed hub cell). For ranking poses: a pose in contact fails
        any clearance bound, and its depth says by how much."""
        return self.axis_reading(q, max_distance)[0]

    def axis_reading(self, q: np.ndarray, max_distance: float) -> tuple[float, float]:
        """(:meth:`ranked_distance`, an upper bound [m] on the spin-invariant pairs' true
        distance at ``q``: inf where none is within ``max_distance``). The second figure holds
        for every pose with the tool axis and tool point of ``q`` (:meth:`spin_invariant`):
        minus a penetration depth where such a pair is in contact, else Drake's own reading
        (the distance of witness points on the two shapes, never below the true distance; the
        certified reading is a lower bound and cannot serve here)."""
        invariant = self.spin_invariant()  # first: finding it poses the context
        query = self.query_at(q)
        if query.HasCollisions():
            try:
                pen = query.ComputePointPairPenetration()
                return (-float(max(p.depth for p in pen)),
                        min((-float(p.depth) for p in pen
                             if invariant(p.id_A, p.id_B)), default=np.inf))
            except RuntimeError:  # a shape pair without a penetration query: signed distances
                pass
        best, upper = float(max_distance), np.inf
        for r in query.ComputeSignedDistancePairwiseClosestPoints(
                max_distance + NARROWPHASE_SLACK):
            if invariant(r.id_A, r.id_B):
                upper = min(upper, float(r.distance))
            best = min(best, self.reading(query, r))
        return best, upper

    def spin_invariant(self):
        """Predicate on a geometry pair: does its distance stay the same for every pose that
        puts the tool point and tool axis at the same place on the hub (every spin about the
        axis, every arm branch)? True for a geometry of the tool that is rotationally symmetric
        about the burr axis (a sphere centred on it; a cylinder or capsule coaxial with it:
        collet, shank, a coaxial spindle body) against any geometry rigidly attached to the
        hub (the hub, its fixture or gripper): the tool and the hub then keep their relative
        pose up to a turn about that axis. Found from the cell's geometry once."""
        if "_spin_invariant" not in self.__dict__:
            sym, rigid = _spin_invariant_ids(self)
            self.__dict__["_spin_invariant"] = (
                lambda a, b: (a in sym and b in rigid) or (b in sym and a in rigid))
        return self.__dict__["_spin_invariant"]

    def memo_probe(self, key: bytes, compute):
        """The cone probe result kept under ``key``, else ``compute()`` kept (the oldest of
        :data:`PROBE_MEMO_SIZE` dropped first)."""
        if key not in self.probes:
            if len(self.probes) >= PROBE_MEMO_SIZE:
                del self.probes[next(iter(self.probes))]
            self.probes[key] = compute()
        return self.probes[key]

    def reading(self, query, r) -> float:
        """Drake's signed distance ``r`` (a ``SignedDistancePair`` of ``query``) held to a
        rigorous lower bound (:func:`drakedeburr.cell.narrowphase.certified_distance`:
        Drake's narrow phase can read a distance over 1 mm too large), solved exactly where
        that bound falls below ``resolve_below`` [m] (:func:`resolve_level`) unless Drake's
        reading itself is below the clearance bound (the pose fails whatever the error: its
        bound is kept); contact (<= 0) as read."""
        d = float(r.distance)
        if not d > 0.0:
            return d
        A, B = self._support(query, r.id_A), self._support(query, r.id_B)
        return certified_distance(
            d, np.asarray(r.nhat_BA_W), A,
            None if A.fixed else query.GetPoseInWorld(r.id_A).GetAsMatrix4(), B,
            None if B.fixed else query.GetPoseInWorld(r.id_B).GetAsMatrix4(),
            solve_below=self.resolve_below, solve_from=self.solve_from)[0]

    def _support(self, query, gid):
        """The support of geometry ``gid``; fixed at its world pose when its body is welded
        to the world (the hub in the tool-in-hand cell, the spindle in the other)."""
        s = self._supports.get(gid)
        if s is None:
            s = ShapeSupport(query.inspector().GetShape(gid))
            if gid in self._welded_ids():
                s = s.posed(query.GetPoseInWorld(gid).GetAsMatrix4())
            self._supports[gid] = s
        return s

    def _welded_ids(self) -> frozenset:
        ids = self.__dict__.get("_welded")
        if ids is None:
            plant, sg = self.cell.plant, self.cell.scene_graph
            inspector = sg.model_inspector()
            ids = frozenset(g for b in plant.GetBodiesWeldedTo(plant.world_body())
                            for g in inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(
                                b.index())))
            self.__dict__["_welded"] = ids
        return ids

    def pairs_within(self, q: np.ndarray, max_distance: float) -> list:
        """(pair ids, certified reading [m]) of every unfiltered pair whose certified reading
        is within ``max_distance`` [m] at ``q``; Drake is asked ``NARROWPHASE_SLACK`` farther
        so that a pair its narrow phase reads too far is still found. Kept per configuration
        and distance (:data:`PAIRS_MEMO_SIZE`): a configuration read again is answered with
        the same readings without posing the context."""
        key = (np.asarray(q, float).tobytes(), float(max_distance))
        if key not in self._read:
            if len(self._read) >= PAIRS_MEMO_SIZE:
                del self._read[next(iter(self._read))]
            self._read[key] = tuple(self._pairs(self.query_at(q), max_distance))
        return list(self._read[key])

    def _pairs(self, query, max_distance: float) -> list:
        """:meth:`pairs_within` on a posed ``query``."""
        out = []
        for r in query.ComputeSignedDistancePairwiseClosestPoints(
                max_distance + NARROWPHASE_SLACK):
            d = self.reading(query, r)
            if d <= max_distance:
                out.append(((r.id_A, r.id_B), d))
        return out

    def distance(self, q: np.ndarray, max_distance: float = 0.01) -> float:
        """Smallest certified signed distance [m] at ``q``, capped at ``max_distance`` (no
        pair names)."""
        best = float(max_distance)
        for _, d in self.pairs_within(q, max_distance):
            best = min(best, d)
        return best

    def min_distances_along(self, q: np.ndarray, max_distance: float) -> np.ndarray:
        """(N,) :meth:`distance` at each row of a dense path ``q`` (N, 6), equal to it row by
        row, with far fewer queries (:func:`drakedeburr.plan.clearance.distances_along`)."""
        from drakedeburr.plan.clearance import distances_along

        return distances_along(self, q, max_distance)[0]

    def min_distance(self, q: np.ndarray,
                     max_distance: float = 0.01) -> tuple[float, tuple[str, str]]:
        """Smallest signed distance [m] at ``q`` (capped at ``max_distance``) and its pair."""
        best, pair = float(max_distance), ("", "")
        for ids, d in self.pairs_within(q, max_distance):
            if d < best:
                best, pair = d, ids
        if pair[0] == "":
            return best, pair
        inspector = self.cell.scene_graph.model_inspector()  # names do not depend on q
        return best, (self._label(inspector, pair[0]), self._label(inspector, pair[1]))

    def _label(self, inspector, gid) -> str:
        body = self.cell.plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        model = self.cell.plant.GetModelInstanceName(body.model_instance())
        return f"{model}::{body.name()}/{inspector.GetName(gid)}"

    def distance_constraint(self, bound: float, influence: float):
        """A ``MinimumDistanceLowerBoundConstraint`` on this context (built once per bound:
        building one enumerates every collision pair, ~0.1 s with a detailed hub)."""
        key = (round(bound, 9), round(influence, 9))
        cache = self.__dict__.setdefault("_constraints", {})
        if key not in cache:
            from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint

            cache[key] = MinimumDistanceLowerBoundConstraint(
                self.cell.plant, bound, self.plant_context, None, influence)
        return cache[key]

    def min_distances(self, q: np.ndarray, max_distance: float = 0.01) -> np.ndarray:
        """(N,) smallest signed distance [m] for each row of ``q`` (N, 6), capped."""
        return np.array([self.distance(row, max_distance) for row in np.atleast_2d(q)])
