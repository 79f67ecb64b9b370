"""``post --workpiece-in-hand --virtual-tcp``: the paper's program without RTCP (source 000),
read back by a small parser written here (not drakedeburr.programs.reading), and the exact
polygon offset of a contour by the tool radius.

The parsers follow the vendors' documented data layouts: ABB RAPID ``tooldata`` /
``wobjdata`` / ``robtarget`` ([x,y,z] mm, quaternion q1..q4 with q1 = w; ABB Technical
reference manual RAPID Instructions, Functions and Data types, "tooldata", "wobjdata":
object frame = uframe * oframe), KUKA ``$BASE`` / ``$TOOL`` / ``E6POS`` (X, Y, Z mm, A B C deg,
R = Rz(A) Ry(B) Rx(C); KUKA System Software 8 Operating and Programming Instructions,
"Coordinate systems"), FANUC ``P[n]{... X = , Y = , Z = mm, W = , P = , R = deg}`` (R =
Rz(R) Ry(P) Rx(W); FANUC R-30iA Controller Operator's Manual, "Frames") with the UTOOL /
UFRAME values as the file gives them.
"""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from drakedeburr.cli import main
from drakedeburr.post.virtual_tcp import offset_contour

CREO = "CreoPost__profilfraesen_2.ncl.2"
NUM = r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"


# ------------------------------------------------------------------ independent geometry
def _pose(xyz_mm, R):
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = np.asarray(xyz_mm, float) / 1000.0
    return X


def _zyx(a_deg, b_deg, c_deg):
    """R = Rz(a) Ry(b) Rx(c), angles in degrees (KUKA A B C; FANUC R P W)."""
    a, b, c = np.radians([a_deg, b_deg, c_deg])
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    return Rz @ Ry @ Rx


def _quat_w_first(q):
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _nums(text):
    return [float(v) for v in re.findall(NUM, text)]


# ------------------------------------------------------------------ independent parsers
def _parse_rapid(text):
    """(X_RT tool in flange, X_RU object frame, [target poses in the object frame] in
    MoveL/MoveJ order)."""
    tool = re.search(r"PERS tooldata \w+ := \[(TRUE|FALSE),\[\[([^\]]*)\],\[([^\]]*)\]\]", text)
    assert tool and tool.group(1) == "TRUE"  # an ordinary, robot-held tool
    X_FT = _pose(_nums(tool.group(2)), _quat_w_first(_nums(tool.group(3))))
    wobj = re.search(r"PERS wobjdata \w+ := \[(TRUE|FALSE),(TRUE|FALSE),\"[^\"]*\","
                     r"\[\[([^\]]*)\],\[([^\]]*)\]\],\[\[([^\]]*)\],\[([^\]]*)\]\]\]", text)
    assert wobj and wobj.group(1) == "FALSE"  # robhold FALSE: a fixed work object
    uframe = _pose(_nums(wobj.group(3)), _quat_w_first(_nums(wobj.group(4))))
    oframe = _pose(_nums(wobj.group(5)), _quat_w_first(_nums(wobj.group(6))))
    targets = {m.group(1): _pose(_nums(m.group(2)), _quat_w_first(_nums(m.group(3))))
               for m in re.finditer(r"CONST robtarget (\w+) := \[\[([^\]]*)\],\[([^\]]*)\]",
                                    text)}
    order = re.findall(r"^\s*Move[LJ] (\w+),", text, re.M)
    return X_FT, uframe @ oframe, [targets[n] for n in order]


def _krl_frame(body):
    v = dict(re.findall(rf"([XYZABC]) ({NUM})", body))
    return _pose([float(v[k]) for k in "XYZ"], _zyx(*(float(v[k]) for k in "ABC")))


def _parse_krl(src, dat):
    assert "$IPO_MODE = #BASE" in src  # robot-guided tool, no external TCP
    X_FT = _krl_frame(re.search(r"\$TOOL = \{([^}]*)\}", src).group(1))
    X_RU = _krl_frame(re.search(r"\$BASE = \{([^}]*)\}", src).group(1))
    points = {m.group(1): _krl_frame(m.group(2))
              for m in re.finditer(r"DECL E6POS (\w+)=\{([^}]*)\}", dat)}
    order = re.findall(r"^\s*(?:LIN|PTP) (\w+)", src, re.M)
    return X_FT, X_RU, [points[n] for n in order]


def _ls_frame(text, name):
    """The frame the LS program sets: ``PR[r,1..6]=`` X, Y, Z, W, P, R then ``NAME[1]=PR[r]``
    (the last assignment of PR[r] before it), or an older file's ``!NAME[1] X=...`` remark."""
    v = {k: float(x) for k, x in re.findall(rf"{name}\[1\] ([XYZWPR])=({NUM})", text)}
    if not v:
        body = text.split(f"{name}[1]=PR[", 1)
        reg = re.match(r"(\d+)\]", body[1]).group(1)
        vals = dict(re.findall(rf"PR\[{reg},([1-6])\]=({NUM})", body[0]))
        v = {k: float(vals[str(i + 1)]) for i, k in enumerate("XYZWPR")}
    return _pose([v["X"], v["Y"], v["Z"]], _zyx(v["R"], v["P"], v["W"]))


def _parse_ls(text):
    mn = text.split("/MN", 1)[1].split("/POS", 1)[0]
    moves = [ln for ln in mn.splitlines() if re.match(r"\s*\d+:\s+[LJ] P", ln)]
    assert moves and not any("RTCP" in ln for ln in moves)  # no Remote TCP option
    X_FT, X_RU = _ls_frame(text, "UTOOL"), _ls_frame(text, "UFRAME")
    pos = text.split("/POS", 1)[1]
    points = {}
    for m in re.finditer(r"P\[(\d+)\]\{(.*?)\};", pos, re.S):
        v = dict(re.findall(rf"\b([XYZWPR]) = ({NUM})", m.group(2)))
        points[m.group(1)] = _pose([float(v[k]) for k in "XYZ"],
                                   _zyx(float(v["R"]), float(v["P"]), float(v["W"])))
    order = re.findall(r"^\s*\d+:\s+[LJ] P\[(\d+)\]", mn, re.M)
    return X_FT, X_RU, [points[n] for n in order]


@pytest.mark.parametrize("robot, suffix, spindle", [
    ("irb1600", ".mod", [700.0, 0, 500, 0, -90, 0]),
    ("kr6_r700", ".src", [450.0, 0, 300, 0, 0, 0]),
    ("m10ia", ".ls", [450.0, 0, 300, 0, 0, 0])])
def test_virtual_tcp_program_puts_every_cl_point_on_the_spindle(extdata, tmp_path, robot,
                                                              suffix, spindle):
    """Without RTCP: every move of the written program, read back by the parsers above and
    composed as the controller does (robot frame * user frame * target * tool^-1 = flange),
    carries the part so that its CL point lies on the spindle's tool point within 0.01 mm,
    with the CL axis along the spindle and the part never turning (translation mode)."""
    from drakedeburr.post.cl_reader import read_cl
    from drakedeburr.robots import get_robot

    cl_path = extdata / "cl_files" / CREO
    out = tmp_path / f"vt{suffix}"
    part = [10.0, -5.0, 100.0, 0, 0, 30.0]  # the part's CL frame on the flange
    assert main(["post", str(cl_path), "--robot", robot, "--workpiece-in-hand", "--virtual-tcp",
                 "--tool", ",".join(map(str, spindle)), "--wobj", ",".join(map(str, part)),
                 "-o", str(out)]) == 0
    text = out.read_text()
    if suffix == ".mod":
        from test_programs_formats import rapidcheck  # third-party RAPID grammar checker

        assert rapidcheck(text) == []
        X_FT, X_RU, targets = _parse_rapid(text)
    elif suffix == ".src":
        X_FT, X_RU, targets = _parse_krl(text, out.with_suffix(".dat").read_text())
    else:
        X_FT, X_RU, targets = _parse_ls(text)
    cl = read_cl(cl_path)  # the input (tool-centre points in the part), not the program
    assert len(targets) == len(cl)
    X_BR = np.asarray(get_robot(robot).X_BR)  # the controller's robot frame in the base
    X_BS = _pose(spindle[:3], _zyx(spindle[5], spindle[4], spindle[3]))
    X_FP = _pose(part[:3], _zyx(part[5], part[4], part[3]))
    err, R_parts = [], []
    for X_UT, p, a in zip(targets, cl.p_C, cl.axis_C, strict=True):
        X_BF = X_BR @ X_RU @ X_UT @ np.linalg.inv(X_FT)  # the flange the controller commands
        X_BP = X_BF @ X_FP
        err.append(np.linalg.norm(X_BP[:3, :3] @ p + X_BP[:3, 3] - X_BS[:3, 3]))
        assert np.allclose(X_BP[:3, :3] @ a, -X_BS[:3, 2], atol=1e-6)  # axis along spindle
        R_parts.append(X_BP[:3, :3])
    assert max(err) < 0.01e-3, max(err)
    turn = Rotation.from_matrix(np.array(R_parts)) * Rotation.from_matrix(R_parts[0]).inv()
    assert np.degrees(turn.magnitude()).max() < 1e-4  # the part only translates


def test_virtual_tcp_refuses_a_varying_tool_axis(extdata, tmp_path, capsys):
    out = tmp_path / "v.mod"
    nx = extdata / "cl_files" / "MECH491_NX_CLSF__APT_Variable_Axis.txt"
    assert main(["post", str(nx), "--units", "inch", "--workpiece-in-hand", "--virtual-tcp",
                 "--tool", "700,0,500,0,-90,0", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "tool axis changes" in err and "without --virtual-tcp" in err and not out.exists()
    assert len(err.strip().splitlines()) == 1


def test_virtual_tcp_needs_workpiece_in_hand(extdata, tmp_path, capsys):
    out = tmp_path / "v.mod"
    assert main(["post", str(extdata / "cl_files" / CREO), "--virtual-tcp", "-o", str(out)]) == 2
    assert "--workpiece-in-hand" in capsys.readouterr().err and not out.exists()


# ------------------------------------------------------------------ polygon offset
def _dist_to_polygon(x, poly):
    """Distance of points x (M, 2) to the closed polygon's edges (N, 2), numpy only."""
    a, b = poly, np.roll(poly, -1, 0)
    ab = b - a
    t = np.clip(np.einsum("mnk,nk->mn", x[:, None] - a[None], ab) / np.sum(ab * ab, 1), 0, 1)
    foot = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(x[:, None] - foot, axis=-1).min(1)


def _inside(x, poly):
    """Even-odd rule, numpy only."""
    a, b = poly, np.roll(poly, -1, 0)
    cross = ((a[:, 1] > x[:, None, 1]) != (b[:, 1] > x[:, None, 1]))
    xint = a[:, 0] + (x[:, None, 1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1] + 1e-300)
    return np.sum(cross & (x[:, None, 0] < xint), 1) % 2 == 1


L_SHAPE = np.array([[0, 0], [80, 0], [80, 30], [30, 30], [30, 60], [0, 60]], float) * 1e-3


@pytest.mark.parametrize("side", ["outward", "inward"])
@pytest.mark.parametrize("reverse", [False, True])
def test_polygon_offset_is_exact_at_corners(side, reverse):
    """A sparse CAM vertex list (an L with a concave corner): every offset point lies at R
    from the polygon (within the arc chord tolerance), on the right side; the concave corner
    outward (and the convex corners inward) are single points at R from both edges, where
    the point-wise offset left R (1 - 1/sqrt 2) = 1.17 mm at R = 4 mm."""
    R, tol = 4e-3, 1e-6
    poly = L_SHAPE[::-1] if reverse else L_SHAPE
    p = np.column_stack([poly, np.zeros(len(poly))])
    out = offset_contour(p, R, side, arc_tolerance=tol)
    d = _dist_to_polygon(out[:, :2], poly)
    assert np.all(np.abs(d - R) < 1e-9)  # vertices on the exact offset
    mid = 0.5 * (out[:, :2] + np.roll(out[:, :2], -1, 0))  # chords within tol of it
    dm = _dist_to_polygon(mid, poly)
    assert np.all(dm > R - tol - 1e-12) and np.all(dm < R + 1e-9)
    assert np.all(_inside(out[:, :2], poly) == (side == "inward"))
    sharp = {"outward": [(0.030 + R, 0.030 + R)],  # the concave corner
             "inward": [(R, R), (0.080 - R, R), (0.080 - R, 0.030 - R), (R, 0.060 - R)]}[side]
    for c in sharp:
        assert np.min(np.linalg.norm(out[:, :2] - c, axis=1)) < 1e-12, c
    # the same way round as the input, starting near its first point
    area = 0.5 * np.sum(out[:, 0] * np.roll(out[:, 1], -1) - np.roll(out[:, 0], -1) * out[:, 1])
    area_in = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1)
                           * poly[:, 1])
    assert np.sign(area) == np.sign(area_in)
    assert np.linalg.norm(out[0, :2] - poly[0]) <= R * np.sqrt(2) + 1e-12


def test_offset_refuses_a_3d_contour_and_a_tool_that_does_not_fit():
    from drakedeburr.errors import InputError

    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    saddle = np.stack([0.05 * np.cos(t), 0.05 * np.sin(t), 0.002 * np.cos(2 * t)], -1)
    with pytest.raises(InputError, match="off the contour's plane.*3-D contour"):
        offset_contour(saddle, 0.004, "outward")
    hole = np.stack([0.003 * np.cos(t), 0.003 * np.sin(t), 0 * t], -1)
    with pytest.raises(InputError, match="does not fit"):
        offset_contour(hole, 0.004, "inward")
    # a tilted plane is fine when its normal is given
    R = Rotation.from_euler("xy", [0.3, -0.2]).as_matrix()
    square = np.array([[0, 0, 0], [0.05, 0, 0], [0.05, 0.05, 0], [0, 0.05, 0]]) @ R.T
    out = offset_contour(square, 0.004, "inward", normal=R[:, 2])
    local = out @ R  # back in the square's plane
    assert np.allclose(local[:, 2], 0, atol=1e-12)
    assert np.allclose(np.sort(local[:, 0]), [0.004, 0.004, 0.046, 0.046], atol=1e-12)


def test_virtual_tcp_reference_pose_sets_the_tool(extdata, tmp_path):
    """--reference X_OP: the written tool data is the TCP that coincides with the spindle at
    that reference pose, X_FT = X_FP X_OP^-1, and every CL point still meets the spindle."""
    from drakedeburr.post.cl_reader import read_cl

    out = tmp_path / "ref.mod"
    spindle, part, ref = [700.0, 0, 500, 0, -90, 0], [0.0, 0, 100, 0, 0, 0], [5, -3, 2, 180, 0, 45]
    assert main(["post", str(extdata / "cl_files" / CREO), "--workpiece-in-hand",
                 "--virtual-tcp", "--tool", ",".join(map(str, spindle)),
                 "--wobj", ",".join(map(str, part)), "--reference", ",".join(map(str, ref)),
                 "-o", str(out)]) == 0
    X_FT, X_RU, targets = _parse_rapid(out.read_text())
    X_FP = _pose(part[:3], _zyx(part[5], part[4], part[3]))
    X_OP = _pose(ref[:3], _zyx(ref[5], ref[4], ref[3]))
    assert np.abs(X_FT - X_FP @ np.linalg.inv(X_OP)).max() < 1e-8
    X_BS = _pose(spindle[:3], _zyx(spindle[5], spindle[4], spindle[3]))
    assert np.abs(X_RU - X_BS).max() < 1e-8  # the user frame is the spindle frame
    cl = read_cl(extdata / "cl_files" / CREO)
    for X_UT, p in zip(targets, cl.p_C, strict=True):
        X_BP = X_RU @ X_UT @ np.linalg.inv(X_FT) @ X_FP
        assert np.linalg.norm(X_BP[:3, :3] @ p + X_BP[:3, 3] - X_BS[:3, 3]) < 0.01e-3
    assert main(["post", str(extdata / "cl_files" / CREO), "--reference", "0,0,0,0,0,0",
                 "--workpiece-in-hand", "--tool", "700,0,500,0,-90,0",
                 "-o", str(tmp_path / "x.mod")]) == 2  # --reference without --virtual-tcp
    assert main(["post", str(extdata / "cl_files" / CREO), "--reference", "0,0,0,0,0,0",
                 "--workpiece-in-hand", "--virtual-tcp", "--tool", "700,0,500,0,-90,0",
                 "-o", str(tmp_path / "x.mod")]) == 2  # CL axis not onto -Z of the spindle
    assert not (tmp_path / "x.mod").exists()
