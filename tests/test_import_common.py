"""hub.import_common: the steps the mesh and the CAD import share - which burrs an opening
is judged by (against the cell's tool library), the refusal text (against each burr's need
computed here), the cache folder (the same file and options: the same folder, another
version: another) and the wheel-size check."""

from __future__ import annotations

import re

import numpy as np
import pytest

import drakedeburr.hub.import_common as mut
from drakedeburr.errors import InputError
from drakedeburr.hub.import_mesh import ImportOptions


def test_the_tool_library_judges_an_opening_smallest_burr_first():
    from drakedeburr.cell.tools import BURR_HEADS

    heads = sorted(h.head_diameter for h in BURR_HEADS.values())
    assert mut.judged_burrs() == pytest.approx(tuple(heads))
    assert mut.judged_burrs(16e-3) == (16e-3,)  # a burr of the caller's alone
    assert mut.judged_burrs(16e-3, (20e-3, 8e-3)) == (8e-3, 20e-3)


def test_a_refusal_names_the_width_and_each_burrs_need():
    burrs, clearance = (6e-3, 12e-3), 2e-3
    text = mut.narrow_reason(8.44e-3, burrs, clearance, 10e-3, "vent slot")
    assert text.startswith("vent slot 8.4 mm wide")
    needs = {float(b): float(n) for b, n in re.findall(r"the (\d+) mm burr needs ([\d.]+) mm",
                                                      text)}
    assert needs == {b * 1e3: pytest.approx((b + 2 * clearance) * 1e3) for b in burrs}
    assert "asked for" not in text
    wider = mut.narrow_reason(12e-3, burrs, clearance, 30e-3)
    assert wider.endswith("the narrowest window asked for is 30.0 mm")


def test_cache_slot_same_file_same_folder(tmp_path):
    f = tmp_path / "my wheel!.stl"
    f.write_bytes(b"solid x\nendsolid x\n")
    a = mut.cache_slot(f, tmp_path / "out", ImportOptions(), 0.0, version=1)
    b = mut.cache_slot(f, tmp_path / "out", ImportOptions(), 0.0, version=1)
    c = mut.cache_slot(f, tmp_path / "out", ImportOptions(), 0.0, version=2)
    d = mut.cache_slot(f, tmp_path / "out", ImportOptions(front="+z"), 0.0, version=1)
    import hashlib

    assert a[0] == hashlib.sha256(f.read_bytes()).hexdigest()
    assert a[:4] == b[:4] and a[4] is None  # nothing written yet: no cached hub
    assert len({a[1], c[1], d[1]}) == 3
    assert a[2] == "my_wheel" and a[3] == tmp_path / "out" / f"my_wheel_{a[1][:12]}"


def test_wheel_size_is_checked_across_the_axis():
    import trimesh

    disc = trimesh.creation.cylinder(radius=0.2, height=0.05)  # 400 mm across +Z
    assert mut.wheel_diameter("disc", disc, (0, 0, 1), "m") == pytest.approx(0.4, abs=2e-3)
    with pytest.raises(InputError, match=r"small: diameter across the hub axis 40 mm"):
        mut.wheel_diameter("small", disc.apply_scale(0.1), (0, 0, 1), "m")
    scene = mut.ray_scene(np.asarray(disc.vertices), np.asarray(disc.faces))
    # the front face of the disc, now 5 mm thick and 40 mm across: z = +2.5 mm
    assert mut.front_origin_offset(scene, 0.015, 0.1) == pytest.approx(2.5e-3, abs=1e-6)


def test_import_options_have_one_home_and_every_field_keys_the_cache():
    """ImportOptions / IMPORT_VERSION live in hub.import_options (import_mesh re-exports the
    same objects), and changing any one option changes the cache key (a stale hub folder is
    never reused for other settings)."""
    import dataclasses

    import drakedeburr.hub.import_mesh as im
    import drakedeburr.hub.import_options as io

    assert im.ImportOptions is io.ImportOptions and im.IMPORT_VERSION == io.IMPORT_VERSION
    base = io.ImportOptions()
    key = mut.cache_key("0" * 64, base, version=io.IMPORT_VERSION)
    assert key != mut.cache_key("0" * 64, base, version=io.IMPORT_VERSION + 1)
    for f in dataclasses.fields(io.ImportOptions):
        v = getattr(base, f.name)
        if v is None:
            other = (0.0, 0.0, 1.0) if f.name == "axis_M" else 1e-3
        elif isinstance(v, str):
            other = v + "x"
        elif isinstance(v, bool):
            other = not v
        elif isinstance(v, int):
            other = v + 1
        elif isinstance(v, float):
            other = v * 1.5 + 1e-4
        else:
            other = (1e-3,)
        changed = dataclasses.replace(base, **{f.name: other})
        assert mut.cache_key("0" * 64, changed, version=io.IMPORT_VERSION) != key, f.name
