"""Virtual TCP (workpiece in hand): compose the part motion and check it against the tool."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drakedeburr.post.virtual_tcp as mut
from drakedeburr.errors import InputError


def _rounded_rect(n_side=20, a=0.06, b=0.04, r=0.01):
    """Closed counter-clockwise contour (z = 0) of a rounded rectangle [m]."""
    pts = []
    corners = [(a - r, b - r, 0), (-a + r, b - r, np.pi / 2), (-a + r, -b + r, np.pi),
               (a - r, -b + r, 1.5 * np.pi)]
    for cx, cy, t0 in corners:
        for t in np.linspace(t0, t0 + np.pi / 2, n_side, endpoint=False):
            pts.append((cx + r * np.cos(t), cy + r * np.sin(t), 0.0))
    return np.array(pts)


def _frame(xyz, rpy):
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()
    X[:3, 3] = xyz
    return X


def test_offset_contour_outward_inward():
    """The polygon through the points offset by R: a sampled circle's offset lies between
    the offset chords and the offset circle; straight sides move by exactly R (the exact
    corner cases: tests/test_virtual_tcp_program.py)."""
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    circle = np.stack([0.05 * np.cos(t), 0.05 * np.sin(t), 0 * t], -1)
    chord = 0.05 * np.cos(np.pi / 90)  # distance of the polygon's edges from the centre
    for pts in (circle, circle[::-1]):  # either direction round
        out = mut.offset_contour(pts, 0.004, "outward")
        inn = mut.offset_contour(pts, 0.004, "inward")
        r_out, r_in = np.hypot(out[:, 0], out[:, 1]), np.hypot(inn[:, 0], inn[:, 1])
        assert np.all(r_out > chord + 0.004 - 1e-12) and np.all(r_out < 0.054 + 1e-12)
        assert np.all(r_in > chord - 0.004 - 1e-12) and np.all(r_in < 0.046 + 1e-12)
    rect = _rounded_rect()
    out = mut.offset_contour(rect, 0.003, "outward")
    # every offset vertex at R from the polygon (point-to-segment distance, numpy only)
    a, b = rect[:, :2], np.roll(rect[:, :2], -1, 0)
    x = out[:, :2]
    u = np.clip(np.einsum("mnk,nk->mn", x[:, None] - a[None], b - a)
                / np.sum((b - a) ** 2, 1), 0, 1)
    d = np.linalg.norm(x[:, None] - (a[None] + u[..., None] * (b - a)[None]), axis=-1).min(1)
    assert np.allclose(d, 0.003, atol=1e-12)
    assert np.allclose(out[:, 1].max(), 0.043, atol=1e-7)  # the top side moved up by R
    with pytest.raises(InputError, match="outward or inward"):
        mut.offset_contour(rect, 0.003, "left")


def test_contour_frames_point_inward():
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    pts = np.stack([0.05 * np.cos(t), 0.05 * np.sin(t), 0 * t], -1)
    X = mut.contour_frames(pts[::-1])
    assert np.allclose(X[:, :3, 0], -pts[::-1] / 0.05, atol=1e-3)  # x toward the centre
    assert np.allclose(X[:, :3, 2], [0, 0, 1])
    for R in X[:, :3, :3]:
        assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1)


def _contour_in_base(X_RP, R_tool):
    p = mut.offset_contour(_rounded_rect(), R_tool, "outward")
    X_PA = mut.contour_frames(p)
    return X_RP[None] @ X_PA, p


def test_translation_mode_brings_each_point_to_the_tool_and_keeps_orientation():
    X_RO = _frame([0.9, -0.2, 0.4], [0.2, -0.1, 0.7])   # fixed spindle (virtual TCP)
    X_RP = _frame([0.9, -0.15, 0.42], [0.25, -0.05, 0.6])  # part at the reference pose
    X_RA, p_PA = _contour_in_base(X_RP, 0.004)
    X_RV = mut.virtual_tcp_poses(X_RO, X_RA, "translation")
    # the TCP never rotates: the part only translates
    assert np.allclose(X_RV[:, :3, :3], X_RO[:3, :3][None])
    X_OA = mut.part_contour_at_virtual(X_RO, X_RV, X_RA)
    assert np.abs(X_OA[:, :3, 3]).max() < 1e-12  # A_i on the tool centre O
    # independent composition: carry the part with the TCP (X_TP fixed at the reference)
    X_TP = np.linalg.inv(X_RO) @ X_RP
    for i in (0, 17, 55):
        X_RP_i = X_RV[i] @ X_TP
        p_R = X_RP_i[:3, :3] @ p_PA[i] + X_RP_i[:3, 3]
        assert np.allclose(p_R, X_RO[:3, 3], atol=1e-12)
        # the tool centre, seen from the part, runs along the offset contour
        X_PR = np.linalg.inv(X_RP_i)
        assert np.allclose(X_PR[:3, :3] @ X_RO[:3, 3] + X_PR[:3, 3], p_PA[i], atol=1e-12)


def test_translation_keep_z_is_paper_eq4():
    X_RO = _frame([0.9, 0.0, 0.4], [0, 0, 0.3])
    X_RA = np.array([_frame([0.93, 0.02, 0.41], [0, 0, 0.3])])  # parallel to O, z_a = 0.01
    X_RV = mut.virtual_tcp_poses(X_RO, X_RA, "translation", keep_z=True)
    X_OA0 = np.linalg.inv(X_RO) @ X_RA[0]
    X_OV = np.linalg.inv(X_RO) @ X_RV[0]
    assert np.allclose(X_OV[:3, 3], X_OA0[:3, 3] * [-1, -1, 1])  # eq. 4
    X_OA = mut.part_contour_at_virtual(X_RO, X_RV, X_RA)[0]
    assert np.allclose(X_OA[:3, 3], [0, 0, 2 * X_OA0[2, 3]])  # slides along the tool axis


def test_rotation_mode_aligns_frames_and_equals_eq7_for_planar():
    X_RO = _frame([0.8, 0.1, 0.5], [0.0, 0.0, 0.4])
    X_RP = _frame([0.83, 0.12, 0.5], [0.0, 0.0, 0.9])  # planar: same z, rotation about z
    X_RA, _ = _contour_in_base(X_RP, 0.002)
    X_RV = mut.virtual_tcp_poses(X_RO, X_RA, "rotation")
    X_OA = mut.part_contour_at_virtual(X_RO, X_RV, X_RA)
    assert np.abs(X_OA - np.eye(4)[None]).max() < 1e-12  # A_i on O and aligned with it
    # paper eq. 4 + eq. 7: mirror, rotate by -alpha about z', angles (-alpha, -beta, -gamma)
    for i in (3, 40, 70):
        X_OA0 = np.linalg.inv(X_RO) @ X_RA[i]
        alpha, beta, gamma = Rotation.from_matrix(X_OA0[:3, :3]).as_euler("ZYX")
        assert abs(beta) < 1e-12 and abs(gamma) < 1e-12
        m = X_OA0[:3, 3] * [-1, -1, 1]
        Rz = Rotation.from_euler("Z", -alpha).as_matrix()
        X_OV = np.eye(4)
        X_OV[:3, :3] = Rotation.from_euler("ZYX", [-alpha, -beta, -gamma]).as_matrix()
        X_OV[:3, 3] = Rz @ m
        assert np.allclose(X_RO @ X_OV, X_RV[i], atol=1e-12)
