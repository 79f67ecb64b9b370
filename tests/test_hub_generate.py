import dataclasses

import numpy as np
import pytest

import drakedeburr.hub.generate as mut
from drakedeburr.errors import InputError
from drakedeburr.hub.catalogue import BUNDLED, DEFAULT_HUB
from drakedeburr.resources import hub_dir


def test_regeneration_is_byte_identical(tmp_path):
    name = DEFAULT_HUB
    res = mut.generate_hub(BUNDLED[name], tmp_path / name)
    committed = hub_dir(name)
    got = sorted(p.relative_to(res.dir).as_posix() for p in res.dir.rglob("*") if p.is_file())
    want = sorted(p.relative_to(committed).as_posix() for p in committed.rglob("*")
                  if p.is_file())
    assert got == want == list(res.files)
    for rel in got:
        assert (res.dir / rel).read_bytes() == (committed / rel).read_bytes(), rel


def test_window_outlines_of_a_custom_hub():
    spec = dataclasses.replace(BUNDLED["h6_curved"], name="h7", spoke_count=7,
                               spoke_width=0.024, spoke_width_outer=0.030)
    wins = mut.build_window_outlines(spec.validate())
    assert len(wins) == 7
    ang = [np.arctan2(*w.poly_mm.mean(axis=0)[::-1]) % (2 * np.pi) for w in wins]
    assert ang == sorted(ang)
    for w in wins:
        r = np.hypot(w.poly_mm[:, 0], w.poly_mm[:, 1]) * 1e-3
        assert r.min() >= spec.window_inner_radius - 5e-6  # chords of the inner arc
        assert r.max() <= spec.window_outer_radius + 1e-6
        seg = np.linalg.norm(np.roll(w.poly_mm, -1, axis=0) - w.poly_mm, axis=1)
        assert seg.max() <= mut.LINE_STEP_MM + 1e-9


def test_window_count_mismatch_is_reported(monkeypatch):
    import drakedeburr.hub.outline as outline

    spec = BUNDLED["h5_straight"]
    four = outline._spoke_polygons(spec)[:4]  # one spoke missing: two windows merge
    monkeypatch.setattr(outline, "_spoke_polygons", lambda s: four)
    with pytest.raises(InputError, match="4 openings in the window annulus, expected 5"):
        mut.build_window_outlines(spec)


def test_fillet_too_large_for_the_window_geometry():
    # validate() would refuse it; the geometric check must too
    spec = dataclasses.replace(BUNDLED["h5_split"], fillet_radius_small=0.022)
    with pytest.raises(InputError, match="'fillet_radius_small'"):
        mut.build_window_outlines(spec)


def test_npz_writer_is_deterministic(tmp_path):
    arrays = {"b": np.arange(5.0), "a": np.eye(3)}
    mut.write_npz(tmp_path / "x.npz", arrays)
    first = (tmp_path / "x.npz").read_bytes()
    mut.write_npz(tmp_path / "x.npz", dict(reversed(arrays.items())))
    assert (tmp_path / "x.npz").read_bytes() == first
    data = np.load(tmp_path / "x.npz")
    np.testing.assert_array_equal(data["a"], np.eye(3))
