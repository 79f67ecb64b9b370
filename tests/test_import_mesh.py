"""hub.import_mesh: mesh file -> hub model folder, checked against a bundled hub's ground truth.

The bundled h5_straight mesh is moved by a random rigid motion and written as a millimetre STL;
the import must find the same window edges (in the file's frame), a collision model that
covers the solid and leaves the openings free, and a folder the cell and the verifier load.
Collision pieces are re-checked here with their own half-space equations (scipy), the solid's
inside/outside with open3d's signed distance: independent of the import's own probes.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import drakedeburr.hub.import_mesh as mut
from drakedeburr.errors import InputError, NoCuttableWindow


def _rigid(rng) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    X = np.eye(4)
    X[:3, :3] = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
    X[:3, 3] = rng.uniform(-0.2, 0.2, 3)
    return X


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    import trimesh

    from drakedeburr.hub.model import load_hub

    truth = load_hub("h5_straight")
    X_MH = _rigid(np.random.default_rng(0))  # where the file puts the bundled hub frame
    V_M = truth.vertices_H @ X_MH[:3, :3].T + X_MH[:3, 3]
    root = tmp_path_factory.mktemp("import")
    stl = root / "wheel.stl"
    trimesh.Trimesh(V_M * 1e3, truth.faces, process=False).export(stl)  # millimetres
    labels = []
    res = mut.import_mesh(stl, root / "cache", progress=lambda d, n, lab: labels.append(lab))
    return {"res": res, "truth": truth, "X_MH_true": X_MH, "stl": stl, "cache": root / "cache",
            "labels": labels}


def _scene(V, F):
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)), o3d.core.Tensor(F.astype(np.uint32)))
    return scene


def _signed_distance(scene, q):
    import open3d as o3d

    return scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32))).numpy()


def _pieces(folder):
    from scipy.spatial import ConvexHull

    from drakedeburr.hub.model import read_obj

    return [ConvexHull(read_obj(p)[0]).equations for p in sorted((folder / "collision").glob(
        "piece_*.obj"))]


def _distance_to_pieces(folder, eqs, q):
    """(K,) exact distance of each point to the union of the collision pieces (0 inside one):
    open3d's distance to the hulls' triangles (scipy's hulls of the pieces' vertices), a reading
    independent of the importer's. The largest plane violation (:func:`_max_violation`) is only
    a lower bound of it: beside a thin slab's edge it read 0.24 mm where the piece was 2.67 mm
    away. ``eqs``: the pieces' plane equations (:func:`_pieces` of the folder)."""
    import open3d as o3d
    from scipy.spatial import ConvexHull

    from drakedeburr.hub.model import read_obj

    scene = o3d.t.geometry.RaycastingScene()
    for p in sorted((folder / "collision").glob("piece_*.obj")):
        V = read_obj(p)[0]
        scene.add_triangles(o3d.core.Tensor(V.astype(np.float32)),
                            o3d.core.Tensor(ConvexHull(V).simplices.astype(np.uint32)))
    d = scene.compute_distance(o3d.core.Tensor(q.astype(np.float32))).numpy().astype(float)
    d[_max_violation(eqs, q) <= 0] = 0.0
    return d


def _max_violation(eqs, q):
    """(K,) min over pieces of the largest plane violation: <= 0 inside some piece; for an
    outside point a lower bound of its distance to the nearest piece."""
    return np.min([np.max(q @ e[:, :3].T + e[:, 3], axis=1) for e in eqs], axis=0)


# ------------------------------------------------------------------------------- bad input
def _box_stl(path, extents, holes=False):
    import trimesh

    m = trimesh.creation.box(extents=extents)
    if holes:
        m = trimesh.Trimesh(m.vertices, m.faces[:-1], process=False)  # one triangle missing
    m.export(path)
    return path


@pytest.mark.parametrize(("content", "match"), [
    (b"", "empty|no triangles|cannot read"),
    (b"this is not a mesh\n", "cannot read|no triangles"),
])
def test_not_a_mesh_is_input_error(tmp_path, content, match):
    f = tmp_path / "broken.stl"
    f.write_bytes(content)
    with pytest.raises(InputError, match=match) as err:
        mut.import_mesh(f, tmp_path / "out")
    assert "broken.stl" in str(err.value)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_unsupported_and_missing_files(tmp_path):
    f = tmp_path / "wheel.step"
    f.write_text("ISO-10303-21;")
    with pytest.raises(InputError, match=r"wheel\.step: not a readable STEP file .*Line \d+"):
        mut.import_mesh(f, tmp_path / "out")  # a STEP file goes to drakedeburr.hub.cad
    with pytest.raises(FileNotFoundError, match="missing.stl"):
        mut.import_mesh(tmp_path / "missing.stl", tmp_path / "out")


def test_absurd_sizes_are_input_errors(tmp_path):
    # 1 m across the axis: a plausible file size (mesh_io accepts it) but no wheel hub
    big = _box_stl(tmp_path / "table.stl", (1.0, 1.0, 0.2))
    with pytest.raises(InputError, match=r"table\.stl: diameter across the hub axis 1000 mm"):
        mut.import_mesh(big, tmp_path / "out")
    tiny = _box_stl(tmp_path / "tiny.stl", (0.01, 0.01, 0.01))
    with pytest.raises(InputError, match=r"tiny\.stl.*not a wheel's size"):
        mut.import_mesh(tiny, tmp_path / "out")


@pytest.mark.parametrize("kw", [dict(front_reach=4e-3), dict(front_reach=0.0),
                                dict(front_band=-1e-3)])
def test_front_reach_options_checked(tmp_path, kw):
    """The front's near reach must be positive and at most the far one, the band not negative:
    refused before the file is read (nothing written)."""
    stl = _box_stl(tmp_path / "any.stl", (0.4, 0.4, 0.2))
    with pytest.raises(InputError, match="front_reach <= front_reach_far"):
        mut.import_mesh(stl, tmp_path / "out", options=mut.ImportOptions(**kw))
    assert not (tmp_path / "out").exists()


def test_no_windows_and_the_audibot_rim_refused_with_reasons(tmp_path, extdata):
    holed = _box_stl(tmp_path / "holed.stl", (0.4, 0.4, 0.1), holes=True)
    with pytest.raises(InputError, match=r"holed\.stl: no window found.*0 through-openings") as e:
        mut.import_mesh(holed, tmp_path / "out")
    assert not isinstance(e.value, NoCuttableWindow)  # no opening at all: not a hub (exit 2)
    disc = _box_stl(tmp_path / "disc.stl", (0.4, 0.4, 0.1))
    with pytest.raises(InputError, match=r"disc\.stl: no window found"):
        mut.import_mesh(disc, tmp_path / "out")
    # a readable hub whose openings no burr fits (8 mm slots): refused with every opening's
    # reason, not a bad model (tests/test_extract.py checks the reasons)
    from hub_meshes import narrow_slot_disc_stl

    slots = narrow_slot_disc_stl(tmp_path / "slots.stl")
    with pytest.raises(NoCuttableWindow, match=r"slots\.stl: no window found.*vent slot 8\.\d mm "
                                              r"wide") as e:
        mut.import_mesh(slots, tmp_path / "out", options=mut.ImportOptions(front="+z"))
    # openings, none a window: a result (exit 1 with a report), with every reason attached
    assert len(e.value.openings) == 7 and e.value.rejected == []
    assert sorted(o["kind"] for o in e.value.openings) == ["centre bore"] + ["too narrow"] * 6
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_the_audibot_wheel_dae_with_its_tyre_reads_as_its_rim(extdata):
    """The COLLADA wheel as the ROS description ships it (tyre + rim, 720 mm across): the
    tyre - the part lying wholly outside the rest - is dropped and said, and the rim gives the
    same windows, widths and openings as the rim alone (the derived STL, cut from the same
    file by hand)."""
    from drakedeburr.hub.extract import extract_window_edges
    from drakedeburr.hub.mesh_io import load_hub_mesh

    res = {}
    for name in ("audibot__wheel.dae", "audibot__wheel_rim_only_DERIVED_m.stl"):
        path = extdata / "wheel_models" / name
        mesh, note = mut._without_tyre(path, load_hub_mesh(path).mesh, None)
        res[name] = (extract_window_edges(mesh, source=name), note)
    (dae, note), (rim, none) = res["audibot__wheel.dae"], res[
        "audibot__wheel_rim_only_DERIVED_m.stl"]
    assert note.startswith("tyre dropped: 1 part(s)") and "720 mm" in note
    assert none is None
    assert len(dae.windows) == len(rim.windows) == 10
    assert dae.notes["not_windows"] == rim.notes["not_windows"] == []
    # radii within 2.5 mm: the hub centre is estimated on each file's own vertices (the
    # tyre's bead-seat fragments inside the rim stay, the low-poly rim has 10 sides)
    a, b = (v[0].notes["loops"] for v in res.values())
    np.testing.assert_allclose(sorted(e["width_mm"] for e in a),
                               sorted(e["width_mm"] for e in b), atol=0.3)
    np.testing.assert_allclose(sorted(np.hypot(*e["center_xy_mm"]) for e in a),
                               sorted(np.hypot(*e["center_xy_mm"]) for e in b), atol=2.5)


def test_a_tyre_is_dropped_only_when_it_rings_the_rest(tmp_path):
    """A 500 mm 'rim' (a tube) inside a 700-800 mm ring: the ring's faces go, exactly; the rim
    alone, or a 800 mm disc with no ring apart from it, is left as it is."""
    import trimesh

    rim = trimesh.creation.annulus(r_min=0.2, r_max=0.25, height=0.2)
    tyre = trimesh.creation.annulus(r_min=0.24, r_max=0.38, height=0.22)
    wheel = trimesh.util.concatenate([rim, tyre])
    kept, note = mut._without_tyre(tmp_path / "w.stl", wheel, (0.0, 0.0, 1.0))
    assert note is not None and "760 mm" in note
    assert len(kept.faces) == len(rim.faces)
    np.testing.assert_allclose(np.sort(kept.vertices, axis=0), np.sort(rim.vertices, axis=0))
    same, none = mut._without_tyre(tmp_path / "w.stl", rim, (0.0, 0.0, 1.0))
    assert same is rim and none is None
    disc = trimesh.creation.cylinder(radius=0.4, height=0.1)
    same, none = mut._without_tyre(tmp_path / "d.stl", disc, (0.0, 0.0, 1.0))
    assert same is disc and none is None
    # two parts, the outer one reaching in to 0.8 of the rest's radius: not a tyre around it
    wide = trimesh.util.concatenate([rim, trimesh.creation.annulus(r_min=0.2, r_max=0.38,
                                                                   height=0.05)])
    same, none = mut._without_tyre(tmp_path / "w2.stl", wide, (0.0, 0.0, 1.0))
    assert same is wide and none is None


def test_gltf_and_off_read_as_the_stl(tmp_path):
    """The same mesh written as glTF (binary) and OFF reads as the STL does (vertices to the
    float32 of glTF), unit detected alike; a STEP file is refused naming what to export."""
    import trimesh

    from drakedeburr.hub.mesh_io import load_hub_mesh

    box = trimesh.creation.box(extents=(400.0, 380.0, 120.0))  # millimetres
    for suffix in (".stl", ".glb", ".off"):
        box.export(tmp_path / f"hub{suffix}")
    ref = load_hub_mesh(tmp_path / "hub.stl")
    for suffix in (".glb", ".off"):
        lm = load_hub_mesh(tmp_path / f"hub{suffix}")
        assert lm.unit == ref.unit == "mm" and lm.watertight
        np.testing.assert_allclose(lm.mesh.bounds, ref.mesh.bounds, atol=1e-7)
    step = tmp_path / "hub.step"
    step.write_text("ISO-10303-21;")
    with pytest.raises(InputError, match=r"hub\.step: a CAD solid \(B-rep\), not a triangle mesh: "
                                         r"read it with drakedeburr\.hub\.cad"):
        load_hub_mesh(step)
    native = tmp_path / "hub.sldprt"
    native.write_text("x")
    with pytest.raises(InputError, match=r"hub\.sldprt: unsupported mesh type '\.sldprt' \(a "
                                         r"native CAD file; export STEP or IGES"):
        load_hub_mesh(native)
    gltf = tmp_path / "hub.gltf"
    gltf.write_text("{}")
    with pytest.raises(InputError, match=r"hub\.gltf: .*separate buffer files.*\.glb"):
        load_hub_mesh(gltf)


def test_a_collada_file_is_read_in_the_unit_it_states(tmp_path):
    """COLLADA states its unit (<unit meter=...>; trimesh keeps it as metadata only): a file
    in millimetres is read as such even where the size rule would call it metres (a 2 mm
    'wheel' here is refused as too small, not scaled up), metres likewise, and a file in
    inches is refused naming the unit - never read as millimetres by size."""
    import trimesh

    from drakedeburr.hub.mesh_io import load_hub_mesh

    box = trimesh.creation.box(extents=(400.0, 380.0, 120.0))
    box.export(tmp_path / "plain.dae")
    text = (tmp_path / "plain.dae").read_text()

    def stated(name: str, meter: str, scale: float = 1.0) -> Path:
        b = box.copy()
        b.apply_scale(scale)
        b.export(tmp_path / "tmp.dae")
        t = (tmp_path / "tmp.dae").read_text().replace(
            "<up_axis>", f'<unit name="{name}" meter="{meter}"/>\n    <up_axis>', 1)
        out = tmp_path / f"{name}_{scale:g}.dae"
        out.write_text(t)
        return out

    assert "<unit" not in text  # trimesh writes none: the size rule reads it (mm)
    assert load_hub_mesh(tmp_path / "plain.dae").unit == "mm"
    lm = load_hub_mesh(stated("millimeter", "0.001"))
    assert lm.unit == "mm"
    np.testing.assert_allclose(lm.mesh.extents, [0.4, 0.38, 0.12], rtol=1e-9)
    with pytest.raises(InputError, match=r"not a wheel's size"):
        load_hub_mesh(stated("millimeter", "0.001", scale=0.005))  # 2 mm stated: too small
    assert load_hub_mesh(stated("meter", "1", scale=1e-3)).unit == "m"
    with pytest.raises(InputError, match=r"inch_1\.dae: the file states its unit as 0\.0254 m"):
        load_hub_mesh(stated("inch", "0.0254"))


# ------------------------------------------------------------------------------- a real hub
def test_frame_and_edges_match_the_bundled_hub(imported):
    from scipy.spatial.distance import directed_hausdorff

    res, truth, X_true = imported["res"], imported["truth"], imported["X_MH_true"]
    assert res.window_count == 5 and not res.cached
    # the hub axis and the origin (on the axis at the centre's front face) are recovered
    angle = np.degrees(np.arccos(np.clip(res.X_MH[:3, 2] @ X_true[:3, 2], -1, 1)))
    assert angle < 0.2
    assert np.linalg.norm(res.X_MH[:3, 3] - X_true[:3, 3]) < 0.5e-3
    from drakedeburr.hub.model import load_hub

    hub = load_hub(res.dir)
    assert hub.spec is None and len(hub.windows) == 5
    R = X_true[:3, :3].T @ res.X_MH[:3, :3]  # imported H axes in the bundled H
    for w in hub.windows:
        p_M = w.p_HE @ res.X_MH[:3, :3].T + res.X_MH[:3, 3]
        p_Hb = (p_M - X_true[:3, 3]) @ X_true[:3, :3]  # in the bundled hub frame
        k = int(np.argmin([np.linalg.norm(t.p_HE.mean(0) - p_Hb.mean(0)) for t in truth.windows]))
        p_true = truth.windows[k].p_HE
        hd = max(directed_hausdorff(p_Hb, p_true)[0], directed_hausdorff(p_true, p_Hb)[0])
        assert hd < 0.5e-3, f"window {w.index}: Hausdorff {hd * 1e3:.3f} mm"
        # normals and tangents from the mesh agree with the analytic ones
        from scipy.spatial import cKDTree

        j = cKDTree(p_true).query(p_Hb)[1]
        for ours, ref, tol in ((w.n_wall_H, truth.windows[k].n_wall_H, 3.0),
                               (w.n_face_H, truth.windows[k].n_face_H, 3.0),
                               (w.t_H, truth.windows[k].t_H, 5.0)):
            err = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", ours @ R.T, ref[j]), -1, 1)))
            assert np.median(err) < 1.0 and np.percentile(err, 95) < tol, (
                f"window {w.index}: normal error median {np.median(err):.2f} deg")


def test_collision_pieces_cover_the_solid_and_leave_the_openings_free(imported):
    res, truth, X_true = imported["res"], imported["truth"], imported["X_MH_true"]
    eqs = _pieces(res.dir)
    assert len(eqs) == res.piece_count > 5
    X_HbH = np.linalg.inv(X_true) @ res.X_MH  # imported H in the bundled H
    X_HHb = np.linalg.inv(X_HbH)
    scene = _scene(truth.vertices_H, truth.faces)
    rng = np.random.default_rng(0)
    lo, hi = truth.vertices_H.min(0), truth.vertices_H.max(0)
    q = rng.uniform(lo, hi, (60000, 3))
    d = _signed_distance(scene, q)
    deep = q[d < -0.7e-3]  # deeper than the simplification tolerance (0.5 mm) + float32 slack
    assert len(deep) > 2000
    viol = _max_violation(eqs, deep @ X_HHb[:3, :3].T + X_HHb[:3, 3])
    assert np.all(viol <= 1e-7), f"{np.sum(viol > 1e-7)} solid points outside every piece"
    # probes 2.5 mm into each window (true wall normal) through the face thickness
    probes = []
    for w in truth.windows:
        for depth in np.linspace(0.5e-3, 19.5e-3, 6):
            probes.append(w.p_HE[::3] + 2.5e-3 * w.n_wall_H[::3] - [0, 0, depth])
    probes = np.concatenate(probes)
    probes = probes[_signed_distance(scene, probes) > 2.0e-3]  # really in the opening
    assert len(probes) > 2000
    q_open = probes @ X_HHb[:3, :3].T + X_HHb[:3, 3]
    gap = _distance_to_pieces(res.dir, eqs, q_open)
    assert np.all(gap >= _max_violation(eqs, q_open) - 1e-7)  # the two readings agree
    assert gap.min() >= 1.0e-3, f"a piece comes {gap.min() * 1e3:.2f} mm near an opening probe"
    # pieces stand at most ~3 mm proud of the surface seen from the front (where the tool
    # works): points above it along its normal are outside every piece
    foot, n = _front_surface(truth, scene, 5e-3)
    # (the import guarantees 3 mm at its own 4 mm probe grid; between its probes a piece may
    # stand a little higher: on this independent 5 mm grid <= 0.1 % at 3.5 mm, none at 5 mm)
    for h, share in ((3.5e-3, 1e-3), (5.0e-3, 0.0)):
        above = foot + h * n
        above = above[_signed_distance(scene, above) > h - 0.5e-3]
        assert len(above) > 3000
        gap = _max_violation(eqs, above @ X_HHb[:3, :3].T + X_HHb[:3, 3])
        assert np.mean(gap <= 0) <= share, (
            f"{np.sum(gap <= 0)} points {h * 1e3} mm above the front inside a piece")
    _front_near_windows_held(truth, eqs, scene, X_HHb)
    summ = json.loads((res.dir / "summary.json").read_text())
    assert summ["collision"]["max_window_intrusion_mm"] <= 1.0
    assert summ["collision"]["front_probes_inside_pieces"] == 0
    assert (summ["collision"]["front_reach_allowed_mm"],
            summ["collision"]["front_reach_far_allowed_mm"],
            summ["collision"]["front_band_mm"]) == (1.0, 3.0, 15.0)
    assert summ["import"]["sha256"] == res.sha256


def _front_surface(truth, scene, spacing):
    """The true front surface seen along -Z_H on a plan-view grid of ``spacing`` [m]: the ray
    hits (K, 3) and the facet normals there, turned to +Z_H (K, 3)."""
    import open3d as o3d

    g = np.arange(-0.24, 0.24, spacing)
    gx, gy = np.meshgrid(g, g)
    rays = np.zeros((gx.size, 6), np.float32)
    rays[:, 0], rays[:, 1], rays[:, 2], rays[:, 5] = gx.ravel(), gy.ravel(), 1.0, -1.0
    ans = scene.cast_rays(o3d.core.Tensor(rays))
    t = ans["t_hit"].numpy()
    hit = np.isfinite(t)
    n = truth.trimesh.face_normals[ans["primitive_ids"].numpy()[hit].astype(np.int64)]
    n[n[:, 2] < 0] *= -1
    return rays[hit, :3] - np.c_[np.zeros((hit.sum(), 2)), t[hit]], n


def _front_near_windows_held(truth, eqs, scene, X_HHb):
    """Near the windows, where the burr's head and shank are low over the face (the shank ~2 mm
    above it at the edge), the pieces stand at most ~1 mm proud of the front
    (``ImportOptions.front_reach`` within ``front_band``): on an independent 2.5 mm grid,
    points 1.5 mm above the front within 12 mm (plan view) of a true window edge are outside
    every piece (measured: 0 of 3872). With the former 3 mm everywhere 8 of them were inside
    one, and on an unseen hub a CoACD hull stood 2.5 mm proud beside a window, which
    could then not be planned."""
    from scipy.spatial import cKDTree

    foot, n = _front_surface(truth, scene, 2.5e-3)
    edge = cKDTree(np.concatenate([w.p_HE[:, :2] for w in truth.windows]))
    d_edge = edge.query(foot[:, :2])[0]
    above = foot + 1.5e-3 * n
    sel = (d_edge <= 12e-3) & (_signed_distance(scene, above) > 1.0e-3)
    assert sel.sum() > 3000
    gap = _max_violation(eqs, above[sel] @ X_HHb[:3, :3].T + X_HHb[:3, 3])
    assert np.all(gap > 0), (f"{np.sum(gap <= 0)} points 1.5 mm above the front within 12 mm "
                             f"of a window inside a piece")


def test_folder_loads_in_the_cell_and_is_cached(imported):
    from drakedeburr.cell.station import load_cell

    res = imported["res"]
    cell = load_cell("tool_in_hand", res.dir)
    assert cell.hub_sdf == res.dir / "hub.sdf"
    assert len(cell.hub_ids) == res.piece_count
    assert "collision pieces (CoACD)" in imported["labels"]
    again = mut.import_mesh(imported["stl"], imported["cache"])
    assert again.cached and again.dir == res.dir and again.piece_count == res.piece_count
    assert [p.name for p in imported["cache"].iterdir()] == [res.dir.name]  # no temp left


def test_cli_hub_import_and_verify_a_mesh(imported, tmp_path, capsys):
    from drakedeburr.cli import main

    stl, cache = imported["stl"], imported["cache"]
    assert main(["-q", "hub", "import", str(stl), "--out", str(cache), "--no-progress"]) == 0
    assert "cached" in capsys.readouterr().out
    assert main(["-q", "hub", "info", str(imported["res"].dir)]) == 0
    assert main(["-q", "hub", "list", "--dir", str(cache)]) == 0
    assert "5 windows (5 large, 0 small)" in capsys.readouterr().out
    # plan (one window: a whole hub is too slow for a unit test) and verify the imported mesh
    f = tmp_path / "report.json"
    code = main(["-q", "verify", str(stl), "--hub-cache", str(cache), "--windows", "0",
                 "--quick", "--no-replay", "--json", str(f)])
    doc = json.loads(f.read_text())
    assert code == (0 if doc["passed"] else 1)
    assert doc["plan"]["windows"] == [0]
    assert str(imported["res"].dir) in doc["plan"]["hub"]


def test_front_openings_and_input_view(imported, capsys):
    """The summary states the front side with its evidence and every opening that is not a
    window; ``hub info --json`` gives the edges in the STL's own coordinates and unit (mm)."""
    from scipy.spatial import cKDTree

    from drakedeburr.cli import main

    res, truth, X_true = imported["res"], imported["truth"], imported["X_MH_true"]
    imp = res.summary["import"]
    assert imp["front"]["decided_by"] == "cues" and len(imp["front"]["evidence"]) >= 2
    kinds = sorted(o["kind"] for o in imp["not_windows"])
    assert kinds == ["centre bore"] + ["lug hole"] * 5
    assert imp["min_window_width_mm"] == pytest.approx(10.0)  # the 6 mm burr's need
    assert imp["burrs_mm"] == [6.0, 12.0]  # smallest first (openings.judged_burrs), as CAD
    assert main(["-q", "hub", "info", str(res.dir), "--json"]) == 0
    view = json.loads(capsys.readouterr().out)["input"]
    assert view["unit"] == "mm" and len(view["edges"]) == 5
    np.testing.assert_allclose(view["hub_axis"]["direction"], X_true[:3, 2], atol=1e-4)
    truth_M = np.concatenate([w.p_HE @ X_true[:3, :3].T + X_true[:3, 3]
                              for w in truth.windows]) * 1e3  # the STL's mm coordinates
    pts = np.concatenate([np.asarray(e["points"]) for e in view["edges"]])
    assert cKDTree(truth_M).query(pts)[0].max() < 0.5  # mm


def test_front_probes_near_the_windows_stand_lower():
    """The importer's front probes stand ``front_reach`` above their surface point within
    ``front_band`` (plan view) of a wall line and ``front_reach_far`` further out (or with no
    walls), each clear of the mesh by more than half its height and the simplification + 0.1 mm
    (a probe inside the simplified solid could never be cut free)."""
    import open3d as o3d
    import trimesh
    from scipy.spatial import cKDTree

    from drakedeburr.hub.import_collision import front_probes
    from drakedeburr.hub.model import load_hub

    truth = load_hub("h5_straight")
    V, F = truth.vertices_H, truth.faces
    scene = _scene(V, F)
    normals = trimesh.Trimesh(V, F, process=False).face_normals
    walls = np.concatenate([w.p_HE[:, :2] for w in truth.windows])
    o = mut.ImportOptions()
    q, cut = front_probes(scene, normals, o, closed=True, walls_xy=walls)
    height = np.linalg.norm(q - cut[:, :3], axis=1)
    near = cKDTree(walls).query(cut[:, :2])[0] <= o.front_band
    assert 1000 < near.sum() < len(q) - 1000
    np.testing.assert_allclose(height[near], o.front_reach, atol=1e-9)
    np.testing.assert_allclose(height[~near], o.front_reach_far, atol=1e-9)
    d = scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32))).numpy()
    assert np.all(d > np.maximum(0.5 * height, o.simplify_tolerance + 0.1e-3) - 1e-7)
    q_far, cut_far = front_probes(scene, normals, o, closed=True)  # no walls
    np.testing.assert_allclose(np.linalg.norm(q_far - cut_far[:, :3], axis=1),
                               o.front_reach_far, atol=1e-9)
