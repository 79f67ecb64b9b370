"""The verifier's distance stage: the tracked sweep reads the same class minima as the cell's
own broad-phase query at every sample, the numpy kinematic tree is the plant's, and the motion
bounds behind the certificate hold on the real trajectory."""

from __future__ import annotations

import numpy as np
import pytest
import verify_support as vs

import drakedeburr.verify.distances as mut
from drakedeburr.cell.chain import KinematicTree
from drakedeburr.resources import add_package_to, resolve_package_url
from drakedeburr.robots import get_robot, robot_names
from drakedeburr.verify import motion_bounds as mb
from drakedeburr.verify.pair_scene import shape_points
from drakedeburr.verify.sweep import sweep


def _samples(plan, n_max=None):
    from drakedeburr.verify.kinematics import VerifyKinematics
    from drakedeburr.verify.sampling import _samples

    cell, _ = vs.cell_and_hub()
    s = _samples(plan, VerifyKinematics(cell), vs.config(**vs.COARSE).tolerances, None)
    return s


def test_tracked_sweep_reads_the_dense_minima(monkeypatch):
    """Per sample and class, the tracked sweep's minimum and pair equal the cell's own
    ComputeSignedDistancePairwiseClosestPoints (the dense reference, each reading certified
    the same way) bit for bit wherever that minimum is within ``narrowphase_resolve`` of the
    class's limit (every reading there is exact, cell.narrowphase). Above it a reading whose
    narrow phase overestimated is kept as its separating-plane bound, which the dense
    reference reads at every pair: the sweep, reading only the pairs that can matter, is then
    at least the dense minimum (never below what it read)."""
    import drakedeburr.verify.sweep as sweep_mod

    cell, _ = vs.cell_and_hub()
    plan = vs.good_plan()
    s = _samples(plan)
    tol = vs.config().tolerances
    monkeypatch.setattr(sweep_mod, "_PART_SAMPLES", 400)  # read in parts, merged
    assert len(sweep_mod.part_bounds(len(s))) >= 4
    sw = sweep(mut.pair_scene_of(cell), plan.trajectory, s.t, s.q, tol, workers=1)
    probe = mut.DistanceProbe(cell, tol.query_distance, tol)
    names = mut.pair_scene_of(cell).pair_names
    mismatch = []
    for i in range(len(s)):
        d = probe.measure(s.q[i])
        for c, (v, pair) in enumerate(((d.clearance, d.clearance_pair),
                                       (d.self_distance, d.self_pair), (d.burr, d.burr_pair))):
            got = sw.best[c, i]
            got_pair = names(sw.best_pair[c, i]) if sw.best_pair[c, i] >= 0 else ("", "")
            if not (got == v or (np.isinf(got) and np.isinf(v))) or got_pair != pair:
                mismatch.append((i, c, got, v))
    level = [tol.min_clearance + tol.narrowphase_resolve, tol.narrowphase_resolve, -np.inf]
    below = [m for m in mismatch if m[3] < level[m[1]] or m[1] == 2 or m[2] < m[3]]
    assert not below, below[:5]
    assert len(mismatch) <= 0.01 * len(s), mismatch[:5]
    # and it reads far fewer pairs than there are pairs x samples
    assert len(sw.rec_pair) < 0.02 * len(s) * len(mut.pair_scene_of(cell).a)


def test_part_bounds_cover_every_sample_whatever_the_machine():
    from drakedeburr.verify.sweep import part_bounds

    for n in (1, 2, 1500, 2999, 3001, 17363, 40000):
        b = part_bounds(n)
        assert b[0][0] == 0 and b[-1][1] == n - 1
        assert all(b[k][1] == b[k + 1][0] for k in range(len(b) - 1))  # one shared sample
        assert all(hi > lo for lo, hi in b) or n == 1


def test_sweep_is_the_same_in_one_process_and_on_a_worker(monkeypatch):
    """The parts read by a pool worker (another process that builds the same cell) give the
    sweep this process reads alone, array for array, and the same narrow-phase tally."""
    import select

    import drakedeburr.pool as parallel
    import drakedeburr.verify.sweep as sweep_mod

    cell, _ = vs.cell_and_hub()
    plan = vs.good_plan()
    s = _samples(plan)
    tol = vs.config().tolerances
    scene = mut.pair_scene_of(cell)
    monkeypatch.setattr(sweep_mod, "_PART_SAMPLES", 600)
    one = sweep(scene, plan.trajectory, s.t, s.q, tol, workers=1)
    tally_one = dict(scene.tally.counts)
    assert cell.recipe is not None  # what a worker builds its cell from
    from_worker = []
    real_map = parallel.map_tasks

    def spy(n, here, remote, workers, done=None, **kw):
        def counted(k, value):
            from_worker.append(k)
            return done(k, value)
        return real_map(n, here, remote, workers, counted, **kw)

    monkeypatch.setattr(parallel, "map_tasks", spy)
    # as `verify PLAN` does: the worker builds the plan's cell before this process has read
    # anything (no fingerprint yet); every part it reads is checked against this cell
    parallel.shutdown_pool(kill=True)
    sweep_mod.warm_workers_for_plan(plan, workers=2)
    worker = parallel._POOL["workers"][0]
    assert worker.task == parallel._WARM
    assert select.select([worker.proc.stdout], [], [], 300)[0]  # the warm-up is done
    two = sweep(scene, plan.trajectory, s.t, s.q, tol, workers=2)
    parallel.shutdown_pool(kill=True)
    assert from_worker  # at least one part came back from the worker
    assert dict(scene.tally.counts) == tally_one
    for f in ("best", "best_pair", "level", "lower", "delta", "e", "rec_sample", "rec_pair",
              "rec_value", "X"):
        assert np.array_equal(getattr(one, f), getattr(two, f)), f
    assert (one.posed, one.refreshes) == (two.posed, two.refreshes)
    # the parts' motion bounds are the whole run's (they depend on each interval alone) and
    # the class minima are exact in both
    monkeypatch.setattr(sweep_mod, "_PART_SAMPLES", 10 ** 9)
    whole = sweep(scene, plan.trajectory, s.t, s.q, tol, workers=1)
    for f in ("best", "best_pair", "X"):
        assert np.array_equal(getattr(one, f), getattr(whole, f)), f
    delta, e = sweep_mod.track_motion(scene, plan.trajectory, s.t, whole.X)
    assert np.array_equal(one.delta, delta) and np.array_equal(one.e, e)


def test_dense_and_tracked_methods_agree():
    cell, _ = vs.cell_and_hub()
    plan = vs.good_plan()
    s = _samples(plan)
    s_short = type(s)(**{k: getattr(s, k)[:300] for k in s.__dataclass_fields__})
    tol = vs.config().tolerances
    dense = mut.measure_samples(cell, s_short, tol, method="dense")
    tracked = mut.measure_samples(cell, s_short, tol, trajectory=plan.trajectory)
    for f in ("clearance", "self_distance", "burr", "clearance_pair", "burr_pair"):
        assert np.array_equal(np.asarray(getattr(dense, f)), np.asarray(getattr(tracked, f))), f
    np.testing.assert_allclose(tracked.manipulability, dense.manipulability, rtol=1e-12,
                               atol=1e-15)
    assert dense.fk_difference <= 1e-12 and tracked.fk_difference <= 1e-12
    assert dense.certificate is None and tracked.certificate is not None
    with pytest.raises(ValueError, match="tracked"):
        mut.measure_samples(cell, s_short, tol, method="magic")


def _arm_plant(name):
    from pydrake.multibody.parsing import Parser
    from pydrake.planning import RobotDiagramBuilder

    builder = RobotDiagramBuilder(0.0)
    plant = builder.plant()
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (robot,) = parser.AddModels(str(resolve_package_url(get_robot(name).model_url)))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base", robot))
    plant.Finalize()
    return builder.Build(), plant


@pytest.mark.parametrize("name", robot_names())
def test_kinematic_tree_is_the_plant_and_reach_bounds_hold(name):
    """Body poses and |det J| vs the Drake plant; each link geometry's distance from every
    joint axis on its path within the reach bound, at random configurations."""
    from pydrake.geometry import Role
    from pydrake.multibody.tree import BodyIndex, JacobianWrtVariable

    diagram, plant = _arm_plant(name)
    tree = KinematicTree(plant)
    rng = np.random.default_rng(0)
    lo, hi = plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    q = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi), (40, plant.num_positions()))
    X = tree.body_poses(q)
    ctx = plant.CreateDefaultContext()
    tip = plant.get_body(BodyIndex(plant.num_bodies() - 1))
    det = tree.jacobian_det(X, int(tip.index()), np.zeros(3))
    for i in range(len(q)):
        plant.SetPositions(ctx, q[i])
        for b in range(plant.num_bodies()):
            X_d = plant.EvalBodyPoseInWorld(ctx, plant.get_body(BodyIndex(b))).GetAsMatrix4()
            np.testing.assert_allclose(X[i, b], X_d, atol=1e-12)
        J = plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kQDot, tip.body_frame(),
                                              np.zeros(3), plant.world_frame(),
                                              plant.world_frame())
        assert det[i] == pytest.approx(abs(np.linalg.det(J)), rel=1e-9, abs=1e-15)
    inspector = diagram.scene_graph().model_inspector()
    X_home = tree.body_poses(np.zeros((1, plant.num_positions())))[0]
    o, a = tree.joint_axes(X)
    checked = 0
    for g in inspector.GetAllGeometryIds(Role.kProximity):
        body = int(plant.GetBodyFromFrameId(inspector.GetFrameId(g)).index())
        link, path = tree.link_of[body], tree.path_of[body]
        if not path:
            continue
        X_LG = np.linalg.inv(X_home[link]) @ X_home[body] @ inspector.GetPoseInFrame(
            g).GetAsMatrix4()
        pts = shape_points(inspector.GetShape(g)) @ X_LG[:3, :3].T + X_LG[:3, 3]
        c = 0.5 * (pts.min(0) + pts.max(0))
        rho = float(np.linalg.norm(pts - c, axis=1).max())
        reach = tree.reach(X_home, path, link, c, rho)
        p_W = np.einsum("nij,kj->nki", X[:, link, :3, :3], pts) + X[:, link, None, :3, 3]
        for j, k in enumerate(path):
            v = p_W - o[:, None, k]
            off = np.linalg.norm(v - np.einsum("nkd,nd->nk", v, a[:, k])[..., None]
                                 * a[:, None, k], axis=2)
            assert off.max() <= reach[j] + 1e-12, (name, g, k)
            checked += 1
    assert checked > 10


def test_motion_bounds_hold_on_the_trajectory():
    """For every track of the cell and random intervals of the good plan (inside one piece):
    every point of the track's geometry stays within s delta + e of where it was at the start
    and (1 - s) delta + e of where it is at the end (dense evaluation, relative to the
    reference link)."""
    cell, _ = vs.cell_and_hub()
    scene = mut.pair_scene_of(cell)
    tree, tracks, traj = scene.tree, scene.tracks, vs.good_plan().trajectory
    rng = np.random.default_rng(1)
    pieces = rng.integers(0, len(traj.t) - 1, 60)
    t_a = traj.t[pieces] + rng.uniform(0, 0.5, 60) * np.diff(traj.t)[pieces]
    h = rng.uniform(0.2, 0.5, 60) * (traj.t[pieces + 1] - t_a)
    qd, qdd = mb.rate_bounds(traj, t_a, h)
    # the rate bounds hold on a dense grid
    s = np.linspace(0, 1, 41)
    tt = t_a[:, None] + h[:, None] * s[None]
    assert np.all(np.abs(traj.derivative(tt.ravel(), 1).reshape(60, 41, 6))
                  <= qd[:, None] + 1e-12)
    assert np.all(np.abs(traj.derivative(tt.ravel(), 2).reshape(60, 41, 6))
                  <= qdd[:, None] + 1e-9)
    X = tree.body_poses(traj.value(tt.ravel())).reshape(60, 41, tree.n_bodies, 4, 4)
    worst = 0.0
    for k in range(len(tracks)):
        g = scene.track_geometry[k]
        pts = shape_points(scene._inspector.GetShape(scene.ids[g]))
        X_LG = scene.X_LG[g]
        pts_L = pts @ X_LG[:3, :3].T + X_LG[:3, 3]
        which = np.full(60, k)
        delta, e = mb.track_interval_bounds(tracks, which, X[:, 0], X[:, -1], qd, qdd, h)
        R, p = mb.relative_pose(X.reshape(-1, tree.n_bodies, 4, 4), tracks.ref[k],
                                tracks.link[k])
        P = (np.einsum("nij,kj->nki", R, pts_L) + p[:, None]).reshape(60, 41, -1, 3)
        from_a = np.linalg.norm(P - P[:, :1], axis=3).max(axis=2)
        from_b = np.linalg.norm(P - P[:, -1:], axis=3).max(axis=2)
        bound_a = s[None] * delta[:, None] + e[:, None]
        bound_b = (1 - s[None]) * delta[:, None] + e[:, None]
        assert np.all(from_a <= bound_a + 1e-12) and np.all(from_b <= bound_b + 1e-12), k
        worst = max(worst, float(np.max(from_a / np.maximum(bound_a, 1e-300))))
    assert worst > 0.3  # the bounds are not vacuous


def test_interval_lower_bound_is_the_smallest_of_the_two_cones():
    rng = np.random.default_rng(2)
    d_a, d_b = rng.uniform(0, 5, 200), rng.uniform(0, 5, 200)
    delta, e = rng.uniform(0, 4, 200), rng.uniform(0, 0.1, 200)
    s = np.linspace(0, 1, 20001)
    brute = np.min(np.maximum(d_a[:, None] - s * delta[:, None],
                              d_b[:, None] - (1 - s) * delta[:, None]), axis=1) - e
    np.testing.assert_allclose(mb.interval_lower_bound(d_a, d_b, delta, e), brute, atol=1e-3)
    assert np.all(mb.interval_lower_bound(d_a, d_b, delta, e) <= brute + 1e-12)
