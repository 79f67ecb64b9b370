"""Every unfiltered collision pair of a cell, classified, with the motion track that bounds it,
and a scene graph to query them one by one.

The cell's own scene graph puts every body's geometry on a dynamic frame, the ~400 pieces of
a hub on its fixture included, and re-poses all of them before a query (~60 us), and its
broad phase over all pairs costs ~0.4-0.7 ms a configuration. Here the same shapes (same
proximity properties, same poses) are registered in a standalone ``SceneGraph`` with the
geometry fixed in the world *anchored* (at the world poses the cell's scene graph computes)
and one frame per moving body, posed from the Drake plant, only the bodies a reading needs;
a pair's signed distance then comes from the same narrow phase with bit-identical poses
(``QueryObject.ComputeSignedDistancePairClosestPoints``, tested equal to the cell's pairwise
query), and the verifier asks only for the pairs its bounds cannot rule out.

Pairs (``a`` < ``b`` by geometry id, as Drake orders them) are those the cell's collision
filters leave, with at least one geometry moving with the robot, in three classes:
``0`` clearance (robot, tool or held hub vs the hub and the cell), ``1`` self (both move with
the robot, neither is the hub), ``2`` burr (burr head vs hub: the process contact).

Each pair is bounded through one *track* (:mod:`drakedeburr.verify.motion_bounds`): the motion
of one of its geometries relative to the link of the other, the side with fewer geometries
on its link moving (a tool part relative to the hub's ~400 pieces, not the reverse).
"""

from __future__ import annotations

import numpy as np

from drakedeburr.cell.chain import KinematicTree
from drakedeburr.cell.narrowphase import ReadingTally, ShapeSupport, box_points, certified_distance
from drakedeburr.verify.motion_bounds import Tracks

__all__ = ["PairScene", "shape_points", "CLEARANCE", "SELF", "BURR", "pair_scene_of",
           "worker_scene", "warm_scene", "checked_scene"]

CLEARANCE, SELF, BURR = 0, 1, 2


def shape_points(shape) -> np.ndarray:
    """Points whose hull contains the shape, in the geometry frame [m]
    (:func:`drakedeburr.cell.narrowphase.box_points`)."""
    return box_points(shape)


def _ball(points: np.ndarray) -> tuple[np.ndarray, float]:
    c = 0.5 * (points.min(0) + points.max(0))
    return c, float(np.linalg.norm(points - c, axis=1).max())


class PairScene:
    """The pairs, tracks and standalone scene of a cell (module docstring).

    Args:
        cell: a :class:`drakedeburr.cell.Cell`.
        tree: its :class:`~drakedeburr.cell.chain.KinematicTree` (default: built here).

    Attributes:
        names: per geometry ``model::body/geometry``; moving: (G,) bool.
        a, b: (P,) geometry indices of each pair; cls: (P,) class; track: (P,) track index.
        tracks: the :class:`~drakedeburr.verify.motion_bounds.Tracks`.
        X_home: (n_bodies, 4, 4) body poses at the cell's home configuration.
    """

    def __init__(self, cell, tree: KinematicTree | None = None) -> None:
        from pydrake.geometry import Role

        self.cell = cell
        self.tree = tree or KinematicTree(cell.plant)
        plant = cell.plant
        inspector = cell.scene_graph.model_inspector()
        self._inspector = inspector
        self.ids = sorted(inspector.GetAllGeometryIds(Role.kProximity),
                          key=lambda g: g.get_value())
        self.X_home = self.tree.body_poses(np.asarray(cell.q_home, float)[None])[0]
        body = np.array([int(plant.GetBodyFromFrameId(inspector.GetFrameId(g)).index())
                         for g in self.ids])
        self.body = body
        self.link = self.tree.link_of[body]
        self.moving = self.link != 0
        self.X_LG = []  # geometry pose in its link frame
        self.c_L, self.rho = np.zeros((len(self.ids), 3)), np.zeros(len(self.ids))
        self.lo_L, self.hi_L = np.zeros((len(self.ids), 3)), np.zeros((len(self.ids), 3))
        for i, g in enumerate(self.ids):
            X_LB = np.linalg.inv(self.X_home[self.link[i]]) @ self.X_home[body[i]]
            X_LG = X_LB @ inspector.GetPoseInFrame(g).GetAsMatrix4()
            self.X_LG.append(X_LG)
            pts = shape_points(inspector.GetShape(g))
            c_G, self.rho[i] = _ball(pts)
            self.c_L[i] = X_LG[:3, :3] @ c_G + X_LG[:3, 3]
            pts_L = pts @ X_LG[:3, :3].T + X_LG[:3, 3]
            self.lo_L[i], self.hi_L[i] = pts_L.min(0), pts_L.max(0)
        self.names = [self._label(g) for g in self.ids]
        self._pairs(cell)
        self._build_scene()

    def _label(self, g) -> str:
        plant = self.cell.plant
        b = plant.GetBodyFromFrameId(self._inspector.GetFrameId(g))
        model = plant.GetModelInstanceName(b.model_instance())
        return f"{model}::{b.name()}/{self._inspector.GetName(g).split('::')[-1]}"

    def _pairs(self, cell) -> None:
        inspector, ids, link = self._inspector, self.ids, self.link
        burr = np.array([g in cell.burr_head_ids for g in ids])
        hub = np.array([g in cell.hub_ids for g in ids])
        count = np.bincount(link, minlength=self.tree.n_bodies)
        depth = np.array([len(p) for p in self.tree.path_of])
        a_list, b_list, cls_list, keys = [], [], [], []
        for i in np.flatnonzero(self.moving):
            for j in range(len(ids)):
                if j == i or (self.moving[j] and j < i):
                    continue  # each pair once; fixed-fixed pairs never
                if inspector.CollisionFiltered(ids[i], ids[j]):
                    continue
                a, b = min(i, j), max(i, j)
                if (burr[a] and hub[b]) or (burr[b] and hub[a]):
                    c = BURR
                elif self.moving[a] and self.moving[b] and not hub[a] and not hub[b]:
                    c = SELF
                else:
                    c = CLEARANCE
                # the moving side: fewer geometries on its link, else the longer joint path
                ka, kb = (count[link[a]], -depth[link[a]]), (count[link[b]], -depth[link[b]])
                g, other = (a, b) if ka <= kb else (b, a)
                a_list.append(a)
                b_list.append(b)
                cls_list.append(c)
                keys.append((int(link[other]), int(g), c))
        self.a, self.b = np.array(a_list, int), np.array(b_list, int)
        self.cls = np.array(cls_list, int)
        uniq = sorted(set(keys))
        index = {k: n for n, k in enumerate(uniq)}
        self.track = np.array([index[k] for k in keys], int)
        nq = self.tree.nq
        seq, reach = -np.ones((len(uniq), nq), int), np.zeros((len(uniq), nq))
        for n, (ref, g, _) in enumerate(uniq):
            path = self.tree.joint_path(ref, int(link[g]))
            seq[n, :len(path)] = path
            reach[n, :len(path)] = self.tree.reach(self.X_home, path, int(link[g]), self.c_L[g],
                                                   float(self.rho[g]))
        self._partner_boxes(uniq)
        geoms = np.array([k[1] for k in uniq], int)
        self.tracks = Tracks(ref=np.array([k[0] for k in uniq], int), link=link[geoms],
                             c=self.c_L[geoms], rho=self.rho[geoms], seq=seq, reach=reach,
                             cls=np.array([k[2] for k in uniq], int))
        self.track_geometry = geoms

    def _partner_boxes(self, uniq: list) -> None:
        """Per track: its pairs and, for each, the other geometry's box in the track's
        reference link frame (the bound used before a pair is read)."""
        geom = np.array([k[1] for k in uniq], int)[self.track]
        other = np.where(geom == self.a, self.b, self.a)
        self.track_pairs = [np.flatnonzero(self.track == k) for k in range(len(uniq))]
        self.box_lo, self.box_hi = self.lo_L[other], self.hi_L[other]

    def _build_scene(self) -> None:
        from pydrake.geometry import (
            FramePoseVector,
            GeometryFrame,
            GeometryInstance,
            ProximityProperties,
            SceneGraph,
        )
        from pydrake.multibody.tree import BodyIndex

        plant, inspector = self.cell.plant, self._inspector
        self.plant_context = plant.CreateDefaultContext()
        sg = SceneGraph()
        source = sg.RegisterSource("drakedeburr.verify")
        bodies = sorted({int(b) for b, m in zip(self.body, self.moving, strict=True) if m})
        frames = {b: sg.RegisterFrame(source, GeometryFrame(f"body_{b}")) for b in bodies}
        self.scene_ids = []
        self._X_fixed: list = []  # world pose of each fixed geometry (None: moving)
        for i, g in enumerate(self.ids):
            b = int(self.body[i])
            # fixed geometry at its world pose as the cell's scene graph composes it (Drake's
            # X_WB * X_BG: the same arithmetic, so the same distances bit for bit)
            X = inspector.GetPoseInFrame(g) if self.moving[i] else plant.EvalBodyPoseInWorld(
                self.plant_context, plant.get_body(BodyIndex(b))).multiply(
                inspector.GetPoseInFrame(g))
            self._X_fixed.append(None if self.moving[i] else X.GetAsMatrix4())
            inst = GeometryInstance(X, inspector.GetShape(g).Clone(), self.names[i])
            inst.set_proximity_properties(ProximityProperties(
                inspector.GetProximityProperties(g)))
            self.scene_ids.append(sg.RegisterGeometry(source, frames[b], inst)
                                  if self.moving[i] else sg.RegisterAnchoredGeometry(source, inst))
        # the cell's collision filters between moving geometry and anything (fixed-fixed
        # pairs are anchored-anchored here: never considered)
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        manager = sg.collision_filter_manager()
        for i in np.flatnonzero(self.moving):
            for j in range(len(self.ids)):
                if (j > i or not self.moving[j]) and inspector.CollisionFiltered(self.ids[i],
                                                                                 self.ids[j]):
                    manager.Apply(CollisionFilterDeclaration().ExcludeBetween(
                        GeometrySet(self.scene_ids[i]), GeometrySet(self.scene_ids[j])))
        self._ctx = sg.CreateDefaultContext()
        self._pose_port = sg.get_source_pose_port(source)
        self._query_port = sg.get_query_output_port()
        self._poses = FramePoseVector()
        self._frames = [(frames[b], plant.get_body(BodyIndex(b))) for b in bodies]
        # per track, the moving bodies its pairs involve (positions in self._frames)
        slot = {b: n for n, b in enumerate(bodies)}
        self.track_bodies = [sorted({slot[int(self.body[g])] for p in pairs
                                     for g in (self.a[p], self.b[p]) if self.moving[g]})
                             for pairs in self.track_pairs]
        self._A = [self.scene_ids[i] for i in self.a]
        self._B = [self.scene_ids[i] for i in self.b]
        self._a, self._b, self._cls = self.a.tolist(), self.b.tolist(), self.cls.tolist()
        self._query = None
        self._posed: dict[int, np.ndarray] = {}  # moving geometry's pose at this configuration
        self._supports: dict = {}
        self.resolve_below = [np.inf] * 3  # per class; until use_tolerances: always solved
        self.tally = ReadingTally()

    def set_configuration(self, q: np.ndarray, bodies=None) -> None:
        """Pose the moving bodies at joints ``q`` (nq,) [rad] through the Drake plant (its
        context :attr:`plant_context` then holds ``q``): all of them, or only ``bodies``
        (indices into :attr:`track_bodies` lists) when the caller reads only their pairs."""
        plant, pc = self.cell.plant, self.plant_context
        plant.SetPositions(pc, q)
        frames = self._frames if bodies is None else [self._frames[b] for b in bodies]
        for frame, body in frames:
            self._poses.set_value(frame, plant.EvalBodyPoseInWorld(pc, body))
        self._pose_port.FixValue(self._ctx, self._poses)
        self._query = self._query_port.Eval(self._ctx)
        self._posed.clear()

    def _pose(self, i: int) -> np.ndarray:
        """World pose (4, 4) of geometry ``i`` at the current configuration, read from the
        query once per configuration (fixed geometry: once)."""
        X = self._X_fixed[i]
        if X is None:
            X = self._posed.get(i)
            if X is None:
                X = self._posed[i] = self._query.GetPoseInWorld(
                    self.scene_ids[i]).GetAsMatrix4()
        return X

    def use_tolerances(self, tol) -> None:
        """Set how readings are certified (:mod:`drakedeburr.cell.narrowphase`) and start a
        new tally: a clearance/self reading whose separating-plane bound falls below its
        class's limit + ``Tolerances.narrowphase_resolve`` is solved exactly."""
        self.resolve_below = (np.array([tol.min_clearance, 0.0, -np.inf]) + float(
            tol.narrowphase_resolve)).tolist()
        self.tally = ReadingTally()

    def distance(self, p: int) -> float:
        """Signed distance of pair ``p`` at the current configuration [m]: Drake's reading,
        held to a rigorous lower bound for the clearance and self classes
        (:meth:`certify`)."""
        r = self._query.ComputeSignedDistancePairClosestPoints(self._A[p], self._B[p])
        d = r.distance
        if not d > 0.0 or self._cls[p] == BURR:
            return d
        n_BA = np.asarray(r.nhat_BA_W)
        if r.id_A != self._A[p]:
            n_BA = -n_BA
        return self.certify(p, d, n_BA, self._pose(self._a[p]), self._pose(self._b[p]))

    def certify(self, p: int, d: float, n_BA: np.ndarray, X_WA: np.ndarray,
                X_WB: np.ndarray) -> float:
        """Drake's reading ``d`` [m] of pair ``p`` (normal ``n_BA`` from its ``b`` toward its
        ``a`` geometry, posed at ``X_WA``, ``X_WB``) as a certified reading
        (:func:`~drakedeburr.cell.narrowphase.certified_distance`), tallied."""
        value, how = certified_distance(d, n_BA, self._support(self._a[p]), X_WA,
                                        self._support(self._b[p]), X_WB,
                                        solve_below=self.resolve_below[self._cls[p]])
        self.tally.add(d, value, how)
        return value

    def _support(self, i: int):
        s = self._supports.get(i)
        if s is None:
            s = ShapeSupport(self._inspector.GetShape(self.ids[i]))
            if self._X_fixed[i] is not None:
                s = s.posed(self._X_fixed[i])
            self._supports[i] = s
        return s

    def digest(self) -> str:
        """A digest of what the readings depend on: the cell's geometry
        (:func:`drakedeburr.cell.fingerprint.geometry_digest`), geometry names, pairs,
        classes, tracks, the fixed geometry's and the home configuration's poses (two
        processes that built the same cell agree on it, so one may read parts of a sweep for
        the other)."""
        d = self.__dict__.get("_digest")
        if d is None:
            import hashlib

            from drakedeburr.cell.fingerprint import geometry_digest

            h = hashlib.sha256((geometry_digest(self.cell) + "\n".join(self.names)).encode())
            for arr in (self.a, self.b, self.cls, self.track, self.X_home, self.tracks.reach,
                        *(X for X in self._X_fixed if X is not None)):
                h.update(np.ascontiguousarray(arr).tobytes())
            d = self.__dict__["_digest"] = h.hexdigest()
        return d

    def pair_names(self, p: int) -> tuple[str, str]:
        return self.names[self.a[p]], self.names[self.b[p]]


def pair_scene_of(cell) -> PairScene:
    """The cell's :class:`PairScene`, built once per cell (kept in ``cell.memo``)."""
    scene = cell.memo.pair_scene
    if scene is None:
        scene = cell.memo.pair_scene = PairScene(cell)
    return scene


_WORKER_SCENE: dict = {}  # in a pool worker: the caller's cell and its PairScene


def worker_scene(recipe: dict, fingerprint: str | None) -> PairScene:
    """In a pool worker: the pair scene of the cell built from ``recipe`` (kept for the
    worker's life, rebuilt when ``fingerprint`` differs)."""
    from drakedeburr.pool import worker_cell

    return worker_cell(recipe, fingerprint, _WORKER_SCENE, pair_scene_of)[1]


def warm_scene(recipe: dict, fingerprint: str | None) -> None:
    """A pool task: build the worker's pair scene now (:func:`worker_scene`)."""
    worker_scene(recipe, fingerprint)


def checked_scene(recipe: dict, fingerprint: str, digest: str, tol) -> PairScene:
    """In a worker: the caller's pair scene (refused when its digest differs), with the
    tolerances set and a fresh reading tally."""
    scene = worker_scene(recipe, fingerprint)
    if scene.digest() != digest:
        raise RuntimeError("the worker's pair scene differs from the caller's")
    scene.use_tolerances(tol)
    return scene
