"""Certified pair distances: Drake's narrow-phase reading held to a rigorous lower bound.

Drake's signed distance of separated shapes (FCL/libccd GJK) converges from above and stops at
a tolerance; on this cell it was measured up to 3.3 mm too large (the burr shank's Cylinder
against a hub piece's Convex: Drake 5.30 mm where the shapes are 2.0-2.1 mm apart,
``benchmarks/study_narrowphase.py``). A clearance proof cannot rest on that number. Here every
positive reading is checked against a bound that holds whatever the narrow phase did:

* for any unit vector ``n`` (from B toward A), ``min_{a in A} n.a - max_{b in B} n.b`` is at
  most the distance of A and B (the separating-plane bound: support functions of the shapes,
  exact for boxes, cylinders, capsules, spheres, ellipsoids and convex hulls);
* along Drake's own normal the bound meets the reading to within ``READING_GAP`` in almost
  every case: the reading is then kept as it is (it lies within that above the true distance);
* otherwise the distance is solved again as a small second-order-cone program (Drake's
  ``MathematicalProgram`` with Clarabel: the closest points of the two convex sets), and the
  reading becomes the separating-plane bound along the solved direction: a rigorous lower bound
  however accurate the solver, and equal to the distance up to its tolerance.

Why partly hand-written: Drake offers no second narrow phase to cross-check FCL's, and the
support functions of its shape types are a few lines each; the optimisation itself is
Drake's.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ShapeSupport", "separation", "certified_distance", "exact_distance", "ReadingTally",
           "READING_GAP", "hull_vertices", "bounding_points", "box_points"]

#: a reading within this of the separating-plane bound along its own normal is kept [m]
READING_GAP = 1e-6


_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def hull_vertices(shape) -> np.ndarray:
    """(k, 3) vertices of the convex hull Drake's proximity engine uses for a Convex or Mesh
    shape, in its frame [m]."""
    hull = shape.GetConvexHull()
    return np.array([hull.vertex(i) for i in range(hull.num_vertices())], float)


def bounding_points(shape) -> tuple[np.ndarray, float]:
    """Points P (k, 3) in the shape's frame and a padding rho [m] with the shape inside
    conv(P) + ball(rho): every convex function of the points (a distance from a point or a
    line) is at most its largest value over P plus rho."""
    from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, Mesh, Sphere

    if isinstance(shape, (Convex, Mesh)):
        return hull_vertices(shape), 0.0
    if isinstance(shape, Box):
        return _CORNERS * 0.5 * np.array([shape.width(), shape.depth(), shape.height()]), 0.0
    if isinstance(shape, Cylinder):
        r = shape.radius()
        return _CORNERS * np.array([r, r, 0.5 * shape.length()]), 0.0
    if isinstance(shape, Ellipsoid):
        return _CORNERS * np.array([shape.a(), shape.b(), shape.c()]), 0.0
    if isinstance(shape, Sphere):
        return np.zeros((1, 3)), float(shape.radius())
    if isinstance(shape, Capsule):
        return np.array([[0, 0, -0.5], [0, 0, 0.5]]) * shape.length(), float(shape.radius())
    raise TypeError(f"unsupported collision shape {type(shape).__name__}")


def box_points(shape) -> np.ndarray:
    """Points whose convex hull contains the shape, in its frame [m]: the
    :func:`bounding_points` with each padded point replaced by the corners of its box."""
    P, rho = bounding_points(shape)
    if rho == 0.0:
        return P
    return (P[:, None, :] + rho * _CORNERS[None]).reshape(-1, 3)


class ShapeSupport:
    """Support function and convex membership of one Drake shape (in its own frame).

    Args:
        shape: a ``pydrake.geometry`` Box, Cylinder, Capsule, Sphere, Ellipsoid, Convex or Mesh
            (the last two as their convex hull, as Drake's proximity engine treats them).
    """

    def __init__(self, shape) -> None:
        from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, Mesh, Sphere

        self.kind = type(shape).__name__
        self.fixed = False  # see posed()
        self.V = None
        if isinstance(shape, (Convex, Mesh)):
            self.V = hull_vertices(shape)
            self.kind = "Convex"
        elif isinstance(shape, Box):
            self.half = np.array([shape.width(), shape.depth(), shape.height()], float) / 2
            self._half = tuple(self.half.tolist())
        elif isinstance(shape, Cylinder):
            self.r, self.h = float(shape.radius()), float(shape.length()) / 2
        elif isinstance(shape, Capsule):
            self.r, self.h = float(shape.radius()), float(shape.length()) / 2
        elif isinstance(shape, Sphere):
            self.r = float(shape.radius())
        elif isinstance(shape, Ellipsoid):
            self.abc = np.array([shape.a(), shape.b(), shape.c()], float)
            self._abc = tuple(self.abc.tolist())
        else:
            raise TypeError(f"unsupported collision shape {type(shape).__name__}")

    def support(self, X: np.ndarray, n: np.ndarray) -> float:
        """max over the shape posed at ``X`` (4, 4) in world of ``n . x`` [m]."""
        # The verifier and the planner call this ~10^5 times a hub: plain floats for the
        # closed forms (numpy's per-call overhead on 3-vectors was most of its cost).
        nl = X[:3, :3].T @ n
        k = self.kind
        if k == "Convex":
            s = float((self.V @ nl).max())
        else:
            x, y, z = nl.tolist()
            if k == "Box":
                hx, hy, hz = self._half
                s = abs(x) * hx + abs(y) * hy + abs(z) * hz
            elif k == "Cylinder":
                s = self.r * math.hypot(x, y) + self.h * abs(z)
            elif k == "Capsule":
                s = self.h * abs(z) + self.r * math.sqrt(x * x + y * y + z * z)
            elif k == "Sphere":
                s = self.r * math.sqrt(x * x + y * y + z * z)
            else:  # Ellipsoid
                a, b, c = self._abc
                s = math.sqrt((a * x) ** 2 + (b * y) ** 2 + (c * z) ** 2)
        return float(X[:3, 3] @ n) + s

    def posed(self, X: np.ndarray) -> ShapeSupport:
        """This shape fixed at world pose ``X`` (4, 4): a support whose :meth:`support`
        ignores its pose argument (always ``X``) and, for a hull, reads world-frame vertices
        computed once (the hub's pieces in the tool-in-hand cell never move)."""
        return _PosedSupport(self, np.array(X, float))

    def add_point(self, prog, X: np.ndarray):
        """A point of the shape posed at ``X`` as decision variables of ``prog``: returns
        (variables, M (3, k), c (3,)) with the world point ``M @ variables + c``."""
        R, c = X[:3, :3], X[:3, 3]
        k = self.kind
        if k == "Convex":
            lam = prog.NewContinuousVariables(len(self.V), "lam")
            prog.AddBoundingBoxConstraint(0.0, 1.0, lam)
            prog.AddLinearEqualityConstraint(np.ones((1, len(lam))), [1.0], lam)
            return lam, R @ self.V.T, c
        x = prog.NewContinuousVariables(3, "x")
        if k == "Box":
            prog.AddBoundingBoxConstraint(-self.half, self.half, x)
        elif k == "Cylinder":  # (r, x0, x1) in the Lorentz cone, |x2| <= h
            prog.AddLorentzConeConstraint(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float),
                                          np.array([self.r, 0, 0]), x)
            prog.AddBoundingBoxConstraint(-self.h, self.h, x[2:])
        elif k == "Capsule":  # the point is within r of (0, 0, s), |s| <= h
            s = prog.NewContinuousVariables(1, "s")
            prog.AddBoundingBoxConstraint(-self.h, self.h, s)
            A = np.zeros((4, 4))
            A[1:, :3] = np.eye(3)
            A[3, 3] = -1.0
            prog.AddLorentzConeConstraint(A, np.array([self.r, 0, 0, 0]),
                                          np.concatenate([x, s]))
        elif k == "Sphere":
            prog.AddLorentzConeConstraint(np.vstack([np.zeros(3), np.eye(3)]),
                                          np.array([self.r, 0, 0, 0]), x)
        else:  # Ellipsoid: |x / abc| <= 1
            prog.AddLorentzConeConstraint(np.vstack([np.zeros(3), np.diag(1.0 / self.abc)]),
                                          np.array([1.0, 0, 0, 0]), x)
        return x, R, c


class _PosedSupport:
    """:meth:`ShapeSupport.posed`: a shape at a fixed world pose."""

    def __init__(self, shape: ShapeSupport, X: np.ndarray) -> None:
        self.shape, self.X, self.kind, self.fixed = shape, X, shape.kind, True
        self._V_W = None if shape.V is None else shape.V @ X[:3, :3].T + X[:3, 3]

    def support(self, X: np.ndarray, n: np.ndarray) -> float:
        if self._V_W is not None:
            return float((self._V_W @ n).max())
        return self.shape.support(self.X, n)

    def add_point(self, prog, X: np.ndarray):
        return self.shape.add_point(prog, self.X)


def separation(A: ShapeSupport, X_WA: np.ndarray, B: ShapeSupport, X_WB: np.ndarray,
               n_BA: np.ndarray) -> float:
    """The separating-plane bound along unit ``n_BA`` (from B toward A) [m]: at most the
    distance of the two posed shapes, whatever ``n_BA``."""
    return -A.support(X_WA, -n_BA) - B.support(X_WB, n_BA)


def exact_distance(A: ShapeSupport, X_WA: np.ndarray, B: ShapeSupport,
                   X_WB: np.ndarray) -> tuple[float, np.ndarray]:
    """The distance of two separated convex shapes by a second-order-cone program (Drake,
    Clarabel), returned as the separating-plane bound along the solved direction (rigorous,
    module docstring). Returns (distance [m] or -inf when the solver failed, unit direction
    from B toward A)."""
    from pydrake.solvers import ClarabelSolver, MathematicalProgram

    prog = MathematicalProgram()
    va, Ma, ca = A.add_point(prog, X_WA)
    vb, Mb, cb = B.add_point(prog, X_WB)
    t = prog.NewContinuousVariables(1, "t")
    # (t, a - b) in the Lorentz cone, minimise t
    na, nb = len(va), len(vb)
    M = np.zeros((4, 1 + na + nb))
    M[0, 0] = 1.0
    M[1:, 1:1 + na], M[1:, 1 + na:] = Ma, -Mb
    z = np.concatenate([t, va, vb])
    prog.AddLorentzConeConstraint(M, np.concatenate([[0.0], ca - cb]), z)
    prog.AddLinearCost(np.ones(1), t)
    result = ClarabelSolver().Solve(prog)
    if not result.is_success():
        return -np.inf, np.zeros(3)
    v = Ma @ result.GetSolution(va) + ca - Mb @ result.GetSolution(vb) - cb
    norm = float(np.linalg.norm(v))
    if norm <= 0.0:
        return -np.inf, np.zeros(3)
    n = v / norm
    return separation(A, X_WA, B, X_WB, n), n


def certified_distance(d: float, n_BA: np.ndarray, A: ShapeSupport, X_WA: np.ndarray,
                       B: ShapeSupport, X_WB: np.ndarray, *, solve_below: float = np.inf,
                       solve_from: float = -np.inf) -> tuple[float, str]:
    """Drake's reading ``d`` [m] with its normal ``n_BA`` (from B toward A), held to the
    separating-plane bound (module docstring).

    Returns (the certified reading [m], how): ``"kept"`` Drake's reading, within ``gap`` =
    :data:`READING_GAP` above the distance; ``"bound"`` the bound along Drake's normal, which
    is at least ``solve_below`` (rigorous; it may understate a distance that is far from
    mattering);
    ``"solved"`` the bound along the exactly solved direction (or Drake's reading when that
    bound confirms it within ``gap``). Readings at or below zero (contact) are kept. A reading
    below ``solve_from`` (a limit it already fails, whatever the error) is not solved: its
    bound is returned (the planner's probes read thousands of blocked poses).
    """
    if not d > 0.0:
        return d, "kept"
    gap = READING_GAP
    sep = separation(A, X_WA, B, X_WB, np.asarray(n_BA, float))
    if sep >= d - gap:
        return d, "kept"
    if sep >= solve_below or d < solve_from:
        return sep, "bound"
    bound, _ = exact_distance(A, X_WA, B, X_WB)
    if bound >= d - gap:  # Drake's distance was right, its normal was not
        return d, "solved"
    return max(bound, sep), "solved"


class ReadingTally:
    """What :func:`certified_distance` did over a run: counts per outcome, and the largest
    amount by which an exactly solved reading fell below Drake's [m] (Drake's overestimate)."""

    def __init__(self) -> None:
        self.counts = {"kept": 0, "bound": 0, "solved": 0}
        self.lowered = 0
        self.overestimate = 0.0

    def add(self, d: float, value: float, how: str) -> None:
        self.counts[how] += 1
        if value < d:
            self.lowered += 1
            if how == "solved":
                self.overestimate = max(self.overestimate, d - value)

    def merge(self, other: ReadingTally) -> None:
        """Add another run's tally (a part of a sweep read in another process)."""
        for k, v in other.counts.items():
            self.counts[k] += v
        self.lowered += other.lowered
        self.overestimate = max(self.overestimate, other.overestimate)

    def summary(self) -> str:
        c = self.counts
        return (f"narrow phase: each of {sum(c.values())} positive readings held to a "
                f"separating-plane lower bound, {self.lowered} lowered to it, {c['solved']} "
                f"solved exactly (SOCP) near the limit, where Drake read up to "
                f"{self.overestimate * 1e3:.3f} mm too far")
