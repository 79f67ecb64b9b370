import numpy as np
import pytest
from scipy.spatial import cKDTree

import drakedeburr.hub.extract as mut
from drakedeburr.errors import InputError
from drakedeburr.hub.mesh_io import load_hub_mesh
from drakedeburr.hub.openings import OpeningSearch
from drakedeburr.path.synthetic import rounded_polygon

AUDIBOT = "wheel_models/audibot__wheel_rim_only_DERIVED_m.stl"


@pytest.fixture(scope="module")
def extdata():
    """shared/extdata beside the checkout or beside any parent (git worktrees live deeper)."""
    from pathlib import Path

    for parent in Path(__file__).resolve().parents:
        if (parent / "shared" / "extdata").is_dir():
            return parent / "shared" / "extdata"
    pytest.fail("shared/extdata not found beside the checkout or its parents")


def _hausdorff(a, b):
    """Hausdorff distance of two closed polylines (densified to 0.05 mm)."""
    a, b = (mut.resample_loop(x, spacing=0.05e-3) for x in (a, b))
    return max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max())


def _window_xy(angle, n=1500):
    pol = [(0.095, -0.30), (0.195, -0.40), (0.195, 0.40), (0.095, 0.30)]
    v = np.array([[r * np.cos(t + angle), r * np.sin(t + angle)] for r, t in pol])
    return rounded_polygon(v, [0.006, 0.014, 0.014, 0.006], n)


@pytest.fixture(scope="module")
def disc_hub(tmp_path_factory):
    """A watertight 'hub': disc of R 0.25 m, 30 mm thick, front face at z = 0, centre bore and
    5 rounded-trapezoid windows cut through (manifold3d), written as millimetre STL."""
    import manifold3d as m3d
    import trimesh

    disc = m3d.Manifold.cylinder(0.03, 0.25, 0.25, 256).translate([0, 0, -0.03])
    bore = m3d.Manifold.cylinder(0.05, 0.03, 0.03, 64).translate([0, 0, -0.04])
    cut = bore
    truth = []
    for k in range(5):
        xy = _window_xy(2 * np.pi * k / 5)
        truth.append(np.c_[xy, np.zeros(len(xy))])
        prism = m3d.Manifold.extrude(m3d.CrossSection([xy.tolist()]), 0.05).translate([0, 0, -0.04])
        cut = cut + prism
    mesh = (disc - cut).to_mesh()
    tm = trimesh.Trimesh(mesh.vert_properties[:, :3] * 1000.0, mesh.tri_verts)
    path = tmp_path_factory.mktemp("hub") / "disc_hub_mm.stl"
    tm.export(path)
    return path, truth


def test_disc_hub_windows_match_ground_truth(disc_hub):
    path, truth = disc_hub
    lm = load_hub_mesh(path)
    assert lm.unit == "mm" and lm.watertight
    res = mut.extract_window_edges(lm.mesh, source=str(path), axis_M=[0, 0, 1],
                                   origin_M=[0, 0, 0], expected_windows=5)
    assert [o["kind"] for o in res.notes["not_windows"]] == ["centre bore"]
    matched = set()
    for w in res.windows:
        k = int(np.argmin([_hausdorff(w.p_HE, t) for t in truth]))
        matched.add(k)
        assert _hausdorff(w.p_HE, truth[k]) <= 0.2e-3
        # CCW seen from +Z_H, and equal arc length sampling (spacing ~2 mm)
        xy = w.p_HE[:, :2]
        area = 0.5 * np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - xy[:, 1] * np.roll(xy[:, 0], -1))
        assert area > 0
        d = np.linalg.norm(np.diff(np.vstack([w.p_HE, w.p_HE[:1]]), axis=0), axis=1)
        assert d.max() < 2.2e-3 and w.kind == "large"
    assert matched == set(range(5))


def test_disc_hub_axis_estimated(disc_hub):
    path, truth = disc_hub
    lm = load_hub_mesh(path)
    # no axis given: estimated from the disc's shape; the windows are still all found
    res = mut.extract_window_edges(lm.mesh, source=str(path))
    assert len(res.windows) == 5
    assert abs(res.X_MH[:3, 2] @ [0, 0, 1]) == pytest.approx(1.0, abs=1e-6)


def test_audibot_rim_front_side_from_its_barrel(extdata):
    """The low-poly game rim (tests/test_extract_real_wheels.py checks its windows): the front
    side is -Y of the file, decided by the cues (the barrel extends behind the face)."""
    lm = load_hub_mesh(extdata / AUDIBOT)
    assert lm.unit == "m" and not lm.watertight
    frame = mut.hub_frame_from_mesh(lm.mesh, source="audibot")
    assert frame.X_MH[:3, 2] @ [0, -1, 0] > 0.999
    assert frame.front.decided_by == "cues" and any("barrel" in e for e in frame.front.evidence)


def test_openings_no_burr_fits_are_refused_with_width_and_each_burrs_need(tmp_path):
    """8 mm slots: narrower than the 6 mm burr's 10 mm and the 12 mm burr's 16 mm (head + 2 x
    2 mm clearance); the refusal names every opening with its measured width and each need."""
    from hub_meshes import narrow_slot_disc_stl

    lm = load_hub_mesh(narrow_slot_disc_stl(tmp_path / "slots.stl"))
    with pytest.raises(InputError) as err:
        mut.extract_window_edges(lm.mesh, source="slots", front="+z")
    msg = str(err.value)
    assert msg.startswith("slots: no window found looking along the hub axis")
    assert msg.count("vent slot 8.") == 6 and "centre bore" in msg
    assert msg.count("the 6 mm burr needs 10.0 mm, the 12 mm burr needs 16.0 mm") == 6
    # a 12 mm slot is a window for the small burr (10 mm), not for the standard one (16 mm)
    lm = load_hub_mesh(narrow_slot_disc_stl(tmp_path / "s12.stl", slot_width=12e-3))
    res = mut.extract_window_edges(lm.mesh, source="s12", front="+z")
    assert len(res.windows) == 6 and all(11.5 < e["width_mm"] < 12.5 for e in res.notes["loops"])
    with pytest.raises(InputError, match="the 12 mm burr needs 16.0 mm"):
        mut.extract_window_edges(lm.mesh, source="s12", front="+z",
                                 search=OpeningSearch.of(burr_diameters=(12e-3,)))


def test_no_opening_and_bad_files(tmp_path):
    import trimesh

    box = trimesh.creation.box([0.4, 0.4, 0.05])
    with pytest.raises(InputError, match="no window found.*0 through-openings: none"):
        mut.extract_window_edges(box, source="box", axis_M=[0, 0, 1])
    bad = tmp_path / "x.step"
    bad.write_text("solid")
    with pytest.raises(InputError, match="a CAD solid"):
        load_hub_mesh(bad)
    with pytest.raises(FileNotFoundError):
        load_hub_mesh(tmp_path / "missing.stl")
    huge = tmp_path / "huge.stl"
    trimesh.creation.box([40.0, 40.0, 40.0]).export(huge)
    with pytest.raises(InputError, match="not a wheel's size"):
        load_hub_mesh(huge, unit="m")


def _bundled_hubs():
    try:
        from drakedeburr.resources import hub_names

        return hub_names()
    except FileNotFoundError:
        return []


@pytest.mark.parametrize("name", _bundled_hubs())
def test_bundled_hub_extraction_matches_ground_truth(name):
    """Every window of every generated hub is found; the fitted edge through the extracted
    points is within 0.2 mm (Hausdorff) of the generator's ground-truth loop."""
    hub_model = pytest.importorskip("drakedeburr.hub.model")
    from drakedeburr.path.edge_curve import fit_edge_curve

    hub = hub_model.load_hub(name)
    axis = None if name == "h5_split" else [0, 0, 1]  # one hub with the axis estimated
    res = mut.extract_window_edges(hub.trimesh, source=name, axis_M=axis,
                                   origin_M=None if axis is None else [0, 0, 0],
                                   expected_windows=len(hub.windows))
    for w in res.windows:
        c = fit_edge_curve(w.p_HE)
        p_H = c.position(np.linspace(0, 1, 4000, endpoint=False))
        p_M = p_H @ res.X_MH[:3, :3].T + res.X_MH[:3, 3]
        d = [_hausdorff(p_M, g.p_HE) for g in hub.windows]
        k = int(np.argmin(d))
        assert d[k] <= 0.2e-3, (name, w.index, d[k])
        assert w.kind == hub.windows[k].kind
