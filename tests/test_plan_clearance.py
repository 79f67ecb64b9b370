"""Clearance along a dense path (drakedeburr.plan.clearance): the motion bound is a bound (every
support point of every moving geometry, read from Drake's own poses, moves no farther than it
says), and the certified skip gives the full query's numbers at every sample."""

import numpy as np
import pytest

import drakedeburr.plan.clearance as mut
from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif("h5_straight" not in hub_names(), reason="no bundled hub")


@pytest.fixture(scope="module", params=["tool_in_hand", "workpiece_in_hand"])
def cell_path(request):
    """A cell and a dense joint path along the start of window 0's CL targets (the burr on its
    edge, 0.25 mm steps, tool axes as planned by the orientation stage)."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.ik import IkOptions, seed_by_spin
    from drakedeburr.plan.interpolate import track_poses
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import window_targets_for_hub
    from drakedeburr.plan.targets import X_HT_from_axis, contact_geometry, tool_point_H

    cell = load_cell(request.param, "h5_straight")
    kin, checker = cell_kinematics(cell), ClearanceChecker(cell)
    wt = window_targets_for_hub(load_hub("h5_straight"), windows=[0])[0]
    r_c, lift = contact_geometry(1.6e-3)
    p = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, lift)[:12]
    X = X_HT_from_axis(p, wt.retract_H[:12], wt.t_H[:12], np.zeros(12))
    q0 = seed_by_spin(kin, None, p[0], wt.retract_H[0], wt.t_H[0], cell.q_home, IkOptions())
    path = track_poses(kin, X, q0, 0.25e-3)
    assert np.all(path.ok)
    return cell, kin, checker, path.q


def test_motion_bound_covers_every_moving_point(cell_path):
    """Step and multi-step displacements of every moving geometry's support points (Drake's
    poses, not our kinematics) stay within the bound, also for joint steps 100x the path's."""
    from pydrake.geometry import Role

    cell, kin, checker, q = cell_path
    mb = mut.motion_bound(cell)
    inspector = cell.scene_graph.model_inspector()
    gids = [g for g in inspector.GetAllGeometryIds(Role.kProximity) if mb.level[mb.row[g]] > 0]
    support = {g: mut._support(inspector.GetShape(g)) for g in gids}

    def points(qi):
        query = checker.query_at(qi)
        out = {}
        for g in gids:
            X = query.GetPoseInWorld(g).GetAsMatrix4()
            P, _ = support[g]
            out[g] = P @ X[:3, :3].T + X[:3, 3]
        return out

    rng = np.random.default_rng(0)
    pairs = [(q[k], q[k + 1]) for k in range(0, len(q) - 1, 7)]
    pairs += [(q[k], q[k] + rng.normal(0, 0.03, 6)) for k in range(0, len(q), 25)]
    for qa, qb in pairs:
        D = mut.step_displacements(mb, np.stack([qa, qb]))[0]
        pa, pb = points(qa), points(qb)
        for g in gids:
            moved = float(np.max(np.linalg.norm(pb[g] - pa[g], axis=1)))
            assert moved <= D[mb.row[g]] + 1e-9, (inspector.GetName(g), moved, D[mb.row[g]])


def test_distances_along_equal_the_full_query(cell_path):
    cell, kin, checker, q = cell_path
    cap = 3e-3
    full = np.array([checker.distance(qi, cap) for qi in q])
    along, stats = mut.distances_along(checker, q, cap)
    assert np.array_equal(along, full)
    # it did skip work: fewer full queries than samples
    assert stats["anchors"] < len(q) / 2
    # near the hub: some samples under the cap, so the comparison is not trivially "all cap"
    assert np.any(full < cap)
