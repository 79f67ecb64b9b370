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


_IPOPT_AT_ITS_CAP = """
import sys
from drakedeburr import cli
cli.configure_logging(int(sys.argv[1]), False)
from pydrake.solvers import IpoptSolver, MathematicalProgram, SolverOptions
prog = MathematicalProgram()
x = prog.NewContinuousVariables(2)
prog.AddCost((x[0] - 1) ** 4 + (x[1] * x[0] - 3) ** 2)
options = SolverOptions()
options.SetOption(IpoptSolver().solver_id(), "max_iter", 1)
print(IpoptSolver().Solve(prog, None, options).get_solution_result())
"""


@pytest.mark.parametrize("verbose", [0, 2])
def test_the_solvers_own_messages_only_with_vv_though_pydrake_is_imported_later(verbose):
    """The CLI configures logging before any command imports pydrake, and importing pydrake
    resets the ``drake`` logger's level: its warnings (IPOPT at its iteration cap, which the
    planner handles) must still stay out of a normal run's output."""
    run = subprocess.run([sys.executable, "-c", _IPOPT_AT_ITS_CAP, str(verbose)],
                         capture_output=True, text=True, check=True)
    assert "IterationLimit" in run.stdout
    assert ("IPOPT terminated after exceeding the maximum iteration limit" in run.stderr) == (
        verbose == 2), run.stderr
