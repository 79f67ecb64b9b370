"""verify.cut_geometry.stretch_coverage: the edge coverage of a partial window's open stretches
(issue 42) on a loop that folds back on itself, as a real window's loop does (down a spoke flank
and back up): the uncut side of the fold is not read as a gap of the cut side."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.verify.cut_geometry import stretch_coverage


def _hairpin() -> np.ndarray:
    """CL points 1 mm apart around a 100 x 4 mm rectangle (a narrow fold), counter-clockwise
    from (0, 0)."""
    bottom = [(x, 0.0) for x in range(100)]
    right = [(100.0, y) for y in range(4)]
    top = [(100.0 - x, 4.0) for x in range(100)]
    left = [(0.0, 4.0 - y) for y in range(4)]
    p = np.array(bottom + right + top + left, float)
    return 1e-3 * np.column_stack([p, np.zeros(len(p))])


def test_the_uncut_side_of_a_fold_is_not_a_gap_of_the_cut_side():
    loop = _hairpin()
    cut = np.arange(10, 91)  # CL 10..90 along the bottom, cut as one stretch
    targets = [SimpleNamespace(p_HC=loop[i]) for i in cut]  # target k aims at CL cut[k]
    cl_of = {k: int(i) for k, i in enumerate(cut)}
    move = np.arange(1, len(cut))  # sample j on the move ending at target j + 1
    contact = loop[cut[1:]]  # the burr on the edge at every sample
    chunks = [np.arange(len(move))]
    edge = loop + np.array([0.0, 0.0, 1e-5])  # the hub edge 0.01 mm off the CL points
    gap, at = stretch_coverage(targets, move, chunks, contact, edge, loop, cl_of)
    assert gap == pytest.approx(1e-5, abs=1e-9)  # the cut side: covered
    assert 11 <= at <= 89  # an edge point of the cut side
    # given to the stretches' own CL points only, the top of the fold lies 4 mm from the cut
    old, at_old = stretch_coverage(targets, move, chunks, contact, edge)
    assert old == pytest.approx(4e-3, rel=1e-3) and loop[at_old][1] == pytest.approx(4e-3)
