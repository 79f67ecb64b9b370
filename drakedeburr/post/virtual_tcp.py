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


def offset_contour(p: np.ndarray, radius: float, side: str = "outward",
                   normal: np.ndarray = (0.0, 0.0, 1.0), closed: bool = True) -> np.ndarray:
    """Offset a planar contour by the tool radius.

    Args:
        p: (N, 3) contour points in a plane normal to ``normal`` [m].
        radius: tool radius [m] (>= 0).
        side: "outward" (outer contour: away from the enclosed area) or "inward" (holes).
        normal: (3,) plane normal; the contour may run either way round it.
        closed: the contour is a loop (required for deciding outward/inward).

    Returns:
        (N, 3) offset points [m].
    """
    p = np.asarray(p, float)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 3:
        raise InputError(f"contour: expected (N >= 3, 3) points, got {p.shape}")
    if side not in ("outward", "inward"):
        raise InputError(f"offset side {side!r}: outward or inward")
    if not radius >= 0:
        raise InputError(f"tool radius must be >= 0 m, got {radius}")
    if not closed:
        raise InputError("outward/inward needs a closed contour")
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    t = _tangents(p, closed)
    out = np.cross(t, n)  # outward for a contour counter-clockwise about n
    if _signed_area(p - p.mean(0), n) < 0:
        out = -out
    return p + (radius if side == "outward" else -radius) * out


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
