"""Signed distances of a cell at many configurations, with the closest pair named.

Two implementations, giving the same answers (tested):

* ``"pairwise"`` (default): the scene graph's
  ``QueryObject.ComputeSignedDistancePairwiseClosestPoints(query_distance)``, its results
  classified by geometry;
* ``"culled"``: candidate pairs culled in numpy (each moving body's geometry boxes, in the
  body frame, against the bounding spheres of fixed geometry; spheres for moving pairs), then
  ``ComputeSignedDistancePairClosestPoints`` pair by pair. It was 2-3x faster with the first
  hub models (~750 convex pieces); with the merged pieces (~450) Drake's broad phase is as fast
  or faster (benchmarks/RESULTS.md), so it is kept as the cross-check.

Collision filters of the scene graph are honoured. Pairs are classified:
    * ``"burr"``: burr head vs hub, the process contact (handled by its own limits);
    * ``"self"``: both geometries move with the robot and neither is the hub;
    * ``"clearance"``: every other unfiltered pair (robot/tool/held hub vs cell and hub).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DistanceProbe", "PairDistances", "measure_samples"]


@dataclass(frozen=True)
class PairDistances:
    """Smallest signed distance per class at one configuration ([m]; ``inf`` if none within
    the query distance) and the pair's geometry names."""

    clearance: float
    clearance_pair: tuple[str, str]
    self_distance: float
    self_pair: tuple[str, str]
    burr: float
    burr_pair: tuple[str, str]


def _shape_points(shape) -> np.ndarray:
    """Points whose hull contains the shape, in the geometry frame [m]."""
    from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, Mesh, Sphere

    if isinstance(shape, (Convex, Mesh)):
        hull = shape.GetConvexHull()
        return np.array([hull.vertex(i) for i in range(hull.num_vertices())])
    if isinstance(shape, Box):
        s = np.array([shape.width(), shape.depth(), shape.height()]) / 2
        return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * s
    if isinstance(shape, Cylinder):
        r, h = shape.radius(), shape.length() / 2
        return np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-h, h)])
    if isinstance(shape, Capsule):
        r, h = shape.radius(), shape.length() / 2 + shape.radius()
        return np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-h, h)])
    if isinstance(shape, Sphere):
        r = shape.radius()
        return np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-r, r)])
    if isinstance(shape, Ellipsoid):
        a = np.array([shape.a(), shape.b(), shape.c()])
        return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * a
    raise TypeError(f"unsupported collision shape {type(shape).__name__}")


class DistanceProbe:
    """Distance queries on a :class:`drakedeburr.cell.Cell` (one diagram context, reused).

    Args:
        cell: the cell (freshly loaded by the verifier).
        query_distance: pairs farther apart than this are not measured [m].
        method: "pairwise" (Drake's broad phase) or "culled" (see module docstring).
    """

    def __init__(self, cell, query_distance: float, method: str = "pairwise") -> None:
        from pydrake.geometry import Role

        if method not in ("pairwise", "culled"):
            raise ValueError(f"method must be 'pairwise' or 'culled', got {method!r}")
        self.method = method
        self.cell = cell
        self.query_distance = float(query_distance)
        self.context = cell.diagram.CreateDefaultContext()
        self.plant_context = cell.plant.GetMyMutableContextFromRoot(self.context)
        self.sg_context = cell.scene_graph.GetMyContextFromRoot(self.context)
        self.port = cell.scene_graph.get_query_output_port()
        query = self.port.Eval(self.sg_context)
        inspector = query.inspector()
        self.inspector = inspector
        ids = sorted(inspector.GetAllGeometryIds(Role.kProximity), key=lambda g: g.get_value())
        hub_moves = cell.mode == "workpiece"
        moving = set(cell.robot_ids)
        if hub_moves:
            moving |= set(cell.hub_ids)
        else:
            moving |= set(cell.burr_head_ids)
        self.moving = [g for g in ids if g in moving]
        self._moving_set = set(self.moving)
        self.fixed = [g for g in ids if g not in moving]
        self.hub = set(cell.hub_ids)
        self.burr_head = set(cell.burr_head_ids)
        self.names = {g: self._label(g) for g in ids}
        plant = cell.plant
        # moving geometry grouped by body: AABB and bounding sphere in the body frame B
        self._bodies = []  # (body, [indices into self.moving], lo_B, hi_B, c_B, r)
        by_body: dict[int, list[int]] = {}
        body_of = {}
        for i, g in enumerate(self.moving):
            body = plant.GetBodyFromFrameId(inspector.GetFrameId(g))
            by_body.setdefault(int(body.index()), []).append(i)
            body_of[int(body.index())] = body
        for b_index in sorted(by_body):
            members = by_body[b_index]
            lo_b, hi_b, c_b, r_b = [], [], [], []
            for i in members:
                g = self.moving[i]
                X_BG = inspector.GetPoseInFrame(g).GetAsMatrix4()
                pts = _shape_points(inspector.GetShape(g)) @ X_BG[:3, :3].T + X_BG[:3, 3]
                lo_b.append(pts.min(0))
                hi_b.append(pts.max(0))
                c = 0.5 * (pts.min(0) + pts.max(0))
                c_b.append(c)
                r_b.append(float(np.linalg.norm(pts - c, axis=1).max()))
            self._bodies.append((body_of[b_index], np.array(members), np.array(lo_b),
                                 np.array(hi_b), np.array(c_b), np.array(r_b)))
        # fixed geometry: bounding spheres in world
        centers, radii = [], []
        for g in self.fixed:
            pts = _shape_points(inspector.GetShape(g))
            X = query.GetPoseInWorld(g).GetAsMatrix4()
            w = pts @ X[:3, :3].T + X[:3, 3]
            c = 0.5 * (w.min(0) + w.max(0))
            centers.append(c)
            radii.append(float(np.linalg.norm(w - c, axis=1).max()))
        self._fixed_c = np.array(centers).reshape(-1, 3)
        self._fixed_r = np.array(radii)
        # pair classes, cached: -2 unknown, -1 filtered, 0 clearance, 1 self, 2 burr
        self._kind_mf = np.full((len(self.moving), len(self.fixed)), -2, np.int8)
        self._kind_mm = np.full((len(self.moving), len(self.moving)), -2, np.int8)
        self._kind_ids: dict[tuple[int, int], int] = {}
        self._by_value = {g.get_value(): g for g in ids}

    def _label(self, g) -> str:
        plant = self.cell.plant
        body = plant.GetBodyFromFrameId(self.inspector.GetFrameId(g))
        model = plant.GetModelInstanceName(body.model_instance())
        return f"{model}::{body.name()}/{self.inspector.GetName(g).split('::')[-1]}"

    def _classify(self, a, b) -> int:
        if self.inspector.CollisionFiltered(a, b):
            return -1
        if (a in self.burr_head and b in self.hub) or (b in self.burr_head and a in self.hub):
            return 2
        if a in self._moving_set and b in self._moving_set and a not in self.hub \
                and b not in self.hub:
            return 1
        return 0

    @staticmethod
    def _near(lo, hi, p, r, d_max):
        """Pairs (box i, sphere j) within d_max: boxes (n, 3) lo/hi, spheres p (m, 3), r (m,)."""
        gap = np.maximum(lo[:, None] - p[None], 0.0) + np.maximum(p[None] - hi[:, None], 0.0)
        d = np.sqrt(np.einsum("nmk,nmk->nm", gap, gap)) - r[None]
        return np.nonzero(d <= d_max)

    def measure(self, q: np.ndarray) -> PairDistances:
        """Smallest distance per class at joints ``q`` [rad] (see module docstring)."""
        if self.method == "culled":
            return self._measure_culled(q)
        self.cell.plant.SetPositions(self.plant_context, q)
        query = self.port.Eval(self.sg_context)
        best = {0: (np.inf, None, None), 1: (np.inf, None, None), 2: (np.inf, None, None)}
        for r in query.ComputeSignedDistancePairwiseClosestPoints(self.query_distance):
            va, vb = r.id_A.get_value(), r.id_B.get_value()
            kind = self._kind_ids.get((va, vb))
            if kind is None:
                kind = self._kind_ids[(va, vb)] = self._classify(r.id_A, r.id_B)
            if kind >= 0 and r.distance < best[kind][0]:
                best[kind] = (float(r.distance), va, vb)

        def named(k):
            d, va, vb = best[k]
            if va is None:
                return d, ("", "")
            return d, (self.names[self._by_value[va]], self.names[self._by_value[vb]])

        (c, cp), (sd, sp), (b, bp) = named(0), named(1), named(2)
        return PairDistances(c, cp, sd, sp, b, bp)

    def _measure_culled(self, q: np.ndarray) -> PairDistances:
        plant = self.cell.plant
        plant.SetPositions(self.plant_context, q)
        d_max = self.query_distance
        poses = [plant.EvalBodyPoseInWorld(self.plant_context, b[0]).GetAsMatrix4()
                 for b in self._bodies]
        pairs_mf, pairs_mm = [], []
        for (_, members, lo, hi, _, _), X in zip(self._bodies, poses, strict=True):
            R, t = X[:3, :3], X[:3, 3]
            p = (self._fixed_c - t) @ R  # fixed sphere centres in B
            ii, jj = self._near(lo, hi, p, self._fixed_r, d_max)
            pairs_mf.append(np.stack([members[ii], jj], axis=1))
        # moving vs moving: bounding spheres in world
        c_W = np.concatenate([c @ X[:3, :3].T + X[:3, 3]
                              for (_, _, _, _, c, _), X in zip(self._bodies, poses, strict=True)])
        r_W = np.concatenate([b[5] for b in self._bodies])
        order = np.concatenate([b[1] for b in self._bodies])
        dm = np.linalg.norm(c_W[:, None] - c_W[None], axis=2) - r_W[:, None] - r_W[None]
        ii, jj = np.nonzero(np.triu(dm <= d_max, k=1))
        pairs_mm.append(np.stack([order[ii], order[jj]], axis=1))
        mf = np.concatenate(pairs_mf) if pairs_mf else np.zeros((0, 2), int)
        mm = np.concatenate(pairs_mm) if pairs_mm else np.zeros((0, 2), int)
        query = self.port.Eval(self.sg_context)
        best = {0: (np.inf, ("", "")), 1: (np.inf, ("", "")), 2: (np.inf, ("", ""))}
        for table, others, pairs in ((self._kind_mf, self.fixed, mf),
                                     (self._kind_mm, self.moving, mm)):
            for i, j in pairs:
                kind = table[i, j]
                a, b = self.moving[i], others[j]
                if kind == -2:
                    kind = table[i, j] = self._classify(a, b)
                if kind < 0:
                    continue
                d = query.ComputeSignedDistancePairClosestPoints(a, b).distance
                if d <= d_max and d < best[kind][0]:
                    best[kind] = (float(d), (self.names[a], self.names[b]))
        return PairDistances(best[0][0], best[0][1], best[1][0], best[1][1], best[2][0],
                             best[2][1])


def measure_samples(cell, samples, tol, progress=None, n_segments: int = 1):
    """Distances, the Drake-plant FK cross-check and the manipulability at every sample
    -> :class:`drakedeburr.verify.sampling.Distances`.

    The flange pose and the tool pose relative to the hub are read from the Drake plant at
    each sample and compared with the verifier's analytic ones (``samples.X_WF``/``X_HT``).
    """
    from pydrake.multibody.tree import JacobianWrtVariable

    from drakedeburr.verify.sampling import Distances

    probe = DistanceProbe(cell, tol.query_distance)
    plant, pc = cell.plant, probe.plant_context
    n = len(samples)
    clear, selfd, burr = np.full(n, np.inf), np.full(n, np.inf), np.full(n, np.inf)
    clear_pair, self_pair, burr_pair = [("", "")] * n, [("", "")] * n, [("", "")] * n
    manip = np.full(n, np.nan)
    fk_diff = 0.0
    every = max(1, n // 50)
    for i in range(n):
        d = probe.measure(samples.q[i])  # sets the positions in probe's context
        X_WF_d = cell.flange_frame.CalcPoseInWorld(pc).GetAsMatrix4()
        X_HT_d = cell.tool_frame.CalcPose(pc, cell.hub_frame).GetAsMatrix4()
        fk_diff = max(fk_diff, float(np.abs(X_WF_d - samples.X_WF[i]).max()),
                      float(np.abs(X_HT_d - samples.X_HT[i]).max()))
        J = plant.CalcJacobianSpatialVelocity(pc, JacobianWrtVariable.kQDot, cell.flange_frame,
                                              np.zeros(3), plant.world_frame(),
                                              plant.world_frame())
        manip[i] = abs(float(np.linalg.det(J)))
        clear[i], clear_pair[i] = d.clearance, d.clearance_pair
        selfd[i], self_pair[i] = d.self_distance, d.self_pair
        burr[i], burr_pair[i] = d.burr, d.burr_pair
        if progress is not None and (i % every == 0 or i == n - 1):
            progress(n_segments + int(n_segments * (i + 1) / n), 2 * n_segments, "distances")
    return Distances(clearance=clear, clearance_pair=tuple(clear_pair), self_distance=selfd,
                     self_pair=tuple(self_pair), burr=burr, burr_pair=tuple(burr_pair),
                     manipulability=manip, fk_difference=fk_diff)
