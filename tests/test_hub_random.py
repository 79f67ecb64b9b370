"""hub.randomhub: the seeded random catalogue (specs, determinism, ranges, files, CLI)."""

import collections
import math

import numpy as np
import pytest

import drakedeburr.hub.randomhub as mut
from drakedeburr.hub.spec import spec_to_yaml


def test_defaults_are_the_cells_burr_and_clearance():
    from drakedeburr.cell.tools import BURR
    from drakedeburr.config import Tolerances
    from drakedeburr.hub import openings

    assert mut.DEFAULT_BURR_DIAMETER == BURR.head_diameter == openings.DEFAULT_BURR_DIAMETER
    assert openings.DEFAULT_CLEARANCE == Tolerances().min_clearance
    # the tool library's heads, and the width each needs: head + 2 x clearance (issue 42)
    from drakedeburr.cell.tools import BURR_HEADS

    assert openings.DEFAULT_BURR_DIAMETERS == tuple(
        sorted((b.head_diameter for b in BURR_HEADS.values()), reverse=True))
    assert openings.min_window_width(12e-3, 2e-3) == pytest.approx(16e-3)
    assert openings.min_window_width((12e-3, 6e-3), 2e-3) == pytest.approx(10e-3)
    assert openings.min_window_width(4e-3, 5e-3) == pytest.approx(14e-3)


def test_same_seed_same_spec_other_seed_other_spec():
    a, b = mut.random_spec(5, 3), mut.random_spec(5, 3)
    assert a == b and spec_to_yaml(a) == spec_to_yaml(b)
    assert a.name == "r5_003"
    assert mut.random_spec(6, 3) != a and mut.random_spec(5, 4) != a
    with pytest.raises(Exception, match="must be >= 0"):
        mut.random_spec(-1, 0)


@pytest.fixture(scope="module")
def specs():
    return [mut.random_spec(101, i) for i in range(24)]


def test_catalogue_spans_the_plants_range(specs):
    """Every spec is valid, sized like a passenger-car wheel (docs/hub.md, Random catalogue),
    and the catalogue covers the styles and features issue 16 asks for."""
    from drakedeburr.cell.tools import BURR

    bound = mut.MIN_WIDTH_FACTOR * BURR.head_diameter
    styles = collections.Counter()
    for s in specs:
        s.validate()
        code = s.rim_barrel_diameter / 0.0254
        assert code == pytest.approx(round(code), abs=0.01) and 15 <= round(code) <= 20
        assert 4 <= s.spoke_count <= 10
        assert 0.0 <= s.dish_depth <= 0.090 + 1e-9
        assert 0.098 - 1e-9 <= s.bolt_circle_diameter <= 0.1397 + 1e-9
        assert 0.054 <= s.center_bore_diameter <= 0.073
        assert s.bolt_count in (4, 5, 6)
        widths = mut.spec_window_widths(s)
        assert len(widths) == s.window_count
        assert min(w for _, w in widths) >= bound - 1e-9, s.name
        style = "twisted" if s.spoke_twist and s.spoke_style == "straight" else s.spoke_style
        styles[style] += 1
    assert set(styles) == {"straight", "curved", "twisted", "split", "twin"}, styles
    assert any(s.edge_round_radius > 0 for s in specs)
    assert any(s.wall_draft > 0 for s in specs)
    assert any(s.face_rise_angle > 0 for s in specs)
    assert any(s.bolt_seat_diameter > 0 for s in specs) and any(
        s.bolt_seat_diameter == 0 for s in specs)
    assert max(s.dish_depth for s in specs) > 0.06 and min(s.dish_depth for s in specs) < 0.02


def test_repair_makes_narrow_windows_wide_enough():
    """A spec whose spokes leave too little room is repaired by narrower spokes (or refused),
    deterministically."""
    s = mut.random_spec(7, 2)
    import dataclasses

    fat = dataclasses.replace(s, spoke_width=s.spoke_width * 1.6,
                              spoke_width_outer=s.spoke_width_outer * 1.6)
    bound = 30e-3
    fixed, why = mut._checked(fat, bound)
    if fixed is None:
        assert "narrower" in why or "field" in why
    else:
        assert min(w for _, w in mut.spec_window_widths(fixed)) >= bound
        assert fixed.spoke_width < fat.spoke_width
        again, _ = mut._checked(fat, bound)
        assert again == fixed


def test_catalogue_files_are_reproducible(tmp_path):
    """Same seed -> byte-identical hub.yaml, edges.npz and exported STL; the STL is the hub
    mesh in the stated unit and pose."""
    import json

    from drakedeburr.hub.model import load_hub, read_obj

    first = mut.random_catalogue(42, 1, tmp_path / "a", start=1, with_collision=False)
    second = mut.random_catalogue(42, 1, tmp_path / "b", start=1, with_collision=False)
    d1, d2 = first[0].dir, second[0].dir
    assert d1.name == "r42_001"
    exp = json.loads((d1 / "export.json").read_text())
    for f in ("hub.yaml", "edges.npz", "summary.json", "hub.obj", exp["file"]):
        assert (d1 / f).read_bytes() == (d2 / f).read_bytes(), f
    hub = load_hub(d1)
    assert len(hub.windows) == hub.spec.window_count
    # the STL: binary, the hub's triangles moved by X_MH and scaled to the unit
    import trimesh

    stl = trimesh.load(d1 / exp["file"], process=False)
    V, F = read_obj(d1 / "hub.obj")
    X = np.asarray(exp["X_MH_m"])
    scale = 1e3 if exp["unit"] == "mm" else 1.0
    want = (V[F] @ X[:3, :3].T + X[:3, 3]) * scale
    got = np.asarray(stl.vertices)[np.asarray(stl.faces)]
    np.testing.assert_allclose(got, want, atol=1e-5 * scale)
    axis = {"+z": [0, 0, 1], "-z": [0, 0, -1], "+y": [0, 1, 0], "-y": [0, -1, 0],
            "+x": [1, 0, 0]}[exp["front"]]
    np.testing.assert_allclose(X[:3, 2], axis)


def test_cli_hub_random(tmp_path, capsys):
    from drakedeburr.cli import main

    assert main(["-q", "hub", "random", "--seed", "3", "--count", "1", "--no-collision",
                 "--no-progress", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "r3_000:" in out and (tmp_path / "r3_000" / "hub.yaml").is_file()
    assert main(["-q", "hub", "random", "--seed", "3", "--count", "0", "-o",
                 str(tmp_path)]) == 2


def test_units_and_poses_of_the_exports_vary():
    """Across a catalogue the exports come in mm and m and in several CAD poses."""
    units, poses = set(), set()
    for i in range(12):
        unit, X, front = mut.export_choice(9, i)
        units.add(unit)
        poses.add(front)
        np.testing.assert_allclose(X[:3, :3] @ X[:3, :3].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(X[:3, :3]) == pytest.approx(1.0)
    assert units == {"mm", "m"} and len(poses) >= 3
    assert math.isclose(mut.MIN_WIDTH_FACTOR, 2.5)
