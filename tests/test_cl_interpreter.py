"""post.cl_types (number and axis checks) and post.cl_interpreter.arc_points, checked directly:
the arc's points against the analytic circle, the tokens against their limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drakedeburr.post.cl_interpreter import ClCircle, arc_points
from drakedeburr.post.cl_types import ClParseError, Notes, number, unit_vector


@pytest.mark.parametrize("token, why", [("abc", "expected a number"), ("nan", "finite"),
                                        ("inf", "finite"), ("1e300", "beyond")])
def test_number_refuses_a_bad_token_naming_file_line_and_token(token, why):
    with pytest.raises(ClParseError, match=why) as e:
        number("part.cl", 7, token)
    assert str(e.value).startswith("part.cl:7:") and repr(token) in str(e.value)


def test_unit_vector_normalises_with_a_warning_and_refuses_zero():
    notes = Notes()
    v = unit_vector("part.cl", 3, [0.0, 0.0, 2.0], notes, "GOTO")
    assert np.allclose(v, (0, 0, 1)) and notes.warning_counts["GOTO"] == 1
    assert np.allclose(unit_vector("part.cl", 4, [1e200, 1e200, 0], Notes(), "GOTO"),
                       (math.sqrt(0.5), math.sqrt(0.5), 0))  # no overflow
    with pytest.raises(ClParseError, match="zero tool axis"):
        unit_vector("part.cl", 5, [0.0, 0.0, 0.0], notes, "GOTO")


@pytest.mark.parametrize("tol", [1e-5, 1e-4])
def test_arc_points_lie_on_the_circle_within_the_chord_tolerance(tol):
    r, c, n = 0.04, np.array([0.1, 0.2, 0.0]), np.array([0.0, 0.0, 1.0])
    p0, p1 = c + [r, 0, 0], c + [0, r, 0]  # a quarter, counter-clockwise about +z
    pts = arc_points("part.cl", ClCircle(9, c, n, r, "40"), p0, p1, tol)
    assert np.allclose(np.linalg.norm(pts - c, axis=1), r, atol=1e-12)
    ang = np.unwrap(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
    assert np.all(np.diff(ang) > 0) and 0 < ang[0] and ang[-1] < math.pi / 2
    # chord height of each step (including the ends) within tol
    steps = np.diff(np.concatenate([[0.0], ang, [math.pi / 2]]))
    assert np.max(r * (1 - np.cos(steps / 2))) <= tol * (1 + 1e-9)
