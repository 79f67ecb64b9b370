"""Local frames on steep stretches of a window edge from the conical burr's contact (issue 42).

The source's frame (eqs. 4-6, :func:`drakedeburr.frames.local_frames.R_HL_from_normals`) puts
the upright axis ``-Z_L = B`` perpendicular to the edge. Where the edge descends a spoke flank
at 45-51 deg that upright leans 45-51 deg off the hub axis, the lead angle of the box adds its
20 deg on a descent, and every axis of the (theta_A, theta_B) box drives the spindle body into
the spoke (measured on the mkz13 and audibot rims, docs/orientation.md).

Contact of a 90 deg conical burr (half-angle alpha = 45 deg) with the edge. The outward normal
of a cone's surface makes 90 deg - alpha with the axis ``Z_T`` (spindle -> tip); the burr cuts
the symmetric chamfer when its tangent plane at the contact is the chamfer plane, normal to the
edge bisector ``b = (n_face + n_wall)/|.|`` (``b`` out of the material, ``n_wall = N_new``, and
for the right-angle edge the source frame assumes, ``n_face = B``; in L: b_L = (1, 0, -1)/sqrt2).
The spindle direction ``-Z_T`` of such a burr lies on the cone of half-angle alpha about ``b``,
and every such axis meets the edge line at >= alpha (a line in a tangent plane of a cone is at
least the half-angle from its axis): the family is the source's upright turned about ``b`` by
any angle psi. Turning the whole frame about ``b`` maps the chamfer plane (normal ``b``, holding
the edge line) onto itself: the turned upright (theta_A = theta_B = 0) cuts exactly the source's
symmetric chamfer, and every axis of the box keeps its angle to ``b`` (its process tilt off the
symmetric-chamfer family, SPEC S3 items 5-6 bounds). What the turn does not keep is the
direction a tilted axis sees the edge from: the chamfer profile is the cone's silhouette seen
along ``T`` (apparent half-angle ``asin(sin(alpha) / sin(phi))`` at an angle phi between axis
and ``T``), so the chamfer a tilted box axis cuts differs from the one it cuts in the source's
frame (on an analytic 50 deg descent by 1.6-9.8 deg at the box corners, 4-5 deg at the box
centre; tests/test_orientation_steep.py). The flank condition phi >= alpha is the same
silhouette's existence condition (below it the burr meets the edge line with its tip).

Rule (:func:`flank_contact_frames`): on a steep stretch the frame is the source's turned about
``b`` by the psi that brings the box centre's spindle direction nearest the approach direction
``+Z_H`` (the side the tool comes from), searched from psi = 0 (the source's frame) in both
directions as long as every axis of the box still meets the edge line at >= alpha (the burr
touches the edge with its flank, never with its tip). :func:`steep_contact_frames` applies it
where the edge's slope to the face plane exceeds a limit and returns its input unchanged (the
same array) where nothing is steep: a flat loop's frames are bit for bit the source's.

Ramp (:func:`turn_share`): applied in full only from ``FULL_TURN_SLOPE`` (55 deg) up; between
the limit (45 deg) and there the frame is turned by the share ``w`` of the rule's psi, ``w`` the
smoothstep ``3x^2 - 2x^3`` of ``x = (slope - limit)/(full - limit)``: 0 at the limit, where the
frame is the source's, 1 at the full slope, its derivative 0 at both ends. Applied at once the
turn made the frame jump where a loop passes the limit (mkz13 rim CL 33 -> 34: the box centre
57.8 -> 18.4 deg off +Z_H). The turn ``w psi`` still keeps every box axis on the flank: the
feasible turns form a run of the psi grid that holds 0 (the source's frame: a box axis'
component along the edge line is sin theta_B, so every box axis is at least 90 deg -
|theta_B|max from it, 64.8 deg for the large box) and the rule's psi, and the run holds every
turn between them.
"""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.frames.local_frames import R_HL_from_normals, axis_from_angles

__all__ = ["BURR_HALF_ANGLE", "FULL_TURN_SLOPE", "box_boundary_axes", "flank_contact_frames",
           "steep_contact_frames", "edge_slopes", "rotation_about", "turn_share"]

#: half-angle of the 90 deg conical burr (cell/tools.py's burrs) [rad]
BURR_HALF_ANGLE = math.radians(45.0)
#: the slope [rad] from which the contact rule's turn applies in full (module docstring: ramp)
FULL_TURN_SLOPE = math.radians(55.0)
#: the edge bisector of a right-angle edge in the local frame [N_new, T, -B]: (N_new + B)/sqrt2
B_L = np.array([1.0, 0.0, -1.0]) / math.sqrt(2.0)
#: the approach direction in H: the tool comes from the front, +Z_H
APPROACH_H = np.array([0.0, 0.0, 1.0])


def rotation_about(axis: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations by ``psi`` (...) [rad] about the unit ``axis`` (3,) (Rodrigues)."""
    k = np.asarray(axis, float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    p = np.asarray(psi, float)[..., None, None]
    return np.eye(3) + np.sin(p) * K + (1.0 - np.cos(p)) * (K @ K)


def box_boundary_axes(theta_min: float, theta_max: float, samples: int = 64) -> np.ndarray:
    """(4 samples, 3) tool axes in L on the boundary of the (theta_A, theta_B) box."""
    s = np.linspace(theta_min, theta_max, samples)
    lo, hi = np.full(samples, theta_min), np.full(samples, theta_max)
    a = np.concatenate([s, s, lo, hi])
    b = np.concatenate([lo, hi, s, s])
    return axis_from_angles(a, b)


def edge_slopes(t_H: np.ndarray) -> np.ndarray:
    """(M,) slope [rad] of the tangents ``t_H`` (M, 3) to the face plane X_H Y_H."""
    t = np.asarray(t_H, float)
    return np.arcsin(np.clip(np.abs(t[:, 2]) / np.linalg.norm(t, axis=1), 0.0, 1.0))


def flank_contact_frames(R_HL: np.ndarray, theta_min: float, theta_max: float, *,
                         approach_H: np.ndarray = APPROACH_H,
                         half_angle: float = BURR_HALF_ANGLE,
                         step: float = math.radians(0.25)) -> tuple[np.ndarray, np.ndarray]:
    """The source's frames ``R_HL`` (M, 3, 3), built on the true edge tangent, each turned about
    its edge bisector by the contact rule (module docstring).

    Returns:
        (frames (M, 3, 3), psi (M,) [rad]): ``frames[i] = R_HL[i] @ rotation_about(B_L, psi[i])``.
        The contact test keeps every box axis at >= ``half_angle`` plus the boundary sampling
        step from the tangent (Y_L of the source frame).
    """
    R = np.asarray(R_HL, float)
    psi_grid = np.arange(-math.pi, math.pi, step)
    i0 = int(np.argmin(np.abs(psi_grid)))
    psi_grid[i0] = 0.0
    rot = rotation_about(B_L, psi_grid)  # (G, 3, 3)
    samples = 64
    A = box_boundary_axes(theta_min, theta_max, samples)
    margin = (theta_max - theta_min) / (samples - 1)
    # |axis . T| for every turned boundary axis (T = Y_L of the source frame)
    tan_dot = np.abs(np.einsum("gj,kj->gk", rot[:, 1, :], A)).max(axis=1)  # (G,)
    contact = tan_dot <= math.cos(half_angle + margin)
    # the feasible run of the grid that holds psi = 0 (the source's frame touches: T _|_ upright)
    lo = i0
    while lo > 0 and contact[lo - 1]:
        lo -= 1
    hi = i0
    while hi < len(psi_grid) - 1 and contact[hi + 1]:
        hi += 1
    c = 0.5 * (theta_min + theta_max)
    psi = _nearest_turn(-axis_from_angles(c, c),
                        np.einsum("mji,j->mi", R, np.asarray(approach_H, float)))
    # the optimum held to the run (the objective is unimodal in psi: clamp, wrapping psi to the
    # copy nearest the run's middle)
    mid = 0.5 * (psi_grid[lo] + psi_grid[hi])
    psi = mid + (psi - mid + math.pi) % (2.0 * math.pi) - math.pi
    psi = np.clip(psi, psi_grid[lo], psi_grid[hi])
    return np.einsum("mij,mjk->mik", R, rotation_about(B_L, psi)), psi


def _nearest_turn(u_L: np.ndarray, z_L: np.ndarray) -> np.ndarray:
    """(M,) the angle psi [rad] of the turn about B_L that brings the unit ``u_L`` (3,) nearest
    the unit ``z_L`` (M, 3): the signed angle between their components normal to B_L (``u``
    then lies in the plane of B_L and ``z``, the angle between them beta - gamma with beta, gamma
    their angles to B_L)."""
    u = u_L - B_L * (u_L @ B_L)
    z = z_L - B_L[None, :] * (z_L @ B_L)[:, None]
    return np.arctan2(np.cross(u, z) @ B_L, z @ u)


def turn_share(slope: np.ndarray, max_slope: float,
               full_slope: float = FULL_TURN_SLOPE) -> np.ndarray:
    """(M,) share in [0, 1] of the contact rule's turn applied at edge slopes ``slope`` (M,)
    [rad]: 0 up to ``max_slope``, the smoothstep ``3x^2 - 2x^3`` of
    ``x = (slope - max_slope) / (full_slope - max_slope)`` between, 1 from ``full_slope`` up
    (a step at ``max_slope`` when ``full_slope <= max_slope``: the turn applied at once)."""
    sl = np.asarray(slope, float)
    if full_slope <= max_slope:
        return (sl > max_slope).astype(float)
    x = np.clip((sl - max_slope) / (full_slope - max_slope), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def steep_contact_frames(R_HL: np.ndarray, t_H: np.ndarray, n_H: np.ndarray,
                         theta_min: float, theta_max: float, max_slope: float,
                         full_slope: float = FULL_TURN_SLOPE, *, name: str = "") -> np.ndarray:
    """``R_HL`` (M, 3, 3) with the frames of the points whose tangent ``t_H`` climbs or descends
    steeper than ``max_slope`` [rad] replaced by the source's frames on the true tangent and the
    inner normals ``n_H``, turned about the edge bisector by the share :func:`turn_share` (full
    from ``full_slope`` up) of :func:`flank_contact_frames`' turn; ``R_HL`` itself (the same
    array) when no point is steep."""
    slope = edge_slopes(t_H)
    steep = slope > max_slope
    if not steep.any():
        return R_HL
    src = R_HL_from_normals(np.asarray(t_H, float)[steep], np.asarray(n_H, float)[steep],
                            name=name)
    psi = flank_contact_frames(src, theta_min, theta_max)[1]
    share = turn_share(slope[steep], max_slope, full_slope)
    out = np.array(R_HL, float, copy=True)
    out[steep] = np.einsum("mij,mjk->mik", src, rotation_about(B_L, share * psi))
    return out
