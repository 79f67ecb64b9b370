"""path.cl_equal_chord on an analytic circle: the march takes equal steps whose chord height
R (1 - cos(phi / 2)) is at delta_max (within the sampling margin), never above it; the sample
count per segment follows the arc length."""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.path import cl_equal_chord as mut
from drakedeburr.path.cl_planning import PlannerParams
from drakedeburr.path.edge_curve import fit_edge_curve


def test_equal_chord_height_on_a_circle_meets_delta_with_equal_steps():
    R = 0.05
    a = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
    curve = fit_edge_curve(np.c_[R * np.cos(a), R * np.sin(a), np.zeros_like(a)])
    params = PlannerParams(delta_max=0.12e-3)
    u = mut.plan_equal_chord_height(curve, params)
    p = curve.position(u)
    phi = np.diff(np.unwrap(np.arctan2(p[:, 1], p[:, 0])))
    height = R * (1 - np.cos(phi / 2))  # analytic chord height of each full step
    assert height.max() <= params.delta_max * (1 + 1e-6)
    assert height.min() >= params.delta_max * (1 - 2 * mut.SAMPLED_MARGIN)
    step = 2 * math.acos(1 - params.delta_max / R)  # the largest angle delta allows
    assert len(u) == math.ceil(2 * np.pi / step) or len(u) == math.ceil(2 * np.pi / step) + 1
    # the last step closes the loop and may be shorter, never higher
    last = 2 * np.pi - (np.unwrap(np.arctan2(p[:, 1], p[:, 0]))[-1]
                        - np.arctan2(p[0, 1], p[0, 0]))
    assert R * (1 - math.cos(last / 2)) <= params.delta_max * (1 + 1e-6)


def test_sample_count_is_one_per_quarter_millimetre_within_its_bounds():
    assert mut.sample_count(1e-3) == 48
    assert mut.sample_count(50e-3) == 200
    assert mut.sample_count(1.0) == 600
