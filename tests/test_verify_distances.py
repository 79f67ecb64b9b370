"""DistanceProbe: Drake's pairwise query classified, the culled narrow phase, and the cell's
own query agree."""

from __future__ import annotations

import numpy as np
import pytest
import verify_support as vs

import drakedeburr.verify.distances as mut


def test_both_methods_match_the_cells_query():
    cell, _ = vs.cell_and_hub()
    plan = vs.good_plan()
    pairwise = mut.DistanceProbe(cell, query_distance=0.02)
    culled = mut.DistanceProbe(cell, query_distance=0.02, method="culled")
    rng = np.random.default_rng(0)
    cut = next(s for s in plan.segments if s.kind == "cut")
    times = np.concatenate([rng.uniform(0, plan.trajectory.duration, 8),
                            rng.uniform(*cut.t_range, 6)])
    for t in times:
        q = plan.trajectory.value(t)
        a, b = pairwise.measure(q), culled.measure(q)
        for field in ("clearance", "self_distance", "burr"):
            assert getattr(a, field) == pytest.approx(getattr(b, field), abs=1e-12), (t, field)
        assert a.clearance_pair == b.clearance_pair and a.burr_pair == b.burr_pair
        # cell.min_distance: all unfiltered pairs but burr-head/hub
        ref, _ = cell.min_distance(q, max_distance=0.02)
        assert abs(min(a.clearance, a.self_distance, 0.02) - ref) <= 1e-12
        with_burr, _ = cell.min_distance(q, ignore_burr_hub=False, max_distance=0.02)
        assert abs(min(a.clearance, a.self_distance, a.burr, 0.02) - with_burr) <= 1e-12
    # during the cut the burr touches the hub
    q = plan.trajectory.value(0.5 * (cut.t_range[0] + cut.t_range[1]))
    d = pairwise.measure(q)
    assert d.burr < 1e-3 and "burr_head" in d.burr_pair[0] + d.burr_pair[1]


def test_unknown_method():
    cell, _ = vs.cell_and_hub()
    with pytest.raises(ValueError, match="pairwise"):
        mut.DistanceProbe(cell, 0.02, method="magic")
