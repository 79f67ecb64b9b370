"""Per-target IK of the real chain around a window fillet, re-checked with Drake's FK and the
cell's signed distances; the analytic-first shortcut against the Drake program at every target."""

from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif(not hub_names(), reason="no bundled hub models")


@pytest.fixture(scope="module")
def fillet():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    cell = load_cell("tool_in_hand", DEFAULT_HUB)
    wt = window_targets_for_hub(load_hub(DEFAULT_HUB), source="toolpath", windows=[0])[0]
    # 30 targets around the sharpest turn of the edge
    turn = np.arccos(np.clip(np.sum(wt.t_H * np.roll(wt.t_H, -1, axis=0), 1), -1, 1))
    seg = np.linalg.norm(np.roll(wt.p_HC, -1, axis=0) - wt.p_HC, axis=1)
    k = int(np.argmax(turn / np.maximum(seg, 1e-4)))
    wt = wt.stretch(max(0, k - 15), max(0, k - 15) + 30)
    r_c, lift = contact_geometry(PlanOptions().contact_radius)
    p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    return cell, cell_kinematics(cell), ClearanceChecker(cell), wt, p_HQ, lift


def _context(fillet, ik):
    from drakedeburr.config import default_tolerances
    from drakedeburr.plan.options import PlanContext, PlanOptions

    cell, kin, checker = fillet[:3]
    return PlanContext(cell=cell, kin=kin, checker=checker, free_checker=None,
                       config=SimpleNamespace(tolerances=default_tolerances()),
                       options=PlanOptions(ik=ik))


def _targets(fillet):
    from drakedeburr.plan.ik import IkTargets

    wt, p_HQ, lift = fillet[3:]
    return IkTargets(p_HQ, wt.retract_H, wt.cone_retract_H, wt.t_H, wt.cone_half_angle, lift)


def _solve(fillet, analytic_first):
    from drakedeburr.plan.ik import IkOptions, solve_window_ik

    ctx = _context(fillet, IkOptions(analytic_first=analytic_first))
    return ctx.options.ik, solve_window_ik(ctx, _targets(fillet), fillet[0].q_home)


def _drake_recheck(fillet, q, opts):
    """Position of the constrained point, angle to the cone axis, clearance: Drake's FK and the
    scene graph, not the planner's analytic kinematics."""
    cell, _, checker, wt, p_HQ, lift = fillet
    ctx = cell.plant.CreateDefaultContext()
    err, ang, clear = [], [], []
    for i, qi in enumerate(q):
        cell.plant.SetPositions(ctx, qi)
        X = cell.plant.CalcRelativeTransform(ctx, cell.hub_frame, cell.tool_frame)
        p = X.translation() + lift * X.rotation().matrix()[:, 2]
        err.append(np.linalg.norm(p - p_HQ[i]))
        axis = -X.rotation().matrix()[:, 2]
        ang.append(np.arccos(np.clip(axis @ wt.cone_retract_H[i], -1, 1)))
        clear.append(checker.min_distance(qi, 0.01)[0])
    return np.array(err), np.array(ang), np.array(clear)


@pytest.mark.parametrize("analytic_first", [True, False], ids=["analytic-first", "drake-all"])
def test_every_target_meets_the_program_constraints(fillet, analytic_first):
    cell, kin, _, wt, _, _ = fillet
    opts, wik = _solve(fillet, analytic_first)
    assert wik.ok.all(), wik.failures
    err, ang, clear = _drake_recheck(fillet, wik.q, opts)
    assert err.max() <= 10 * opts.position_tolerance
    assert ang.max() <= wt.cone_half_angle + 1e-6
    assert clear.min() >= opts.min_distance_floor - 1e-6
    assert np.all(kin.within_limits(wik.q))
    # one configuration: small steps, the wrist on one side and off its singularity
    assert np.max(np.abs(np.diff(wik.q, axis=0))) <= opts.trust_region + 1e-9
    assert np.all(np.sign(wik.q[:, 4]) == np.sign(wik.q[0, 4]))
    assert np.min(np.abs(wik.q[:, 4])) >= opts.min_wrist - 1e-6


def test_analytic_first_takes_the_preferred_axis_and_solves_the_rest_with_drake(fillet):
    cell, kin, checker, wt, _, _ = fillet
    opts, fast = _solve(fillet, True)
    _, full = _solve(fillet, False)
    n = len(wt)
    accepted = fast.stats["analytic_accepted"]
    assert 0 < accepted < n  # the fillet has targets where the preferred axis lacks clearance
    # where the warm start was taken, the axis is the preferred one exactly
    axis = -fast.X_HT[:, :3, 2]
    pref_angle = np.arccos(np.clip(np.sum(axis * wt.retract_H, 1), -1, 1))
    assert np.sum(pref_angle < 1e-6) >= accepted
    # where Drake solved with the distance constraint active, it tilted the axis for clearance
    # and both variants agree on how much room there is (same program, same bound)
    _, _, clear_fast = _drake_recheck(fillet, fast.q, opts)
    _, _, clear_full = _drake_recheck(fillet, full.q, opts)
    assert abs(clear_fast.min() - clear_full.min()) < 0.2e-3
    assert full.stats["analytic_accepted"] == 0


def test_cone_probe_tells_unreachable_targets_from_solver_failures():
    """h5_deepdish with the source's theta box (0.26-0.44 rad) has a stretch of every window
    where the spindle body meets the rising dish face at every axis in the cone: the probe must
    say so and name the pair; elsewhere it must return a pose that is admissible (Drake FK) and
    clear. The hub's own recipe (process.yaml: the small windows' box) clears that stretch."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import ProcessParameters
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.ik import IkOptions, cone_clearance_probe
    from drakedeburr.plan.ik_seeds import IkTarget, ProbeSettings, unreachable
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    if "h5_deepdish" not in hub_names():
        pytest.skip("h5_deepdish not bundled")
    cell = load_cell("tool_in_hand", "h5_deepdish")
    kin, checker = cell_kinematics(cell), ClearanceChecker(cell)
    hub = load_hub("h5_deepdish")
    r_c, lift = contact_geometry(PlanOptions().contact_radius)
    bound = IkOptions().min_distance_floor
    settings = ProbeSettings(bound=bound, lift=lift)

    def probe(wt, i, ch=checker):
        p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
        return p_HQ[i], cone_clearance_probe(
            kin, ch, IkTarget(p_HQ[i], wt.cone_retract_H[i], wt.retract_H[i], wt.t_H[i]),
            wt.cone_half_angle, cell.q_home, settings)

    def assert_admissible(wt, i, p_HQ, res):
        assert res.feasible
        ctx = cell.plant.CreateDefaultContext()
        cell.plant.SetPositions(ctx, res.q)
        X = cell.plant.CalcRelativeTransform(ctx, cell.hub_frame, cell.tool_frame)
        R = X.rotation().matrix()
        assert np.linalg.norm(X.translation() + lift * R[:, 2] - p_HQ) < 1e-6
        assert (np.arccos(np.clip(-R[:, 2] @ wt.cone_retract_H[i], -1, 1))
                <= wt.cone_half_angle + 1e-9)
        assert checker.min_distance(res.q, 0.01)[0] >= bound
        assert kin.within_limits(res.q)

    source_box = window_targets_for_hub(hub, source="toolpath", windows=[4],
                                        params=ProcessParameters())[0]
    # the blocked stretch: the CL point whose tool point is deepest in the dish's wall region
    # (CL 57-64 of 109 with the planner's CL settings; scanned from the middle of the loop)
    r, i_blocked = None, -1
    for i in range(len(source_box) // 2, len(source_box) // 2 + 16):
        _, r = probe(source_box, i)
        if not r.feasible:
            i_blocked = i
            break
    assert not r.feasible, "expected targets no axis in the cone can reach"
    # every axis of the cone read (2 + 3 rings x 16), the blocked ones no further
    assert r.best_clearance < bound and r.queries >= 50
    assert any("spindle" in name for name in r.pair) and any("hub" in n for n in r.pair)
    assert_admissible(source_box, 0, *probe(source_box, 0))
    # the hub's recipe: same CL points (the path stage does not depend on the box), other cone
    assert hub.process.bounds_large.theta_max <= ProcessParameters().bounds_large.theta_min
    recipe = window_targets_for_hub(hub, source="toolpath", windows=[4])[0]
    assert np.allclose(recipe.p_HC, source_box.p_HC)
    assert_admissible(recipe, i_blocked, *probe(recipe, i_blocked))
    # poses in contact are ranked by their penetration and rejected by Drake's contact test,
    # not read by the signed distances: reading every pose's distances instead gives the same
    # verdicts, and a clear pose found either way is admissible
    # (and axes blocked by a spin-invariant pair are not searched past their first pose)
    slow = ClearanceChecker(cell)
    slow.collides = lambda q: False
    slow.axis_reading = lambda q, cap: (ClearanceChecker.distance(slow, q, cap), np.inf)
    for wt, i in ((source_box, i_blocked), (source_box, 0), (recipe, i_blocked)):
        p_HQ, fast = probe(wt, i)
        full = probe(wt, i, slow)[1]
        assert fast.feasible == full.feasible
        assert unreachable(fast, IkOptions()) == unreachable(full, IkOptions())
        assert fast.queries <= full.queries
        if fast.feasible:
            assert_admissible(wt, i, p_HQ, fast)
    # the memo: the same target probed again (another start on the same branch) is answered
    # without a query, with what a fresh checker's search returns; another branch is searched
    calls = []
    counted = ClearanceChecker(cell)
    read = counted.axis_reading
    counted.axis_reading = lambda q, cap: calls.append(1) or read(q, cap)
    p_HQ, first = probe(source_box, i_blocked, counted)
    n_first = len(calls)
    again = probe(source_box, i_blocked, counted)[1]
    assert n_first > 0 and len(calls) == n_first
    fresh = probe(source_box, i_blocked, ClearanceChecker(cell))[1]
    for res in (again, fresh):
        assert res.feasible == first.feasible and res.pair == first.pair
        assert res.best_clearance == first.best_clearance
        assert np.array_equal(res.q, first.q) and res.q is not first.q
    q_other = cell.q_home.copy()
    q_other[4] = -q_other[4]  # the other wrist branch
    assert not np.array_equal(kin.branch_of(q_other), kin.branch_of(cell.q_home))
    cone_clearance_probe(kin, counted, IkTarget(
        p_HQ, source_box.cone_retract_H[i_blocked], source_box.retract_H[i_blocked],
        source_box.t_H[i_blocked]), source_box.cone_half_angle, q_other, settings)
    assert len(calls) > n_first
    # the ranking value: the certified distance of a clear pose, minus the depth in contact
    assert checker.ranked_distance(cell.q_home, 0.01) == checker.distance(cell.q_home, 0.01) > 0
    from drakedeburr.plan.ik_seeds import _probe_candidates

    p_HQ = tool_point_H(source_box.p_HC, source_box.n_H, source_box.retract_H,
                        source_box.depth_of_cut, r_c, 0.0)[i_blocked]
    poses = np.concatenate(_probe_candidates(
        kin, p_HQ, [source_box.cone_retract_H[i_blocked]], source_box.t_H[i_blocked],
        cell.q_home, settings))
    hits = [q for q in poses if checker.collides(q)]
    assert hits, "expected poses of the blocked target in contact"
    for q in hits[:5]:
        ranked, signed = checker.ranked_distance(q, 0.01), checker.distance(q, 0.01)
        assert ranked < 0 and signed <= 0
    # spin invariance (geometric truth): every pose of one axis at a target (other spins,
    # other branches) puts each spin-invariant tool geometry at the same pose relative to each
    # geometry rigidly attached to the hub, up to a turn about its own axis (the third row of
    # the relative transform and the Gram matrix of its first two rows are unchanged); the
    # spindle bracket, not symmetric about the burr axis, is not invariant and moves
    invariant = checker.spin_invariant()
    inspector = cell.scene_graph.model_inspector()
    ids = [g for g in inspector.GetAllGeometryIds() if inspector.GetProximityProperties(g)]
    named = {inspector.GetName(g): g for g in ids}
    sym = {g for g in ids if any(invariant(g, h) for h in cell.hub_ids)}
    assert {inspector.GetName(g) for g in sym} >= {"spindle::spindle_body", "spindle::collet",
                                                   "spindle::burr_shank"}
    assert named["spindle::bracket"] not in sym and named["spindle::burr_head"] not in sym
    hub_some = sorted(cell.hub_ids, key=lambda g: g.get_value())[::40]

    def relative(q, g, h):
        query = checker.query_at(q)
        X = np.linalg.inv(query.GetPoseInWorld(g).GetAsMatrix4()) @ query.GetPoseInWorld(
            h).GetAsMatrix4()
        return X[2], X[:2].T @ X[:2]

    spun = poses[:: max(1, len(poses) // 6)]
    assert len(spun) >= 4
    for g in (*sym, named["spindle::bracket"]):
        for h in hub_some:
            ref = relative(spun[0], g, h)
            same = all(np.allclose(a, b, atol=1e-9) for q in spun[1:]
                       for a, b in zip(ref, relative(q, g, h), strict=True))
            assert same == (g in sym), inspector.GetName(g)
    # the figure the probe prunes with: an invariant pair in contact at one pose is in
    # contact at all; clear, its Drake reading bounds every pose's clearance from above
    upper = checker.axis_reading(spun[0], 0.01)[1]
    assert upper < 0
    assert all(checker.collides(q) for q in spun)
    p_HQ2 = tool_point_H(recipe.p_HC, recipe.n_H, recipe.retract_H, recipe.depth_of_cut, r_c,
                         0.0)[i_blocked]
    clear = np.concatenate(_probe_candidates(
        kin, p_HQ2, [recipe.cone_retract_H[i_blocked]], recipe.t_H[i_blocked], cell.q_home,
        settings))
    upper = checker.axis_reading(clear[0], 0.01)[1]
    assert 0 < upper < 0.01
    for q in clear[:: max(1, len(clear) // 6)]:
        assert checker.ranked_distance(q, 0.01) <= upper + 1e-9


class _AxisField:
    """A stand-in for the cell's distance queries: every pose reads ``top - slope * angle``
    from its tool axis to the axis ``peak`` (a distance that depends on the axis alone, as a
    spin-invariant pair's does), never in contact."""

    def __init__(self, kin, peak, top, slope):
        self.kin, self.peak, self.top, self.slope = kin, peak, top, slope

    def value(self, axis):
        return self.top - self.slope * np.arccos(np.clip(axis @ self.peak, -1.0, 1.0))

    def axis_of(self, q):
        return -self.kin.X_HT_from_q(q)[:3, 2]

    def axis_reading(self, q, cap):
        d = self.value(self.axis_of(q))
        return d, d

    def collides(self, q):
        return False

    def min_distance(self, q, cap):
        return self.axis_reading(q, cap)[0], ("spindle::burr/spindle::burr_shank", "hub::hub")

    def memo_probe(self, key, compute):  # the checker's probe memo: none in the stand-in
        return compute()


def test_a_near_miss_is_searched_between_the_sampled_axes(fillet):
    """Where the sampled axes come within NEAR_MISS of the bound, a search between them finds
    the best axis in the cone: a field peaking 1.3 half-angles off the cone axis, between two
    sampled azimuths, is best on the rim toward the peak. With that best above the bound the
    probe returns a pose there (in the cone, reading above the bound); below it, the largest
    reading found is the field's maximum over the cone to 1 um, and the target is unreachable
    although the sampled best alone is a near miss."""
    from drakedeburr.frames.vectors import perpendicular_basis
    from drakedeburr.plan.ik import IkOptions, cone_clearance_probe
    from drakedeburr.plan.ik_seeds import NEAR_MISS, IkTarget, ProbeSettings, unreachable

    cell, kin, _, wt, p_HQ, lift = fillet
    bound = IkOptions().min_distance_floor
    c = wt.cone_retract_H[0] / np.linalg.norm(wt.cone_retract_H[0])
    half = wt.cone_half_angle
    e1, e2, _ = perpendicular_basis(c).T
    phi = np.radians(11.25)  # half way between two of the 16 sampled azimuths
    ring = np.cos(phi) * e1 + np.sin(phi) * e2
    peak = np.cos(1.3 * half) * c + np.sin(1.3 * half) * ring
    slope = 0.01  # [m/rad]
    best_in_cone = slope * 0.3 * half  # below the peak, on the rim toward it
    for margin in (0.02e-3, -0.03e-3):
        field = _AxisField(kin, peak, bound + margin + best_in_cone, slope)
        res = cone_clearance_probe(kin, field, IkTarget(p_HQ[0], c, wt.retract_H[0], wt.t_H[0]),
                                   half, cell.q_home, ProbeSettings(bound=bound, lift=lift))
        sampled = max(field.value(np.cos(r * half) * c + np.sin(r * half) * (
            np.cos(f) * e1 + np.sin(f) * e2)) for r in (0.0, 0.33, 0.66, 0.98)
            for f in np.linspace(0, 2 * np.pi, 16, endpoint=False))
        assert bound - NEAR_MISS <= sampled < bound  # the case: a near miss when sampled
        if margin > 0:
            assert res.feasible and not unreachable(res, IkOptions())
            axis = field.axis_of(res.q)
            assert np.arccos(np.clip(axis @ c, -1, 1)) <= half + 1e-9
            assert field.value(axis) >= bound
            X = kin.X_HT_from_q(res.q)
            assert np.linalg.norm(X[:3, 3] + lift * X[:3, 2] - p_HQ[0]) < 1e-6
        else:
            assert not res.feasible and unreachable(res, IkOptions())
            assert res.best_clearance >= bound - NEAR_MISS  # the sampled verdict alone
            assert abs(res.axis_bound - (bound + margin)) < 1e-6
            assert res.axis_bound <= bound + margin + 1e-12


#: how close the forward IK from the tracked-back start arrives at the probe's pose [rad], per
#: warm-start spin rule: measured 5e-5 (joint cost) and 2.9e-3 (frame: each target keeps the
#: previous frame's spin, so the forward track is not the backward one's exact reverse; the
#: first track arrived 1.8 rad off)
ARRIVAL = {"joint_cost": 1e-3, "frame": 5e-3}


@pytest.mark.parametrize("rule", sorted(ARRIVAL))
def test_a_start_tracked_back_from_an_admissible_pose_arrives_there(fillet, rule):
    """When a window's IK fails at a target where its cone probe found an admissible pose, a
    start is tracked back from that pose to the first target (window._backward_seed): the
    start meets the first target (Drake's FK: position, cone, clearance), and the forward IK
    from it reaches every target up to the failed one, arriving at the probe's pose
    (:data:`ARRIVAL`), with either warm-start spin rule."""
    from dataclasses import replace

    from drakedeburr.plan.ik import cone_clearance_probe, solve_window_ik
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.types import FailureRecord
    from drakedeburr.plan.window import _backward_seed

    cell, kin, checker, wt, p_HQ, lift = fillet
    options = PlanOptions()
    options = replace(options, ik=replace(options.ik, seed_spin=rule))
    opts = options.ik
    ctx = PlanContext(cell=cell, kin=kin, checker=checker, free_checker=None, config=None,
                      options=options)

    def forward(q_first):
        return solve_window_ik(ctx, _targets(fillet), cell.q_home, q_first=q_first,
                               stop_at_failure=True)

    trial = forward(None)
    i = 20
    assert trial.ok[:i + 1].all()
    probe = cone_clearance_probe(kin, checker, _targets(fillet).at(i),
                                 max(float(wt.cone_half_angle), 1e-3), trial.q[i - 1],
                                 opts.probe_settings(lift))
    assert probe.feasible
    failed = replace(trial, ok=np.arange(len(trial.ok)) < i, failures=(FailureRecord(
        window=wt.window_index, kind="ik", point=i, reason="stand-in failure"),),
        probes={i: probe})
    loop = np.arange(len(wt))
    assert _backward_seed(ctx, wt, loop, p_HQ, lift, replace(failed, probes={}), i) is None
    start = _backward_seed(ctx, wt, loop, p_HQ, lift, failed, i)
    assert start is not None
    err, ang, clear = _drake_recheck(fillet, start[None], opts)
    assert err[0] < 1e-5 and ang[0] <= wt.cone_half_angle + 1e-6
    assert clear[0] >= opts.min_distance_floor - 1e-9 and kin.within_limits(start)
    again = forward(start)
    assert again.ok[:i + 1].all()
    err, ang, clear = _drake_recheck(fillet, again.q[:i + 1], opts)
    assert err.max() < 1e-5 and ang.max() <= wt.cone_half_angle + 1e-6
    assert clear.min() >= opts.min_distance_floor - 1e-9
    # the probe's pose is of another family than the one the first track arrived in (5e-5
    # rad from it when written, the first track 1.8 rad off)
    assert np.abs(trial.q[i] - probe.q).max() > opts.trust_region
    assert np.abs(again.q[i] - probe.q).max() <= ARRIVAL[rule]


def test_the_ik_clearance_bounds_follow_the_tolerance(fillet):
    """The IK's bounds are Tolerances.min_clearance plus their margins, as the planning
    context holds them: a pose whose clearance d is read by the cell is accepted as a target's
    solution with the tolerance 10 um below d - CLEARANCE_MARGIN and refused 10 um above it."""
    from dataclasses import replace

    from drakedeburr.config import default_tolerances
    from drakedeburr.plan.ik import CLEARANCE_MARGIN, FLOOR_MARGIN, IkOptions, seed_by_spin
    from drakedeburr.plan.ik_seeds import analytic_accept

    cell, kin, checker, wt, p_HQ, lift = fillet
    for c in (2e-3, 3e-3):
        ik = _context(fillet, IkOptions()).options.ik if c == 2e-3 else replace(
            _context(fillet, IkOptions()), config=SimpleNamespace(
                tolerances=default_tolerances(min_clearance=c))).options.ik
        assert ik.min_distance == pytest.approx(c + CLEARANCE_MARGIN, abs=1e-15)
        assert ik.min_distance_floor == pytest.approx(c + FLOOR_MARGIN, abs=1e-15)
        assert ik.probe_settings(lift).bound == ik.min_distance_floor
    opts = IkOptions()
    q = seed_by_spin(kin, None, p_HQ[0] + lift * wt.retract_H[0], wt.retract_H[0], wt.t_H[0],
                     cell.q_home, opts)
    d = checker.distance(q, 0.05)
    assert 0 < d < 0.05
    anchor = q + np.array([1e-3, 0, 0, 0, 0, 0])
    target = _targets(fillet).at(0)
    for shift, accepted in ((-1e-5, True), (1e-5, False)):
        ik = opts.at_clearance(d - CLEARANCE_MARGIN + shift)
        got = analytic_accept(kin, checker, q, anchor, target, wt.cone_half_angle, ik, lift)
        assert (got is not None) == accepted, (shift, d)
        if accepted:
            assert got[1] == pytest.approx(d, abs=1e-9)


def test_a_program_solved_again_is_answered_from_the_memo_with_the_same_bits(fillet,
                                                                              monkeypatch):
    from pydrake.solvers import SnoptSolver

    import drakedeburr.plan.ik as mut

    opts = mut.IkOptions(analytic_first=False)
    ctx = _context(fillet, opts)
    mut._SOLVED.pop(ctx.checker, None)
    first = mut.solve_window_ik(ctx, _targets(fillet), fillet[0].q_home)
    assert mut._SOLVED[ctx.checker]  # every target ran the Drake program
    calls = []
    real = mut._solve_program
    monkeypatch.setattr(mut, "_solve_program", lambda *a: calls.append(1) or real(*a))
    again = mut.solve_window_ik(ctx, _targets(fillet), fillet[0].q_home)
    assert not calls  # the same window again: every program answered from the memo
    assert again.q.tobytes() == first.q.tobytes() and again.ok.tolist() == first.ok.tolist()
    assert again.X_HT.tobytes() == first.X_HT.tobytes()
    # the memo's answer is the program's own: solved afresh, the same bits
    run = SimpleNamespace(cell=fillet[0], checker=ctx.checker, lift=fillet[5],
                          half=max(float(fillet[3].cone_half_angle), 1e-3))
    tg, solver, q1 = _targets(fillet).at(1), SnoptSolver(), first.q[0]
    served = mut._solve_point(run, tg, q1, q1, False, solver, opts)
    fresh = real(run, tg, q1, q1, False, solver, opts)
    assert served[0] == fresh[0] and served[1].tobytes() == fresh[1].tobytes()
    served[1][:] = 0.0  # a caller's change does not reach the memo
    assert mut._solve_point(run, tg, q1, q1, False, solver, opts)[1].tobytes() == \
        fresh[1].tobytes()
    # and the solutions hold the program's constraints (Drake's FK and distances)
    err, ang, clear = _drake_recheck(fillet, again.q, opts)
    assert first.ok.all()
    assert np.all(err <= 10 * opts.position_tolerance)
    assert np.all(ang <= fillet[3].cone_half_angle + 1e-6)
    assert np.all(clear >= opts.min_distance - 1e-5)
