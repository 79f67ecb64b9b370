"""Robot contours: Feature settings -> tool poses, speed profile, .ls program."""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drakedeburr.laser.feature as mut
from drakedeburr.errors import InputError
from drakedeburr.laser import fanuc_ls, shapes


def _X(rpy, p):
    from pydrake.math import RigidTransform, RollPitchYaw

    return RigidTransform(RollPitchYaw(rpy), p).GetAsMatrix4()


def test_poses_on_contour_with_travel_and_work_angles():
    X_WP = _X([0.2, -0.1, 0.5], [0.9, -0.2, 0.4])
    s = mut.FeatureSettings(travel_angle=np.deg2rad(10), work_angle=np.deg2rad(-5),
                            point_spacing=1e-3)
    tg = mut.plan_contour(shapes.Slot(length=0.08, width=0.03, lead_in=0.005), X_WP, s)
    R_WP, p_WP = X_WP[:3, :3], X_WP[:3, 3]
    # positions: on the plane and at the contour points
    p_P = (tg.p_WT - p_WP) @ R_WP
    assert np.allclose(p_P[:, 2], 0, atol=1e-12)
    assert np.allclose(p_P[:, :2], tg.contour.p_P, atol=1e-12)
    # orientations: proper rotations; beam angle to the plate normal
    R = tg.R_WT
    assert np.allclose(np.einsum("nji,njk->nik", R, R), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    z_T = R[:, :, 2]
    cos_tilt = z_T @ (-R_WP[:, 2])
    assert np.allclose(cos_tilt, np.cos(s.travel_angle) * np.cos(s.work_angle), atol=1e-12)
    # travel angle leans the beam along the travel direction
    t_W = tg.contour.t_P @ R_WP[:, :2].T
    assert np.allclose(np.sum(z_T * t_W, axis=1),
                       np.sin(s.travel_angle) * np.cos(s.work_angle), atol=1e-12)


def test_speed_profile_and_command():
    s = mut.FeatureSettings(speed=0.1, acceleration=2.0, point_spacing=1e-3)
    tg = mut.plan_contour(shapes.Rectangle(width=0.2, height=0.1), settings=s)
    assert tg.speed.max() == pytest.approx(0.1, rel=1e-3)
    assert tg.speed[tg.contour.corner].max() < 1e-6  # stops at the sharp corners
    # the timing is consistent: time between points ~ distance / mean speed where moving
    dt = np.diff(tg.t)
    ds = np.diff(tg.contour.s)
    fast = (tg.speed[:-1] > 0.099) & (tg.speed[1:] > 0.099)
    assert np.allclose(ds[fast] / dt[fast], 0.1, rtol=1e-2)
    # accelerating from a corner takes about v^2 / (2 a) of path
    k = np.flatnonzero(tg.contour.corner)[0]
    s_acc = tg.contour.s[k + np.argmax(tg.speed[k:] > 0.099)] - tg.contour.s[k]
    assert s_acc == pytest.approx(0.1**2 / (2 * 2.0), abs=1.01 * s.point_spacing)
    free = (tg.command > tg.power.min_command) & (tg.command < tg.power.max_command)
    assert np.allclose(tg.command[free] / tg.speed[free], tg.power.gain, rtol=1e-9)


def test_contour_ls_program(tmp_path):
    from drakedeburr.laser.robot_job import LaserCell

    tg = mut.plan_contour(shapes.Hexagon(across_flats=0.1, lead_in=0.01),
                          settings=mut.FeatureSettings(travel_angle=0.1))
    X_RP = _X([np.pi, 0, 0], [1.0, 0.0, 0.5])  # the plate: the program's UFRAME
    text = fanuc_ls.contour_program_ls(tg, "hex100", LaserCell("m10ia", X_RP))
    assert "DEFAULT_GROUP\t= 1,*,*,*,*;" in text
    uf = _ls_frame(text, "UFRAME")
    assert np.allclose(uf[:3], [1000.0, 0.0, 500.0], atol=1e-3)
    w_, p_, r_ = np.deg2rad(uf[3:])  # FANUC W, P, R: R = Rz(r) Ry(p) Rx(w)
    R_uf = (Rotation.from_euler("z", r_) * Rotation.from_euler("y", p_)
            * Rotation.from_euler("x", w_)).as_matrix()
    assert np.allclose(R_uf, X_RP[:3, :3], atol=1e-9)
    assert text.index("UFRAME[1]=PR[10]") < text.index("UFRAME_NUM=1 ;")
    assert "UFRAME_NUM=1 ;" in text and "UF : 1, UT : 1" in text
    xyz = np.array(re.findall(r"X =\t(-?[\d.]+)\tmm,\tY =\t(-?[\d.]+)\tmm,\tZ =\t(-?[\d.]+)",
                              text), float)
    assert np.allclose(xyz / 1e3, tg.p_WT, atol=1e-9)
    wpr = np.array(re.findall(r"W =\t(-?[\d.]+)\tdeg,\tP =\t(-?[\d.]+)\tdeg,\tR =\t(-?[\d.]+)",
                              text), float)
    # FANUC W, P, R: R = Rz(r) Ry(p) Rx(w)
    w, p, r = np.deg2rad(wpr).T
    for k in range(0, len(tg), 17):
        cw, sw, cp, sp, cr, sr = (np.cos(w[k]), np.sin(w[k]), np.cos(p[k]), np.sin(p[k]),
                                  np.cos(r[k]), np.sin(r[k]))
        Rx = np.array([[1, 0, 0], [0, cw, -sw], [0, sw, cw]])
        Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
        Rz = np.array([[cr, -sr, 0], [sr, cr, 0], [0, 0, 1]])
        assert np.allclose(Rz @ Ry @ Rx, tg.R_WT[k], atol=1e-6)
    per = {"mm/sec": 1.0, "cm/min": 1 / 6}
    speeds = np.array([int(v) * per[u] for v, u in
                       re.findall(r"L P\[\d+\] (\d+)(mm/sec|cm/min)", text)])
    assert len(speeds) == len(tg) - 1 and speeds.max() == 100


def test_bad_settings():
    with pytest.raises(InputError, match="point_spacing must be > 0"):
        mut.FeatureSettings(point_spacing=0)
    with pytest.raises(InputError, match="travel_angle must be within"):
        mut.FeatureSettings(travel_angle=2.0)


def _ls_frame(text: str, label: str, n: int = 1) -> list[float]:
    """X, Y, Z [mm], W, P, R [deg] a FANUC LS program sets ``label[n]`` to: the ``PR[k,i]=v``
    statements before ``label[n]=PR[k]`` (parsed here, not by the package's reader)."""
    lines = [ln.split(":", 1)[1].strip().rstrip(";").strip() for ln in text.splitlines()
             if re.match(r"\s*\d+:", ln)]
    end = next(i for i, ln in enumerate(lines) if re.fullmatch(rf"{label}\[{n}\]=PR\[\d+\]", ln))
    pr = re.fullmatch(rf"{label}\[{n}\]=PR\[(\d+)\]", lines[end]).group(1)
    vals = {}
    for ln in lines[:end]:
        m = re.fullmatch(rf"PR\[{pr},([1-6])\]=(-?[\d.]+)", ln)
        if m:
            vals[int(m.group(1))] = float(m.group(2))
    return [vals[i] for i in range(1, 7)]
