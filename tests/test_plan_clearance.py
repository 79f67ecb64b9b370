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

    from drakedeburr.cell.narrowphase import bounding_points

    cell, kin, checker, q = cell_path
    mb = mut.motion_bound(cell)
    inspector = cell.scene_graph.model_inspector()
    gids = [g for g in inspector.GetAllGeometryIds(Role.kProximity) if mb.level[mb.row[g]] > 0]
    support = {g: bounding_points(inspector.GetShape(g)) for g in gids}

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


def test_relative_travel_covers_every_point_of_a_counted_body_pair(cell_path):
    """The anchor bound of a counted body pair (two moving bodies with a pair the checker's
    filters let through): the support points of either body's geometries, read in the other
    body's frame from Drake's own poses, move no farther per step than the relative bound of
    the body's ball says; each pair's column takes the least of the two relative bounds and
    the two bodies' own steps together (each bounds how far the pair's distance can change),
    each solo body's column its geometries' largest own step."""
    from pydrake.multibody.tree import BodyIndex

    from drakedeburr.cell.narrowphase import bounding_points

    cell, kin, checker, q = cell_path
    mb = mut.motion_bound(cell)
    bodies, members, solo, pairs, centre, radius = mut._counted(checker, mb)
    assert len(pairs) and np.any(solo)
    inspector = cell.scene_graph.model_inspector()
    gid_of = {i: g for g, i in mb.row.items()}
    rng = np.random.default_rng(2)
    path = np.vstack([q[::5], q[-1] + np.cumsum(rng.normal(0, 0.02, (6, 6)), axis=0)])
    X = mb.tree.body_poses(path)
    D = mut.step_displacements(mb, path, X)
    M = mut.anchor_travel(checker, mb, path, D, X)
    ctx = cell.plant.CreateDefaultContext()

    def pose(body, qi):
        cell.plant.SetPositions(ctx, qi)
        return cell.plant.EvalBodyPoseInWorld(
            ctx, cell.plant.get_body(BodyIndex(int(body)))).GetAsMatrix4()

    def relative_motion(rows, a, b):  # (N-1,) measured: the rows' points in b's frame
        worst = np.zeros(len(path) - 1)
        for g in rows:
            gid = gid_of[int(g)]
            P, rho = bounding_points(inspector.GetShape(gid))
            X_AG = np.linalg.inv(pose(a, cell.q_home)) @ (
                checker.query_at(cell.q_home).GetPoseInWorld(gid).GetAsMatrix4())
            P_A = P @ X_AG[:3, :3].T + X_AG[:3, 3]
            X_ba = [np.linalg.inv(pose(b, qi)) @ pose(a, qi) for qi in path]
            pts = np.array([P_A @ x[:3, :3].T + x[:3, 3] for x in X_ba])
            step = np.max(np.linalg.norm(np.diff(pts, axis=0), axis=2), axis=1)
            turn = [np.arccos(np.clip(0.5 * (np.trace(x0[:3, :3].T @ x1[:3, :3]) - 1), -1, 1))
                    for x0, x1 in zip(X_ba[:-1], X_ba[1:], strict=True)]
            worst = np.maximum(worst, step + np.array(turn) * rho)
        return worst

    own = np.stack([D[:, m].max(axis=1) for m in members], axis=1)
    n_solo = int(np.sum(solo))
    assert np.allclose(np.diff(M[:, :n_solo], axis=0), own[:, solo], rtol=0, atol=1e-12)
    for col, (x, y) in enumerate(pairs, start=n_solo):
        ax, bx = int(bodies[x]), int(bodies[y])
        rel_xy = mut._relative_steps(X, centre[[x]], radius[[x]], [ax], [bx])[:, 0]
        rel_yx = mut._relative_steps(X, centre[[y]], radius[[y]], [bx], [ax])[:, 0]
        assert np.all(relative_motion(members[x], ax, bx) <= rel_xy + 1e-9)
        assert np.all(relative_motion(members[y], bx, ax) <= rel_yx + 1e-9)
        step = np.minimum.reduce([rel_xy, rel_yx, own[:, x] + own[:, y]])
        assert np.allclose(np.diff(M[:, col]), step, rtol=0, atol=1e-12)


@pytest.mark.parametrize("filter_burr_contact", [True, False])
def test_every_candidate_pair_is_covered_by_an_anchor_column(cell_path, filter_burr_contact):
    """Every pair Drake counts in the checker's context (``GetCollisionCandidates``, the
    burr-contact filter applied or not) has an anchor column: a moving geometry against a fixed
    one its body's solo column, two moving geometries their bodies' pair column; no column
    for a pair Drake filters out (a column for nothing only costs anchors)."""
    from drakedeburr.plan.kinematics import ClearanceChecker

    cell = cell_path[0]
    checker = ClearanceChecker(cell, filter_burr_contact=filter_burr_contact)
    mb = mut.motion_bound(cell)
    bodies, members, solo, pairs, _, _ = mut._counted(checker, mb)
    body_of = {int(g): i for i, m in enumerate(members) for g in m}
    candidates = checker.query_at(cell.q_home).inspector().GetCollisionCandidates()
    assert candidates
    need_solo, need_pair = set(), set()
    for ga, gb in candidates:
        ra, rb = mb.row[ga], mb.row[gb]
        moving = [body_of[r] for r in (ra, rb) if mb.level[r] > 0]
        if len(moving) == 1:
            need_solo.add(moving[0])
        elif len(moving) == 2:
            assert moving[0] != moving[1]  # Drake never pairs geometries of one body
            need_pair.add(tuple(sorted(moving)))
    assert need_solo == set(np.flatnonzero(solo).tolist())
    assert need_pair == {tuple(p) for p in pairs.tolist()}


@pytest.mark.parametrize("reach", [20e-3, 4e-3])
def test_distances_along_equal_the_full_query(cell_path, reach):
    """Equal at every sample, also with a short anchor reach (anchors every few samples, so
    a pair the anchor bound let through unread would show)."""
    cell, kin, checker, q = cell_path
    cap = 3e-3
    full = np.array([checker.distance(qi, cap) for qi in q])
    along, stats = mut.distances_along(checker, q, cap, reach=reach)
    assert np.array_equal(along, full)
    # it did skip work: fewer full queries than samples
    assert stats["anchors"] < len(q) / 2
    # near the hub: some samples under the cap, so the comparison is not trivially "all cap"
    assert np.any(full < cap)


def test_readings_are_held_to_a_rigorous_bound(cell_path):
    """The checker's readings never exceed the separating-plane bound by more than the reading
    gap: a reading Drake gets 1 mm too far (its distance raised, its normal tilted, as FCL's
    GJK was measured to do on this hub) comes back at the shapes' distance where it matters
    (below the solve level) and at a lower bound elsewhere; the capped query reports only
    certified readings within its cap, looking NARROWPHASE_SLACK beyond it."""
    from types import SimpleNamespace

    from drakedeburr.cell.narrowphase import READING_GAP, ShapeSupport, exact_distance
    from drakedeburr.plan.kinematics import NARROWPHASE_SLACK

    cell, kin, checker, q = cell_path
    k = int(np.argmin([checker.distance(qi, 3e-3) for qi in q]))
    query = checker.query_at(q[k])
    pairs = [r for r in query.ComputeSignedDistancePairwiseClosestPoints(0.01) if r.distance > 0]
    assert pairs
    inspector = query.inspector()
    for r in pairs[:6]:
        X_A, X_B = (query.GetPoseInWorld(g).GetAsMatrix4() for g in (r.id_A, r.id_B))
        A, B = (ShapeSupport(inspector.GetShape(g)) for g in (r.id_A, r.id_B))
        exact, _ = exact_distance(A, X_A, B, X_B)
        assert checker.reading(query, r) <= exact + READING_GAP
        tilt = np.asarray(r.nhat_BA_W) + 0.2 * np.cross(r.nhat_BA_W, [0.0, 0.0, 1.0])
        wrong = SimpleNamespace(distance=r.distance + 1e-3, nhat_BA_W=tilt / np.linalg.norm(tilt),
                                id_A=r.id_A, id_B=r.id_B)
        got = checker.reading(query, wrong)
        assert got <= exact + READING_GAP
        if exact < checker.resolve_below - 1e-4:  # solved: the distance itself
            assert got >= exact - 1e-6
    # the capped query reports what it certifies, each pair at most the cap, and every pair
    # Drake reads within the cap + NARROWPHASE_SLACK is certified (none is left out)
    got = checker.pairs_within(q[k], 3e-3)
    assert got and all(d <= 3e-3 for _, d in got)
    wide = [r for r in query.ComputeSignedDistancePairwiseClosestPoints(3e-3 + NARROWPHASE_SLACK)
            if checker.reading(query, r) <= 3e-3]
    assert sorted(p for p, _ in got) == sorted((r.id_A, r.id_B) for r in wide)


def test_the_planning_bound_covers_what_hides_between_two_samples():
    """PlanContext.cut_clearance: the limit plus the dip of a point passing a hub edge or
    vertex between two samples (the distance along the pass is sqrt(d^2 + s^2)), for any
    phase of the samples along the pass, never below the verifier's limit; the fillet repair
    and the program fit (program_fit.conform_to_program) hold new samples to it."""
    from types import SimpleNamespace

    from drakedeburr.config import default_tolerances
    from drakedeburr.plan.options import PlanContext, PlanOptions

    tol = default_tolerances()
    ctx = PlanContext(cell=None, kin=None, checker=None, free_checker=None,
                      config=SimpleNamespace(tolerances=tol), options=PlanOptions())
    d, step = tol.min_clearance, PlanOptions().dense_step
    margin = ctx.cut_clearance - d
    assert 0 < margin < 10e-6
    # the worst dip over every phase of the two samples against the pass's closest point,
    # samples at both ends reading at least the bound: the minimum between them stays >= d
    s = np.linspace(-step, step, 4001)
    dist = np.sqrt(d ** 2 + s ** 2)
    worst = 0.0
    for phase in np.linspace(0.0, step, 101):
        inside = (s >= phase - step) & (s <= phase)
        ends = np.sqrt(d ** 2 + np.array([phase - step, phase]) ** 2)
        worst = max(worst, ends.min() - dist[inside].min())
    assert worst <= margin
    assert ctx.cut_clearance - worst >= d


def test_a_configuration_read_again_gives_the_readings_of_a_fresh_checker(cell_path,
                                                                          monkeypatch):
    """ClearanceChecker.pairs_within keeps its answers per configuration: a repeat is served
    without a query, and every answer equals that of a checker that never read before."""
    from drakedeburr.plan.kinematics import ClearanceChecker

    cell, kin, checker, q = cell_path
    rows = q[:: max(1, len(q) // 8)]
    first = [checker.pairs_within(qi, 5e-3) for qi in rows]
    queried = []
    real = type(checker)._pairs
    monkeypatch.setattr(type(checker), "_pairs",
                        lambda self, *a: queried.append(1) or real(self, *a))
    again = [checker.pairs_within(qi.copy(), 5e-3) for qi in rows]
    assert not queried and again == first
    again[0].append("x")  # a caller's change does not reach the memo
    assert checker.pairs_within(rows[0], 5e-3) == first[0]
    fresh = ClearanceChecker(cell, filter_burr_contact=checker.filter_burr_contact,
                             tolerances=checker.tolerances)
    assert [fresh.pairs_within(qi, 5e-3) for qi in rows] == first
    assert [checker.distance(qi, 5e-3) for qi in rows] == [fresh.distance(qi, 5e-3)
                                                           for qi in rows]
    # the memo keys the distance too: a wider look is a new query, and finds at least as much
    queried.clear()  # (the fresh checker queried)
    wider = [checker.pairs_within(qi, 8e-3) for qi in rows]
    assert queried and all(len(w) >= len(f) for w, f in zip(wider, first, strict=True))
    # geometric truth: the readings are distances of the pairs at those poses (Drake's own
    # signed distance of the pair is never below the certified reading)
    for qi, pairs in zip(rows, first, strict=True):
        query = fresh.query_at(qi)
        for (a, b), d in pairs:
            assert d <= query.ComputeSignedDistancePairClosestPoints(a, b).distance + 1e-12
