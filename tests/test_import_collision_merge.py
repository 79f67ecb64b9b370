"""hub.import_collision's shell merge under the generator's rule: two touching boxes merge
into one hull; a probe point in the gap their hull would fill keeps them apart."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from drakedeburr.hub import import_collision as mut


def _box(x0: float, x1: float) -> np.ndarray:
    """Corners of a 10 x 10 mm box of 1 mm height from x0 to x1 [m]."""
    return np.array([[x, y, z] for x in (x0, x1) for y in (0.0, 0.01) for z in (0.0, 0.001)])


def test_touching_pieces_merge_unless_a_probe_lies_in_their_hull():
    pieces = [_box(0.0, 0.01), _box(0.01, 0.02)]
    none = SimpleNamespace(pts=np.zeros((0, 3)))
    merged = mut._merge_shell(pieces, none, 0.001)
    assert len(merged) == 1
    lo, hi = merged[0].min(axis=0), merged[0].max(axis=0)
    assert np.allclose(lo, [0, 0, 0]) and np.allclose(hi, [0.02, 0.01, 0.001])
    # a probe inside the merged hull (on the seam) forbids the merge
    probe = SimpleNamespace(pts=np.array([[0.01, 0.005, 0.0005]]))
    assert len(mut._merge_shell(pieces, probe, 0.001)) == 2
