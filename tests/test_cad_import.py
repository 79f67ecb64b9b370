"""STEP/IGES wheels through OpenCASCADE (drakedeburr.hub.cad / import_cad), checked against
wheels built with a CAD kernel (build123d, tests/cad_wheels.py), not with our own generator:
loops against the B-rep's own edges (OpenCASCADE BRepExtrema), normals against the drafts and
fillets the wheel was built with, window counts against the construction."""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import cad_wheels  # noqa: E402

from drakedeburr.cli import main  # noqa: E402
from drakedeburr.hub.cad import read_cad  # noqa: E402
from drakedeburr.hub.import_cad import read_cad_windows  # noqa: E402
from drakedeburr.hub.import_mesh import ImportOptions  # noqa: E402

pytestmark = pytest.mark.slow
ON_EDGE_MM = 0.02  # issue 42: STEP loops lie on the B-rep edge within 0.02 mm


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    return cad_wheels.make_wheel("straight", tmp_path_factory.mktemp("cad"))


@pytest.fixture(scope="module")
def straight_windows(straight):
    return read_cad_windows(straight.step, ImportOptions())


def _edges_compound(shape):
    """All edges of the B-rep as one compound (what the loops must lie on)."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS_Compound

    comp, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(comp)
    exp = TopExp_Explorer(shape, TopAbs_EDGE)
    while exp.More():
        builder.Add(comp, exp.Current())
        exp.Next()
    return comp


def _distances_mm(shape_edges, p_mm: np.ndarray) -> np.ndarray:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.gp import gp_Pnt

    out = []
    for q in p_mm:
        d = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*q)).Vertex(),
                                       shape_edges)
        assert d.IsDone()
        out.append(d.Value())
    return np.array(out)


def _in_file_mm(cw, p_H: np.ndarray) -> np.ndarray:
    X = cw["X_MH"]
    return (p_H @ X[:3, :3].T + X[:3, 3]) * 1e3


def test_step_loops_lie_on_the_brep_edges_and_count_the_windows(straight, straight_windows):
    from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
    from OCP.gp import gp_Pnt

    cw = straight_windows
    assert len(cw["windows"]) == straight.windows == 5
    kinds = sorted(o["kind"] for o in cw["notes"]["not_windows"])
    assert kinds == ["centre bore"] + ["lug hole"] * 5, kinds
    assert all(o["width_mm"] == pytest.approx(14.0, abs=0.3)  # the Ø14 lug holes
               for o in cw["notes"]["not_windows"] if o["kind"] == "lug hole")
    edges = _edges_compound(read_cad(straight.step).shape)
    worst = 0.0
    for w, k in zip(cw["windows"], cw["kept"], strict=True):
        p = _in_file_mm(cw, w.p_HE[::15])
        worst = max(worst, float(_distances_mm(edges, p).max()))
        nurbs = k["loop"].nurbs
        assert nurbs is not None
        on_nurbs = [GeomAPI_ProjectPointOnCurve(gp_Pnt(*q), nurbs).LowerDistance() for q in p]
        assert max(on_nurbs) < 1e-3, max(on_nurbs)  # the joined NURBS is the same curve
        # a closed loop, CCW seen from +Z_H, spaced as asked
        seg = np.linalg.norm(np.diff(np.vstack([w.p_HE, w.p_HE[:1]]), axis=0), axis=1)
        assert seg.max() <= 0.5e-3 + 1e-6 and seg.min() > 0
        x, y = w.p_HE[:, 0], w.p_HE[:, 1]
        assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0
    assert worst <= ON_EDGE_MM, worst


def test_the_loop_is_the_face_side_line_of_the_round_and_normals_are_exact(straight_windows):
    """On the spoke flanks of the straight wheel: the face-side tangent line of the 1 mm
    edge round lies 0.734 + 0.949 mm from the cut's top outline (draft 3 deg over the 14 mm
    from the cut's top to the face; r tan(43.5 deg) of a round between faces 87 deg apart),
    the face normal is the disc face's +Z, the wall normal rises at the draft angle."""
    cw = straight_windows
    z_face = None
    half = 0.5 * cad_wheels.SPOKE_WIDTH
    drop = cad_wheels.Z_CUT_TOP - cad_wheels.Z_FACE
    draft = math.radians(cad_wheels.DRAFT_DEG)
    setback = cad_wheels.EDGE_ROUND * math.tan(0.5 * (math.pi / 2 - draft))
    expected = half + drop * math.tan(draft) - setback  # [mm] from the spoke's centre line
    lateral_all, n_face_z, n_wall_z = [], [], []
    for w in cw["windows"]:
        p = w.p_HE * 1e3
        r = np.hypot(p[:, 0], p[:, 1])
        if z_face is None:
            z_face = float(np.median(p[(r > 100) & (r < 150), 2]))
        flank = (r > 100) & (r < 150) & (np.abs(p[:, 2] - z_face) < 1e-3)
        lateral = []
        for k in range(cad_wheels.N_SPOKES):
            a = math.radians(cad_wheels.PHASE_DEG + 72.0 * k)
            along = p[:, 0] * math.cos(a) + p[:, 1] * math.sin(a)
            across = -p[:, 0] * math.sin(a) + p[:, 1] * math.cos(a)
            lateral.append(np.where(along > 0, np.abs(across), np.inf))
        lateral = np.min(lateral, axis=0)[flank]
        assert len(lateral) > 100
        lateral_all.append(lateral)
        n_face_z.append(w.n_face_H[flank, 2])
        n_wall_z.append(w.n_wall_H[flank, 2])
        # everywhere: the wall normal points into the opening and is no face normal
        chord = np.roll(w.p_HE, -1, axis=0) - np.roll(w.p_HE, 1, axis=0)
        left = np.c_[-chord[:, 1], chord[:, 0]] / np.linalg.norm(chord[:, :2], axis=1)[:, None]
        assert np.einsum("ij,ij->i", w.n_wall_H[:, :2], left).min() > 0.0
        assert np.einsum("ij,ij->i", w.n_wall_H, w.n_face_H).max() < 0.6
    lateral_all = np.concatenate(lateral_all)
    np.testing.assert_allclose(lateral_all, expected, atol=0.02)
    np.testing.assert_allclose(np.concatenate(n_face_z), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.concatenate(n_wall_z), math.sin(draft), atol=1e-6)


def test_the_loop_climbs_into_the_rim_lip(straight_windows):
    """The windows open into the lip cone (r 176 -> 200 mm rising 12 mm): the loop's outer
    end lies on the cone, up to (184 - 176) / 2 = 4 mm above the disc face (less the round)."""
    for w in straight_windows["windows"]:
        z = w.p_HE[:, 2] * 1e3
        rise = float(z.max() - np.median(z))
        assert 3.0 < rise <= 4.0 + 1e-6, rise


def test_iges_reads_the_same_windows(straight, straight_windows):
    cw = read_cad_windows(straight.iges, ImportOptions())
    assert len(cw["windows"]) == 5
    edges = _edges_compound(read_cad(straight.step).shape)
    for w in cw["windows"]:
        d = _distances_mm(edges, _in_file_mm(cw, w.p_HE[::40]))
        assert d.max() <= ON_EDGE_MM, d.max()  # on the STEP's B-rep edges


def _loop_edges_compound(cw):
    """The edges of the windows' B-rep loops (the front boundaries) as one compound."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    comp, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(comp)
    for k in cw["kept"]:
        for e in k["loop"].edges:
            builder.Add(comp, e)
    return comp


def test_mesh_export_loops_near_the_brep_edges(straight, straight_windows):
    """Issue 42 item 5: loops from the fine STL export of the same wheel within its chordal
    tolerance + 0.1 mm of the B-rep's window edges (the edges the STEP loops run on; not any
    B-rep edge: the disc face's crease 1.9 mm from a window's inner end is an edge too) - the
    mesh extraction of drakedeburr.hub.extract.

    Two defects of hub.edgeline's face test were found here (measured, fine STL, before ->
    after): (1) the band test called a sample band when its normal differed by BAND_ANGLE from
    the one 1 mm further out, whichever way: the 1.8 mm disc-face strip between a window's
    1 mm round (face-side line at r = 81.8 mm) and the crease at r = 80 mm to a 31 deg slope
    read as band and the edge went past the crease (windows 3 and 4, 1.877 mm off); the band
    now turns toward the front (the surface ahead faces the front more) or right there (within
    a quarter lag). (2) The 8 deg band test stops R sin(8 deg) = 0.14 mm inside a round of
    R = 1 mm (0.189 mm worst, 1.6 % of the points over 0.15 mm); the face start now steps on
    while the surface still turns toward the front by more than FACE_ANGLE (at most sin 8 deg
    x the band read, and 0.3 mm). Worst point now 0.103 mm."""
    from drakedeburr.hub.extract import extract_window_edges
    from drakedeburr.hub.mesh_io import load_hub_mesh

    tol = cad_wheels.STL_TOLERANCES["fine"][0]
    lm = load_hub_mesh(straight.stl["fine"])
    res = extract_window_edges(lm.mesh, source="fine stl", spacing=2e-3)
    assert len(res.windows) == straight.windows
    edges = _loop_edges_compound(straight_windows)
    d = []
    for w in res.windows:
        X = res.X_MH
        d.append(_distances_mm(edges, (w.p_HE[::2] @ X[:3, :3].T + X[:3, 3]) * 1e3))
    worst = float(np.concatenate(d).max())
    assert worst <= tol + 0.1, worst


def _inscribed_width_mm(p_H: np.ndarray) -> float:
    """Diameter [mm] of the largest circle inside the loop's plan polygon (shapely's
    maximum_inscribed_circle: independent of the import's raster)."""
    import shapely

    poly = shapely.Polygon(p_H[:, :2] * 1e3)
    return 2.0 * shapely.maximum_inscribed_circle(poly, 0.01).length


def _check_spoked(wheel, cw, windows: int, corner_mm: float):
    """``windows`` windows, the other openings the bore and the 5 lug holes, the loops on the
    B-rep's edges, each window's width as measured by the import (within its 0.25 mm raster),
    and the frames turning no faster from point to point than plan corners of ``corner_mm``
    less the 1 mm edge round on either side allow (a sharp step in a window's outline, as the
    Y spoke's trunk standing 1.9 mm proud of its arms once made, turned them 21 deg in
    0.5 mm: the planned tool axis left its cone there, window 4 of the Y wheel)."""
    assert len(cw["windows"]) == windows
    kinds = sorted(o["kind"] for o in cw["notes"]["not_windows"])
    assert kinds[:6] == ["centre bore"] + ["lug hole"] * 5, kinds
    edges = _edges_compound(read_cad(wheel.step).shape)
    step_mm = ImportOptions().edge_spacing * 1e3
    bound = step_mm / (corner_mm - 2 * cad_wheels.EDGE_ROUND)  # [rad] per step
    for w, loop in zip(cw["windows"], cw["notes"]["loops"], strict=True):
        d = _distances_mm(edges, _in_file_mm(cw, w.p_HE[::25]))
        assert d.max() <= ON_EDGE_MM, (w.index, d.max())
        assert loop["width_mm"] == pytest.approx(_inscribed_width_mm(w.p_HE), abs=0.3)
        for v in (w.t_H, w.n_wall_H, w.n_face_H):
            turn = np.arccos(np.clip(np.einsum("ij,ij->i", v, np.roll(v, -1, axis=0)), -1, 1))
            assert turn.max() <= bound, (w.index, float(turn.max()), bound)


def test_y_wheel_loops_on_the_brep_edges_and_every_window(tmp_path):
    """5 Y spokes: 5 large windows between the spokes and 5 small ones (~17 mm) between the
    arms of each Y, all of them windows a burr of the tool library fits; the blind pockets
    behind the spokes are not openings."""
    wheel = cad_wheels.make_wheel("y", tmp_path, formats=("step",))
    cw = read_cad_windows(wheel.step, ImportOptions())
    _check_spoked(wheel, cw, wheel.windows, wheel.corner_mm)
    assert wheel.windows == 10 and len(cw["notes"]["not_windows"]) == 6  # no blind one


def test_twin_slot_only_the_small_burr_fits_is_a_window(tmp_path):
    """Twin spokes with a 12 mm slot between the bars: the loop (the face-side line of the
    1 mm round) is the slot less the 3 deg draft over the 14 mm down to the face plus the
    round's set-back on both sides wide, 12.4 mm: the 12 mm burr (needs 16 mm with the 2 mm
    clearance) does not fit, the 6 mm one (10 mm) does. With the tool library all 10 openings
    are windows; with the 12 mm burr alone the 5 slots are refused, each with its measured
    width and the burr's need."""
    from drakedeburr.hub.openings import burr_need

    slot = 12.0
    wheel = cad_wheels.make_wheel("twin", tmp_path, formats=("step",), slot=slot)
    draft = math.radians(cad_wheels.DRAFT_DEG)
    setback = cad_wheels.EDGE_ROUND * math.tan(0.5 * (math.pi / 2 - draft))
    width = slot - 2 * (cad_wheels.Z_CUT_TOP - cad_wheels.Z_FACE) * math.tan(draft) + 2 * setback
    assert burr_need(6e-3) * 1e3 < width < burr_need(12e-3) * 1e3
    cw = read_cad_windows(wheel.step, ImportOptions())
    # the kernel cannot fit the 7 mm plan corners into the 12 mm slot: half of it there
    _check_spoked(wheel, cw, wheel.windows, 0.5 * cad_wheels.CORNER)
    assert cw["notes"]["burrs_mm"] == [6.0, 12.0]
    slots = [k["width_mm"] for k in cw["notes"]["loops"] if k["width_mm"] < 20]
    assert len(slots) == 5 and np.allclose(slots, width, atol=0.3), (slots, width)
    alone = read_cad_windows(wheel.step, ImportOptions(burr_diameters=(12e-3,)))
    _check_spoked(wheel, alone, 5, wheel.corner_mm)
    narrow = [o for o in alone["notes"]["not_windows"] if o["kind"] == "too narrow"]
    assert len(narrow) == 5
    for o in narrow:
        measured = float(re.search(r"(?:opening|vent slot) ([\d.]+) mm wide", o["reason"]).group(1))
        assert measured == pytest.approx(width, abs=0.3)
        assert "the 12 mm burr needs 16.0 mm" in o["reason"] and "6 mm" not in o["reason"]


def _box_step(tmp_path) -> Path:
    from build123d import Box, export_step

    f = tmp_path / "box.step"
    export_step(Box(40, 40, 10), str(f))
    return f


def test_bad_cad_files_are_refused_naming_what_is_wrong(tmp_path, capsys):
    box = _box_step(tmp_path)
    text = box.read_text()
    cut = tmp_path / "cut.step"
    cut.write_text(text[: len(text) // 2])
    face = re.search(r"^#(\d+) = ADVANCED_FACE\('',\((#\d+)\),(#\d+),", text, re.M)
    direction = re.search(r"^#(\d+) = DIRECTION\(", text, re.M).group(1)
    broken = tmp_path / "broken.step"
    broken.write_text(text.replace(face.group(0), face.group(0).replace(
        face.group(3) + ",", f"#{direction},")))
    nonsense = tmp_path / "nonsense.iges"
    nonsense.write_text("hello")
    device = tmp_path / "zero.step"
    device.symlink_to("/dev/zero")
    big = tmp_path / "big.stp"
    with open(big, "wb") as f:
        f.truncate(2 << 30)  # sparse: no disk used
    cases = [(device, r"zero\.step: CAD file is a character device; only regular files"),
             (big, r"big\.stp: CAD file is 2 GiB, more than the mesh read limit of 1 GiB"),
             (cut, r"cut\.step: not a readable STEP file .*Line \d+"),
             (broken, rf"broken\.step: 1 of 6 faces did not transfer: entity #{face.group(1)} "
                      r"ADVANCED_FACE"),
             (nonsense, r"nonsense\.iges: no IGES entity"),
             (box, r"box\.step: diameter across the hub axis \d+ mm .* is not a wheel hub's")]
    for f, pattern in cases:
        capsys.readouterr()
        assert main(["-q", "hub", "import", str(f), "--out", str(tmp_path / "out")]) == 2, f
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and re.search(pattern, err[0]), err


def test_cl_reads_a_step_wheel(straight, tmp_path):
    """``drakedeburr cl WHEEL.step --json``: the windows of the B-rep, in the file's frame (mm)
    and on its edges."""
    import json

    out = tmp_path / "cl.json"
    assert main(["-q", "cl", str(straight.step), "--method", "proposed", "--json",
                 str(out)]) == 0
    view = json.loads(out.read_text())["input"]
    assert view["unit"] == "mm" and len(view["edges"]) == straight.windows
    shape_edges = _edges_compound(read_cad(straight.step).shape)
    p = np.array(view["edges"][0]["points"])[::10]  # resampled at 2 mm along the 0.5 mm loop
    assert _distances_mm(shape_edges, p).max() <= ON_EDGE_MM


def test_loop_frames_are_square_and_turn_no_faster_than_the_corners(straight_windows):
    """The frames the planner turns the tool with: per loop point t square to both normals
    and along the loop, and from point to point (0.5 mm apart) turning no faster than the
    wheel's tightest plan corner allows (the 7 mm corner radius less the 1 mm edge round on
    either side): exact B-rep normals jump by up to 27 deg where the disc face meets the lip
    cone and by a corner's whole turn where two walls meet."""
    step_mm = ImportOptions().edge_spacing * 1e3
    bound = step_mm / (cad_wheels.CORNER - 2 * cad_wheels.EDGE_ROUND)  # [rad] per step
    for w in straight_windows["windows"]:
        t, nw, nf = w.t_H, w.n_wall_H, w.n_face_H
        np.testing.assert_allclose(np.linalg.norm(nw, axis=1), 1.0, atol=1e-9)
        assert np.abs(np.einsum("ij,ij->i", t, nw)).max() < 1e-9
        assert np.abs(np.einsum("ij,ij->i", t, nf)).max() < 1e-9
        chord = np.roll(w.p_HE, -1, axis=0) - np.roll(w.p_HE, 1, axis=0)
        assert np.einsum("ij,ij->i", t, chord).min() > 0
        seg = np.linalg.norm(np.roll(w.p_HE, -1, axis=0) - w.p_HE, axis=1) * 1e3
        assert seg.max() <= step_mm + 1e-6
        for v in (t, nw, nf):
            turn = np.arccos(np.clip(np.einsum("ij,ij->i", v, np.roll(v, -1, axis=0)), -1, 1))
            assert turn.max() <= bound, (w.index, float(turn.max()), bound)


def test_hub_import_folder_loads_with_the_loops_nurbs(straight, tmp_path):
    """``hub import WHEEL.step``: the folder loads as a hub (load_hub, the hub edges' member
    check), with the windows of the B-rep, and each loop's NURBS (poles, weights, knots in H)
    evaluated independently (scipy's B-spline of the homogeneous poles) runs along the loop's
    points within 0.02 mm both ways."""
    from scipy.interpolate import BSpline
    from scipy.spatial import cKDTree

    from drakedeburr.hub.import_cad import import_cad
    from drakedeburr.hub.model import load_hub

    res = import_cad(straight.step, tmp_path / "hubs")
    hub = load_hub(res.dir)
    assert len(hub.windows) == straight.windows
    with np.load(res.dir / "edges.npz") as data:
        for w in hub.windows:
            poles, wts = data[f"w{w.index}_nurbs_poles"], data[f"w{w.index}_nurbs_weights"]
            knots = data[f"w{w.index}_nurbs_knots"]
            k = int(data[f"w{w.index}_nurbs_degree"].ravel()[0])  # stored as one float
            u = np.linspace(knots[k], knots[-k - 1], 60000)
            q = BSpline(knots, poles * wts[:, None], k)(u) / BSpline(knots, wts, k)(u)[:, None]
            d_loop = cKDTree(q).query(w.p_HE)[0]
            d_curve = cKDTree(w.p_HE).query(q)[0]
            assert d_loop.max() * 1e3 <= ON_EDGE_MM, d_loop.max()
            # the loop's points are 0.5 mm apart: a curve point is within half of that
            assert d_curve.max() * 1e3 <= 0.25 + ON_EDGE_MM, d_curve.max()
