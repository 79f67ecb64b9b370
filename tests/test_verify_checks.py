"""verify_plan: a good plan passes; injected faults fail with the right item named."""

from __future__ import annotations

import numpy as np
import pytest
import verify_support as vs

import drakedeburr.verify.checks as mut
from drakedeburr.errors import InputError
from drakedeburr.plan.types import JointTrajectory
from drakedeburr.verify import faults
from drakedeburr.verify.geometry import closed_polyline_distance, point_segment, spline_extremes
from drakedeburr.verify.report import report_json


def test_good_plan_passes_dense():
    report = vs.good_report()
    assert report.passed, report.failed
    names = [i.name for i in report.items]
    for required in ("path_deviation", "edge_deviation", "cone", "clearance", "self_collision",
                     "burr_contact", "joint_position", "joint_velocity", "joint_acceleration",
                     "tcp_speed_band", "tcp_speed_max", "wrist_singularity", "windows",
                     "fk_agreement", "cl_chord_error", "configuration"):
        assert required in names
    tol = report.settings["tolerances"]
    assert report.item("path_deviation").value <= tol["path_deviation"]
    assert report.item("fk_agreement").value <= 1e-9
    # dense: every 0.5 mm of tool travel on the cuts
    s = report.series
    cut = s["kind"] == 3
    for w in vs.WINDOWS:
        p = s["p_HT"][cut & (s["window"] == w)]
        assert np.linalg.norm(np.diff(p, axis=0), axis=1).max() <= tol["dense_step"] + 1e-9


def test_clearance_matches_drake_pairwise_query():
    """Second implementation: the cell's own broad-phase query at the worst sample."""
    report = vs.good_report()
    cell, _ = vs.cell_and_hub()
    item = report.item("clearance")
    q = vs.good_plan().trajectory.value(item.time)
    d, pair = cell.min_distance(q, max_distance=0.05)
    if "hub::" in pair[0] + pair[1] or "fixture::" in pair[0] + pair[1]:
        # the same pair: Drake's GJK converges from above and stops at a tolerance, and the
        # verifier's reading is the certified one (cell/narrowphase.py: Drake's kept where it
        # meets the separating-plane bound within 1 um, else solved again): never above
        # Drake's, below it only by Drake's stopping error (2.6 um seen on the shank)
        assert item.value <= d + 1e-12
        assert d - item.value <= 10e-6
    else:
        # a self pair nearer than every environment pair
        assert d <= item.value + 1e-12


def test_json_is_deterministic_apart_from_run():
    plan = vs.good_plan()
    coarser = {"dense_step": 5e-3, "time_step": 0.5}
    a = vs.verify(plan, sampling=coarser)
    b = vs.verify(plan, sampling=coarser)
    assert a.passed and b.passed
    assert report_json(a, include_run=False) == report_json(b, include_run=False)
    assert '"run"' in report_json(a)


def test_knot_shifted_into_hub_fails_contact_and_deviation():
    plan = vs.good_plan()
    cell, _ = vs.cell_and_hub()
    k = faults.cut_knot_index(plan, window=0)
    bad = faults.shift_knot_into_hub(plan, k, depth=0.005, cell=cell)
    report = vs.verify(bad)
    assert not report.passed
    for name in ("path_deviation", "burr_contact"):
        assert name in report.failed
    item = report.item("burr_contact")
    assert "hub::" in item.pair[1] and "burr_head" in item.pair[0]
    assert item.window == 0
    tk = plan.trajectory.t
    assert abs(item.time - tk[k]) <= tk[k + 1] - tk[k - 1]
    assert report.item("path_deviation").value == pytest.approx(0.005, rel=0.05)


def test_velocity_fault_names_joint_velocity():
    plan = vs.good_plan()
    si = next(i for i, s in enumerate(plan.segments) if s.kind == "transition")
    bad = faults.speed_up_segment(plan, si, factor=4.0)
    report = vs.verify(bad)
    assert "joint_velocity" in report.failed
    item = report.item("joint_velocity")
    seg = bad.segments[si]
    assert seg.t_range[0] <= item.time <= seg.t_range[1]
    assert item.value > 1.0


def test_axis_out_of_cone_names_cone():
    from drakedeburr.verify.synthetic import ReferenceOptions, reference_plan

    plan = reference_plan(vs.SCENARIO, vs.HUB, [0], params=vs.PARAMS,
                          options=ReferenceOptions(axis_tilt={0: -0.5}))
    report = vs.verify(plan, expected_windows=[0])
    assert "cone" in report.failed
    item = report.item("cone")
    assert item.window == 0 and item.value < -0.02


def test_dropped_window_names_window():
    plan = vs.good_plan()
    bad = faults.drop_window(plan, 1)
    report = vs.verify(bad)
    assert "windows" in report.failed
    item = report.item("windows")
    assert item.window == 1 and "[1]" in item.detail
    assert report.item("structure").passed


def test_malformed_plan_is_input_error():
    plan = vs.good_plan()
    t = plan.trajectory.t.copy()
    t[5] = t[4]
    bad = faults.replace(plan, trajectory=JointTrajectory(t=t, c=plan.trajectory.c))
    with pytest.raises(InputError, match="strictly increasing at knot 5"):
        mut.verify_plan(bad, vs.config())
    short = faults.replace(plan, trajectory=JointTrajectory(t=plan.trajectory.t,
                                                            c=plan.trajectory.c[:, :-1]))
    with pytest.raises(InputError, match="pieces must be"):
        mut.verify_plan(short, vs.config())


def test_spline_extremes_are_certified():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.05, 0.3, 12))
    t -= t[0]
    traj = JointTrajectory.from_hermite(t=t, q=rng.normal(0, 1, (12, 6)),
                                        qd=rng.normal(0, 2, (12, 6)))
    ext = spline_extremes(traj)
    tt = np.linspace(t[0], t[-1], 200001)
    for key, order in (("q", 0), ("qd", 1), ("qdd", 2)):
        dense = traj.value(tt) if order == 0 else traj.derivative(tt, order)
        vals, _, rem = ext[key]
        # the readings plus the remainder bound every sample, and come close to them
        top = (vals + rem[:, None]).max(axis=(0, 1))
        bottom = (vals - rem[:, None]).min(axis=(0, 1))
        scale = np.abs(dense).max(axis=0)
        assert np.all(top >= dense.max(axis=0) - 1e-9 * scale)
        assert np.all(bottom <= dense.min(axis=0) + 1e-9 * scale)
        assert np.allclose(top, dense.max(axis=0), rtol=0, atol=1e-3 * scale.max())
        assert np.allclose(bottom, dense.min(axis=0), rtol=0, atol=1e-3 * scale.max())


def test_point_segment_distances_against_brute_force():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(50, 3))
    a = rng.normal(size=(7, 3))
    b = a + rng.normal(size=(7, 3))
    d, k, f = point_segment(p, a, b)
    s = np.linspace(0, 1, 2001)
    pts = a[:, None] + s[None, :, None] * (b - a)[:, None]  # (7, 2001, 3)
    for i in range(len(p)):
        best = np.linalg.norm(pts - p[i], axis=2).min()
        assert d[i] == pytest.approx(best, abs=1e-5)
        assert np.linalg.norm(p[i] - (a[k[i]] + f[i] * (b[k[i]] - a[k[i]]))) == pytest.approx(d[i])
    loop = np.c_[np.cos(np.linspace(0, 2 * np.pi, 200, endpoint=False)),
                 np.sin(np.linspace(0, 2 * np.pi, 200, endpoint=False)), np.zeros(200)]
    q = rng.normal(size=(30, 3)) * 0.3 + np.array([0.8, 0, 0])
    d2, c = closed_polyline_distance(q, loop)
    dd, _, _ = point_segment(q, loop, np.roll(loop, -1, axis=0))
    assert np.allclose(d2, dd, atol=1e-12)


def test_point_segment_pruned_reading_equals_the_reading_against_every_segment():
    """Many points against many segments are read against the nearest few first (KD-tree of
    the midpoints): the same distances, segments and fractions bit for bit as against every
    segment - on a sampled loop, at its vertices (a tie between two segments goes to the
    first, as against every segment), far from it (no segment settles at once), and where
    a long segment's half-length keeps points open (the fallback)."""
    import drakedeburr.verify.geometry as geo

    rng = np.random.default_rng(3)
    t = np.linspace(0, 2 * np.pi, 1501)
    loop = np.c_[0.1 * np.cos(t), 0.06 * np.sin(t) + 0.01 * np.sin(5 * t), 2e-3 * np.sin(3 * t)]
    a, b = loop[:-1], loop[1:]
    b_long = b.copy()
    b_long[700] = a[700] + 40 * (b[700] - a[700])  # one long segment: every point stays open
    cases = [(loop + rng.normal(0, 1e-4, loop.shape), a, b),  # a cut around its edge
             (loop[:-1], a, b),  # exactly at the vertices: ties
             (rng.normal(0, 0.3, (800, 3)), a, b),  # far away
             (loop + rng.normal(0, 1e-4, loop.shape), a, b_long)]
    for p, aa, bb in cases:
        assert len(p) * len(aa) > geo._DENSE_PAIRS
        ab = bb - aa
        L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
        ref = geo._point_segment_all(p, aa, ab, L2, 256)
        got = geo.point_segment(p, aa, bb)
        for x, y in zip(got, ref, strict=True):
            assert np.array_equal(x, y)
    # at a vertex the two segments meeting there tie: the first one is named
    _, k, f = geo.point_segment(loop[1:-1], a, b)
    assert np.array_equal(k, np.arange(len(loop) - 2)) and np.all(f == 1.0)
    # a non-finite point reads as NaN at any size (the KD-tree would refuse it)
    bad = loop.copy()
    bad[5] = np.nan
    d, _, _ = geo.point_segment(bad, a, b)
    assert np.isnan(d[5]) and np.all(np.isfinite(np.delete(d, 5)))


def test_plan_without_tool_path_uses_hub_edges():
    """A plan that carries no ToolPath is still checked against the true edge (the CL points
    are inferred from the targets, the local frames from the hub's ground truth)."""
    plan = faults.replace(vs.good_plan(), tool_path=None)
    report = vs.verify(plan)
    for name in ("windows", "edge_deviation", "edge_coverage", "burr_engagement",
                 "cl_chord_length"):
        assert report.item(name).passed, report.item(name)
    cone = report.item("cone")
    assert cone.value is not None
    assert all(v["reference"].startswith("hub edge") for v in cone.per_window.values())
    # the inferred contact points (nearest edge point to T) stay on the true edge
    assert report.item("edge_deviation").value <= report.settings["tolerances"]["edge_deviation"]
    # the fixed-axis plan leaves the source's default box [0.26, 0.44]: named by the cone check
    assert "cone" in report.failed


def test_samples_are_put_on_the_moves_in_execution_order():
    """A closed loop ends on its first point: the nearest move alone puts the last samples on
    the first move (where the program's orientation may differ by a wrist turn); the monotone
    assignment keeps them on the last move. Distances and fractions are the true ones."""
    from drakedeburr.plan.program_reading import moves_in_order

    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]], float)
    a, b = corners[:-1], corners[1:]
    t = np.linspace(0, 4, 401)
    k = np.minimum(t.astype(int), 3)
    p = a[k] + (t - k)[:, None] * (b[k] - a[k]) + np.array([0, 0, 1e-4])  # 0.1 mm above
    d, m, f = moves_in_order(p, a, b)
    assert np.all(np.diff(m) >= 0) and m[-1] == 3 and m[0] == 0
    np.testing.assert_allclose(d, 1e-4, atol=1e-12)
    np.testing.assert_allclose(a[m] + f[:, None] * (b[m] - a[m]) + [0, 0, 1e-4], p, atol=1e-12)
    _, m_near, _ = point_segment(p, a, b)
    assert m_near[-1] == 0  # the ambiguity the ordered assignment removes
    # a sample that strays towards an earlier move still counts on the current one
    q = p.copy()
    q[250] = [0.5, 0.02, 0.0]  # on move 2's time but next to move 0
    _, m2, _ = moves_in_order(q, a, b)
    assert np.all(np.diff(m2) >= 0) and m2[250] == 2


def test_passing_fractions_follow_the_progress_not_the_projection():
    """Round a 90 deg corner with an arc: the corner target is passed where the path comes
    nearest to it (the arc's middle); the travel share grows with the tool's progress through
    the zone, where the projection on the move's segment lags behind."""
    from drakedeburr.plan.program_reading import moves_in_order, passing_fractions

    targets = np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1, 0]])
    r = 0.2  # corner rounded by a quarter circle from (0.8, 0) to (1, 0.2)
    line1 = np.column_stack([np.linspace(0, 0.8, 81), np.zeros(81), np.zeros(81)])
    th = np.linspace(0, np.pi / 2, 32)[1:]
    arc = np.column_stack([0.8 + r * np.sin(th), r - r * np.cos(th), np.zeros(len(th))])
    line2 = np.column_stack([np.ones(80), np.linspace(0.21, 1.0, 80), np.zeros(80)])
    p = np.vstack([line1, arc, line2])
    m, f = passing_fractions(p, targets)
    _, m_proj, f_proj = moves_in_order(p, targets[:-1], targets[1:])
    assert np.all(np.diff(m) >= 0) and m[0] == 0 and m[-1] == 1
    for k in (0, 1):
        assert np.all(np.diff(f[m == k]) > 0)  # strictly growing with the travel
    assert f[0] == 0.0 and f[-1] == 1.0
    # the move changes at the arc's middle (th = 45 deg, halfway between samples 95 and 96)
    assert np.flatnonzero(m == 1)[0] == 96
    # there the tool has all but finished move 0; its projection on the segment lags
    last0 = np.flatnonzero(m == 0)[-1]
    assert f[last0] > 0.99 and f_proj[last0] < 0.95
    # true share of the travel between passing points (arc length of the samples)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    np.testing.assert_allclose(f[m == 0], s[m == 0] / (0.5 * (s[95] + s[96])), atol=1e-4)


def test_passing_fractions_resolve_moves_shorter_than_the_sampling():
    """Moves of 0.25 mm read from samples 0.5 mm apart (a tight corner's program against the
    verifier's 0.5 mm re-check): each sample gets its exact move and share, as it would from
    samples ten times denser."""
    from drakedeburr.plan.program_reading import passing_fractions

    x_t = np.concatenate([[0.0], np.cumsum(np.full(40, 0.25e-3))])  # 10 mm in 0.25 mm moves
    targets = np.column_stack([x_t, np.zeros(41), np.zeros(41)])
    for step in (0.5e-3, 0.05e-3, 0.37e-3):
        x = np.append(np.arange(0.0, x_t[-1], step), x_t[-1])
        m, f = passing_fractions(np.column_stack([x, np.zeros_like(x), np.zeros_like(x)]),
                                 targets)
        np.testing.assert_allclose(x_t[m] + f * 0.25e-3, x, atol=1e-12)


def test_slow_stretches_are_located_and_needless_slack_is_named():
    """The good plan leaves the band only where its cuts start and stop at rest, and every
    such stretch lies at a cut end; a stretch slowed for no reason (time warped, path kept)
    fails the band, and the required ``slowdowns_justified`` names its window with no limit
    near binding there, at the tool travel where the warp slows the tool."""
    good = vs.verify(vs.good_plan())
    assert "slowdowns_justified" not in good.failed + good.advisory_failed
    band = good.item("tcp_speed_band")
    for w, info in band.per_window.items():
        st = info["slow_stretches"]
        assert st and {s["at"] for s in st} <= {"start", "end"}, (w, st)
        assert st[0]["from_m"] == 0.0 and st[0]["at"] == "start"
        assert st[-1]["at"] == "end"
        # the in-band share and the stretches cover the cut exactly once
        slow = sum(s["to_m"] - s["from_m"] for s in st)
        assert slow == pytest.approx((1 - info["fraction_in_band"]) * st[-1]["to_m"], rel=1e-9)

    plan = vs.good_plan()
    bad = faults.slow_down_stretch(plan, window=1, start=0.3, end=0.7, factor=2.0)
    report = vs.verify(bad)
    assert report.item("tcp_speed_band").value < good.item("tcp_speed_band").value - 0.2
    assert "slowdowns_justified" in report.failed
    item = report.item("slowdowns_justified")
    assert item.window == 1 and item.value < 0.3
    inside = [s for s in report.item("tcp_speed_band").per_window[1]["slow_stretches"]
              if s["at"] == "inside"]
    assert len(inside) == 1
    # independent: the tool travel of the warp's middle (FK along the cut's knots)
    cell, _ = vs.cell_and_hub()
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(cell)
    seg = next(s for s in bad.segments if s.kind == "cut" and s.window_index == 1)
    tt = np.linspace(*seg.t_range, 4000)
    p = kin.X_HT_from_q(bad.trajectory.value(tt))[:, :3, 3]
    run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    seg0 = next(s for s in plan.segments if s.kind == "cut" and s.window_index == 1)
    t_mid = seg0.t_range[0] + 0.5 * (seg0.t_range[1] - seg0.t_range[0])
    t_mid_bad = float(np.interp(t_mid, plan.trajectory.t, bad.trajectory.t))
    s_mid = float(np.interp(t_mid_bad, tt, run))
    assert inside[0]["from_m"] < s_mid < inside[0]["to_m"]
    assert inside[0]["min_mps"] == pytest.approx(vs.PARAMS.grinding_speed / 2.0, rel=0.05)


def test_wrist_singularity_guards_the_linear_segments():
    """J5 = 0 on a joint move (the controller interpolates joints there) is reported, not
    failed; on a cut it fails at that sample."""
    from types import SimpleNamespace

    from drakedeburr.config import default_tolerances
    from drakedeburr.verify.checks_motion import wrist_singularity
    from drakedeburr.verify.types import KIND_CODE

    q = np.zeros((5, 6))
    q[:, 4] = [0.6, 0.0, 0.4, 0.5, 0.3]
    kind = np.array([KIND_CODE[k] for k in ("home", "transition", "approach", "cut", "cut")])
    sp = SimpleNamespace(samples=SimpleNamespace(q=q, kind=kind), where=lambda i: {})
    cfg = SimpleNamespace(tolerances=default_tolerances())
    item = wrist_singularity(sp, cfg)
    assert item.passed and item.value == pytest.approx(0.3) and "0.00 deg" in item.detail
    q[3, 4] = 0.01
    item = wrist_singularity(sp, cfg)
    assert not item.passed and item.value == pytest.approx(0.01)
