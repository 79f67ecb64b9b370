"""Package skeleton: resources, units, config, atomic I/O, CLI plumbing."""

import json

import numpy as np
import pytest

import drakedeburr
import drakedeburr._io as io_mut
import drakedeburr.config as config_mut
import drakedeburr.resources as mut
import drakedeburr.units as units
from drakedeburr.errors import InputError


def test_models_dir_has_package_xml():
    assert (mut.models_dir() / "package.xml").is_file()


def test_resolve_package_url():
    assert mut.resolve_package_url("package://drakedeburr/package.xml").is_file()
    with pytest.raises(ValueError, match="not a package://drakedeburr/"):
        mut.resolve_package_url("package://other/x")


def test_unknown_hub_and_scenario_are_named():
    with pytest.raises(FileNotFoundError, match="no bundled hub 'nope'"):
        mut.hub_dir("nope")
    with pytest.raises(FileNotFoundError, match="no scenario 'nope'"):
        mut.scenario_path("nope")


def test_units_round_trip():
    x = np.array([1.5, -2.0])
    assert np.allclose(units.m_from_mm(units.mm_from_m(x)), x)
    assert units.mm_from_m(0.15) == pytest.approx(150.0)
    assert units.deg_from_rad(np.pi) == pytest.approx(180.0)
    assert units.m_from_inch(1.0) == pytest.approx(0.0254)


def test_config_from_yaml(tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text("grinding_speed: 0.1\nbounds_small: {theta_min: 0.1, theta_max: 0.2}\n")
    p = config_mut.dataclass_from_yaml(config_mut.ProcessParameters, f)
    assert p.grinding_speed == 0.1 and p.bounds_small.theta_max == 0.2
    assert p.bounds_large.theta_min == pytest.approx(0.26)
    f.write_text("grinding_sped: 0.1\n")
    with pytest.raises(ValueError, match="unknown ProcessParameters field 'grinding_sped'"):
        config_mut.dataclass_from_yaml(config_mut.ProcessParameters, f)


def test_process_parameters_of_a_part(tmp_path):
    """Defaults, then the part's process.yaml, then explicit overrides; bad files are named."""
    assert config_mut.process_parameters(tmp_path) == config_mut.ProcessParameters()
    (tmp_path / config_mut.PROCESS_FILE).write_text(
        "bounds_large: {theta_min: 0.09, theta_max: 0.26}\ngrinding_speed: 0.12\n")
    p = config_mut.process_parameters(tmp_path)
    assert p.bounds_large == config_mut.OrientationBounds(0.09, 0.26)
    assert p.grinding_speed == 0.12
    assert p.bounds_small == config_mut.ProcessParameters().bounds_small
    assert config_mut.process_parameters(tmp_path, grinding_speed=0.1).grinding_speed == 0.1
    assert config_mut.process_parameters(tmp_path, grinding_speed=None).grinding_speed == 0.12
    for text, what in (("bounds_large: {theta_min: 0.3, theta_max: 0.2}\n", "theta_min <"),
                       ("bounds_small: {theta_min: 0.1}\n", "bounds_small"),
                       ("bounds_small: {lo: 0.1, hi: 0.2}\n", "bounds_small"),
                       ("[1, 2]\n", "expected a mapping"),
                       ("a: [\n", "not valid YAML")):
        (tmp_path / config_mut.PROCESS_FILE).write_text(text)
        with pytest.raises(InputError, match=what) as err:
            config_mut.process_parameters(tmp_path)
        assert str(tmp_path / config_mut.PROCESS_FILE) in str(err.value)


def test_bundled_hub_recipes_are_valid():
    """Every bundled hub's process.yaml loads; h5_deepdish carries the smaller tilt box."""
    from drakedeburr.hub import load_hub

    for name in mut.hub_names():
        load_hub(name).process  # noqa: B018 - raises on a bad recipe
    if "h5_deepdish" in mut.hub_names():
        assert load_hub("h5_deepdish").process.bounds_large.theta_max <= 0.26


def test_atomic_write_keeps_old_file_on_failure(tmp_path):
    f = tmp_path / "out.json"
    io_mut.atomic_write_json(f, {"a": 1})

    class Boom:
        pass

    with pytest.raises(TypeError):
        io_mut.atomic_write_json(f, {"a": Boom()})
    assert json.loads(f.read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]


def test_lazy_public_api():
    assert drakedeburr.ProcessParameters().grinding_speed == pytest.approx(0.150)
    with pytest.raises(AttributeError):
        drakedeburr.does_not_exist  # noqa: B018


def test_atomic_write_gives_normal_permissions(tmp_path):
    import os

    f = io_mut.atomic_write_text(tmp_path / "r.html", "x")
    umask = os.umask(0)
    os.umask(umask)
    assert (f.stat().st_mode & 0o777) == (0o666 & ~umask)


def test_every_public_name_resolves():
    """Each name re-exported at the top level is the object its defining module holds under
    that name (a class or function, not renamed), or a value of a drakedeburr type."""
    import importlib
    import inspect

    from drakedeburr.resources import hub_names

    for name in drakedeburr.__all__:
        obj = getattr(drakedeburr, name)
        if name == "__version__":
            assert obj == drakedeburr.__version__ and obj.count(".") == 2, obj
        elif inspect.isclass(obj) or inspect.isfunction(obj):
            assert obj.__name__ == name, (name, obj.__name__)
            assert obj.__module__.startswith("drakedeburr."), (name, obj.__module__)
            assert getattr(importlib.import_module(obj.__module__), name) is obj, name
        elif isinstance(obj, str):  # DEFAULT_HUB
            assert obj in hub_names(), (name, obj)
        else:  # BURR, IRB1600_10_120: instances of the package's own records
            assert type(obj).__module__.startswith("drakedeburr."), (name, type(obj))
