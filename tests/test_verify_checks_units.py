"""Checks of verify.checks_plan and verify.checks_path on inputs whose answer is known: the
planner-failure digest per window, and the CL chord figures of CL points on a circle
(chord height R (1 - cos(pi/N)), chord length 2 R sin(pi/N)) and of a plan without CL."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.config import ProcessParameters
from drakedeburr.plan.types import FailureRecord
from drakedeburr.verify import checks_path, checks_plan


def test_failures_item_digests_each_window():
    plan = SimpleNamespace(failures=(
        FailureRecord(2, "ik", "unreachable", point=55, value=1.34e-3, limit=2e-3, unit="m",
                      tried=("cone probe", "spin")),
        FailureRecord(2, "ik", "unreachable", point=56, tried=("spin", "other branch")),
        FailureRecord(2, "relaxation", "milder recipes failed too", tried=("theta box",)),
        FailureRecord(-1, "home", "joint move blocked"),
    ))
    item = checks_plan.failures_item(plan)
    assert not item.passed and item.value == 4.0 and item.window == 2
    w2 = item.per_window[2]
    assert w2["records"] == 3 and w2["kinds"] == ["ik", "relaxation"]
    assert w2["reasons"]["ik"] == str(plan.failures[0])  # the first of each kind
    assert w2["worst"] == {"value": 1.34e-3, "limit": 2e-3, "unit": "m"}
    assert w2["tried"] == ["cone probe", "spin", "other branch", "theta box"]
    assert item.per_window[-1]["kinds"] == ["home"]
    ok = checks_plan.failures_item(SimpleNamespace(failures=()))
    assert ok.passed and ok.value == 0.0 and ok.per_window == {}


def _sp(p_HC, p_HE):
    return SimpleNamespace(cut_windows=[0], edge_of={0: SimpleNamespace(p_HE=p_HE)},
                           refs={0: SimpleNamespace(p_HC=p_HC, tool_path=object())},
                           memo=lambda key, compute: compute())


@pytest.mark.parametrize("n", [40, 90])
def test_cl_chords_on_a_circle(n):
    R = 0.08
    a = 2 * np.pi * np.arange(n) / n
    cl = np.stack([R * np.cos(a), R * np.sin(a), np.zeros(n)], 1)
    b = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    edge = np.stack([R * np.cos(b), R * np.sin(b), np.zeros_like(b)], 1)
    cfg = SimpleNamespace(process=ProcessParameters())
    err = checks_path.cl_chord_error(_sp(cl, edge), cfg)
    length = checks_path.cl_chord_length(_sp(cl, edge), cfg)
    assert err.value == pytest.approx(R * (1 - math.cos(math.pi / n)), rel=1e-3)
    assert length.value == pytest.approx(2 * R * math.sin(math.pi / n), rel=1e-9)
    assert err.passed is (err.value <= cfg.process.delta_max)
    assert length.passed is (length.value <= cfg.process.l_max + 1e-12)


def test_cl_chords_not_measurable_without_cl_points():
    sp = SimpleNamespace(cut_windows=[0], edge_of={}, refs={0: None},
                         memo=lambda key, compute: compute())
    cfg = SimpleNamespace(process=ProcessParameters())
    for check in (checks_path.cl_chord_error, checks_path.cl_chord_length):
        item = check(sp, cfg)
        assert not item.passed and item.value is None and "not measurable" in item.detail
