"""Synthetic test geometry for the frames/orientation/registration tests (analytic truth).

A plate whose front face is z = 0 (material below, z in [-thickness, 0]) with through-openings
shaped as rounded rectangles; the edge loops, tangents, wall normals and curvature are known
in closed form. Used until (and beside) the bundled hubs.
"""

from __future__ import annotations

import numpy as np

from drakedeburr.hub.types import ScanCloud
from drakedeburr.path.types import ClPath


def rounded_rect_loop(a, b, r, n, center=(0.0, 0.0), angle=0.0):
    """CCW loop of a rounded rectangle (half sizes a, b, corner radius r) at z = 0.

    Returns p (n, 3), t (n, 3), n_wall (n, 3) (into the opening), kappa (n,), s (n,)."""
    corners = [(a - r, b - r, 0.0), (-(a - r), b - r, np.pi / 2),
               (-(a - r), -(b - r), np.pi), (a - r, -(b - r), 1.5 * np.pi)]
    straight = [2 * (b - r), 2 * (a - r), 2 * (b - r), 2 * (a - r)]
    arc = np.pi / 2 * r
    total = 2 * sum(straight[:2]) + 4 * arc
    # start at (a, 0) going +y; segments: half straight, corner, straight, corner, ...
    s = np.linspace(0, total, n, endpoint=False)
    segs = [("line", straight[0] / 2, (a, 0.0), (0.0, 1.0))]
    for k, (cx, cy, phi) in enumerate(corners):
        segs.append(("arc", arc, (cx, cy), phi))
        nxt = straight[(k + 1) % 4]
        ang = phi + np.pi / 2
        start = (cx + r * np.cos(ang), cy + r * np.sin(ang))
        tdir = (-np.sin(ang), np.cos(ang))
        segs.append(("line", nxt if k < 3 else nxt / 2, start, tdir))
    P = np.zeros((n, 2))
    T = np.zeros((n, 2))
    K = np.zeros(n)
    acc = 0.0
    for kind, length, o, extra in segs:
        sel = (s >= acc - 1e-15) & (s < acc + length)
        u = s[sel] - acc
        if kind == "line":
            P[sel] = np.asarray(o) + u[:, None] * np.asarray(extra)
            T[sel] = extra
        else:
            ang = extra + u / r
            P[sel] = np.c_[o[0] + r * np.cos(ang), o[1] + r * np.sin(ang)]
            T[sel] = np.c_[-np.sin(ang), np.cos(ang)]
            K[sel] = 1.0 / r
        acc += length
    c, sn = np.cos(angle), np.sin(angle)
    Rz = np.array([[c, -sn], [sn, c]])
    P = P @ Rz.T + np.asarray(center)
    T = T @ Rz.T
    p = np.c_[P, np.zeros(n)]
    t = np.c_[T, np.zeros(n)]
    n_wall = np.c_[-T[:, 1], T[:, 0], np.zeros(n)]
    return p, t, n_wall, K, s


def rounded_rect_cross_section(a, b, r, center=(0.0, 0.0), angle=0.0):
    from manifold3d import CrossSection

    cs = CrossSection.square((2 * (a - r), 2 * (b - r)), center=True).offset(
        r, join_type=__import__("manifold3d").JoinType.Round, circular_segments=720)
    return cs.rotate(np.degrees(angle)).translate(center)


def plate_with_openings(openings, size=(0.08, 0.06), thickness=0.01, round_segments=96):
    """trimesh plate [-sx/2, sx/2] x [-sy/2, sy/2] x [-thickness, 0] minus the openings
    (list of (a, b, r, center, angle))."""
    import trimesh
    from manifold3d import Manifold

    plate = Manifold.cube((size[0], size[1], thickness), center=True).translate(
        (0, 0, -thickness / 2))
    for a, b, r, center, angle in openings:
        cs = rounded_rect_cross_section(a, b, r, center, angle)
        hole = Manifold.extrude(cs, thickness * 3).translate((0, 0, -thickness * 2))
        plate = plate - hole
    mesh = plate.to_mesh()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))


def scan_of(mesh, spacing=0.3e-3, sigma=0.05e-3, seed=0, box=None):
    """Noisy point cloud of the mesh surface (uniform density, Gaussian noise along the true
    normal), optionally cropped to box = (lo, hi)."""
    import trimesh

    rng = np.random.default_rng(seed)
    count = int(mesh.area / spacing**2)
    pts, fid = trimesh.sample.sample_surface(mesh, count, seed=seed)
    pts = pts + rng.normal(0.0, sigma, len(pts))[:, None] * mesh.face_normals[fid]
    if box is not None:
        keep = np.all((pts >= box[0]) & (pts <= box[1]), axis=1)
        pts = pts[keep]
    return ScanCloud(pts, None, source="synthetic scan")


def cl_from_loop(p, t, kappa, s, window_index=0, kind="large"):
    total = float(s[-1] + np.linalg.norm(p[0] - p[-1]))
    return ClPath(window_index, kind, "test", s / total, p, t, kappa, s, total)


def disc_with_windows(n=5, radius=0.06, thickness=0.012, window=(0.012, 0.008, 0.004),
                      ring=0.035, segments=180):
    """A hub-like disc (front face z = 0) with n rounded-rectangle windows on a ring; the
    windows' long axis is radial, so the part is n-fold symmetric about +Z."""
    import trimesh
    from manifold3d import Manifold

    disc = Manifold.cylinder(thickness, radius, radius, segments).translate((0, 0, -thickness))
    hub = Manifold.cylinder(thickness * 2, 0.008, 0.008, 64).translate((0, 0, -thickness * 1.5))
    boss = Manifold.cylinder(0.006, 0.018, 0.014, 64)  # front boss: no front/back symmetry
    disc = (disc + boss) - hub
    a, b, r = window
    for k in range(n):
        ang = 2 * np.pi * k / n
        cs = rounded_rect_cross_section(a, b, r, (ring * np.cos(ang), ring * np.sin(ang)), ang)
        disc = disc - Manifold.extrude(cs, thickness * 3).translate((0, 0, -thickness * 2))
    mesh = disc.to_mesh()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))
