import json

import numpy as np
import pytest
from scipy.spatial.distance import pdist

import drakedeburr.path.metrics as mut
from drakedeburr.path.edge_curve import fit_edge_curve
from drakedeburr.path.synthetic import hub_like_window


def test_cv_and_segment_figures_on_square_points_of_circle():
    R = 0.05
    th = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    c = fit_edge_curve(np.c_[R * np.cos(th), R * np.sin(th), np.zeros(400)])
    u = np.array([0.0, 0.25, 0.5, 0.75])
    m = mut.cl_metrics(c, u)
    assert m["count"] == 4
    assert m["cv"] == pytest.approx(0.0, abs=1e-9)
    assert m["max_chord_length_m"] == pytest.approx(R * np.sqrt(2), rel=1e-6)
    assert m["max_chord_height_m"] == pytest.approx(R * (1 - np.sqrt(0.5)), rel=1e-6)
    # all pairs: four sides R sqrt2 and two diagonals 2R
    d = np.r_[[R * np.sqrt(2)] * 4, [2 * R] * 2]
    assert m["cv_pairwise"] == pytest.approx(d.std() / d.mean(), rel=1e-6)
    seg = mut.segment_figures(c, np.array([0.0, 0.1, 0.5]))
    np.testing.assert_allclose(seg["arc"], 2 * np.pi * R * np.array([0.1, 0.4, 0.5]), rtol=1e-6)


def test_coefficient_of_variation():
    x = np.random.default_rng(0).uniform(1, 2, 100)
    assert mut.coefficient_of_variation(x) == pytest.approx(np.std(x) / np.mean(x))
    assert mut.coefficient_of_variation(pdist(np.eye(3))) == pytest.approx(0.0)




def test_cl_table_library_and_format():
    from drakedeburr.hub.types import WindowEdge
    from drakedeburr.path.table import cl_table, format_table

    wins = [WindowEdge(0, "small", hub_like_window("small", 63))]
    t = cl_table(wins, methods=["isoparametric", "adaptive"])
    assert [w["index"] for w in t["windows"]] == [0]
    e = t["windows"][0]["methods"]
    assert set(e) == {"isoparametric", "adaptive"}
    for m in e.values():
        assert {"count", "cv", "max_chord_height_m"} <= set(m)
        assert m["max_chord_height_m"] <= 0.12e-3
    json.dumps(t)
    assert "count adaptive" in format_table(t)


def test_cli_cl_on_mesh_writes_json(tmp_path):
    import manifold3d as m3d
    import trimesh

    from drakedeburr.cli import main
    from drakedeburr.path.synthetic import rounded_polygon

    disc = m3d.Manifold.cylinder(0.02, 0.22, 0.22, 128).translate([0, 0, -0.02])
    v = np.array([[0.09, -0.03], [0.18, -0.06], [0.18, 0.06], [0.09, 0.03]])
    xy = rounded_polygon(v, 0.008, 400)
    hole = m3d.Manifold.extrude(m3d.CrossSection([xy.tolist()]), 0.04).translate([0, 0, -0.03])
    mesh = (disc - hole).to_mesh()
    path = tmp_path / "one_window.stl"
    trimesh.Trimesh(mesh.vert_properties[:, :3], mesh.tri_verts).export(path)
    out = tmp_path / "t.json"
    rc = main(["cl", str(path), "--method", "isoparametric", "--method", "equal_chord_height",
               "--json", str(out)])
    assert rc == 0
    t = json.loads(out.read_text())
    assert len(t["windows"]) == 1
    assert t["windows"][0]["methods"]["isoparametric"]["max_chord_height_m"] <= 0.12e-3
    assert main(["cl", str(path), "--method", "nope"]) == 2
    assert main(["cl", str(tmp_path / "missing.stl")]) == 2


def _dense_closed(p, step):
    """Points every ~``step`` along the closed polyline p (an independent reading)."""
    q = np.vstack([p, p[:1]])
    out = [np.linspace(a, b, max(2, int(np.ceil(np.linalg.norm(b - a) / step)) + 1))[:-1]
           for a, b in zip(q[:-1], q[1:], strict=True)]
    return np.vstack(out)


def test_chord_edge_deviation_square_chords_of_circle():
    """Four CL points on a circle: the chords' deviation from the (400-gon) edge is the square's
    sagitta R (1 - sqrt(1/2)), less the 400-gon's own sagitta at most."""
    R = 0.05
    th = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    c = fit_edge_curve(np.c_[R * np.cos(th), R * np.sin(th), np.zeros(400)])
    d = mut.chord_edge_deviation(c, np.array([0.0, 0.25, 0.5, 0.75]))
    assert d == pytest.approx(R * (1 - np.sqrt(0.5)), abs=R * (1 - np.cos(np.pi / 400)) + 1e-9)


def test_cl_table_chords_vs_edge_on_a_polygon_loop():
    """A 12-gon window (30 mm facets) sampled every 2 mm, as `cl` reads a low-poly mesh: the
    chords are planned against the fit, which stands off the polygon; the table's 'chords vs
    edge' is the two-sided distance of the CL polyline from the loop's polyline (checked against a
    dense independent sampling), at least the points' chord height, and a note says
    when it passes delta_max."""
    from scipy.spatial import cKDTree

    from drakedeburr.hub.extract import resample_loop
    from drakedeburr.hub.types import WindowEdge
    from drakedeburr.path.cl_planning import plan_cl
    from drakedeburr.path.table import cl_table, format_table
    from drakedeburr.path.window_fit import fit_window_edge

    a = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    poly = np.c_[0.058 * np.cos(a), 0.058 * np.sin(a), 0.004 * np.sin(3 * a)]
    p = resample_loop(poly, 2e-3)
    t = cl_table([WindowEdge(0, "large", p)], methods=["isoparametric", "adaptive"])
    curve = fit_window_edge(p, chord_tolerance=0.12e-3, name="polygon")
    edge = _dense_closed(p, 2e-6)  # the loop the table is given (the polyline of its points)
    for name, m in t["windows"][0]["methods"].items():
        cl = curve.position(plan_cl(curve, name, window_index=0, kind="large").u)
        chords = _dense_closed(cl, 2e-6)
        truth = max(cKDTree(chords).query(edge)[0].max(), cKDTree(edge).query(chords)[0].max())
        assert m["chord_edge_deviation_m"] == pytest.approx(truth, abs=3e-6)
        assert m["chord_edge_deviation_m"] >= m["max_chord_height_points_m"] - 1e-9
    text = format_table(t)
    assert "chords vs edge [mm] adaptive" in text and "chord height vs fit [mm]" in text
    worst = max(m["chord_edge_deviation_m"] for m in t["windows"][0]["methods"].values()
                if m["max_chord_height_m"] <= 0.12e-3)
    assert ("note: chords vs edge" in text) == (worst > 0.12e-3)
