"""Shape generator: exact area/perimeter vs analytic formulas, sampling, lead-in, errors."""

import math

import numpy as np
import pytest

import drakedeburr.laser.shapes as mut
from drakedeburr.errors import InputError


def _shoelace(p):
    return 0.5 * abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _keyhole_area_perimeter(D, w, ell):
    R, h = D / 2, w / 2
    d = math.sqrt(R * R - h * h)
    alpha = math.asin(h / R)
    cap = R * R * alpha - d * h  # circle segment below the chord y = -d
    area = math.pi * R * R + w * (ell - d) + math.pi * h * h / 2 - cap
    perim = R * (2 * math.pi - 2 * alpha) + 2 * (ell - d) + math.pi * h
    return area, perim


CASES = [
    (mut.Circle(diameter=0.010), math.pi * 0.005**2, math.pi * 0.010),
    (mut.Semicircle(diameter=0.012), math.pi * 0.006**2 / 2, math.pi * 0.006 + 0.012),
    (mut.Rectangle(width=0.020, height=0.010), 2e-4, 0.060),
    (mut.Rectangle(width=0.020, height=0.010, corner_radius=0.003),
     2e-4 - (4 - math.pi) * 0.003**2, 0.060 - 8 * 0.003 + 2 * math.pi * 0.003),
    (mut.Slot(length=0.020, width=0.006), 0.014 * 0.006 + math.pi * 0.003**2,
     2 * 0.014 + math.pi * 0.006),
    (mut.Keyhole(head_diameter=0.012, slot_width=0.005, slot_length=0.012),
     *_keyhole_area_perimeter(0.012, 0.005, 0.012)),
    (mut.Hexagon(across_flats=0.017), 1.5 * math.sqrt(3) * (0.017 / math.sqrt(3))**2,
     6 * 0.017 / math.sqrt(3)),
    (mut.Polyline(points=((0, 0), (0.01, 0), (0.01, 0.004), (0.004, 0.004), (0.004, 0.01),
                          (0, 0.01))), 0.01 * 0.004 + 0.004 * 0.006, 0.040),
]


@pytest.mark.parametrize("shape,area,perimeter", CASES, ids=[c[0].kind + str(i)
                                                            for i, c in enumerate(CASES)])
@pytest.mark.parametrize("clockwise", [False, True])
def test_area_perimeter_match_analytic(shape, area, perimeter, clockwise):
    import dataclasses

    rng = np.random.default_rng(0)
    shape = dataclasses.replace(shape, center=tuple(rng.uniform(-0.01, 0.01, 2)),
                                rotation=float(rng.uniform(-3, 3)), clockwise=clockwise)
    c = mut.build_contour(shape, spacing=0.05e-3)
    assert c.area == pytest.approx(area, rel=1e-12)
    assert c.perimeter == pytest.approx(perimeter, rel=1e-12)
    # the sampled polygon converges to the exact shape (chord error O(spacing^2))
    assert _shoelace(c.p_P[:-1]) == pytest.approx(area, rel=2e-4)
    seg = np.linalg.norm(np.diff(c.p_P, axis=0), axis=1)
    assert seg.sum() == pytest.approx(perimeter, rel=2e-4)
    assert seg.max() <= 0.05e-3 + 1e-12
    assert np.allclose(c.p_P[0], c.p_P[-1], atol=1e-12)  # closed
    # cut direction: signed area sign
    p = c.p_P[:-1]
    signed = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    assert (signed < 0) == clockwise
    # tangents point along the path
    d = np.diff(c.p_P, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.min(np.sum(d * c.t_P[:-1], axis=1)) > 0.9


def test_circle_points_on_circle_and_spacing():
    c = mut.build_contour(mut.Circle(diameter=0.008, center=(0.001, -0.002)), spacing=0.1e-3)
    r = np.linalg.norm(c.p_P - [0.001, -0.002], axis=1)
    assert np.allclose(r, 0.004, atol=1e-15)
    assert len(c) == math.ceil(math.pi * 0.008 / 0.1e-3) + 1
    assert not c.corner[1:-1].any()


def test_corners_marked():
    c = mut.build_contour(mut.Hexagon(across_flats=0.01), spacing=0.5e-3)
    assert c.corner.sum() == 6  # six vertices (start/end is mid-flat)
    c = mut.build_contour(mut.Rectangle(width=0.01, height=0.01, corner_radius=0.002), 0.5e-3)
    assert not c.corner.any()  # tangent-continuous


def test_lead_in():
    c = mut.build_contour(mut.Circle(diameter=0.010, lead_in=0.003), spacing=0.2e-3)
    n = np.argmax(c.is_cut)
    assert n > 0 and not c.is_cut[:n].any()
    assert np.allclose(c.p_P[0], [0.002, 0.0])  # pierce 3 mm inside the start point
    assert np.allclose(c.p_P[n], [0.005, 0.0])
    assert c.corner[n]
    assert c.s[-1] == pytest.approx(0.003 + math.pi * 0.010, rel=1e-4)
    with pytest.raises(InputError, match="circle: lead_in .* outside the hole"):
        mut.build_contour(mut.Circle(diameter=0.004, lead_in=0.005), spacing=0.2e-3)


def test_bad_shapes_rejected():
    with pytest.raises(InputError, match="circle: diameter must be > 0"):
        mut.build_contour(mut.Circle(diameter=-1.0), 1e-3)
    with pytest.raises(InputError, match="rectangle: corner_radius"):
        mut.build_contour(mut.Rectangle(width=0.01, height=0.004, corner_radius=0.003), 1e-3)
    with pytest.raises(InputError, match="slot: length"):
        mut.build_contour(mut.Slot(length=0.002, width=0.004), 1e-3)
    with pytest.raises(InputError, match="keyhole: slot_width"):
        mut.build_contour(mut.Keyhole(head_diameter=0.004, slot_width=0.005,
                                      slot_length=0.01), 1e-3)
    with pytest.raises(InputError, match="polyline: point 1 repeats"):
        mut.build_contour(mut.Polyline(points=((0, 0), (1, 1), (1, 1), (0, 1))), 1e-3)
    with pytest.raises(InputError, match="point spacing"):
        mut.build_contour(mut.Circle(diameter=0.01), 0.0)


def test_shape_kinds_registry():
    assert set(mut.SHAPE_KINDS) == {"circle", "semicircle", "rectangle", "slot", "keyhole",
                                    "hexagon", "polyline"}


def test_rotation_and_center_move_the_points():
    a = mut.build_contour(mut.Rectangle(width=0.02, height=0.01), spacing=1e-3)
    b = mut.build_contour(mut.Rectangle(width=0.02, height=0.01, rotation=math.pi / 2,
                                        center=(0.003, -0.004)), spacing=1e-3)
    R = np.array([[0.0, -1.0], [1.0, 0.0]])
    assert np.allclose(b.p_P, a.p_P @ R.T + [0.003, -0.004], atol=1e-15)
    assert np.allclose(b.t_P, a.t_P @ R.T, atol=1e-15)


def test_polyline_given_clockwise_is_cut_in_the_requested_direction():
    pts = ((0, 0), (0, 0.01), (0.01, 0.01), (0.01, 0))  # clockwise input
    c = mut.build_contour(mut.Polyline(points=pts), 0.5e-3)
    p = c.p_P[:-1]
    signed = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    assert signed == pytest.approx(1e-4)
    assert mut.Polyline(points=pts).points == pts  # the dataclass is not rewritten
