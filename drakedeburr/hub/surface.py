"""Front and back surface of a parametric hub's face plate, and the window edge profile
(millimetres inside this module, frame H).

Front height ``z = dish(r) + twist(x, y) + rise(x, y)``, back ``dish(r) + twist(x, y) -
face_thickness`` (see :mod:`drakedeburr.hub.spec` for the parameters):

* ``dish(r) = HubSpec.z_face(r)`` (C1 smoothstep);
* ``twist``: each spoke turns about its radial centre line by ``a(r) = spoke_twist sin^2(pi u)``,
  ``u`` from 0 at the window inner radius to 1 at the outer one; a point at signed lateral
  distance ``l`` from the nearest spoke's centre line is lifted by ``l tan a(r)``. (The switch
  between neighbouring spokes lies inside the windows, where there is no material.)
* ``rise``: within ``b = face_rise_band`` of a window outline the face falls toward the
  edge, ``-tan(face_rise_angle) b/2 (1 - d/b)^2`` at distance ``d`` from the outline: C1 at
  ``d = b``, slope ``face_rise_angle`` at the edge.

The **edge profile** at each outline vertex (a cross-section normal to the outline): the wall
leans by ``wall_draft`` into the opening going down; a round of ``edge_round_radius`` joins
it to the front face, tangent to both (its tangent length is capped so the rounded outline
stays valid). The ring where the round meets the face is the deburring edge ``p_HE``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drakedeburr.hub.outline import Window, densify, outline_normals
from drakedeburr.hub.spec import HubSpec

__all__ = ["FaceSurface", "EdgeRings", "edge_rings", "ROUND_SEGMENTS"]

ROUND_SEGMENTS = 4  # segments of an edge round's arc in the mesh
_GRAD_STEP_MM = 1e-3  # central differences of the smooth part of the face [mm]


class FaceSurface:
    """Height field of the front (and back) face [mm] over plan-view points (K, 2) [mm]."""

    def __init__(self, spec: HubSpec, windows: list[Window]):
        from scipy.spatial import cKDTree

        self.spec = spec
        self.t = spec.face_thickness * 1e3
        self.has_twist = bool(spec.spoke_twist)
        self.has_rise = bool(spec.face_rise_angle)
        if self.has_rise:
            pts = [densify(w.poly_mm, 0.1) for w in windows]
            nrm = [outline_normals(p) for p in pts]
            self._edge_pts = np.concatenate(pts)
            self._edge_n = np.concatenate(nrm)
            self._tree = cKDTree(self._edge_pts)

    # ----------------------------------------------------------------- components
    def dish(self, xy: np.ndarray) -> np.ndarray:
        r = np.hypot(xy[:, 0], xy[:, 1]) * 1e-3
        return self.spec.z_face(r) * 1e3

    def twist(self, xy: np.ndarray) -> np.ndarray:
        s = self.spec
        r = np.hypot(xy[:, 0], xy[:, 1])
        r_in, r_out = s.window_inner_radius * 1e3, s.window_outer_radius * 1e3
        u = np.clip((r - r_in) / (r_out - r_in), 0.0, 1.0)
        alpha = s.spoke_twist * np.sin(np.pi * u) ** 2  # C1 where the spoke meets the rings
        theta = np.arctan2(xy[:, 1], xy[:, 0])
        centre = s.spoke_phase + s.spoke_sweep * u * u
        pitch = 2 * math.pi / s.spoke_count
        rel = (theta - centre + 0.5 * pitch) % pitch - 0.5 * pitch  # to the nearest spoke
        return r * np.sin(rel) * np.tan(alpha)

    def _distance(self, xy: np.ndarray):
        d, i = self._tree.query(xy)
        return d, i

    def rise(self, xy: np.ndarray) -> np.ndarray:
        b = self.spec.face_rise_band * 1e3
        d, _ = self._distance(xy)
        x = np.clip(d / b, 0.0, 1.0)
        return -math.tan(self.spec.face_rise_angle) * 0.5 * b * (1.0 - x) ** 2

    # ----------------------------------------------------------------- surfaces
    def front(self, xy: np.ndarray) -> np.ndarray:
        """(K,) front face height [mm]."""
        z = self.dish(xy)
        if self.has_twist:
            z = z + self.twist(xy)
        if self.has_rise:
            z = z + self.rise(xy)
        return z

    def back(self, xy: np.ndarray) -> np.ndarray:
        """(K,) back face height [mm]."""
        z = self.dish(xy)
        if self.has_twist:
            z = z + self.twist(xy)
        return z + (-self.t)

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """(K, 2) gradient of the front height [-]. Dish and twist by central differences,
        the rise analytically (its distance field is only C0 on the outline itself, where the
        direction away from the edge is used)."""
        h = _GRAD_STEP_MM
        g = np.zeros((len(xy), 2))
        for k in range(2):
            e = np.zeros(2)
            e[k] = h
            zp, zm = self.dish(xy + e), self.dish(xy - e)
            if self.has_twist:
                zp, zm = zp + self.twist(xy + e), zm + self.twist(xy - e)
            g[:, k] = (zp - zm) / (2 * h)
        if self.has_rise:
            b = self.spec.face_rise_band * 1e3
            d, i = self._distance(xy)
            away = -self._edge_n[i]  # out of the opening, into the material
            far = d > 1e-6
            away[far] = (xy[far] - self._edge_pts[i[far]]) / d[far, None]
            slope = math.tan(self.spec.face_rise_angle) * np.clip(1.0 - d / b, 0.0, 1.0)
            g += slope[:, None] * away
        return g

    def normal(self, xy: np.ndarray) -> np.ndarray:
        """(K, 3) unit outward normal of the front face (+Z side)."""
        g = self.gradient(xy)
        n = np.column_stack([-g, np.ones(len(g))])
        return n / np.linalg.norm(n, axis=1, keepdims=True)


@dataclass(frozen=True)
class EdgeRings:
    """The wall of one window from the front face down to the back face [mm].

    Attributes:
        rings: (R, N, 3) points; ring 0 is the front face's boundary (the deburring edge),
            ring R-1 the back face's; the rings in between are the round's arc and the
            round's lower tangent line.
        normals2d: (N, 2) outline vertex normals into the opening.
        wall_normal: (N, 3) unit normal of the wall below the round, into the opening.
    """

    rings: np.ndarray
    normals2d: np.ndarray
    wall_normal: np.ndarray


def edge_rings(spec: HubSpec, surf: FaceSurface, poly: np.ndarray,
               a_max: float) -> EdgeRings:
    """Edge profile rings of one CCW window outline ``poly`` (N, 2) [mm] (module doc).

    Without draft and round the two rings are the outline lifted onto the front and back
    faces (the hub's original construction, bit for bit)."""
    m = outline_normals(poly)
    rho = spec.edge_round_radius * 1e3
    tan_d = math.tan(spec.wall_draft)
    top = poly
    if rho > 0:
        top, arc = _round_profile(surf, poly, m, rho, tan_d, a_max)
    h0 = surf.front(poly)
    if tan_d:
        bottom = poly + ((h0 - surf.back(poly)) * tan_d)[:, None] * m
    else:
        bottom = poly
    rings = [np.column_stack([top, surf.front(top)])]
    if rho > 0:
        rings.extend(arc)
    rings.append(np.column_stack([bottom, surf.back(bottom)]))
    wall = np.column_stack([m * math.cos(spec.wall_draft),
                            np.full(len(m), math.sin(spec.wall_draft))])
    return EdgeRings(np.stack(rings), m, wall)


def _round_profile(surf: FaceSurface, poly: np.ndarray, m: np.ndarray, rho: float,
                   tan_d: float, a_max: float):
    """Face tangent line (N, 2) and the arc rings [(N, 3)] of an edge round of radius ``rho``
    in the plane through each outline vertex spanned by its normal ``m`` and +Z.

    Coordinates in that plane: u along -m (into the material), z up. The face leaves the sharp
    corner C = (0, h0) along f = (1, sigma) (sigma: the face slope into the material), the wall
    along w = (-tan_d, -1)."""
    h0 = surf.front(poly)
    sigma = -np.einsum("ij,ij->i", surf.gradient(poly), m)
    f = np.column_stack([np.ones(len(m)), sigma])
    f /= np.linalg.norm(f, axis=1, keepdims=True)
    w = np.array([-tan_d, -1.0]) / math.hypot(tan_d, 1.0)
    phi = np.arccos(np.clip(f @ w, -1.0, 1.0))  # interior angle at the corner
    a = np.minimum(rho / np.tan(0.5 * phi), a_max)  # tangent length (capped)
    r = a * np.tan(0.5 * phi)  # the round's radius where the cap applies
    bis = f + w
    bis /= np.linalg.norm(bis, axis=1, keepdims=True)
    centre = (r / np.sin(0.5 * phi))[:, None] * bis
    start = a[:, None] * f - centre  # face tangent point, relative to the centre
    end = a[:, None] * w - centre  # wall tangent point
    a0 = np.arctan2(start[:, 1], start[:, 0])
    a1 = np.arctan2(end[:, 1], end[:, 0])
    sweep = (a1 - a0 + np.pi) % (2 * np.pi) - np.pi
    top = poly - (a * f[:, 0])[:, None] * m
    arc = []
    for k in range(1, ROUND_SEGMENTS + 1):
        ang = a0 + sweep * k / ROUND_SEGMENTS
        uz = centre + r[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
        arc.append(np.column_stack([poly - uz[:, 0:1] * m, h0 + uz[:, 1]]))
    return top, arc
