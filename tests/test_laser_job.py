"""One laser job (source 004): holes by the Cutting Tool, the contour by the robot, in a
real plate frame, joints and CONFIG from the arm's IK. Everything is read back from the
written .ls text and re-checked with the controller's view of it (the pose + CONFIG ->
joints of robots.configuration, the OPW forward map) and an independent five-bar FK."""

import json
import re

import numpy as np
import pytest

from drakedeburr.cli import main
from drakedeburr.laser.model import NOZZLE_LENGTH
from drakedeburr.robots import fk_opw, get_robot, joints_from_configuration

JOB = """robot: m10ia
plate: [800, 100, 200, 0, 0, 30]     # UFRAME: mm, deg
feed_m_min: 6
contour: {kind: rectangle, width: 200, height: 100, corner_radius: 10, lead_in: 5}
holes:
  - {kind: circle, diameter: 10, at: [50, 20], lead_in: 2}
  - {kind: polyline, points: [[0, 0], [6, 0], [0, 4]], at: [-50, -20]}
"""


def _wpr(w, p, r):
    w, p, r = np.deg2rad([w, p, r])
    cw, sw, cp, sp, cr, sr = np.cos(w), np.sin(w), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    Rx = np.array([[1, 0, 0], [0, cw, -sw], [0, sw, cw]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cr, -sr, 0], [sr, cr, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx  # FANUC W, P, R


def _X(v):
    X = np.eye(4)
    X[:3, :3] = _wpr(*v[3:])
    X[:3, 3] = np.asarray(v[:3]) / 1e3
    return X


def _frame(text, label):
    from test_laser_feature import _ls_frame  # the PR statements, parsed there

    return _X(_ls_frame(text, label))


def _points(text):
    pat = (r"P\[(\d+)\]\{\n   GP1:\n\tUF : 1, UT : 1,\t\tCONFIG : '([^']*)',\n"
           r"\tX =\t(\S+)\tmm,\tY =\t(\S+)\tmm,\tZ =\t(\S+)\tmm,\n"
           r"\tW =\t(\S+)\tdeg,\tP =\t(\S+)\tdeg,\tR =\t(\S+)\tdeg")
    return [(int(n), cfg, _X([float(v) for v in vals]))
            for n, cfg, *vals in re.findall(pat, text)]


def _head_mm(q_deg, l0=30.0, l1=40.0, l2=40.0, l3=75.0, l4=75.0):
    """Five-bar head J5 [mm] by intersecting the two link circles (source 004 Fig. 3)."""
    q = np.deg2rad(q_deg)
    j3 = np.stack([l1 * np.sin(q[:, 0]), -l1 * np.cos(q[:, 0])], 1)
    j4 = np.stack([l2 * np.sin(q[:, 1]), l0 - l2 * np.cos(q[:, 1])], 1)
    d = np.linalg.norm(j4 - j3, axis=1)
    a = (l3 ** 2 - l4 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(l3 ** 2 - a ** 2)
    u = (j4 - j3) / d[:, None]
    return j3 + a[:, None] * u + h[:, None] * np.stack([u[:, 1], -u[:, 0]], 1)


def _seg_dist(p, poly):
    """Distance of points p (N, 2) to the closed polygon's edges."""
    out = np.full(len(p), np.inf)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        t = np.clip(((p - a) @ (b - a)) / ((b - a) @ (b - a)), 0, 1)
        out = np.minimum(out, np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=1))
    return out


@pytest.fixture(scope="module")
def job(tmp_path_factory):
    d = tmp_path_factory.mktemp("job")
    f = d / "part7.yaml"
    f.write_text(JOB)
    assert main(["laser", "job", str(f), "-o", str(d / "out")]) == 0
    return {p.stem: p.read_text() for p in (d / "out").glob("*.ls")}, json.loads(
        (d / "out" / "part7_summary.json").read_text())


def test_one_job_calls_each_hole_then_cuts_the_contour(job):
    texts, summary = job
    assert set(texts) == {"part7", "part7_h01", "part7_h02"}
    main_mn = texts["part7"].split("/MN")[1].split("/POS")[0]
    calls = re.findall(r"CALL (\w+) ;", main_mn)
    assert calls == ["PART7_H01", "PART7_H02"]
    assert main_mn.index("CALL PART7_H02") < main_mn.index("DO[1]=ON")  # holes first
    assert "DEFAULT_GROUP\t= *,1,*,*,*;" in texts["part7_h01"]
    assert "DEFAULT_GROUP\t= 1,*,*,*,*;" in texts["part7"]
    assert "UFRAME_NUM=1 ;" in main_mn and summary["holes"] == 2


def test_contour_in_the_plate_frame_with_the_arms_configuration(job):
    """The points are in the UFRAME (= the plate pose given), the TCP runs on the rectangle
    in the plate's x-y plane with the beam into it, and the CONFIG written per point makes
    the controller take a continuous joint path (a fixed 'N U T, 0, 0, 0' would not: J6
    turns once around with the rectangle)."""
    texts, _ = job
    text = texts["part7"]
    X_RP, X_FT = _frame(text, "UFRAME"), _frame(text, "UTOOL")
    assert np.allclose(X_RP, _X([800, 100, 200, 0, 0, 30]), atol=1e-6)
    pts = _points(text)
    contour = pts[2:]
    spec = get_robot("m10ia")
    q = []
    for _, cfg, X_PT in contour:
        X_BF = spec.X_BR @ X_RP @ X_PT @ np.linalg.inv(X_FT)
        qi = joints_from_configuration(spec.kinematics, X_BF, "fanuc", cfg)
        assert np.abs(fk_opw(spec.kinematics.opw, qi) @ X_FT - spec.X_BR @ X_RP @ X_PT).max() \
            < 1e-9
        q.append(qi)
    q = np.array(q)
    fine = {int(n) for n in re.findall(r"L P\[(\d+)\] \S+ FINE ;", text)}
    into_fine = np.array([n in fine for n, _, _ in contour[1:]])
    step = np.abs(np.diff(q, axis=0)).max(axis=1)
    assert into_fine.sum() == 2  # the lead-in's end (a right angle) and the last point
    assert step[~into_fine].max() < 0.35  # 2 mm steps, 10 mm corner radius
    assert step[into_fine].max() < np.pi / 2 + 0.1  # the stop at the lead-in: 90 deg
    assert len({c for _, c, _ in contour}) >= 2  # the J6 turn number changes on the way
    assert np.ptp(q[:, 5]) > np.pi
    # TCP on the rounded rectangle (half sizes 100 x 50, corners r 10) in the plate plane
    p = np.array([X[:3, 3] for _, _, X in contour]) * 1e3
    assert np.abs(p[:, 2]).max() < 1e-6
    beam = np.array([X[:3, 2] for _, _, X in contour])
    assert np.allclose(beam, [0, 0, -1], atol=1e-9)
    cut = p[-150:, :2]
    dx = np.maximum(np.abs(cut[:, 0]) - 90, 0)
    dy = np.maximum(np.abs(cut[:, 1]) - 40, 0)
    inner = (np.abs(cut[:, 0]) <= 90) | (np.abs(cut[:, 1]) <= 40)
    r = np.where(inner, np.maximum(np.abs(cut[:, 0]) - 100, np.abs(cut[:, 1]) - 50) + 10,
                 np.hypot(dx, dy))
    assert np.abs(r - 10).max() < 0.02


def test_holes_cut_where_the_plate_says_by_robot_and_tool_together(job):
    """Robot pose over each hole (from its P[] + CONFIG) x the Cutting Tool's servo angles
    (independent circle-intersection FK) put the laser TCP on the hole's outline given in
    the plate frame: the 10 mm circle at (50, 20) and the triangle at (-50, -20), which is not
    symmetric, so a contour not mirrored into the tool's plane would miss it."""
    texts, _ = job
    text = texts["part7"]
    X_RP, X_FT = _frame(text, "UFRAME"), _frame(text, "UTOOL")
    spec = get_robot("m10ia")
    home = np.array([65.0, 15.0])  # the default tool's home point in C [mm]
    X_CT = np.eye(4)
    X_CT[:3, 3] = [home[0] / 1e3, home[1] / 1e3, NOZZLE_LENGTH]
    X_FC = X_FT @ np.linalg.inv(X_CT)
    outlines = {1: ("circle", np.array([50.0, 20.0])),
                2: ("triangle", np.array([[0, 0], [6, 0], [0, 4]], float) + [-50.0, -20.0])}
    for k, (_, cfg, X_PT) in enumerate(_points(text)[:2], start=1):
        X_BF = spec.X_BR @ X_RP @ X_PT @ np.linalg.inv(X_FT)
        qr = joints_from_configuration(spec.kinematics, X_BF, "fanuc", cfg)
        servo = np.array(re.findall(r"J1 =\t(-?[\d.]+)\tdeg,\tJ2 =\t(-?[\d.]+)\tdeg",
                                    texts[f"part7_h{k:02d}"]), float)
        head = _head_mm(servo) / 1e3
        p_C = np.c_[head, np.full(len(head), NOZZLE_LENGTH), np.ones(len(head))]
        X_PF = np.linalg.solve(spec.X_BR @ X_RP, fk_opw(spec.kinematics.opw, qr))
        p_P = (X_PF @ X_FC @ p_C.T).T[:, :3] * 1e3
        assert np.abs(p_P[:, 2]).max() < 1e-6
        kind, ref = outlines[k]
        if kind == "circle":
            err = np.abs(np.linalg.norm(p_P[-40:, :2] - ref, axis=1) - 5.0)
        else:
            err = _seg_dist(p_P[:, :2], ref)
        assert err.max() < 0.05, (k, err.max())


def test_job_bad_input_exit_2_one_line(tmp_path, capsys):
    f = tmp_path / "bad.yaml"
    for text, expected in [
            ("robot: irb1600\nholes: [{kind: circle, diameter: 5, at: [0, 0]}]\n",
             "abb controller"),
            ("holes: [{kind: circle, diameter: 5}]\n", "holes[0]: 'at: [x, y]'"),
            ("holes: [{kind: circle, diameter: 50, at: [0, 0]}]\n", "hole 1: circle"),
            ("contour: {kind: circle, diameter: 100}\nplate: [3000, 0, 0, 0, 0, 0]\n",
             "out of reach"),
            ("colour: red\n", "unknown key(s) ['colour']")]:
        f.write_text(text)
        assert main(["laser", "job", str(f), "-o", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err.strip()
        assert expected in err and len(err.splitlines()) == 1, (expected, err)
