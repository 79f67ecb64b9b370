"""Issue 43 item 8: generated files are the same bytes on every machine.

Every committed generated file is regenerated here and compared byte for byte (CI runs this
on a fresh clone). A file is the same on another machine only if the last bits of its
floating-point arithmetic (libm, BLAS, compiler contraction differ between machines: seen, an
arm SDF reading ``...69689661813`` where another machine wrote ``...69689661815``) cannot
reach it: the writers round every number to :data:`drakedeburr._io.FILE_DIGITS` significant
digits. So the tests also (a) check that no number in a generated file carries more digits,
and (b) regenerate from inputs moved by a few units in the last place (what another
machine's arithmetic does) and require the same bytes.

Families: :data:`FAMILIES` (name -> (committed file of a key, the generator's texts)). The
arm models (drakedeburr.robots.arm_models, models/robots) are compared by
tests/test_robots_arms.py; add them here once their writer rounds (FILE_DIGITS).
"""

from __future__ import annotations

import re
from dataclasses import fields, replace

import numpy as np
import pytest

from drakedeburr._io import FILE_DIGITS, round_numbers
from drakedeburr.resources import models_dir


def _tools(perturb=None):
    from drakedeburr.cell import tools

    spindle, stand = tools.FLOATING_SPINDLE, tools.SPINDLE_STAND
    if perturb is not None:
        spindle, stand = perturb(spindle), perturb(stand)
    return {f"tools/{k}": v for k, v in tools.tool_model_texts(spindle, stand).items()}


def _laser(perturb=None):
    from drakedeburr.laser import model
    from drakedeburr.laser.kinematics import FiveBarGeometry

    g = FiveBarGeometry()
    return {model.DEFAULT_SDF: model.five_bar_sdf(perturb(g) if perturb else g)}


def _pedestals(perturb=None):
    from drakedeburr.cell import mounts
    from drakedeburr.resources import models_dir

    root = models_dir()
    return {str(mounts._pedestal_file(url).relative_to(root)): text
            for url, text in mounts.pedestal_texts().items()}


FAMILIES = {"tools": _tools, "laser": _laser, "pedestals": _pedestals}

_LITERAL = re.compile(r"(?<![\w.])-?\d+\.\d+(?:[eE][-+]?\d+)?(?![\w.])")


def _ulps(obj, n: int = 3):
    """``obj`` (a frozen dataclass, nested) with every float field moved ``n`` units in the
    last place: what another machine's last-bit differences do to computed inputs."""
    changes = {}
    for f in fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, float) and v != 0.0:
            for _ in range(n):
                v = float(np.nextafter(v, np.inf))
            changes[f.name] = v
        elif hasattr(v, "__dataclass_fields__"):
            changes[f.name] = _ulps(v, n)
    return replace(obj, **changes)


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_generated_files_are_committed_byte_for_byte(family):
    texts = FAMILIES[family]()
    assert texts
    root = models_dir()
    for rel, text in texts.items():
        assert (root / rel).read_bytes() == text.encode("utf-8"), rel


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_generated_numbers_are_rounded(family):
    for rel, text in FAMILIES[family]().items():
        long = [lit for lit in _LITERAL.findall(text)
                if len(lit.split("e")[0].split("E")[0].lstrip("-").replace(".", "")
                       .lstrip("0")) > FILE_DIGITS]
        assert not long, (rel, long[:5])


@pytest.mark.parametrize("family", ["tools", "laser"])
def test_last_bit_differences_do_not_reach_the_files(family):
    """Inputs 3 ulps off (another machine's arithmetic) give the committed bytes."""
    here, there = FAMILIES[family](), FAMILIES[family](_ulps)
    assert here.keys() == there.keys()
    for rel in here:
        assert here[rel] == there[rel], rel
    if family == "tools":  # unrounded, the last bits would show: the rounding keeps them out
        from drakedeburr.cell import tools

        a = tools._f(tools.FLOATING_SPINDLE.burr.stick_out)
        b = tools._f(_ulps(tools.FLOATING_SPINDLE).burr.stick_out)
        assert a != b


def test_round_numbers_keeps_short_literals_and_names():
    text = '<sdf version="1.9"><link name="link_1.5"><pose>0.050 1.0 -0.22186666666666668 ' \
           '1.2345678901234567e-05 3</pose></link></sdf>'
    out = round_numbers(text)
    assert out == ('<sdf version="1.9"><link name="link_1.5"><pose>0.050 1.0 -0.221866666667 '
                   '1.23456789012e-05 3</pose></link></sdf>')
    assert round_numbers("3.0000000000000013 0.047999999999999994") == "3.0 0.048"
    assert abs(float("-0.221866666667") - -0.22186666666666668) < 1e-12
