"""Benchmark of the planning stage (issue 5): a whole hub end to end vs the naive alternative.

1. A whole hub (all windows) planned in the tool-in-hand cell: each stage's share, IK time per
   CL point, cycle time vs the physical limit (edge length / 150 mm/s + the same transitions).
2. The naive alternative a Drake user writes first: one KinematicTrajectoryOptimization per
   window with position + cone + minimum-distance constraints at every CL point, timed on the
   same window (or its first ``--naive-points`` points) with its accuracy at the CL points.
3. Timing cross-check: Drake's TOPP-RA (AddFrameTranslationalSpeedLimit) on the same cut path
   vs the planner's own passes: duration and the speed overshoot between grid points.
4. ``--accel-sweep``: how the speed band and the cut time depend on the robot model's
   acceleration limits, which are assumed values (``PlanOptions.acceleration_scale`` on the
   joint accelerations and the TCP path acceleration cap), on windows 0-1 of the hub; the
   x1 row is the baseline of the same run.
5. ``--fillets``: the same hub planned again with the fillet repair (``PlanOptions.fillets``):
   cut time, share in band and planning time per window against the run of item 1.

Run:  PYTHONPATH=. python benchmarks/bench_plan.py [--quick] [--hub NAME] [--accel-sweep]
      [--fillets]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drakedeburr.config import load_config


def _table(rows, header):
    w = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    line = "  ".join(str(h).ljust(w[i]) for i, h in enumerate(header))
    print(line)
    for r in rows:
        print("  ".join(str(c).ljust(w[i]) for i, c in enumerate(r)))


def naive_kto(cell, wt, max_points: int, iterations: int = 300):
    """One KTO over a window with constraints at every CL point; returns (seconds, max error)."""
    from pydrake.multibody.inverse_kinematics import (
        AngleBetweenVectorsConstraint,
        MinimumDistanceLowerBoundConstraint,
        PositionConstraint,
    )
    from pydrake.planning import KinematicTrajectoryOptimization
    from pydrake.solvers import SnoptSolver, SolverOptions

    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import PlanOptions
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    kin = cell_kinematics(cell)
    checker = ClearanceChecker(cell)
    m = min(len(wt), max_points)
    r_c, lift = contact_geometry(PlanOptions().contact_radius)
    p_HT = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, lift)[:m]
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p_HT, axis=0), axis=1))])
    r = s / s[-1]
    t0 = time.perf_counter()
    kto = KinematicTrajectoryOptimization(6, max(8, m // 2), spline_order=4)
    kto.AddDurationCost(1.0)
    kto.AddPositionBounds(cell.q_lower, cell.q_upper)
    kto.AddVelocityBounds(cell.v_lower, cell.v_upper)
    kto.AddDurationConstraint(0.1, 60.0)
    keep = []
    ctx = checker.plant_context
    dist = MinimumDistanceLowerBoundConstraint(cell.plant, 2e-3, ctx, None, 2e-3)
    keep.append(dist)
    for i in range(m):
        pc = PositionConstraint(cell.plant, cell.hub_frame, p_HT[i] - 1e-6, p_HT[i] + 1e-6,
                                cell.tool_frame, np.zeros(3), ctx)
        ac = AngleBetweenVectorsConstraint(cell.plant, cell.hub_frame, wt.cone_retract_H[i],
                                           cell.tool_frame, np.array([0, 0, -1.0]), 0.0,
                                           wt.cone_half_angle, ctx)
        keep += [pc, ac]
        kto.AddPathPositionConstraint(pc, float(r[i]))
        kto.AddPathPositionConstraint(ac, float(r[i]))
        kto.AddPathPositionConstraint(dist, float(r[i]))
    # warm start: the home configuration everywhere (what a first attempt does)
    prog = kto.get_mutable_prog()
    opts = SolverOptions()
    opts.SetOption(SnoptSolver().solver_id(), "Major iterations limit", iterations)
    # SNOPT's total (minor) iteration cap, 10000 by default, ends this program in ~2 s (info 31)
    # long before the major cap: lift it with the budget so the budget is what limits
    opts.SetOption(SnoptSolver().solver_id(), "Iterations limit", 1000 * iterations)
    q0 = np.tile(cell.q_home, (kto.num_control_points(), 1)).T
    prog.SetInitialGuess(kto.control_points(), q0)
    result = SnoptSolver().Solve(prog, None, opts)
    seconds = time.perf_counter() - t0
    traj = kto.ReconstructTrajectory(result)
    errs = []
    for i in range(m):
        q = traj.value(traj.start_time() + r[i] * (traj.end_time() - traj.start_time())).ravel()
        errs.append(np.linalg.norm(kin.X_HT_from_q(q)[:3, 3] - p_HT[i]))
    del keep
    info = result.get_solver_details().info  # SNOPT's exit code (e.g. 1 optimal, 13 infeasible)
    return seconds, float(np.max(errs)), f"{result.is_success()} (SNOPT info {info})", m


def toppra_check(cell, plan):
    """Time window 0's cut with Drake TOPP-RA at 150 mm/s; duration and dense max speed."""
    from pydrake.multibody.optimization import CalcGridPointsOptions, Toppra
    from pydrake.trajectories import PiecewisePolynomial

    from drakedeburr.plan.kinematics import cell_kinematics

    seg = next(s for s in plan.segments if s.kind == "cut")
    tr = plan.trajectory
    sel = (tr.t >= seg.t_range[0]) & (tr.t <= seg.t_range[1])
    q = tr.q[sel]
    kin = cell_kinematics(cell)
    p = kin.X_HT_from_q(q)[:, :3, 3]
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    path = PiecewisePolynomial.CubicWithContinuousSecondDerivatives(s, q.T, np.zeros(6),
                                                                    np.zeros(6))
    t0 = time.perf_counter()
    grid = Toppra.CalcGridPoints(path, CalcGridPointsOptions())
    topp = Toppra(path, cell.plant, grid)
    topp.AddJointVelocityLimit(cell.v_lower, cell.v_upper)
    topp.AddJointAccelerationLimit(cell.a_lower, cell.a_upper)
    topp.AddFrameTranslationalSpeedLimit(cell.tool_frame, 0.150)
    sdot = topp.SolvePathParameterization()
    seconds = time.perf_counter() - t0
    if sdot is None:
        return seconds, None, None
    tt = np.linspace(sdot.start_time(), sdot.end_time(), 4000)
    ss = np.array([sdot.value(t)[0, 0] for t in tt])
    pp = kin.X_HT_from_q(np.array([path.value(x).ravel() for x in ss]))[:, :3, 3]
    v = np.linalg.norm(np.diff(pp, axis=0), axis=1) / np.diff(tt)
    return seconds, sdot.end_time(), float(v.max())


def accel_sweep(cell, wts, hub_name: str, scales=(1.0, 2.0, 4.0, 10.0, 20.0)) -> None:
    """Plan the same windows with the model's acceleration limits scaled; print the share of
    each window's cutting within +-5 % of the grinding speed and the cut time vs the physical
    limit (edge length / grinding speed), per scale."""
    from drakedeburr.plan.planner import PlanOptions, plan_windows

    rows = []
    base_cut = None
    for f in scales:
        t0 = time.perf_counter()
        plan = plan_windows(cell, wts, load_config("tool_in_hand", hub_name),
                            options=PlanOptions(acceleration_scale=f))
        sec = time.perf_counter() - t0
        ws = plan.meta["windows"]
        cut = sum(w["cut_seconds"] for w in ws)
        base_cut = cut if base_cut is None else base_cut
        band = ", ".join(f"{100 * w['speed_in_band_fraction']:.0f} %" for w in ws)
        ratio = ", ".join(f"{w['cut_seconds'] / (w['tool_travel_m'] / 0.15):.2f}" for w in ws)
        rows.append([f"x{f:g}", band, ratio, f"{cut:.2f}", f"{cut / base_cut:.2f}",
                     len(plan.failures), f"{sec:.0f}"])
    print(f"\nacceleration limits scaled (windows {[w.window_index for w in wts]}, "
          "tool in hand; target: >= 95 % in band, cut <= 1.05x):\n")
    _table(rows, ["accelerations", "in band per window", "cut / limit per window", "cut s",
                  "vs x1", "failures", "plan s"])


def fillet_compare(cell, wts, hub_name: str, plan, t_plan: float) -> None:
    """Plan the same windows with the fillet repair; print each window's cut time and share in
    band without/with it and the planning times (the run without is item 1's)."""
    from drakedeburr.plan.fillets import FilletOptions
    from drakedeburr.plan.planner import PlanOptions, plan_windows

    t0 = time.perf_counter()
    fixed = plan_windows(cell, wts, load_config("tool_in_hand", hub_name),
                         options=PlanOptions(fillets=FilletOptions()))
    t_fixed = time.perf_counter() - t0
    rows = []
    for a, b in zip(plan.meta["windows"], fixed.meta["windows"], strict=True):
        rows.append([a["window"], f"{a['cut_seconds']:.2f}", f"{b['cut_seconds']:.2f}",
                     f"{b['cut_seconds'] / a['cut_seconds']:.2f}",
                     f"{100 * a['speed_in_band_fraction']:.0f} %",
                     f"{100 * b['speed_in_band_fraction']:.0f} %"])
    print("\nfillet repair (PlanOptions.fillets), same windows:\n")
    _table(rows, ["win", "cut s without", "cut s with", "ratio", "in band without",
                  "in band with"])
    m0, m1 = plan.meta, fixed.meta
    print(f"\ncycle {m0['cycle_seconds']:.2f} s -> {m1['cycle_seconds']:.2f} s "
          f"({m1['cycle_seconds'] / m0['cycle_seconds']:.3f}x); planning {t_plan:.1f} s -> "
          f"{t_fixed:.1f} s ({t_fixed / t_plan:.1f}x); failure records {len(fixed.failures)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two windows, 40-point naive KTO")
    ap.add_argument("--hub", default=None)
    ap.add_argument("--source", default="auto", choices=("auto", "toolpath", "edges"))
    ap.add_argument("--naive-points", type=int, default=None)
    ap.add_argument("--fillets", action="store_true",
                    help="also plan the hub with the fillet repair (same run, vs without)")
    ap.add_argument("--accel-sweep", action="store_true",
                    help="also plan windows 0-1 with the acceleration limits x1, x2, x4, x10, x20")
    args = ap.parse_args()

    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan.planner import plan_windows, window_targets_for_hub

    hub_name = args.hub or DEFAULT_HUB
    t0 = time.perf_counter()
    cell = load_cell("tool_in_hand", hub_name)
    t_cell = time.perf_counter() - t0
    hub = load_hub(hub_name)
    t0 = time.perf_counter()
    wts = window_targets_for_hub(hub, source=args.source,
                                 windows=(0, 1) if args.quick else None)
    t_targets = time.perf_counter() - t0
    t0 = time.perf_counter()
    plan = plan_windows(cell, wts, load_config("tool_in_hand", hub_name))
    t_plan = time.perf_counter() - t0
    m = plan.meta
    ws = m["windows"]
    ik = sum(w["ik_seconds"] for w in ws)
    dense = sum(w["dense_seconds"] for w in ws)
    timing = sum(w["timing_seconds"] for w in ws)
    trans = m["timings"]["transition_seconds"]
    total = t_cell + t_targets + t_plan
    points = sum(w["ik"]["points"] for w in ws)
    print(f"## plan: hub {hub_name}, {len(ws)} windows, {points} CL targets, "
          f"{len(plan.failures)} failure records\n")
    rows = [["load cell", f"{t_cell:.1f}", f"{100 * t_cell / total:.0f} %"],
            ["targets (CL + orientation)", f"{t_targets:.1f}", f"{100 * t_targets / total:.0f} %"],
            ["IK at CL targets", f"{ik:.1f}", f"{100 * ik / total:.0f} %"],
            ["executed motion + clearance", f"{dense:.1f}", f"{100 * dense / total:.0f} %"],
            ["timing", f"{timing:.2f}", f"{100 * timing / total:.1f} %"],
            ["transitions", f"{trans:.1f}", f"{100 * trans / total:.0f} %"],
            ["total", f"{total:.1f}", "100 %"]]
    _table(rows, ["stage", "seconds", "share"])
    print(f"\nIK per CL point: {1e3 * ik / points:.1f} ms (mean over the hub)")
    wrows = [[w["window"], w["kind"], w["cl_points"], f"{1e3 * w['ik']['seconds_per_point']:.0f}",
              w["ik"]["distance_resolves"], w["ik"]["failed"],
              f"{w['j4_range_deg']:.1f}", f"{w['j5_range_deg']:.1f}", f"{w['j6_range_deg']:.1f}",
              f"{w['min_clearance_m'] * 1e3:.2f}", f"{100 * w['speed_in_band_fraction']:.0f} %",
              f"{w['cut_seconds']:.2f}", f"{w['tool_travel_m'] / 0.15:.2f}"] for w in ws]
    print()
    _table(wrows, ["win", "kind", "CL", "ms/pt", "dist", "fail", "J4 deg", "J5 deg", "J6 deg",
                   "clear mm", "in band", "cut s", "limit s"])
    seg = m["segment_seconds"]
    moves = sum(v for k, v in seg.items() if k != "cut")
    limit = m["physical_cut_seconds"] + moves
    print(f"\ncycle {m['cycle_seconds']:.2f} s = cut {seg.get('cut', 0):.2f} s + other moves "
          f"{moves:.2f} s; physical limit {m['physical_cut_seconds']:.2f} s + {moves:.2f} s = "
          f"{limit:.2f} s -> ratio {m['cycle_seconds'] / limit:.2f} (target <= 1.05); cut time "
          f"ratio {m['cut_time_ratio']:.2f}")

    n_naive = args.naive_points or (40 if args.quick else len(wts[0]))
    ours_window = ws[0]["ik_seconds"] + ws[0]["dense_seconds"] + ws[0]["timing_seconds"]
    # the naive program with growing iteration budgets: its time to an accurate window (the
    # tolerance of the plan's dense check, 0.05 mm at the CL points), or the largest budget's
    caps = (300,) if args.quick else (300, 1000, 3000)
    nrows, needed = [], None
    for cap in caps:
        sec, err, ok, npts = naive_kto(cell, wts[0], n_naive, iterations=cap)
        nrows.append([cap, npts, f"{sec:.1f}", ok, f"{err * 1e3:.3f}"])
        if ok.startswith("True") and err <= 0.05e-3:
            needed = sec
            break
    print(f"\nnaive KTO on window {wts[0].window_index} (one KTO, constraints at every CL "
          "point, home warm start):\n")
    _table(nrows, ["SNOPT major iterations", "CL points", "seconds", "success",
                   "max error at CL points mm"])
    if needed is None:
        verdict = (f"the naive program reached no accurate window within {caps[-1]} "
                   f"iterations ({float(nrows[-1][2]):.1f} s)")
        ref = float(nrows[-1][2])
    else:
        verdict = f"the naive program needed {needed:.1f} s for one accurate window"
        ref = needed
    print(f"\nours, same window (all {ws[0]['cl_points']} points): {ours_window:.1f} s, position "
          f"error <= 1e-3 mm at targets; whole hub {t_plan:.1f} s = {t_plan / ref:.2f} x "
          f"{'that' if needed is not None else 'its largest budget'}; {verdict}")
    ts, dur, vmax = toppra_check(cell, plan)
    if dur is None:
        print(f"\nTOPP-RA: no solution ({ts * 1e3:.0f} ms)")
    else:
        print(f"\nTOPP-RA on window {ws[0]['window']}'s cut: {ts * 1e3:.0f} ms, duration "
              f"{dur:.2f} s vs ours {ws[0]['cut_seconds']:.2f} s; max dense TCP speed "
              f"{vmax * 1e3:.1f} mm/s (limit 150)")
    if args.fillets:
        fillet_compare(cell, wts, hub_name, plan, t_plan)
    if args.accel_sweep:
        accel_sweep(cell, wts[:2], hub_name, scales=(1.0, 4.0) if args.quick else
                    (1.0, 2.0, 4.0, 10.0, 20.0))


if __name__ == "__main__":
    main()
