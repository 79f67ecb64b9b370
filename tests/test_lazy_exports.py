"""The stage packages' lazy re-exports (drakedeburr/_lazy.py): every public name resolves to
the object of its defining module, and building the command line imports none of the heavy
libraries (the reason they are lazy)."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import drakedeburr

PACKAGES = sorted(p.parent.name for p in Path(drakedeburr.__file__).parent.glob("*/__init__.py"))


@pytest.mark.parametrize("name", PACKAGES)
def test_every_public_name_resolves_to_its_module_object(name):
    pkg = importlib.import_module(f"drakedeburr.{name}")
    assert pkg.__all__ and len(set(pkg.__all__)) == len(pkg.__all__)
    for public in pkg.__all__:
        value = getattr(pkg, public)
        if inspect.isclass(value) or inspect.isfunction(value):
            assert getattr(importlib.import_module(value.__module__), public) is value
        assert public in dir(pkg)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        pkg.not_a_name  # noqa: B018
    star: dict = {}
    exec(f"from drakedeburr.{name} import *", star)  # noqa: S102
    assert set(pkg.__all__) <= set(star)


def test_a_submodule_is_still_imported_by_from_import():
    from drakedeburr.verify import checks_distance

    assert checks_distance.__name__ == "drakedeburr.verify.checks_distance"


def test_the_command_line_parser_imports_no_heavy_library():
    code = ("import sys; from drakedeburr import cli; cli._build_parser(); "
            "print(' '.join(m for m in ('pydrake', 'scipy', 'open3d', 'sklearn', 'matplotlib') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == ""
