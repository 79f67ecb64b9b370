"""Virtual TCP for workpiece-in-hand machining (SPEC.md S0, seed 000).

The robot holds the part; the tool (mill, belt) is fixed in the cell with frame O (the virtual
TCP). The robot's TCP frame is set so that, at the reference pose where the contour points
A_i were taught/planned (X_RA in the robot base R), the robot TCP coincides with O. Moving the
TCP to a *virtual point* V_i then carries the part so that A_i meets the tool:

    X_OA_i(after) = X_OV_i . X_OA_i          (the part moves with the TCP)

- translation mode (paper eqs. 1-6): X_OV_i = [I, M . p_OA_i]: the TCP keeps O's orientation
  (the part only translates, no cable wind-up) and the position is the mirror image of A_i,
  M = diag(-1, -1, -1); with ``keep_z=True`` M = diag(-1, -1, 1) exactly as eq. 4 (the
  contact then slides along the tool axis to height 2 z_a: fine for a cylindrical mill, and
  identical when the contour lies in the tool's xy plane). The paper's eq. 4 keeps A's own
  angles (alpha, beta, gamma); that coincides with this form in the paper's set-up where the
  contour frames are parallel to O, and only this form keeps the part orientation fixed in
  general.
- rotation mode (eq. 7, belt grinding): X_OV_i = X_OA_i^-1, A_i meets O *and* its frame
  aligns with O's; for a planar contour (beta = gamma = 0, z = 0) this is the mirrored point
  rotated by -alpha about z' with angles (-alpha, ...), exactly eq. 7.

Back to the robot base: X_RV = X_RO . X_OV (eqs. 5-6, 8). The tool radius R is applied to the
contour beforehand (:func:`offset_contour`: outward for outer contours, inward for holes);
:func:`contour_frames` gives each point's frame from its neighbours (x = inward contour normal,
z = plane normal), step (4) of the paper.
"""

from __future__ import annotations

import numpy as np

from drakedeburr.errors import InputError

__all__ = [
    "VIRTUAL_TCP_MODES",
    "virtual_tcp_poses",
    "offset_contour",
    "contour_frames",
    "part_contour_at_virtual",
]

VIRTUAL_TCP_MODES = ("translation", "rotation")


def _as_poses(X: np.ndarray, what: str) -> np.ndarray:
    X = np.asarray(X, float)
    if X.ndim == 2:
        X = X[None]
    if X.ndim != 3 or X.shape[1:] != (4, 4) or not np.all(np.isfinite(X)):
        raise InputError(f"{what}: expected finite (N, 4, 4) transforms, got {X.shape}")
    return X


def virtual_tcp_poses(X_RO: np.ndarray, X_RA: np.ndarray, mode: str = "translation",
                      keep_z: bool = False) -> np.ndarray:
    """Robot TCP targets (virtual points) for contour frames.

    Args:
        X_RO: (4, 4) fixed tool frame O (virtual TCP) in the robot base R [m].
        X_RA: (N, 4, 4) contour frames A_i in R at the reference pose [m] (already offset by
            the tool radius).
        mode: "translation" or "rotation" (module docstring).
        keep_z: translation mode only: mirror x, y and keep z (paper eq. 4).

    Returns:
        (N, 4, 4) X_RV: TCP targets in R.
    """
    if mode not in VIRTUAL_TCP_MODES:
        raise InputError(f"virtual TCP mode {mode!r}: use translation or rotation")
    X_RO = _as_poses(X_RO, "X_RO")[0]
    X_RA = _as_poses(X_RA, "X_RA")
    X_OA = np.linalg.solve(X_RO[None], X_RA)  # eq. 1-2
    X_OV = np.zeros_like(X_OA)
    if mode == "translation":
        M = np.array([-1.0, -1.0, 1.0 if keep_z else -1.0])
        X_OV[:, :3, :3] = np.eye(3)
        X_OV[:, :3, 3] = X_OA[:, :3, 3] * M  # eq. 4
        X_OV[:, 3, 3] = 1.0
    else:
        X_OV = np.linalg.inv(X_OA)  # eq. 7 generalised
    return X_RO[None] @ X_OV  # eq. 6 / 8


def part_contour_at_virtual(X_RO: np.ndarray, X_RV: np.ndarray, X_RA: np.ndarray) -> np.ndarray:
    """Where contour frame A_i is, in the tool frame O, when the robot TCP is at V_i.

    The part is rigid with the TCP, which coincides with O at the reference pose, so
    X_OA_i(after) = X_RO^-1 X_RV_i X_RO^-1 X_RA_i. Used to check a virtual trajectory.

    Returns:
        (N, 4, 4) X_OA after the move.
    """
    X_RO = _as_poses(X_RO, "X_RO")[0]
    X_OR = np.linalg.inv(X_RO)
    return X_OR[None] @ _as_poses(X_RV, "X_RV") @ X_OR[None] @ _as_poses(X_RA, "X_RA")


def _tangents(p: np.ndarray, closed: bool) -> np.ndarray:
    if closed:
        t = np.roll(p, -1, 0) - np.roll(p, 1, 0)
    else:
        t = np.gradient(p, axis=0)
    n = np.linalg.norm(t, axis=1, keepdims=True)
    if np.any(n < 1e-12):
        raise InputError("contour has repeated consecutive points: cannot take tangents")
    return t / n


def _signed_area(p: np.ndarray, normal: np.ndarray) -> float:
    return 0.5 * float(np.sum(np.cross(p, np.roll(p, -1, 0)) @ normal))


def _plane_basis(normal: np.ndarray) -> np.ndarray:
    """(3, 3) rows u, v, n: a right-handed frame whose third axis is ``normal``."""
    from drakedeburr.frames.vectors import perpendicular_basis

    n = np.asarray(normal, float)
    if n.shape != (3,) or not np.all(np.isfinite(n)) or np.linalg.norm(n) < 1e-12:
        raise InputError(f"contour plane normal: expected a finite non-zero 3-vector, got {n}")
    return perpendicular_basis(n).T


def _quad_segs(radius: float, arc_tolerance: float) -> int:
    """Segments per quarter circle so a chord stays within ``arc_tolerance`` of the arc."""
    if radius <= arc_tolerance:
        return 1
    step = 2.0 * np.arccos(1.0 - arc_tolerance / radius)  # chord angle for that sagitta
    return max(1, int(np.ceil((np.pi / 2) / step)))


def offset_contour(p: np.ndarray, radius: float, side: str = "outward",
                   normal: np.ndarray = (0.0, 0.0, 1.0), closed: bool = True,
                   arc_tolerance: float = 1e-6, planar_tolerance: float = 1e-6) -> np.ndarray:
    """Offset a planar contour (a polygon through the points) by the tool radius.

    The contour is taken as the polygon through its points (CAM vertex lists are sparse) and
    offset exactly (shapely's buffer, GEOS): every point of the result lies at distance R
    from the polygon. Outward, a convex corner becomes an arc of radius R about the corner
    (the tool rolls round it) and a concave corner the intersection of the two offset edges,
    at distance R from both edges; inward (holes) the other way round. The arcs are split
    into chords within ``arc_tolerance``. (The earlier point-wise offset along the averaged
    vertex normal under-offset a 90 deg corner by R (1 - 1/sqrt 2).)

    Args:
        p: (N, 3) contour points in a plane normal to ``normal`` [m], either way round.
        radius: tool radius [m] (>= 0).
        side: "outward" (outer contour: away from the enclosed area) or "inward" (holes).
        normal: (3,) plane normal.
        closed: the contour is a loop (required for deciding outward/inward).
        arc_tolerance: largest gap between a round corner and its chords [m].
        planar_tolerance: largest distance of a point from the contour's plane [m]; a 3-D
            contour (e.g. a parting line on a curved surface) is refused: offsetting it on
            its surface is not implemented, and offsetting it as if planar would be wrong.

    Returns:
        (M, 3) offset polygon [m], running the same way round as ``p`` and starting near its
        first point (M differs from N where corners became arcs).

    Raises:
        InputError: bad arguments, a contour that is not planar or crosses itself, or one
            that the offset splits or closes (a hole smaller than the tool).
    """
    from shapely.geometry import Polygon

    p = np.asarray(p, float)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 3 or not np.all(np.isfinite(p)):
        raise InputError(f"contour: expected finite (N >= 3, 3) points, got {p.shape}")
    if side not in ("outward", "inward"):
        raise InputError(f"offset side {side!r}: outward or inward")
    if not radius >= 0:
        raise InputError(f"tool radius must be >= 0 m, got {radius}")
    if not closed:
        raise InputError("outward/inward needs a closed contour")
    B = _plane_basis(normal)
    c = p.mean(0)
    local = (p - c) @ B.T
    height = local[:, 2] - np.median(local[:, 2])
    k = int(np.argmax(np.abs(height)))
    if abs(height[k]) > planar_tolerance:
        raise InputError(
            f"contour point {k + 1} is {abs(height[k]) * 1e3:.3f} mm off the contour's plane "
            f"(tolerance {planar_tolerance * 1e3:.3f} mm): offsetting a 3-D contour on its "
            "surface is not implemented; give the tool-centre path (CL points) instead")
    z0 = float(np.median(local[:, 2]))
    poly = Polygon(local[:, :2])
    if not poly.is_valid or poly.area <= 0:
        raise InputError("contour: the polygon through the points crosses itself or has no "
                         "area; cannot tell outward from inward")
    if radius == 0:
        return p.copy()
    d = radius if side == "outward" else -radius
    off = poly.buffer(d, quad_segs=_quad_segs(radius, arc_tolerance), join_style="round")
    if off.is_empty or off.geom_type != "Polygon":
        raise InputError(f"contour: offset {side} by {radius * 1e3:.3f} mm leaves "
                         + ("nothing (the tool does not fit)" if off.is_empty else
                            f"{len(off.geoms)} separate pieces (the tool does not pass "
                            "a narrow part)"))
    ring = np.asarray(off.exterior.coords)[:-1]
    if (_signed_area(np.column_stack([ring, 0 * ring[:, 0]]), np.eye(3)[2]) > 0) != (
            _signed_area(local, np.eye(3)[2]) > 0):
        ring = ring[::-1]
    ring = np.roll(ring, -int(np.argmin(np.linalg.norm(ring - local[0, :2], axis=1))), 0)
    out = np.column_stack([ring, np.full(len(ring), z0)])
    return out @ B + c


def contour_frames(p: np.ndarray, normal: np.ndarray = (0.0, 0.0, 1.0),
                   closed: bool = True) -> np.ndarray:
    """Frames of contour points: x = inward in-plane normal (toward the enclosed area),
    z = plane normal, y = z x x; origin at the point.

    For a planar contour this is the normal of the plane through the neighbouring points
    (paper step 4) made into a frame.

    Returns:
        (N, 4, 4) frames in the contour's frame [m].
    """
    p = np.asarray(p, float)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    t = _tangents(p, closed)
    inward = -np.cross(t, n)
    if closed and _signed_area(p - p.mean(0), n) < 0:
        inward = -inward
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    X = np.zeros((p.shape[0], 4, 4))
    X[:, :3, 0] = inward
    X[:, :3, 2] = n
    X[:, :3, 1] = np.cross(n[None], inward)
    X[:, :3, 3] = p
    X[:, 3, 3] = 1.0
    return X
