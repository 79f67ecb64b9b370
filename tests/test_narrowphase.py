"""Certified pair distances (cell.narrowphase): the support functions and the exact solve
against analytic distances, the separating-plane bound never above the distance, a brute-force
reading of random convex pairs as a second implementation, and Drake's recorded overestimates
on the default hub's plan held to the exact distance."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, Sphere
from scipy.spatial.transform import Rotation

import drakedeburr.cell.narrowphase as mut

DATA = Path(__file__).parent / "data" / "narrowphase_overestimates.json"


def _pose(rotvec=(0.0, 0.0, 0.0), p=(0.0, 0.0, 0.0)) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    X[:3, 3] = p
    return X


def _cube(half: float = 0.01) -> Convex:
    pts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * half
    return Convex(pts.T, "cube")


# (shape A at the origin, shape B, B's pose, analytic distance [m])
ANALYTIC = [
    # cylinder side (r 3 mm) facing a box face 5 mm away along x
    (Cylinder(0.003, 0.04), Box(0.02, 0.02, 0.02), _pose(p=(0.003 + 0.005 + 0.01, 0, 0)),
     0.005),
    # cylinder cap (half length 20 mm) above a cube's face: 4 mm
    (Cylinder(0.003, 0.04), _cube(), _pose(p=(0, 0, 0.02 + 0.004 + 0.01)), 0.004),
    # cylinder rim to a cube's edge: diagonal gap
    (Cylinder(0.003, 0.04), _cube(), _pose(rotvec=(0, 0, np.pi / 4),
                                           p=(0.003 + 0.002 + 0.01 * np.sqrt(2), 0, 0)), 0.002),
    (Sphere(0.01), Sphere(0.02), _pose(p=(0.0, 0.05, 0.0)), 0.02),
    (Capsule(0.005, 0.03), Sphere(0.01), _pose(p=(0.0, 0.0, 0.015 + 0.005 + 0.01 + 0.003)),
     0.003),
    (Ellipsoid(0.01, 0.02, 0.03), Box(0.01, 0.01, 0.01), _pose(p=(0.0, 0.02 + 0.007 + 0.005, 0)),
     0.007),
]


@pytest.mark.parametrize("A, B, X_WB, expected", ANALYTIC)
def test_exact_distance_and_bound_meet_the_analytic_distance(A, B, X_WB, expected):
    SA, SB = mut.ShapeSupport(A), mut.ShapeSupport(B)
    X_WA = np.eye(4)
    d, n = mut.exact_distance(SA, X_WA, SB, X_WB)
    assert d == pytest.approx(expected, abs=1e-7)
    assert d <= expected + 1e-12  # a lower bound, also as computed
    # along the solved direction the bound is the distance; along any other it is lower
    rng = np.random.default_rng(0)
    for _ in range(50):
        m = n + 0.3 * rng.normal(size=3)
        m /= np.linalg.norm(m)
        assert mut.separation(SA, X_WA, SB, X_WB, m) <= expected + 1e-12


def _hull_points(S: mut.ShapeSupport, X: np.ndarray, rng, n: int = 20000) -> np.ndarray:
    """Points on a cylinder's surface or a convex hull's vertices/faces (world)."""
    if S.kind == "Cylinder":
        phi, z = rng.uniform(0, 2 * np.pi, n), rng.uniform(-S.h, S.h, n)
        rim = np.c_[S.r * np.cos(phi), S.r * np.sin(phi), z]
        rho = S.r * np.sqrt(rng.uniform(0, 1, n))
        caps = np.c_[rho * np.cos(phi), rho * np.sin(phi), np.where(z > 0, S.h, -S.h)]
        P = np.vstack([rim, caps])
    else:
        w = rng.dirichlet(np.full(len(S.V), 0.05), n)  # concentrated near the vertices/faces
        P = np.vstack([S.V, w @ S.V])
    return P @ X[:3, :3].T + X[:3, 3]


def test_random_pairs_against_a_brute_force_reading():
    """Random cylinder / convex-hull pairs: the exact solve is at most the smallest distance of
    dense surface samples (any two points bound it from above) and within the samples'
    resolution of it; Drake's own reading is never below the certified one."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(1)
    for k in range(6):
        cyl = Cylinder(0.003, 0.03)
        pts = rng.normal(size=(12, 3)) * 0.01
        hull = Convex(pts.T, f"piece{k}")
        SA, SB = mut.ShapeSupport(cyl), mut.ShapeSupport(hull)
        X_WA = _pose(rng.normal(size=3), (0, 0, 0))
        X_WB = _pose(rng.normal(size=3), rng.normal(size=3) * 0.005 + (0.03, 0, 0))
        d, _ = mut.exact_distance(SA, X_WA, SB, X_WB)
        PA, PB = _hull_points(SA, X_WA, rng), _hull_points(SB, X_WB, rng)
        brute = float(cKDTree(PB).query(PA)[0].min())
        assert d <= brute + 1e-9
        assert d >= brute - 0.5e-3, (d, brute)


def test_recorded_drake_overestimates_are_held_to_the_exact_distance():
    """Readings of the default hub's plan where Drake's cylinder/convex distance was up to
    1.3 mm too large (recorded with its normal): the certified reading is the exact distance
    (a lower bound, within 1 um); the same two shapes in a scene of their own are certified
    within the reading gap above it whatever Drake reads there."""
    from pydrake.geometry import GeometryInstance, ProximityProperties, SceneGraph
    from pydrake.math import RigidTransform

    cases = json.loads(DATA.read_text())
    assert cases and max(c["drake"] - c["exact"] for c in cases) > 1e-3
    for c in cases:
        cyl = Cylinder(*c["cyl"])
        hull = Convex(np.array(c["V"]).T, "piece")
        X_WA, X_WB = np.array(c["X_WA"]), np.array(c["X_WB"])
        SA, SB = mut.ShapeSupport(cyl), mut.ShapeSupport(hull)
        exact, _ = mut.exact_distance(SA, X_WA, SB, X_WB)
        assert exact == pytest.approx(c["exact"], abs=1e-6)
        value, how = mut.certified_distance(c["drake"], np.array(c["nhat_BA_W"]), SA, X_WA,
                                            SB, X_WB)
        assert how == "solved" and exact - 1e-6 <= value <= exact + 1e-9
        # Drake's narrow phase on the same two shapes, anchored at the recorded poses
        sg = SceneGraph()
        src = sg.RegisterSource("t")
        ids = []
        for shape, X in ((cyl, X_WA), (hull, X_WB)):
            inst = GeometryInstance(RigidTransform(X), shape, f"g{len(ids)}")
            inst.set_proximity_properties(ProximityProperties())
            ids.append(sg.RegisterAnchoredGeometry(src, inst))
        query = sg.get_query_output_port().Eval(sg.CreateDefaultContext())
        r = query.ComputeSignedDistancePairClosestPoints(ids[0], ids[1])
        nhat = np.asarray(r.nhat_BA_W) * (1.0 if r.id_A == ids[0] else -1.0)
        value, how = mut.certified_distance(r.distance, nhat, SA, X_WA, SB, X_WB)
        assert exact - 1e-6 <= value <= exact + mut.READING_GAP and value <= r.distance


def test_accurate_readings_are_kept_bit_for_bit_and_far_ones_bounded():
    SA, SB = mut.ShapeSupport(Cylinder(0.003, 0.04)), mut.ShapeSupport(Box(0.02, 0.02, 0.02))
    X_WA, X_WB = np.eye(4), _pose(p=(0.018, 0, 0))
    n = np.array([-1.0, 0.0, 0.0])  # from B toward A
    value, how = mut.certified_distance(0.005, n, SA, X_WA, SB, X_WB)
    assert (value, how) == (0.005, "kept")
    # a reading 1 mm too large with a tilted normal: bounded, and solved where it matters
    tilted = np.array([-1.0, 0.4, 0.0]) / np.hypot(1.0, 0.4)
    value, how = mut.certified_distance(0.006, tilted, SA, X_WA, SB, X_WB, solve_below=-1.0)
    assert how == "bound" and value < 0.005
    assert value == mut.separation(SA, X_WA, SB, X_WB, tilted)
    value, how = mut.certified_distance(0.006, tilted, SA, X_WA, SB, X_WB, solve_below=0.01)
    assert how == "solved" and value == pytest.approx(0.005, abs=1e-7) and value <= 0.005
    # a reading already below the limit it is checked against is not solved: its bound
    value, how = mut.certified_distance(0.006, tilted, SA, X_WA, SB, X_WB, solve_below=0.01,
                                        solve_from=0.007)
    assert how == "bound" and value == mut.separation(SA, X_WA, SB, X_WB, tilted)
    # contact readings are the process's business: kept
    assert mut.certified_distance(-0.001, n, SA, X_WA, SB, X_WB) == (-0.001, "kept")


def test_tally_reports_what_was_done():
    t = mut.ReadingTally()
    t.add(0.005, 0.005, "kept")
    t.add(0.006, 0.005, "solved")
    t.add(0.009, 0.007, "bound")
    assert t.counts == {"kept": 1, "bound": 1, "solved": 1} and t.lowered == 2
    assert t.overestimate == pytest.approx(0.001)
    assert "3 positive readings" in t.summary() and "1.000 mm" in t.summary()


def test_bounding_and_box_points_contain_each_shape():
    """bounding_points (points + padding) and box_points hold every shape: its support along
    random directions never exceeds theirs, and equals it where conv(P) + ball(rho) is the
    shape itself (box, capsule, sphere)."""
    from pydrake.geometry import Box, Capsule, Cylinder, Ellipsoid, Sphere

    from drakedeburr.cell.narrowphase import ShapeSupport, bounding_points, box_points

    rng = np.random.default_rng(5)
    n = rng.normal(size=(200, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    I = np.eye(4)
    for shape in (Box(0.1, 0.2, 0.3), Cylinder(0.05, 0.2), Capsule(0.03, 0.1), Sphere(0.04),
                  Ellipsoid(0.1, 0.05, 0.02)):
        s = np.array([ShapeSupport(shape).support(I, v) for v in n])
        P, rho = bounding_points(shape)
        assert np.all((P @ n.T).max(0) + rho >= s - 1e-12)
        assert np.all((box_points(shape) @ n.T).max(0) >= s - 1e-12)
        if isinstance(shape, (Box, Capsule, Sphere)):  # exact: conv(P) + ball(rho) is the shape
            assert np.isclose(((P @ n.T).max(0) + rho - s).min(), 0.0, atol=1e-12)


def _shape_points(shape, n: int = 20000) -> np.ndarray:
    """Dense points of a shape in its frame whose hull is within ~1e-4 of it (a second
    description of each shape: corners, rims, spheres)."""
    k = np.arange(n) + 0.5
    phi, z = np.pi * (1 + 5 ** 0.5) * k, 1 - 2 * k / n  # Fibonacci sphere
    u = np.c_[np.sqrt(1 - z ** 2) * np.cos(phi), np.sqrt(1 - z ** 2) * np.sin(phi), z]
    if isinstance(shape, Box):
        half = np.array([shape.width(), shape.depth(), shape.height()]) / 2
        return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    if isinstance(shape, Cylinder):
        a = np.linspace(0, 2 * np.pi, n, endpoint=False)
        rim = np.c_[shape.radius() * np.cos(a), shape.radius() * np.sin(a), np.zeros(n)]
        h = np.array([0, 0, shape.length() / 2])
        return np.vstack([rim + h, rim - h])
    if isinstance(shape, Capsule):
        h = np.array([0, 0, shape.length() / 2])
        return np.vstack([shape.radius() * u + h, shape.radius() * u - h])
    if isinstance(shape, Sphere):
        return shape.radius() * u
    if isinstance(shape, Ellipsoid):
        return u * np.array([shape.a(), shape.b(), shape.c()])
    return mut.hull_vertices(shape)


def test_support_is_the_largest_projection_and_posed_shapes_agree():
    """Each shape kind's support is the largest n.x over dense points of the posed shape (its
    hull's vertices for Box/Convex: exact; surface samples otherwise, within their spacing), and
    a shape fixed at its pose (`posed`, world vertices computed once) gives the same support
    and the same exact distance."""
    rng = np.random.default_rng(7)
    shapes = [Box(0.1, 0.2, 0.3), Cylinder(0.05, 0.2), Capsule(0.03, 0.1), Sphere(0.04),
              Ellipsoid(0.1, 0.05, 0.02), _cube(0.02)]
    for shape in shapes:
        S = mut.ShapeSupport(shape)
        X = _pose(rng.normal(size=3), rng.normal(size=3) * 0.1)
        P = _shape_points(shape) @ X[:3, :3].T + X[:3, 3]
        fixed = S.posed(X)
        for _ in range(20):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            s = S.support(X, n)
            top = float((P @ n).max())
            assert s >= top - 1e-12, (S.kind, s, top)
            assert s <= top + 1e-4, (S.kind, s, top)
            assert abs(fixed.support(np.eye(4), n) - s) <= 1e-12
        other = mut.ShapeSupport(Sphere(0.01))
        X_o = _pose(p=X[:3, 3] + (0.5, 0.0, 0.0))
        assert abs(mut.exact_distance(fixed, np.eye(4), other, X_o)[0]
                   - mut.exact_distance(S, X, other, X_o)[0]) <= 1e-9
