"""Where the tool point T goes for a CL point: burr contact geometry and depth of cut.

Geometry (all in the hub frame H, local frame ``R_HL = [N, T, B]`` of the orientation stage:
N inner normal out of the material into the opening, T feed tangent, B ~ face normal).

The burr is a cone (half-angle ``alpha`` = 45 deg). The tool frame T of the tool models sits on
the burr axis at the height of the *nominal contact circle* of radius ``r_c``
(``BurrGeometry.contact_radius``); +Z_T points spindle -> tip, i.e. ``z_T = -a`` with ``a`` the
CAM tool axis (tip -> spindle) of the ToolPath.

The edge point C is the corner between the front face and the window's side wall. Cutting a
chamfer of leg ``d`` (the depth of cut, 1.5 mm large / 1.2 mm small windows) means the cone's
flank passes through the point ``C' = C - d N`` on the face, ``d`` into the material, and the
flank then meets the side wall ``d`` below the face (for an upright 45 deg burr: a symmetric
45 deg chamfer of leg ``d``). We put ``C'`` on the nominal contact circle, so the tool point is

    p_HT = C - d N + r_c u,      u = (N - (N.a) a) / |N - (N.a) a|

(u: the inner normal projected into the plane normal to the axis, from the contact toward the
axis, which lies over the opening). Inverse (what a verifier uses to compare a tool pose with
the true edge): ``C = p_HT - r_c u + d N``.

Cutting lower on the flank (a circle of radius r < r_c, :func:`contact_geometry`) raises T by
``lift = (r_c - r) / tan(alpha)`` along the axis: ``p_HT = C - d N + r u + lift a``. The planner
uses r = 1.6 mm by default (``PlanOptions.contact_radius``): it lifts the burr shank 1.4 mm,
which it needs for 2 mm clearance over the face with the orientation stage's lead angle
(docs/plan.md); it only just exceeds the 1.5 mm depth of cut (the chamfer's bottom is cut near
the apex - a trade-off documented in docs/plan.md).

The offset is computed with the preferred axis of the ToolPath; the IK ties the circle's centre
``Q = C - d N + r u`` (not T) to its target and may tilt the axis inside the cone about it,
which moves the implied edge point only through the tilt of u (``r * |du|``);
:func:`edge_point_from_tool_pose` gives the exact implied point for any pose.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "tool_point_H",
    "edge_point_from_tool_pose",
    "X_HT_from_axis",
    "spin_of",
    "burr_contact_radius",
    "contact_geometry",
    "cross",
]


def burr_contact_radius(burr=None) -> float:
    """Nominal contact radius r_c [m] of the burr (default: the bundled tool models')."""
    if burr is None:
        from drakedeburr.cell.tools import BURR as burr
    return float(burr.contact_radius)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of (..., 3) float arrays, bit for bit: the same products and differences in
    the same order (``a1 b2 - a2 b1``, ``a2 b0 - a0 b2``, ``a0 b1 - a1 b0``), without its
    axis handling, which costs ~20 us a call on the few rows of a cone search's cells."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` over their norms: ``np.linalg.norm(v, axis=-1, keepdims=True)`` spelled as
    numpy computes it for a float array (the root of the reduced squares), bit for bit."""
    return v / np.sqrt(np.add.reduce(v * v, axis=-1, keepdims=True))


def _u(n_H: np.ndarray, retract_H: np.ndarray) -> np.ndarray:
    a = _unit(np.asarray(retract_H, float))
    n = np.asarray(n_H, float)
    return _unit(n - np.sum(n * a, axis=-1, keepdims=True) * a)


def tool_point_H(p_HC: np.ndarray, n_H: np.ndarray, retract_H: np.ndarray, depth: float,
                 r_c: float, lift: float = 0.0) -> np.ndarray:
    """Tool point p_HT for CL points.

    Args:
        p_HC: (M, 3) edge (CL) points in H [m].
        n_H: (M, 3) unit inner normals (out of the material into the opening).
        retract_H: (M, 3) unit tool axes (tip -> spindle).
        depth: chamfer leg / depth of cut [m].
        r_c: radius of the flank circle that touches C' [m].
        lift: distance [m] from that circle's centre back along the axis (toward the spindle)
            to the tool frame T (0 when the circle is T's own; see :func:`contact_geometry`).

    Returns:
        (M, 3) tool points in H [m].
    """
    n = np.asarray(n_H, float)
    a = _unit(np.asarray(retract_H, float))
    return np.asarray(p_HC, float) - depth * n + r_c * _u(n, a) + lift * a


def edge_point_from_tool_pose(X_HT: np.ndarray, n_H: np.ndarray, depth: float,
                              r_c: float, lift: float = 0.0) -> np.ndarray:
    """The edge point a tool pose cuts (inverse of :func:`tool_point_H`).

    Args:
        X_HT: (..., 4, 4) tool poses in H [m].
        n_H: (..., 3) inner normals at the edge.
        depth, r_c, lift: as in :func:`tool_point_H`.

    Returns:
        (..., 3) implied edge points in H [m].
    """
    X_HT = np.asarray(X_HT, float)
    a = -X_HT[..., :3, 2]
    n = np.asarray(n_H, float)
    return X_HT[..., :3, 3] - lift * a - r_c * _u(n, a) + depth * n


def contact_geometry(r_contact: float | None = None, burr=None) -> tuple[float, float]:
    """(radius, lift) of the flank circle used for cutting [m].

    The tool frame T sits at the height of the burr's nominal contact circle
    (``BurrGeometry.contact_radius``, 3 mm). Cutting lower on the flank, on a circle of radius
    ``r_contact`` < r_c, raises the whole burr (and its shank) by ``lift = (r_c - r_contact) /
    tan(alpha)`` for the same chamfer; the circle must still reach the chamfer's far side
    (r_contact > depth of cut).

    Args:
        r_contact: radius of the cutting circle [m] (None: the nominal one, lift 0).
    """
    if burr is None:
        from drakedeburr.cell.tools import BURR as burr
    r_c = float(burr.contact_radius)
    if r_contact is None:
        return r_c, 0.0
    if not 0.0 < r_contact <= burr.head_radius:
        raise ValueError(f"contact radius {r_contact} m is not on the burr's flank "
                         f"(0, {burr.head_radius}]")
    return float(r_contact), float((r_c - r_contact) / np.tan(burr.cone_half_angle))


def X_HT_from_axis(p_HT: np.ndarray, retract_H: np.ndarray, t_H: np.ndarray,
                   spin: np.ndarray | float = 0.0) -> np.ndarray:
    """Tool poses from a position, a tool axis and a spin about it.

    +Z_T = -axis; spin 0 puts +X_T along the feed tangent projected normal to the axis; the
    spin [rad] turns X_T about +Z_T.

    Args:
        p_HT: (M, 3) [m]; retract_H: (M, 3) unit (tip -> spindle); t_H: (M, 3) feed tangents;
        spin: scalar or (M,) [rad].

    Returns:
        (M, 4, 4) X_HT.
    """
    # the cone search builds ~20 k of these for a few axes each: numpy's reductions, products
    # and cross products written out (the same operations in the same order, bit for bit) so
    # that the per-call overhead does not dominate
    p = np.atleast_2d(np.asarray(p_HT, float))
    z = -_unit(np.atleast_2d(np.asarray(retract_H, float)))
    t = np.atleast_2d(np.asarray(t_H, float))
    e1 = _unit(t - np.add.reduce(t * z, axis=-1, keepdims=True) * z)
    e2 = cross(z, e1)
    s = np.asarray(spin, float)
    if s.ndim == 0:  # one spin: its cosine and sine once (the same factors on every row)
        x = np.cos(s) * e1 + np.sin(s) * e2
    else:
        s = np.broadcast_to(s, (p.shape[0],))[:, None]
        x = np.cos(s) * e1 + np.sin(s) * e2
    y = cross(z, x)
    X = np.empty((p.shape[0], 4, 4))
    X[:, :3, 0], X[:, :3, 1], X[:, :3, 2], X[:, :3, 3] = x, y, z, p
    X[:, 3, :3] = 0.0
    X[:, 3, 3] = 1.0
    return X


def spin_of(X_HT: np.ndarray, t_H: np.ndarray) -> np.ndarray:
    """Spin [rad] of tool poses (..., 4, 4) about their axis, relative to the feed tangent."""
    X_HT = np.asarray(X_HT, float)
    z = X_HT[..., :3, 2]
    t = np.asarray(t_H, float)
    e1 = _unit(t - np.sum(t * z, axis=-1, keepdims=True) * z)
    e2 = cross(z, e1)
    x = X_HT[..., :3, 0]
    return np.arctan2(np.sum(x * e2, axis=-1), np.sum(x * e1, axis=-1))
