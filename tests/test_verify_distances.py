"""DistanceProbe (culled pairwise narrow phase) vs the scene graph's own pairwise query."""

from __future__ import annotations

import numpy as np
import verify_support as vs

import drakedeburr.verify.distances as mut


def test_probe_matches_scene_graph_query():
    cell, _ = vs.cell_and_hub()
    plan = vs.good_plan()
    probe = mut.DistanceProbe(cell, query_distance=0.02)
    rng = np.random.default_rng(0)
    times = rng.uniform(0, plan.trajectory.duration, 12)
    for t in times:
        q = plan.trajectory.value(t)
        d = probe.measure(q)
        # cell.min_distance: all unfiltered pairs but burr-head/hub, Drake's broad phase
        ref, pair = cell.min_distance(q, max_distance=0.02)
        mine = min(d.clearance, d.self_distance, 0.02)
        assert abs(mine - ref) <= 1e-12, (t, d, ref, pair)
        with_burr, _ = cell.min_distance(q, ignore_burr_hub=False, max_distance=0.02)
        assert abs(min(mine, d.burr) - with_burr) <= 1e-12
