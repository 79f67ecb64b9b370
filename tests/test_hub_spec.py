import dataclasses
import math

import numpy as np
import pytest
import yaml

import drakedeburr.hub.spec as mut
from drakedeburr.errors import InputError
from drakedeburr.hub.catalogue import BUNDLED
from drakedeburr.resources import hubs_dir


@pytest.mark.parametrize("name", sorted(BUNDLED))
def test_yaml_round_trip_and_committed_yaml_matches_catalogue(name):
    spec = BUNDLED[name]
    text = mut.spec_to_yaml(spec)
    assert mut.spec_from_mapping(yaml.safe_load(text), "mem") == spec
    assert mut.load_spec(hubs_dir() / name) == spec
    assert "_mm" in text and "spoke_count: " in text


def test_round_trip_of_a_modified_spec():
    spec = dataclasses.replace(BUNDLED["h6_curved"], name="custom", spoke_sweep=math.radians(17.5),
                               face_thickness=0.0215, fillet_radius=0.0085)
    assert mut.spec_from_mapping(yaml.safe_load(mut.spec_to_yaml(spec))) == spec


@pytest.mark.parametrize("changes, field", [
    ({"spoke_width": 0.090}, "spoke_width"),  # too wide for 5 spokes at the inner radius
    ({"spoke_width_outer": 0.200}, "spoke_width_outer"),
    ({"fillet_radius": 0.060}, "fillet_radius"),
    ({"face_thickness": -0.01}, "face_thickness"),
    ({"spoke_style": "wavy"}, "spoke_style"),
    ({"spoke_count": 2}, "spoke_count"),
    ({"window_outer_radius": 0.212}, "window_outer_radius"),
    ({"hub_pad_radius": 0.095}, "hub_pad_radius"),
    ({"bolt_circle_diameter": 0.150}, "bolt_circle_diameter"),
    ({"fillet_radius_small": 0.020}, "fillet_radius_small"),
])
def test_bad_values_name_the_field(changes, field):
    spec = dataclasses.replace(BUNDLED["h5_straight"], **changes)
    with pytest.raises(InputError, match=f"'{field}'"):
        spec.validate()


def test_split_arms_too_wide_for_the_small_window():
    spec = dataclasses.replace(BUNDLED["h5_split"], spoke_width_outer=0.070)
    with pytest.raises(InputError, match="spoke_width_outer"):
        spec.validate()


def test_unknown_key_and_wrong_type_in_yaml():
    data = mut.spec_to_mapping(BUNDLED["h5_split"])
    with pytest.raises(InputError, match="unknown hub field 'spokes'"):
        mut.spec_from_mapping({**data, "spokes": 5}, "x.yaml")
    with pytest.raises(InputError, match="'face_thickness_mm' must be a number"):
        mut.spec_from_mapping({**data, "face_thickness_mm": "thick"}, "x.yaml")
    with pytest.raises(InputError, match="'spoke_count' must be an integer"):
        mut.spec_from_mapping({**data, "spoke_count": 5.5}, "x.yaml")


def test_dish_profile_values_and_derivative():
    spec = BUNDLED["h5_deepdish"]
    assert spec.z_face(0.0) == 0.0
    assert spec.z_face(spec.dish_inner_radius) == 0.0
    assert spec.z_face(spec.dish_outer_radius) == pytest.approx(spec.dish_depth, abs=1e-15)
    assert spec.z_face(0.23) == pytest.approx(spec.dish_depth, abs=1e-15)
    r = np.random.default_rng(0).uniform(0.0, 0.23, 200)
    h = 1e-7
    numeric = (spec.z_face(r + h) - spec.z_face(r - h)) / (2 * h)
    np.testing.assert_allclose(spec.dz_face_dr(r), numeric, atol=1e-6)
