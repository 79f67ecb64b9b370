"""Clearance along a dense joint path with a certified skip (fewer signed-distance queries,
the same numbers).

A signed-distance query of the whole cell (:meth:`ClearanceChecker.distance`) costs ~0.35-0.6
ms, most of it Drake's broadphase over the hub's hundreds of convex pieces; the planner asks it
at every dense sample of every cut, ~1500 samples a window, several times. Consecutive samples
are a fraction of a millimetre apart, and the pairs that come within the query's cap are few
(the burr shank over the hub face). So along a path:

* an *anchor* sample queries the whole cell with a larger radius ``cap + reach`` and keeps every
  pair within it, with its distance;
* at the following samples a kept pair's distance can have fallen by at most how far the points
  of its two geometries moved since it was last measured (:class:`MotionBound`, summed step by
  step along the path); a pair whose last distance minus that bound is still at least ``cap +
  slack`` is not queried; the others are queried one by one
  (``ComputeSignedDistancePairClosestPoints``: the same narrowphase as the full query, with
  bit-identical distances, and no broadphase);
* a pair that was not kept was farther than ``cap + reach`` at the anchor: a new anchor is
  queried before the motion since the anchor could bring one within ``cap + slack``. Only
  pairs the checker counts (its collision filters) can matter, so that motion is read per
  moving body against the fixed cell, and per counted pair of moving bodies as the motion of
  one body's geometries relative to the other's frame (:func:`anchor_travel`): two links of
  the arm turn together, and the distance between them changes only by the joints between
  them. (Before: the two largest travels of any geometries, e.g. the forearm's and the
  wrist's, which never meet - 110 anchors on a default-hub cut, now 70.)

Every pair whose distance at a sample is below ``cap`` is therefore measured exactly there, so
the result equals the full query's capped minimum at every sample. Every reading is the
checker's certified one (:meth:`ClearanceChecker.reading`: Drake's (FCL/libccd)
cylinder-vs-convex distances were measured up to 1.3 mm too large, so each is held to a
separating-plane lower bound and solved exactly near the clearance bound); ``slack`` covers
what is left of the readings' inconsistency between neighbouring configurations (a reading far
from the bound may be a loose lower bound at one sample and exact at the next), so a skip
never leans on a thinner margin.

:class:`MotionBound` is the motion bound (joint motion x link reach): a point of a geometry
moved by robot joints ``1..b`` is displaced by a joint change ``dq`` by at most
``sum_j |dq_j| R_j``, ``R_j`` a configuration-independent bound on its distance from joint
``j``'s axis: for ``j = b`` the distance of the geometry's points from that axis (fixed in link
``b``), for ``j < b`` the chain ``|o_{j+1} - o_j| + ... + |o'_b - o_{b-1}| + max |p - o'_b|``
of points ``o`` on the axes (each term fixed in one link's frame). Every moving geometry also
gets the rigid-motion bound of its body's poses (``|dp_c| + theta * r``, the plant's numpy
kinematic tree, :mod:`drakedeburr.cell.chain`), the smaller of the two is used: the joint-reach
bound of the wrist links summed ~3 m over a window where they move ~0.3 m, and every anchor
query it forced costs a broad phase over the whole cell. The verifier's clearance certificate
has its own bound (drakedeburr/verify); the two are to be unified.

Why hand-written: Drake's collision checkers query every configuration in full; skipping by a
motion bound along a given path is not offered for capped signed distances.

The second half of the module asks what no arm pose can change (issue 42, real wheels whose
loops run down spoke flanks): :class:`ToolScene` holds the cell's round tool parts (shank,
collet, spindle body, clamp: the same distance to the hub at every spin about the burr axis)
and the hub's pieces in one standalone SceneGraph, and :func:`tool_axis_clearance` searches a
cone of axes at each CL target by branch and bound (Drake readings; the bound is the tool's
rigid turn about its constrained point), proving where no axis of the cone keeps the
clearance. :func:`drakedeburr.plan.window.tool_refusal` refuses such a window before its IK.
"""

from __future__ import annotations

import heapq
import weakref
from dataclasses import dataclass

import numpy as np

from drakedeburr.cell.narrowphase import bounding_points

__all__ = ["MotionBound", "motion_bound", "step_displacements", "distances_along",
           "QUERY_SLACK", "AxisSearch", "ToolScene", "tool_scene", "spin_invariant_parts",
           "tool_axis_clearance", "cone_poses", "CONE_CELLS", "CONE_HALVINGS", "CONE_READS"]

#: margin [m] a skipped pair keeps over the cap: the distance query's own inconsistency
#: between neighbouring configurations (module docstring; 0.55 mm measured)
QUERY_SLACK = 1e-3


@dataclass(frozen=True, eq=False)
class MotionBound:
    """How far the points of each collision geometry can move for a joint change.

    Attributes:
        row: geometry id -> row of the arrays below.
        level: (G,) the last robot joint (1..6) that moves the geometry; 0 fixed in the world.
        reach: (G, 6) ``R[g, j]`` bound on the distance of the geometry's points from joint
            ``j+1``'s axis over every configuration [m] (0 for joints that do not move it).
        body: (G,) the plant body each geometry is fixed to (``tree`` numbering).
        c_B: (G, 3) its centre in that body's frame [m]; radius: (G,) the largest distance of
            its points from that centre [m] (moving geometries).
        tree: the plant's :class:`~drakedeburr.cell.chain.KinematicTree` (body poses).
    """

    row: dict
    level: np.ndarray
    reach: np.ndarray
    body: np.ndarray
    c_B: np.ndarray
    radius: np.ndarray
    tree: object


def _foot(p: np.ndarray, axis) -> np.ndarray:
    """The point of the line ``axis`` (point, unit direction) nearest ``p``."""
    a, u = axis
    return a + ((p - a) @ u) * u


def _chain_points(axes: list, tip: np.ndarray) -> np.ndarray:
    """Points o_j on each joint axis: o_6 nearest ``tip``, each o_j nearest o_{j+1}."""
    out = np.zeros((len(axes), 3))
    target = tip
    for j in range(len(axes) - 1, -1, -1):
        out[j] = target = _foot(target, axes[j])
    return out


def _reach_row(P: np.ndarray, rho: float, b: int, axes: list, o: np.ndarray) -> np.ndarray:
    """(6,) reach of a geometry with world support points P moved by joints 1..b."""
    row = np.zeros(len(axes))
    a, u = axes[b - 1]
    rel = P - a
    row[b - 1] = float(np.max(np.linalg.norm(rel - np.outer(rel @ u, u), axis=1))) + rho
    if b == 1:
        return row
    o_b = _foot(P.mean(axis=0), axes[b - 1])  # on axis b: fixed in links b-1 and b
    r = float(np.max(np.linalg.norm(P - o_b, axis=1))) + rho + np.linalg.norm(o_b - o[b - 2])
    for j in range(b - 2, -1, -1):
        row[j] = r
        if j > 0:
            r += float(np.linalg.norm(o[j] - o[j - 1]))
    return row


def motion_bound(cell) -> MotionBound:
    """The :class:`MotionBound` of a loaded cell (read at ``q_home``; kept in ``cell.memo``)."""
    cached = cell.memo.motion_bound
    if cached is not None:
        return cached
    from pydrake.geometry import Role

    from drakedeburr.robots import JOINT_NAMES

    plant, inspector = cell.plant, cell.scene_graph.model_inspector()
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, np.asarray(cell.q_home, float))
    level_of_body, axes = {}, []
    for k, name in enumerate(JOINT_NAMES, start=1):
        jt = plant.GetJointByName(name, cell.robot)
        for b in plant.GetBodiesWeldedTo(jt.child_body()):
            level_of_body[int(b.index())] = k
        X = jt.frame_on_child().CalcPoseInWorld(ctx)
        u = X.rotation().matrix() @ np.asarray(jt.revolute_axis(), float)
        axes.append((X.translation(), u / np.linalg.norm(u)))
    from drakedeburr.cell.chain import KinematicTree

    gids = list(inspector.GetAllGeometryIds(Role.kProximity))
    G = len(gids)
    level, body_of = np.zeros(G, int), np.zeros(G, int)
    support: list = [None] * G
    X_WB: dict = {}
    for i, gid in enumerate(gids):
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        body_of[i] = int(body.index())
        level[i] = level_of_body.get(body_of[i], 0)
        if level[i] == 0:
            continue
        X_WB[i] = plant.EvalBodyPoseInWorld(ctx, body).GetAsMatrix4()
        X_WG = X_WB[i] @ inspector.GetPoseInFrame(gid).GetAsMatrix4()
        P, rho = bounding_points(inspector.GetShape(gid))
        support[i] = (P @ X_WG[:3, :3].T + X_WG[:3, 3], rho)
    riders = [s[0] for s, lv in zip(support, level, strict=True) if lv == 6]
    o = _chain_points(axes, np.vstack(riders).mean(axis=0) if riders else axes[-1][0])
    reach, c_B, radius = np.zeros((G, 6)), np.zeros((G, 3)), np.zeros(G)
    for i in np.flatnonzero(level > 0):
        P, rho = support[i]
        reach[i] = _reach_row(P, rho, int(level[i]), axes, o)
        c = P.mean(axis=0)
        radius[i] = float(np.max(np.linalg.norm(P - c, axis=1))) + rho
        X_BW = np.linalg.inv(X_WB[i])
        c_B[i] = X_BW[:3, :3] @ c + X_BW[:3, 3]
    out = MotionBound(row={gid: i for i, gid in enumerate(gids)}, level=level, reach=reach,
                      body=body_of, c_B=c_B, radius=radius, tree=KinematicTree(plant))
    cell.memo.motion_bound = out
    return out


def step_displacements(mb: MotionBound, q: np.ndarray, X: np.ndarray | None = None
                       ) -> np.ndarray:
    """(N-1, G) bound on how far each geometry's points move [m] from sample k to k+1 of a
    path (joints ``q`` (N, 6)): the smaller of the joint-reach bound and the rigid-motion
    bound ``|dp_c| + theta r`` of the geometry's body poses (numpy kinematic tree; ``X``
    (N, n_bodies, 4, 4) when already computed)."""
    dq = np.abs(np.diff(q, axis=0))
    D = dq @ mb.reach.T
    mv = np.flatnonzero(mb.level > 0)
    if len(mv) and len(q) > 1:
        bodies, inv = np.unique(mb.body[mv], return_inverse=True)
        X = (mb.tree.body_poses(q) if X is None else X)[:, bodies]  # (N, B, 4, 4)
        R, p = X[..., :3, :3], X[..., :3, 3]
        c_W = np.einsum("ngij,gj->ngi", R[:, inv], mb.c_B[mv]) + p[:, inv]  # (N, Gm, 3)
        dc = np.linalg.norm(np.diff(c_W, axis=0), axis=2)
        D[:, mv] = np.minimum(D[:, mv], dc + _step_angles(R)[:, inv] * mb.radius[mv][None])
    return D


def _step_angles(R: np.ndarray) -> np.ndarray:
    """(N-1, B) rotation angle [rad] of each frame from sample k to k+1 (``R`` (N, B, 3, 3)),
    never below the chord of its columns (acos loses ~1e-8 rad near 0)."""
    cos_t = 0.5 * (np.einsum("nbij,nbij->nb", R[:-1], R[1:]) - 1.0)
    theta = np.arccos(np.clip(cos_t, -1.0, 1.0))
    return np.maximum(theta, np.max(np.linalg.norm(R[1:] - R[:-1], axis=2), axis=2))


def _counted(checker, mb: MotionBound) -> tuple:
    """The moving bodies and which of their pairs the checker counts (its collision filters):
    (bodies (B,) plant body indices, members: per body its geometry rows, solo (B,): a pair
    with a fixed geometry counts, pairs (P, 2): body pairs with a pair between them that
    counts, centre (B, 3) and radius (B,): per body a ball in its frame holding all its
    geometries). Kept on the checker (``ClearanceChecker.counted``) with ``mb``."""
    cached = checker.counted
    if cached is not None and cached[0] is mb:
        return cached[1]
    mv = np.flatnonzero(mb.level > 0)
    bodies = np.unique(mb.body[mv])
    members = [mv[mb.body[mv] == b] for b in bodies]
    gid_of = {i: gid for gid, i in mb.row.items()}
    fixed = [gid_of[int(g)] for g in np.flatnonzero(mb.level == 0)]
    inspector = checker.query_at(checker.cell.q_home).inspector()

    def counts(rows, others) -> bool:
        return any(not inspector.CollisionFiltered(gid_of[int(a)], b)
                   for a in rows for b in others)

    solo = np.array([counts(m, fixed) for m in members], bool)
    pairs = np.array([(x, y) for x in range(len(bodies)) for y in range(x + 1, len(bodies))
                      if counts(members[x], [gid_of[int(g)] for g in members[y]])],
                     int).reshape(-1, 2)
    centre = np.array([mb.c_B[m].mean(axis=0) for m in members]).reshape(-1, 3)
    radius = np.array([np.max(np.linalg.norm(mb.c_B[m] - c, axis=1) + mb.radius[m])
                       for m, c in zip(members, centre, strict=True)])
    out = (bodies, members, solo, pairs, centre, radius)
    checker.counted = (mb, out)
    return out


def _relative_steps(X: np.ndarray, centre: np.ndarray, radius: np.ndarray, a: np.ndarray,
                    b: np.ndarray) -> np.ndarray:
    """(N-1, P) bound on how far the points of P balls (``centre`` (P, 3) in the frames of
    bodies ``a`` (P,), ``radius`` (P,)) move relative to the frames of bodies ``b`` (P,) from
    sample k to k+1 (``X`` (N, n_bodies, 4, 4) body poses): ``|dc| + theta r``."""
    Xa, Xb = X[:, a], X[:, b]  # (N, P, 4, 4)
    Ra, pa, Rb, pb = Xa[..., :3, :3], Xa[..., :3, 3], Xb[..., :3, :3], Xb[..., :3, 3]
    Rb_T = np.swapaxes(Rb, -1, -2)
    c_W = (Ra @ centre[:, :, None])[..., 0] + pa  # (N, P, 3)
    c = (Rb_T @ (c_W - pb)[..., None])[..., 0]  # in b's frame
    R = Rb_T @ Ra  # a's rotation in b's frame
    return np.linalg.norm(np.diff(c, axis=0), axis=2) + _step_angles(R) * radius[None]


def anchor_travel(checker, mb: MotionBound, q: np.ndarray, D: np.ndarray,
                  X: np.ndarray | None = None) -> np.ndarray:
    """(N, K) cumulative bounds from sample 0 on how much closer a pair that counts can have
    come: one column per moving body with a counted pair against the fixed geometry (its
    geometries' largest step ``D`` (N-1, G), summed) and one per counted body pair (the
    smaller of either body's ball's motion relative to the other body, per step: two
    links of the arm move together, and their distance changes only by the joints between
    them; never more than the two bodies' own steps together). A pair farther than ``cap +
    reach`` at an anchor stays beyond ``cap + slack`` while no column has grown by ``reach -
    slack`` since. ``X`` (N, n_bodies, 4, 4): the body poses when already computed."""
    bodies, members, solo, pairs, centre, radius = _counted(checker, mb)
    own = np.stack([D[:, m].max(axis=1) for m in members], axis=1) if members else None
    cols = [own[:, i] for i in np.flatnonzero(solo)]
    if len(pairs) and len(q) > 1:
        X = mb.tree.body_poses(q) if X is None else X
        x, y = pairs[:, 0], pairs[:, 1]
        rel = np.minimum.reduce([
            _relative_steps(X, centre[x], radius[x], bodies[x], bodies[y]),
            _relative_steps(X, centre[y], radius[y], bodies[y], bodies[x]),
            own[:, x] + own[:, y]])
        cols.extend(rel.T)
    steps = np.stack(cols, axis=1) if cols else np.zeros((max(len(q) - 1, 0), 0))
    return np.vstack([np.zeros((1, steps.shape[1])), np.cumsum(steps, axis=0)])


def distances_along(checker, q: np.ndarray, cap: float, reach: float = 20e-3,
                    slack: float = QUERY_SLACK) -> tuple[np.ndarray, dict]:
    """The capped minimum signed distance at every configuration of a path (module docstring).

    Args:
        checker: :class:`drakedeburr.plan.kinematics.ClearanceChecker` (its collision filters
            decide which pairs count).
        q: (N, 6) joints [rad] along a path (consecutive rows close together).
        cap: the distances are capped at this [m] (``max_distance`` of the full query).
        reach: extra radius of the anchor queries [m]; slack: see :data:`QUERY_SLACK`.

    Returns:
        (N,) distances [m], equal to ``checker.distance(q[i], cap)`` at every row, and counts
        {"anchors", "pair_queries", "samples_queried"}.
    """
    q = np.asarray(q, float)
    n = len(q)
    out = np.full(n, float(cap))
    stats = {"anchors": 0, "pair_queries": 0, "samples_queried": 0}
    if n == 0:
        return out, stats
    mb = motion_bound(checker.cell)
    # C[k, g]: bound on the travel of geometry g's points from sample 0 to sample k
    X = mb.tree.body_poses(q)
    D = step_displacements(mb, q, X)
    C = np.vstack([np.zeros((1, len(mb.level))), np.cumsum(D, axis=0)])
    M = anchor_travel(checker, mb, q, D, X)
    anchor = -1
    ia = ib = at = np.zeros(0, int)
    d = np.zeros(0)
    ids: list = []
    for k in range(n):
        if anchor < 0 or (M.shape[1] and np.max(M[k] - M[anchor]) > reach - slack):
            anchor = k
            stats["anchors"] += 1
            res = checker.pairs_within(q[k], cap + reach)
            ids = [p for p, _ in res]
            ia = np.array([mb.row[a] for a, _ in ids], int)
            ib = np.array([mb.row[b] for _, b in ids], int)
            d = np.array([r for _, r in res], float)
            at = np.full(len(ids), k)
            if len(d):
                out[k] = min(out[k], float(d.min()))
            continue
        if not len(d):
            continue
        moved = C[k, ia] - C[at, ia] + C[k, ib] - C[at, ib]
        due = np.flatnonzero(d - moved < cap + slack)
        if not len(due):
            continue
        query = checker.query_at(q[k])
        stats["samples_queried"] += 1
        stats["pair_queries"] += len(due)
        for j in due:
            d[j] = checker.reading(query, query.ComputeSignedDistancePairClosestPoints(*ids[j]))
        at[due] = k
        out[k] = min(out[k], float(d[due].min()))
    return out, stats


# --- the tool alone against the part: is there any axis at a CL target? -------------------

#: the cone search (:func:`tool_axis_clearance`): cells across the cone's tangent-plane disc
#: at the start, halvings of a cell at most, axes read at one target at most
CONE_CELLS = 4
CONE_HALVINGS = 4
CONE_READS = 400


@dataclass(frozen=True, eq=False)
class AxisSearch:
    """What :func:`tool_axis_clearance` found at each CL target of a window.

    Attributes:
        best: (M,) the largest clearance [m] of the round tool parts (shank, collet, spindle
            body, its clamp: the parts symmetric about the burr axis) to the part over the
            axes read (negative: minus the penetration depth of the least bad axis).
        part: (M,) the tool part nearest the part at that axis (geometry name).
        best_axis_H: (M, 3) that axis (unit, tip -> spindle).
        proven: (M,) True where the search proved that NO axis of the cone reaches the bound
            (every cell of the cone ruled out, see :func:`tool_axis_clearance`); False where
            an axis reached it or the search stopped at its limits.
        reads: (M,) axes read at each target.
        half_angle: the cone's half-angle [rad].
    """

    best: np.ndarray
    part: tuple
    best_axis_H: np.ndarray
    proven: np.ndarray
    reads: np.ndarray
    half_angle: float


class ToolScene:
    """The round tool parts and the part's collision pieces in one standalone ``SceneGraph``
    (hub pieces anchored in H, the tool parts on one frame posed at X_HT), for the question no
    arm pose can change: with the burr's cutting circle on the edge and the axis ``a``, does
    the tool clear the part? The parts are those whose distance to the hub is the same for
    every spin about the burr axis and every arm pose (:meth:`ClearanceChecker.spin_invariant`),
    with the cell's own shapes, proximity properties and relative poses (read at home), so a
    reading here is the cell's reading of that pair at any pose with that tool point and axis.

    Args:
        checker: a :class:`~drakedeburr.plan.kinematics.ClearanceChecker` of the cell.
    """

    def __init__(self, checker) -> None:
        from pydrake.geometry import (
            FramePoseVector,
            GeometryFrame,
            GeometryInstance,
            ProximityProperties,
            SceneGraph,
        )
        from pydrake.math import RigidTransform

        cell = checker.cell
        sym = spin_invariant_parts(checker)  # first: finding them poses the context
        query = checker.query_at(cell.q_home)
        inspector = query.inspector()
        X_WT = cell.tool_frame.CalcPoseInWorld(checker.plant_context).GetAsMatrix4()
        X_WH = cell.hub_frame.CalcPoseInWorld(checker.plant_context).GetAsMatrix4()
        sg = SceneGraph()
        source = sg.RegisterSource("drakedeburr.tool_scene")
        self._frame = sg.RegisterFrame(source, GeometryFrame("tool"))
        self.names: dict = {}
        self.reach: dict = {}  # tool part -> farthest point from T [m]

        def add(g, X_ref, frame=None):
            X_RG = np.linalg.inv(X_ref) @ query.GetPoseInWorld(g).GetAsMatrix4()
            shape = inspector.GetShape(g)
            inst = GeometryInstance(RigidTransform(X_RG), shape.Clone(), inspector.GetName(g))
            inst.set_proximity_properties(ProximityProperties(
                inspector.GetProximityProperties(g)))
            if frame is None:
                gid = sg.RegisterAnchoredGeometry(source, inst)
            else:
                gid = sg.RegisterGeometry(source, frame, inst)
                P, rho = bounding_points(shape)
                P_T = P @ X_RG[:3, :3].T + X_RG[:3, 3]
                self.reach[gid] = float(np.linalg.norm(P_T, axis=1).max() + rho)
            self.names[gid] = inspector.GetName(g).split("::")[-1]

        for g in sorted(cell.hub_ids, key=lambda g: g.get_value()):
            add(g, X_WH)
        self.tool_parts = sym
        for g in sym:
            add(g, X_WT, self._frame)
        self._sg, self._ctx = sg, sg.CreateDefaultContext()
        self._port = sg.get_source_pose_port(source)
        self._poses = FramePoseVector()
        self._rt = RigidTransform

    def clearance(self, X_HT: np.ndarray, max_distance: float) -> tuple[float, object]:
        """(distance [m] of the round tool parts to the part, capped at ``max_distance``, or
        minus the deepest penetration in contact; the tool part's geometry id, None when
        nothing is within the cap) at the tool pose ``X_HT`` (4, 4)."""
        self._poses.set_value(self._frame, self._rt(np.asarray(X_HT, float)))
        self._port.FixValue(self._ctx, self._poses)
        query = self._sg.get_query_output_port().Eval(self._ctx)
        if query.HasCollisions():
            pen = max(query.ComputePointPairPenetration(), key=lambda p: p.depth)
            return -float(pen.depth), pen.id_A if pen.id_A in self.reach else pen.id_B
        best, part = float(max_distance), None
        for r in query.ComputeSignedDistancePairwiseClosestPoints(max_distance):
            if r.distance < best:
                best, part = float(r.distance), r.id_A if r.id_A in self.reach else r.id_B
        return best, part


def spin_invariant_parts(checker) -> tuple:
    """The cell's tool geometries whose distance to the hub is the same at every spin about the
    burr axis (:meth:`ClearanceChecker.spin_invariant`: shank, collet, a coaxial spindle body
    and its clamp), in geometry-id order."""
    cell = checker.cell
    invariant = checker.spin_invariant()
    hub = next(iter(cell.hub_ids))
    return tuple(sorted((g for g in cell.robot_ids | cell.environment_ids if invariant(g, hub)),
                        key=lambda g: g.get_value()))


_SCENES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def tool_scene(checker) -> ToolScene:
    """The :class:`ToolScene` of a checker's cell, built once per checker."""
    if checker not in _SCENES:
        _SCENES[checker] = ToolScene(checker)
    return _SCENES[checker]


def tool_axis_clearance(scene: ToolScene, wt, p_HQ: np.ndarray, lift: float, *, bound: float,
                        margin: float = 0.0, half_angle: float | None = None,
                        about: np.ndarray | None = None) -> AxisSearch:
    """Per CL target of a window: is there an axis in the cone on which the round tool parts
    keep ``bound`` off the part, the constrained point held where the IK holds it? A branch
    and bound over the cone, in its gnomonic tangent plane (axis ``c + x e1 + y e2``,
    normalised; the cone is the disc ``|(x, y)| <= tan(half_angle)``): square cells, each read
    at its centre (pulled into the disc). Turning the tool about its constrained point by an
    angle ``phi`` moves a point of a tool part ``r`` from that point by at most ``r phi``, so
    the nearest pair at the read axis (its tool part reaching ``r`` from the constrained point)
    is at most ``r phi`` farther at any axis of the cell, whose axes lie within ``phi`` of the
    read one (the gnomonic map shortens distances: ``phi`` <= the cell's radius in the plane).
    A cell whose reading plus that is below ``bound - margin`` holds no clear axis and is
    dropped; the others are halved (:data:`CONE_HALVINGS`, :data:`CONE_READS` at most), the
    cell with the highest bound read first. The preferred axis is read first; a target's
    search stops at the first axis with ``bound``.

    Args:
        scene: the :class:`ToolScene`; wt: the window's
            :class:`~drakedeburr.plan.window_targets.WindowTargets`.
        p_HQ: (M, 3) the IK's constrained points (the cutting circle's centre, ``lift`` below
            T on the axis; :func:`drakedeburr.plan.window.cut_targets`) [m].
        bound: the clearance sought [m]; margin: how far under it a cell must stay to be
            dropped [m] (the readings' own spread).
        half_angle: cone half-angle [rad] (default the window's); about: (M, 3) cone axes
            (tip -> spindle; default the window's ``cone_retract_H``).
    """
    from drakedeburr.frames.vectors import perpendicular_basis

    half = float(wt.cone_half_angle if half_angle is None else half_angle)
    c_all = np.asarray(wt.cone_retract_H if about is None else about, float)
    m, rad = len(wt), float(np.tan(half))
    best, best_axis = np.full(m, -np.inf), np.zeros((m, 3))
    proven, reads = np.zeros(m, bool), np.zeros(m, int)
    part: list = [""] * m
    s0 = rad / CONE_CELLS
    g = -rad + s0 * (2 * np.arange(2 * CONE_CELLS) + 1)
    start = np.array([(x, y, s0) for x in g for y in g
                      if np.hypot(x, y) - np.sqrt(2) * s0 <= rad])
    for i in range(m):
        c = c_all[i] / np.linalg.norm(c_all[i])
        e1, e2, _ = perpendicular_basis(c).T
        t = _Target(scene, p_HQ[i], lift, wt.t_H[i], bound)
        t.cone = (c, e1, e2, rad)
        if not t.read(*cone_poses(p_HQ[i], lift, wt.retract_H[i][None], wt.t_H[i]))[2]:
            proven[i] = _branch_and_bound(t, start, bound - margin, s0)
        best[i], best_axis[i], reads[i] = t.best, t.axis, t.reads
        part[i] = scene.names[t.gid] if t.gid is not None else ""
    return AxisSearch(best=best, part=tuple(part), best_axis_H=best_axis, proven=proven,
                      reads=reads, half_angle=half)


def cone_poses(p_Q: np.ndarray, lift: float, axes: np.ndarray, t_H: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Tool poses at many axes of one CL target in one call: ((K, 3) unit axes, (K, 4, 4) X_HT,
    T ``lift`` above ``p_Q`` (3,) on each axis, spin 0 to the feed tangent ``t_H`` (3,)); row k
    is :func:`~drakedeburr.plan.targets.X_HT_from_axis` of axis k alone, bit for bit."""
    from drakedeburr.plan.targets import X_HT_from_axis

    A = np.asarray(axes, float)
    A = A / np.linalg.norm(A, axis=1, keepdims=True)
    X = X_HT_from_axis(np.asarray(p_Q, float)[None] + lift * A, A,
                       np.broadcast_to(np.asarray(t_H, float), A.shape))
    return A, X


class _Target:
    """The readings of one CL target's search: the best axis so far and how many were read."""

    def __init__(self, scene: ToolScene, p_Q, lift: float, t_H, bound: float) -> None:
        self.scene, self.p_Q, self.lift, self.t_H, self.bound = scene, p_Q, lift, t_H, bound
        self.best, self.axis, self.gid, self.reads, self.cone = -np.inf, np.zeros(3), None, 0, ()

    def read(self, A: np.ndarray, X: np.ndarray, k: int = 0) -> tuple[float, float, bool]:
        """(clearance [m] at axis ``A[k]`` (pose ``X[k]``), the reach of its nearest tool
        part from the constrained point [m] (inf when nothing is near), clear)."""
        d, gid = self.scene.clearance(X[k], self.bound + 1e-3)
        self.reads += 1
        if d > self.best:
            self.best, self.axis, self.gid = d, A[k], gid
        return d, (self.scene.reach[gid] + self.lift if gid is not None else np.inf), \
            d >= self.bound

    def cells(self, xys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cells (K, 3) (centre x, y in the gnomonic plane, half-size) -> (their read points
        pulled into the cone's disc (K, 2), unit axes (K, 3), poses (K, 4, 4)), in one call."""
        c, e1, e2, rad = self.cone
        x, y = xys[:, 0], xys[:, 1]
        r = np.hypot(x, y)[:, None]
        inside = r <= rad  # as the scalar search: (x * rad / r, y * rad / r) outside
        pxy = np.where(inside, xys[:, :2], xys[:, :2] * rad / np.where(inside, 1.0, r))
        A = c[None] + pxy[:, :1] * e1[None] + pxy[:, 1:] * e2[None]
        return (pxy, *cone_poses(self.p_Q, self.lift, A, self.t_H))


def _branch_and_bound(t: _Target, start: np.ndarray, drop: float, s0: float) -> bool:
    """The cone search at one target after its preferred axis (:func:`tool_axis_clearance`):
    True when every cell is ruled out (``reading + reach * radius < drop``)."""
    rad = t.cone[3]
    pxy, A, X = t.cells(start)
    # best first: the cell whose parent's bound is highest (the start cells first)
    heap = [(-np.inf, k, (start[k], pxy[k], A, X, k)) for k in range(len(start))]
    heapq.heapify(heap)
    clear, order = False, len(heap)
    while heap and not clear and t.reads < CONE_READS:
        _, _, ((x, y, s), (px, py), A, X, k) = heapq.heappop(heap)
        d, reach, clear = t.read(A, X, k)
        upper = d + reach * (np.hypot(px - x, py - y) + np.sqrt(2) * s)
        if clear or upper < drop:
            continue
        if s <= s0 / 2 ** CONE_HALVINGS:
            return False  # the search's resolution: not proven
        h = s / 2
        kids = np.array([(x + dx, y + dy, h) for dx in (-h, h) for dy in (-h, h)
                         if np.hypot(x + dx, y + dy) - np.sqrt(2) * h <= rad]).reshape(-1, 3)
        if not len(kids):
            continue
        kxy, KA, KX = t.cells(kids)
        for j in range(len(kids)):
            order += 1
            heapq.heappush(heap, (-upper, order, (kids[j], kxy[j], KA, KX, j)))
    return not clear and not heap
