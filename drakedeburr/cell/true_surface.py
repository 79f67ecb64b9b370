"""The burr head against the hub's true surface, where its collision pieces over-state contact.

The scene graph measures the burr head against the hub's convex collision pieces. The pieces
contain the part's material but may stand proud of its surface: a generated hub's pieces
reach at most ``Tolerances.collision_model_excess`` (0.5 mm) into a window opening and 1 mm
above the front face within 30 mm of a window (elsewhere the average-thickness rule allows
more locally: 3.7 mm was seen beside a CL point before the front probes,
:func:`drakedeburr.hub.collision.front_probes`), an imported CAD mesh's by up to
``ImportOptions.window_reach`` into an opening and ``front_reach`` above the face near a
window (1 mm each; ``front_reach_far``, 3 mm, further out), where a finer decomposition would
cost minutes. Where the pieces' reading fails ``burr_contact``, this module reads the same samples
against the triangle mesh itself (``HubModel.vertices_H`` / ``faces``).

Written here because no library at hand measures it: Drake's signed distance needs convex
shapes (or a watertight mesh for a hydroelastic volume), open3d's signed distance and
occupancy need a watertight mesh, and CAD exports are often neither.

The measure. The burr head is a solid cone (base at ``z_b``, apex at ``z_a`` on +Z_T, half
angle alpha; :class:`drakedeburr.cell.tools.BurrGeometry`), so a point's signed distance to
it is the 2-D distance in the point's meridian half-plane (z, rho) to the triangle
(z_b, 0), (z_b, r_b), (z_a, 0) (negative inside: minus the distance to the base or the flank;
the axis is no boundary). How deep the material reaches into the cone is the largest depth
of a material point. Depth is a concave function on the cone, so its largest value over a
region lies on the region's boundary (here: the hub's surface) unless the region holds the
cone's deepest point, its in-centre (depth = in-radius): a sample whose in-centre lies inside
a collision piece (which contains the material) keeps the pieces' reading, unless the hub's
mesh is closed and consistently oriented and the in-centre lies outside it by the generalised
winding number (libigl): a convex piece may bridge a concave corner or a fillet by more than
the model excess (on an unseen catalogue hub, in-centres 1.6 mm outside the material lay
inside a piece). The largest depth over the surface is found by branch and bound over its
triangles (:func:`true_surface_distances`); the reading is the bound's upper end, a lower
bound of the signed distance within ``tolerance`` of it.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, cKDTree

#: [m] an in-centre closer than this to the surface (the surface read this near the in-radius
#: deep) keeps the pieces' reading: its inside/outside test would rest on float rounding
INCENTRE_MARGIN = 1e-5

__all__ = ["BurrCone", "TrueSurfaceReading", "burr_cone", "cone_signed_distance",
           "true_surface_distances"]


@dataclass(frozen=True)
class BurrCone:
    """The burr head's solid cone in the tool frame T [m]: base plane z = z_base (radius
    r_base), apex at z = z_apex on the axis, half angle ``alpha`` [rad]."""

    z_base: float
    z_apex: float
    r_base: float
    alpha: float

    @property
    def inradius(self) -> float:
        """Radius of the largest ball inside the cone (touching base and flank)."""
        s = math.sin(self.alpha)
        return (self.z_apex - self.z_base) * s / (1 + s)

    @property
    def incentre_T(self) -> np.ndarray:
        return np.array([0.0, 0.0, self.z_base + self.inradius])

    @property
    def centre_T(self) -> np.ndarray:
        """Centre of the bounding ball used for the queries (mid-height on the axis)."""
        return np.array([0.0, 0.0, 0.5 * (self.z_base + self.z_apex)])

    @property
    def bounding_radius(self) -> float:
        half = 0.5 * (self.z_apex - self.z_base)
        return math.hypot(self.r_base, half)


def burr_cone() -> BurrCone:
    """The verifier's burr (:data:`drakedeburr.cell.tools.BURR`) as a cone in T."""
    from drakedeburr.cell.tools import BURR

    z_apex = BURR.apex_offset
    return BurrCone(z_base=z_apex - BURR.head_length, z_apex=z_apex, r_base=BURR.head_radius,
                    alpha=BURR.cone_half_angle)


def _segment_distance(z, r, a, b) -> np.ndarray:
    """2-D distance of points (z, r) to the segment a-b."""
    d = np.asarray(b, float) - np.asarray(a, float)
    pz, pr = z - a[0], r - a[1]
    u = np.clip((pz * d[0] + pr * d[1]) / (d @ d), 0.0, 1.0)
    return np.hypot(pz - u * d[0], pr - u * d[1])


def cone_signed_distance(cone: BurrCone, p_T: np.ndarray) -> np.ndarray:
    """(n,) signed distance of points in T to the solid cone [m]: negative inside (minus the
    depth below the base or the flank), positive outside."""
    z, r = p_T[:, 2], np.hypot(p_T[:, 0], p_T[:, 1])
    base = _segment_distance(z, r, (cone.z_base, 0.0), (cone.z_base, cone.r_base))
    flank = _segment_distance(z, r, (cone.z_base, cone.r_base), (cone.z_apex, 0.0))
    inside = (z >= cone.z_base) & (z <= cone.z_apex) & (
        r <= (cone.z_apex - z) * math.tan(cone.alpha))
    return np.where(inside, -np.minimum(base, flank), np.minimum(base, flank))


def _depth_supergradient(cone: BurrCone, p_T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n,) depth (minus the signed distance) of points in T and (n, 3) a supergradient of it.

    The depth is concave on all of space (a convex set's signed distance is convex): inside,
    it is the least distance to the cone's supporting planes (the base and the flank's tangent
    plane in the point's meridian), each linear; outside, minus the distance to the nearest
    point. So depth(x) <= depth(y) + g(y) . (x - y) for every x: the bound that settles a
    triangle where one plane is the nearest (:func:`true_surface_distances`)."""
    x, y, z = p_T[:, 0], p_T[:, 1], p_T[:, 2]
    r = np.hypot(x, y)
    safe = np.where(r > 0.0, r, 1.0)
    ex, ey = np.where(r > 0.0, x / safe, 1.0), np.where(r > 0.0, y / safe, 0.0)
    sa, ca = math.sin(cone.alpha), math.cos(cone.alpha)
    sd = cone_signed_distance(cone, p_T)
    inside = sd <= 0.0
    # inside: the nearer of the base plane (depth z - z_b) and the flank's tangent plane
    # (depth (z_a - z) sin a - r cos a)
    base_d = z - cone.z_base
    flank_d = (cone.z_apex - z) * sa - r * ca
    use_base = base_d <= flank_d
    g_in = np.where(use_base[:, None], np.array([0.0, 0.0, 1.0]),
                    np.stack([-ca * ex, -ca * ey, np.full_like(z, -sa)], axis=1))
    # outside: minus the unit vector from the nearest point of the meridian triangle
    q = np.stack([_nearest_on_segment(z, r, (cone.z_base, 0.0), (cone.z_base, cone.r_base)),
                  _nearest_on_segment(z, r, (cone.z_base, cone.r_base), (cone.z_apex, 0.0))])
    dist = np.hypot(z - q[..., 0], r - q[..., 1])
    pick = np.argmin(dist, axis=0)
    qz, qr = np.choose(pick, q[..., 0]), np.choose(pick, q[..., 1])
    dz, dr = z - qz, r - qr
    norm = np.maximum(np.hypot(dz, dr), 1e-300)
    g_out = -np.stack([dr * ex, dr * ey, dz], axis=1) / norm[:, None]
    return -sd, np.where(inside[:, None], g_in, g_out)


def _nearest_on_segment(z, r, a, b) -> np.ndarray:
    """(n, 2) nearest points (z, r) of the segment a-b to the points (z, r)."""
    a, d = np.asarray(a, float), np.asarray(b, float) - np.asarray(a, float)
    u = np.clip(((z - a[0]) * d[0] + (r - a[1]) * d[1]) / (d @ d), 0.0, 1.0)
    return np.stack([a[0] + u * d[0], a[1] + u * d[1]], axis=1)


@dataclass(frozen=True)
class TrueSurfaceReading:
    """Samples read against the true surface.

    Attributes:
        index: (k,) sample indices read; value: (k,) lower bound of the burr head's signed
            distance to the surface [m] (the reading less ``resolution``); engulfed: (k,) the
            cone's in-centre lies inside a collision piece and, where the mesh is closed,
            inside the material (the pieces' reading stands).
        resolution: [m] the largest gap left between the bounds of a sample.
        points: how many (sample, triangle) bounds were read.
    """

    index: np.ndarray
    value: np.ndarray
    engulfed: np.ndarray
    resolution: float
    points: int


class _MeshIndex:
    """A hub mesh's triangles [m] with their bounding balls and a KD-tree of their centroids,
    and (on first use) its closed form: built once per mesh content (:func:`_mesh_index`)."""

    def __init__(self, V: np.ndarray, F: np.ndarray):
        self.V, self.F = V, F
        self.tri = V[F]  # (P, 3, 3)
        self.c = self.tri.mean(axis=1)
        self.rad = np.sqrt(((self.tri - self.c[:, None]) ** 2).sum(axis=2).max(axis=1))
        # the triangles by bounding radius, each class with its own tree (a generated hub's
        # long barrel and face triangles are half its triangles, up to 0.12 m across): a
        # query ball meets a triangle's only if its centroid is within the class's largest
        # radius of the ball
        cls = np.maximum(np.ceil(np.log2(np.maximum(self.rad, 1e-12) / 5e-3)), 0.0).astype(int)
        self.classes = []
        for j in np.unique(cls):
            members = np.flatnonzero(cls == j)
            self.classes.append((members, float(self.rad[members].max()),
                                 cKDTree(self.c[members])))

    @functools.cached_property
    def closed(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(V, F), vertices merged, when the mesh is closed and consistently and outward
        oriented (inside and outside well defined), else None (trimesh, 0.1-0.3 s a hub)."""
        import trimesh

        mesh = trimesh.Trimesh(self.V, self.F, process=True)
        if not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.0):
            return None
        return np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64)


_INDEX: dict[str, _MeshIndex] = {}


def _mesh_index(hub_model) -> _MeshIndex:
    """The :class:`_MeshIndex` of the hub's mesh, kept per mesh content (a digest of its
    arrays, a few ms): a planner reads every window and a verifier every reading against the
    same mesh, whose triangles, tree and closed form take ~0.1 s and 0.1-0.3 s to build."""
    v = np.ascontiguousarray(hub_model.vertices_H, float)
    f = np.ascontiguousarray(hub_model.faces, np.int64)
    digest = hashlib.blake2b(repr((v.shape, f.shape)).encode(), digest_size=16)
    digest.update(v.tobytes())
    digest.update(f.tobytes())
    key = digest.hexdigest()
    if key not in _INDEX:
        if len(_INDEX) >= 4:  # a process sees one hub at a time, a test session a few
            _INDEX.pop(next(iter(_INDEX)))
        v, f = v.copy(), f.copy()  # kept: the caller's arrays may change later
        v.flags.writeable = f.flags.writeable = False
        _INDEX[key] = _MeshIndex(v, f)
    return _INDEX[key]


def _initial_pairs(mesh: _MeshIndex, centres: np.ndarray, radii: np.ndarray):
    """(sample, triangle) pairs whose bounding balls meet: the sample's query ball
    (``centres``, ``radii``) and the triangle's (centroid, farthest vertex)."""
    ks, ts = [], []
    for members, r_max, tree in mesh.classes:
        lists = tree.query_ball_point(centres, radii + r_max)
        counts = np.fromiter((len(x) for x in lists), int, len(lists))
        k = np.repeat(np.arange(len(lists)), counts)
        t = members[np.fromiter(itertools.chain.from_iterable(lists), int, int(counts.sum()))]
        d = mesh.c[t] - centres[k]
        keep = np.einsum("ij,ij->i", d, d) <= (radii[k] + mesh.rad[t]) ** 2
        ks.append(k[keep])
        ts.append(t[keep])
    if not ks:  # a mesh without triangles
        return np.zeros(0, int), np.zeros(0, int)
    return np.concatenate(ks).astype(int), np.concatenate(ts).astype(int)


def _split(tri: np.ndarray) -> np.ndarray:
    """Each triangle into four by its edge midpoints: (4P, 3, 3), children of triangle i at
    rows i, P + i, 2P + i, 3P + i."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
    return np.concatenate([np.stack(t, axis=1) for t in
                           ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


@functools.lru_cache(maxsize=4)
def _piece_planes(paths: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Half-space equations of every collision piece's hull: (P, 4) stacked rows and (n+1,)
    offsets of each piece's rows."""
    import trimesh

    rows, offsets = [], [0]
    for path in paths:
        mesh = trimesh.load(str(path), force="mesh", process=False)
        eq = ConvexHull(np.asarray(mesh.vertices, float)).equations
        rows.append(eq)
        offsets.append(offsets[-1] + len(eq))
    return np.concatenate(rows), np.array(offsets)


def _closed_mesh(hub_model):
    """(V, F) of the hub's mesh, vertices merged, when it is closed and consistently and
    outward oriented (inside and outside well defined), else None."""
    return _mesh_index(hub_model).closed


def _outside_material(hub_model, p_H: np.ndarray) -> np.ndarray | None:
    """(n,) whether each point lies outside the hub's material by the generalised winding
    number (libigl; exact, < 1/2 outside), or None when the mesh is not closed and
    consistently oriented (an open CAD export: inside is not defined, the pieces decide)."""
    closed = _closed_mesh(hub_model)
    if closed is None:
        return None
    import igl

    w = igl.winding_number(closed[0], closed[1], np.ascontiguousarray(p_H, float))
    return np.asarray(w) < 0.5


def _inside_a_piece(planes, offsets, p_H: np.ndarray) -> np.ndarray:
    """(n,) whether each point lies inside (or on) some collision piece."""
    out = np.zeros(len(p_H), bool)
    for a in range(0, len(p_H), 64):  # (64, P) at a time: P is ~10^4-10^5 rows
        s = p_H[a:a + 64] @ planes[:, :3].T + planes[:, 3]
        worst = np.maximum.reduceat(s, offsets[:-1], axis=1)  # per piece: largest excess
        out[a:a + 64] = (worst <= 0.0).any(axis=1)
    return out


def true_surface_distances(hub_model, X_HT: np.ndarray, index: np.ndarray, *,
                           reach: np.ndarray | float, tolerance: float = 2e-6,
                           max_levels: int = 24, cone: BurrCone | None = None,
                           shallow: np.ndarray | float | None = None) -> TrueSurfaceReading:
    """The burr head's signed distance to the hub's triangle mesh at samples ``index``.

    Branch and bound over the mesh's triangles, per sample: a triangle's vertices give a
    lower bound of the largest depth (minus signed distance) of the surface in the cone, and
    its vertices' largest depth + longest edge / sqrt(3) (every point of a triangle lies that
    close to a vertex; depth is 1-Lipschitz) an upper bound; triangles whose upper bound
    cannot beat the sample's lower bound are dropped, the others split in four, until the
    bounds meet within ``tolerance``.

    Args:
        hub_model: :class:`drakedeburr.hub.HubModel` (its mesh and collision pieces, in H).
        X_HT: (N, 4, 4) the samples' tool poses in H.
        index: the samples to read.
        reach: (per sample or one) distances beyond this are not resolved (read as
            ``reach``) [m]; 0 where only a penetration matters.
        tolerance: [m] the bounds' gap at which a sample is settled.
        max_levels: splits at most; a sample still open then keeps its upper bound.
        cone: the burr head (default :func:`burr_cone`).
        shallow: (per sample or one) a depth [m]: a sample whose upper bound of the depth is
            already no deeper is settled there (its reading: that upper bound, within its true
            value's side of ``shallow``); None: every sample to ``tolerance``.
    """
    cone = cone or burr_cone()
    index = np.asarray(index, int)
    n = len(index)
    X = X_HT[index]
    R, p = X[:, :3, :3], X[:, :3, 3]
    centres = p + R @ cone.centre_T
    reach = np.broadcast_to(np.maximum(np.asarray(reach, float), 0.0), (n,)).copy()
    mesh = _mesh_index(hub_model)
    k, t = _initial_pairs(mesh, centres, cone.bounding_radius + reach)
    tri = mesh.tri[t]
    lower = -reach  # depth: anything farther than reach reads as reach
    upper = np.full(n, -np.inf)
    settled = np.zeros(n, bool)
    top = np.full(n, -np.inf)
    early = (np.full(n, -np.inf) if shallow is None
             else np.broadcast_to(np.asarray(shallow, float), (n,)))
    pairs = 0
    for _level in range(max_levels + 1):
        pairs += len(k)
        if not len(k):
            break
        p_T = np.einsum("pvj,pji->pvi", tri - p[k][:, None], R[k])
        sd = cone_signed_distance(cone, p_T.reshape(-1, 3)).reshape(-1, 3)
        depth = (-sd).max(axis=1)  # the deepest vertex of each triangle
        np.maximum.at(lower, k, depth)
        edge = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        # two upper bounds: depth is 1-Lipschitz (every point lies within edge / sqrt(3) of
        # a vertex), and concave (below its tangent plane at the centroid: exact where one
        # supporting plane of the cone is the nearest over the whole triangle)
        c_T = p_T.mean(axis=1)
        f_c, g_c = _depth_supergradient(cone, c_T)
        lin = f_c + np.einsum("pvi,pi->pv", p_T - c_T[:, None], g_c).max(axis=1)
        ub = np.minimum(depth + edge / math.sqrt(3.0), lin)
        live = ub > lower[k]
        k, tri, ub = k[live], tri[live], ub[live]
        top = np.full(n, -np.inf)
        np.maximum.at(top, k, ub)
        done = ~settled & ((top - lower <= tolerance) | (top <= early))
        upper[done] = np.maximum(lower[done], top[done])
        settled |= done
        keep = ~settled[k]
        k, tri = k[keep], tri[keep]
        tri = _split(tri)
        k = np.tile(k, 4)
    open_ = ~settled  # still open after max_levels (or nothing within reach): the last bound
    upper[open_] = np.maximum(lower[open_], top[open_])
    gap = float(np.max(upper - lower)) if n else 0.0
    engulfed = np.zeros(n, bool)
    if hub_model.collision_paths:
        planes, offsets = _piece_planes(tuple(str(q) for q in hub_model.collision_paths))
        incentres = p + R @ cone.incentre_T
        engulfed = _inside_a_piece(planes, offsets, incentres)
        # a piece may bridge a concave corner or fillet: where the mesh is closed, the
        # in-centre is read against the material itself (deep surface readings stay engulfed)
        clear = engulfed & (upper < cone.inradius - INCENTRE_MARGIN)
        if clear.any():
            outside = _outside_material(hub_model, incentres[clear])
            if outside is not None:
                engulfed[np.flatnonzero(clear)[outside]] = False
    return TrueSurfaceReading(index=index, value=np.minimum(-upper, reach), engulfed=engulfed,
                              resolution=max(gap, tolerance), points=pairs)
