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


def test_limit_use_is_read_at_the_knots_where_the_timing_binds():
    """A slow stretch whose wrist acceleration reaches 0.9 of its limit only in narrow peaks
    at the trajectory's knots (the timing bounds the limits there; between knots a degree-6
    piece's acceleration can fall off within a fraction of a millisecond: catalogue hub
    271128_043 read 0.83-0.85 on the 0.5 ms grid where J3 is at 0.90 at every knot). The
    grid alone misses the peaks; with the knots every point of the stretch has a limit at
    0.9 within 1 mm, the analytic peak."""
    from types import SimpleNamespace

    from scipy.special import erf

    from drakedeburr.verify import checks_process as mut

    v, sigma, A, a_max = 0.08, 0.03e-3, 0.9 * 50.0, 50.0  # m/s, s, rad/s^2
    knots = np.arange(0.0, 0.2 + 1e-12, 3.1e-3)
    sign = np.where(np.arange(len(knots)) % 2 == 0, 1.0, -1.0)

    def acc(t):
        return A * np.sum(sign * np.exp(-((t[:, None] - knots) / sigma) ** 2), axis=1)

    def vel(t):
        return A * sigma * np.sqrt(np.pi) / 2 * np.sum(
            sign * (erf((t[:, None] - knots) / sigma) + 1.0), axis=1)

    def value(t):
        t = np.atleast_1d(np.asarray(t, float))
        q = np.zeros((len(t), 6))
        q[:, 0] = v * t  # the tool point moves along x at v (FK below: q[:3] is the point)
        return q

    def derivative(t, n):
        t = np.atleast_1d(np.asarray(t, float))
        d = np.zeros((len(t), 6))
        if n == 1:
            d[:, 0], d[:, 3] = v, vel(t)
        else:
            d[:, 3] = acc(t)
        return d

    def X_HT(q):
        X = np.tile(np.eye(4), (len(q), 1, 1))
        X[:, :3, 3] = q[:, :3]
        return X

    traj = SimpleNamespace(t=knots, value=value, derivative=derivative)
    sp = SimpleNamespace(plan=SimpleNamespace(trajectory=traj), kin=SimpleNamespace(X_HT=X_HT),
                         limits=SimpleNamespace(velocity=np.full(6, 10.0),
                                                acceleration=np.full(6, a_max)))
    cfg = SimpleNamespace(process=SimpleNamespace(tcp_acceleration=3.0))
    t0, t1 = 0.0103, 0.1897
    t, s, r, on_grid = mut._limit_ratios(sp, cfg, t0, t1)
    n_grid = int(np.ceil((t1 - t0) / 0.5e-3)) + 1  # the 0.5 ms grid
    assert np.all(np.diff(t) >= 0) and on_grid.sum() == n_grid
    np.testing.assert_allclose(t[on_grid], np.linspace(t0, t1, n_grid))
    inner = knots[(knots > t0) & (knots < t1)]
    assert (~on_grid).sum() == 2 * len(inner)
    grid_only = mut._windowed_max(s[on_grid], r[on_grid], 1e-3, np.ones(on_grid.sum(), bool))
    with_knots = mut._windowed_max(s, r, 1e-3, on_grid)
    assert len(with_knots[0]) == on_grid.sum()
    assert grid_only[0].min() < 0.85  # the grid misses the peaks
    np.testing.assert_allclose(with_knots[0], 0.9, rtol=1e-6)  # the analytic peak, A / a_max
    assert set(with_knots[1].tolist()) == {6 + 3}  # J4 acceleration (_LIMITS' column)
