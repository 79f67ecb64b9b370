"""Local frames at CL points (source eqs. 4-6) and the tool axis <-> (theta_A, theta_B) maps.

Source eqs. 4-6: ``B = T x N``, ``N_new = B x T``, ``R_loc = [N_new, T, B]``. As printed that
matrix has determinant -1 (``N_new x T = -B``): it is a reflection, not a frame. We keep the
source's X and Y and make the frame right-handed:

* ``X_L = N_new``: the inner-side normal of the window's side wall, pointing out of the
  material into the opening, made orthogonal to the tangent (eq. 5);
* ``Y_L = T``: the unit tangent = feed direction (window loops run counter-clockwise seen
  from +Z_H, DESIGN.md);
* ``Z_L = X_L x Y_L = -B``: for a CCW loop, B = T x N points out of the visible front face,
  so Z_L points *into* the material (-Z_H on a flat hub) - the direction a tool approaches the
  edge from above.

``R_HL = [N_new, T, -B]`` is a proper rotation (checked in the tests).

Tool axis. Throughout drakedeburr the *tool axis* is DESIGN.md's ``+Z_T``: the unit vector
along the burr from the spindle toward the tip. (A CAM/APT (i, j, k) vector is ``-Z_T``.)
With both angles zero the tool stands upright over the front face, ``Z_T = Z_L``. The tool
orientation is the source's "rotate about Y by theta_A, then about X by theta_B", read as
intrinsic rotations of the local frame (the source's wording is not self-consistent,
SPEC.md S3.5)::

    R_LT = R_y(-theta_A) @ R_x(theta_B)
    Z_T in L = R_LT @ e_z = (-sin(theta_A) cos(theta_B),  -sin(theta_B),  cos(theta_A) cos(theta_B))

(``R_LT`` also fixes the spin about the axis: X_T is N rotated with it; a planner may use it
as the preferred tool orientation.) Geometric meaning, which is what the inverse uses:

* ``theta_A`` (work / tilt angle, about the feed direction) = ``atan2(-Z_T . N, Z_T . Z_L)``:
  the angle of the axis, projected into the plane normal to the feed, from the upright. Positive
  theta_A leans the spindle out over the opening (+N) and tilts the tip toward the material
  (-N). The burr sits in the opening and cuts the edge with its flank; leaning the spindle the
  other way would bring the shank and the spindle body down over the front face (the planner
  measured 1.5-2.0 mm shank clearance and hundreds of IK/clearance failures with that sign on
  the default hub, none with this one).
* ``theta_B`` (lead / travel angle) = ``asin(-Z_T . T)``: the angle of the axis out of the
  plane normal to the feed. Positive theta_B tilts the tip backward (-T): the spindle top leads
  the tip in the feed direction, the usual sign of a milling "lead angle".

The source calls theta_A "the angle between tool axis and normal" and theta_B "the angle to the
tangent"; with this definition those angles are ``pi/2 - theta_A`` (for theta_B = 0) and
``pi/2 + theta_B``. The maps are exact inverses for |theta_A| < pi/2, |theta_B| < pi/2.
"""

from __future__ import annotations

import numpy as np

from drakedeburr.errors import InputError

__all__ = [
    "R_HL_from_normals",
    "axis_from_angles",
    "angles_from_axis",
    "axis_jacobian",
    "zT_H_from_angles",
    "angles_from_zT_H",
    "check_rotations",
    "R_LT_from_angles",
]


def _unit_rows(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def R_HL_from_normals(t_H: np.ndarray, n_H: np.ndarray, *, name: str = "") -> np.ndarray:
    """Right-handed local frames R_HL = [N_new, T, -B] (eqs. 4-6, see module docstring).

    Args:
        t_H: (M, 3) tangents (feed direction) in H; normalised here.
        n_H: (M, 3) inner-side normals in H (need not be exactly orthogonal to t_H).
        name: item name for error messages (e.g. "window 2").

    Returns:
        (M, 3, 3) rotations; column 0 = N_new, 1 = T, 2 = N_new x T = -B (B = T x N).

    Raises:
        InputError: shapes differ, or a normal is (nearly) parallel to its tangent.
    """
    t = np.asarray(t_H, float)
    n = np.asarray(n_H, float)
    if t.shape != n.shape or t.ndim != 2 or t.shape[1] != 3:
        raise InputError(f"{name or 'R_HL_from_normals'}: t_H {t.shape} and n_H {n.shape} "
                         "must both be (M, 3)")
    t = _unit_rows(t)
    b = np.cross(t, n)
    nb = np.linalg.norm(b, axis=1)
    bad = np.flatnonzero(nb < 1e-6 * np.maximum(np.linalg.norm(n, axis=1), 1e-300))
    if bad.size:
        raise InputError(
            f"{name or 'R_HL_from_normals'}: normal parallel to tangent at point(s) "
            f"{bad[:10].tolist()}"
        )
    b = b / nb[:, None]
    n_new = np.cross(b, t)
    return np.stack([n_new, t, -b], axis=2)


def axis_from_angles(theta_A: np.ndarray, theta_B: np.ndarray) -> np.ndarray:
    """Tool axis in the local frame L from (theta_A, theta_B).

    Args:
        theta_A: (...) work/tilt angle [rad] (see module docstring).
        theta_B: (...) lead/travel angle [rad].

    Returns:
        (..., 3) unit tool axis +Z_T (spindle -> tip) in L.
    """
    a = np.asarray(theta_A, float)
    b = np.asarray(theta_B, float)
    cb = np.cos(b)
    return np.stack([-np.sin(a) * cb, -np.sin(b), np.cos(a) * cb], axis=-1)


def angles_from_axis(axis_L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`axis_from_angles`.

    Args:
        axis_L: (..., 3) axis in L (any positive length).

    Returns:
        (theta_A, theta_B) [rad], each (...).
    """
    v = np.asarray(axis_L, float)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    theta_A = np.arctan2(-v[..., 0], v[..., 2])
    theta_B = np.arcsin(np.clip(-v[..., 1], -1.0, 1.0))
    return theta_A, theta_B


def axis_jacobian(theta_A: np.ndarray, theta_B: np.ndarray) -> np.ndarray:
    """d axis_L / d(theta_A, theta_B).

    Returns:
        (..., 3, 2): column 0 = d/d theta_A, column 1 = d/d theta_B.
    """
    a = np.asarray(theta_A, float)
    b = np.asarray(theta_B, float)
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    d_a = np.stack([-ca * cb, np.zeros_like(a), -sa * cb], axis=-1)
    d_b = np.stack([sa * sb, -cb, -ca * sb], axis=-1)
    return np.stack([d_a, d_b], axis=-1)


def zT_H_from_angles(R_HL: np.ndarray, theta_A: np.ndarray, theta_B: np.ndarray) -> np.ndarray:
    """Tool axis in H: (M, 3) from (M, 3, 3) frames and (M,) angles [rad]."""
    return np.einsum("mij,mj->mi", np.asarray(R_HL, float), axis_from_angles(theta_A, theta_B))


def angles_from_zT_H(R_HL: np.ndarray, zT_H: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(theta_A, theta_B) [rad], each (M,), of (M, 3) axes given in H w.r.t. frames R_HL."""
    axis_L = np.einsum("mji,mj->mi", np.asarray(R_HL, float), np.asarray(zT_H, float))
    return angles_from_axis(axis_L)


def check_rotations(R: np.ndarray) -> np.ndarray:
    """Per-frame error max(|R^T R - I|, |det R - 1|) of (M, 3, 3) matrices."""
    R = np.asarray(R, float)
    orth = np.abs(np.einsum("mki,mkj->mij", R, R) - np.eye(3)).max(axis=(1, 2))
    det = np.abs(np.linalg.det(R) - 1.0)
    return np.maximum(orth, det)


def R_LT_from_angles(theta_A: np.ndarray, theta_B: np.ndarray) -> np.ndarray:
    """Tool orientation in the local frame, R_y(-theta_A) @ R_x(theta_B): (..., 3, 3).

    Column 2 is :func:`axis_from_angles`; column 0 (X_T) is N_new turned with the tool.
    """
    a = np.asarray(theta_A, float)
    b = np.asarray(theta_B, float)
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    z = np.zeros_like(a)
    x_t = np.stack([ca, z, sa], axis=-1)
    y_t = np.stack([-sa * sb, cb, ca * sb], axis=-1)
    z_t = np.stack([-sa * cb, -sb, ca * cb], axis=-1)
    return np.stack([x_t, y_t, z_t], axis=-1)
