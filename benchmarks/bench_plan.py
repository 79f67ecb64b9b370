"""Benchmark of the planning stage: planning time per bundled hub and per stage, against the
previous implementation in the same run (issue 19), and the extras of issue 5.

1. Speed (default): every bundled hub in both cells planned by the previous implementation
   (``--baseline REF``: that commit's tree, extracted by ``git archive`` into a temporary folder
   and imported through PYTHONPATH) and by this tree, one process (``--workers 1``) and the
   default (windows on all cores), interleaved per hub so that both see the same machine load;
   each run in its own subprocess (benchmarks/plan_run.py). Prints wall and CPU time (worker
   processes included), the share of each cut in the feed band (and the planner's bound), and
   per stage the wall/CPU time of the one-process runs (exclusive: nested stages apart).
2. ``--naive``: one KinematicTrajectoryOptimization per window with position + cone +
   minimum-distance constraints at every CL point (what a Drake user writes first).
3. ``--toppra``: Drake's TOPP-RA on window 0's cut path vs the planner's own timing.
4. ``--accel-sweep``: share in band and cut time vs the robot model's acceleration limits.

Run:  PYTHONPATH=. python benchmarks/bench_plan.py [--quick] [--hubs A,B] [--cells tool,workpiece]
      [--baseline REF] [--naive] [--toppra] [--accel-sweep]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drakedeburr.config import load_config

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ("--accel-sweep",)
QUICK_ARGS = ("--quick", "--accel-sweep")


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


def _run(tree: str, scenario: str, hub: str, workers: int | None) -> dict:
    """One planning run of the tree at ``tree`` in a subprocess (benchmarks/plan_run.py)."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parent / "plan_run.py"
    cmd = [sys.executable, str(script), scenario, hub]
    if workers is not None:
        cmd += ["--workers", str(workers)]
    env = {**os.environ, "PYTHONPATH": tree}
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tree)
    lines = [x for x in out.stdout.splitlines() if x.startswith("{")]
    if out.returncode or not lines:
        raise RuntimeError(f"{tree}: {scenario} {hub} failed:\n{out.stderr[-2000:]}")
    return json.loads(lines[-1])


def _band(r: dict) -> str:
    return "/".join(f"{100 * w['in_band']:.0f}" for w in r["windows"])


def speed(hubs, cells, baseline: str) -> None:
    """Item 1 (module docstring)."""
    import os
    from pathlib import Path

    here = str(Path(__file__).resolve().parent.parent)
    from _baseline import tree_at

    base = str(tree_at(baseline, "bench_plan_base_"))
    load = os.getloadavg()[0]
    print(f"## planning time: previous implementation ({baseline}) vs this tree, same run "
          f"(load average {load:.1f} at the start, {os.cpu_count()} cores)\n")
    rows, stages = [], {}
    for cell in cells:
        for hub in hubs:
            b = _run(base, cell, hub, None)
            b1 = _run(base, cell, hub, 1)
            n1 = _run(here, cell, hub, 1)
            n = _run(here, cell, hub, None)
            stages[(cell, hub)] = (b1, n1)  # one process each: every stage in this process
            bounds = [w["bound"] for w in n["windows"] if w["bound"] is not None]
            rows.append([hub, cell.split("_")[0], f"{b['wall']:.1f}", f"{b1['wall']:.1f}",
                         f"{n1['wall']:.1f}", f"{n['wall']:.1f}", f"{b['wall'] / n['wall']:.2f}",
                         f"{b['cpu'] + b['cpu_children']:.1f}",
                         f"{n['cpu'] + n['cpu_children']:.1f}",
                         f"{b['failures']}/{n['failures']}",
                         "yes" if n1["digest"] == n["digest"] else "NO",
                         "yes" if b1["digest"] == n1["digest"] else "no",
                         _band(b), _band(n),
                         f"{100 * min(bounds):.0f}" if bounds else "-"])
            print("  ".join(rows[-1]), flush=True)
    print()
    _table(rows, ["hub", "cell", "before s", "before 1 proc s", "now 1 proc s", "now s",
                  "speed-up", "before CPU s",
                  "now CPU s", "failures", "same plan 1/N proc", "same plan as before",
                  "in band % before",
                  "in band % now", "least bound %"])
    for (cell, hub), (b, n1) in stages.items():
        names = list(dict.fromkeys(list(b["stages_wall"]) + list(n1["stages_wall"])))
        srows = []
        for name in names:
            bw, nw = b["stages_wall"].get(name, 0.0), n1["stages_wall"].get(name, 0.0)
            srows.append([name, f"{bw:.2f}", f"{b['stages_cpu'].get(name, 0.0):.2f}",
                          f"{nw:.2f}", f"{n1['stages_cpu'].get(name, 0.0):.2f}"])
        rest_b = b["wall"] - sum(b["stages_wall"].values())
        rest_n = n1["wall"] - sum(n1["stages_wall"].values())
        srows.append(["other", f"{rest_b:.2f}", "", f"{rest_n:.2f}", ""])
        srows.append(["total", f"{b['wall']:.2f}", f"{b['cpu']:.2f}", f"{n1['wall']:.2f}",
                      f"{n1['cpu']:.2f}"])
        print(f"\n### stages, {hub}, {cell} (one process; seconds, exclusive)\n")
        _table(srows, ["stage", "before wall", "before CPU", "now wall", "now CPU"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="h5_straight, tool in hand only")
    ap.add_argument("--hubs", default=None, help="comma-separated hubs (default all bundled)")
    ap.add_argument("--cells", default="tool_in_hand,workpiece_in_hand")
    ap.add_argument("--baseline", default="6f7875c",
                    help="commit of the previous implementation (default: main before issue 19)")
    ap.add_argument("--no-speed", action="store_true", help="skip item 1")
    ap.add_argument("--naive", action="store_true", help="item 2 on the default hub")
    ap.add_argument("--naive-points", type=int, default=None)
    ap.add_argument("--toppra", action="store_true", help="item 3 on the default hub")
    ap.add_argument("--accel-sweep", action="store_true",
                    help="item 4: windows 0-1 with the acceleration limits x1, x2, x4, x10, x20")
    args = ap.parse_args()

    from drakedeburr.hub import DEFAULT_HUB
    from drakedeburr.resources import hub_names

    hubs = (["h5_straight"] if args.quick else
            args.hubs.split(",") if args.hubs else sorted(hub_names()))
    cells = ["tool_in_hand"] if args.quick else args.cells.split(",")
    if not args.no_speed:
        speed(hubs, cells, args.baseline)
    if not (args.naive or args.toppra or args.accel_sweep):
        return
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.planner import plan_windows, window_targets_for_hub

    cell = load_cell("tool_in_hand", DEFAULT_HUB)
    wts = window_targets_for_hub(load_hub(DEFAULT_HUB), windows=(0, 1))
    if args.naive:
        n = args.naive_points or len(wts[0])
        sec, err, ok, npts = naive_kto(cell, wts[0], n, iterations=300)
        print(f"\nnaive KTO on window {wts[0].window_index}: {npts} CL points, {sec:.1f} s, "
              f"{ok}, max error at the CL points {err * 1e3:.3f} mm")
    if args.toppra:
        plan = plan_windows(cell, wts[:1], load_config("tool_in_hand", DEFAULT_HUB))
        ts, dur, vmax = toppra_check(cell, plan)
        ours = plan.meta["windows"][0]["cut_seconds"]
        print(f"\nTOPP-RA on window 0's cut: {ts * 1e3:.0f} ms, duration "
              f"{'-' if dur is None else f'{dur:.2f}'} s vs ours {ours:.2f} s; max dense TCP "
              f"speed {'-' if vmax is None else f'{vmax * 1e3:.1f}'} mm/s (limit 150)")
    if args.accel_sweep:
        accel_sweep(cell, wts, DEFAULT_HUB)


if __name__ == "__main__":
    main()
