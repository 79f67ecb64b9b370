"""Orientation benchmark: exact solver vs the source's PSO on the same `axis` model, per window
of a bundled hub, on an idle machine and with a busy loop on the other core; plus
normal-estimation and registration time.

    python benchmarks/bench_orientation.py [--hub h5_split] [--quick] [--repeats 7]
                                           [--no-busy] [--solvers-only]

Both solvers see the same problem (CL points every 2 mm, ground-truth normals). PSO uses the
source's settings (50 particles, 200 iterations, inertia 0.8, c1 = c2 = 2, seed 0) and its
Gaussian smoothing; its objective is reported after smoothing (the pipeline's output) and
raw. Every timed solve gets a freshly built problem (built outside the timed call: the same
input for both solvers) with the exact solver's index-table cache emptied, i.e. it pays
everything a first solve of a new window pays (the problem's coupling bands, the band layout,
the model tables); nothing is warmed up. The solves are interleaved (exact,
PSO, exact, PSO, ...) and each solver's median wall and process-CPU time over --repeats is
kept; the ratio is PSO / exact of those medians, window by window.

The whole comparison runs twice in the same process: "idle" (whatever else the machine runs)
and "busy", with a child process spinning `while True: pass` (a busy loop that keeps one of
the 2 cores saturated) for the duration of the busy pass. The load average before each pass
is printed. --quick: two windows, no registration of the wrong model; --solvers-only: skip
normals and registration.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

import numpy as np

import drakedeburr.orientation.exact as exact_module
from drakedeburr.config import OrientationBounds
from drakedeburr.frames.local_frames import R_HL_from_normals
from drakedeburr.frames.normals import inner_normals_from_cloud
from drakedeburr.hub import ScannerModel, load_hub, simulate_scan
from drakedeburr.orientation import OrientOptions, problem_for, solve_problem
from drakedeburr.orientation.commands import cl_points_from_edge
from drakedeburr.orientation.models import make_problem

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--quick", "--no-busy", "--repeats", "3")


def _solver_caches():
    """Every functools cache of the exact solver's modules (the band layout tables)."""
    import importlib

    mods = [exact_module]
    try:
        mods.append(importlib.import_module("drakedeburr.orientation.banded"))
    except ImportError:  # an older implementation (benchmarked with PYTHONPATH)
        pass
    return [f for m in mods for f in vars(m).values() if hasattr(f, "cache_clear")]


def _fresh(prob):
    """The same problem, rebuilt (no cached coupling matrix), the solver's caches emptied."""
    for f in _solver_caches():
        f.cache_clear()
    return make_problem(prob.model, prob.p_HC, prob.R_HL,
                        OrientationBounds(prob.theta_min, prob.theta_max),
                        w1=prob.w1, w2=prob.w2,
                        second_difference_weight=prob.second_difference_weight, name=prob.name)


def _timed(prob, solver, opts):
    fresh = _fresh(prob)  # the same input for both solvers: not timed
    c0, t0 = time.process_time(), time.perf_counter()
    rep = solve_problem(fresh, solver, opts)
    return rep, time.perf_counter() - t0, time.process_time() - c0


def compare_solvers(problems, opts, repeats, label):
    """One pass over the windows; prints a table, returns the per-window wall / CPU ratios."""
    print(f"\n### {label}: load average {os.getloadavg()[0]:.2f} "
          f"(1 min) at the start of the pass")
    print(f"{'':>14} {'exact (projected Newton)':^30} {'PSO (50 x 200 + smoothing)':^37} "
          f"{'PSO / exact':^20}")
    print(f"{'win':>3} {'kind':>5} {'M':>4} {'objective':>10} {'it':>3} {'wall ms':>8} "
          f"{'cpu ms':>7} {'objective':>10} {'raw':>10} {'wall ms':>7} {'cpu ms':>7} "
          f"{'wall':>6} {'cpu':>6} {'obj':>6}")
    wall, cpu = [], []
    for edge, prob in problems:
        t_ex, t_ps, c_ex, c_ps = [], [], [], []
        for _ in range(max(repeats, 1)):
            ex, t, c = _timed(prob, "exact", opts)
            t_ex.append(t)
            c_ex.append(c)
            ps, t, c = _timed(prob, "pso", opts)
            t_ps.append(t)
            c_ps.append(c)
        assert ex.success, ex.message
        assert ps.objective >= ex.objective, "PSO better than the exact optimum"
        te, tp, ce, cp = (float(np.median(v)) for v in (t_ex, t_ps, c_ex, c_ps))
        wall.append(tp / te)
        cpu.append(cp / max(ce, 1e-9))
        print(f"{edge.index:>3} {edge.kind:>5} {prob.m:>4} {ex.objective:>10.4f} "
              f"{ex.iterations:>3} {1e3 * te:>8.2f} {1e3 * ce:>7.2f} "
              f"{ps.objective:>10.4f} {ps.info['objective_raw']:>10.4f} "
              f"{1e3 * tp:>7.0f} {1e3 * cp:>7.0f} "
              f"{wall[-1]:>5.0f}x {cpu[-1]:>5.0f}x {ps.objective / ex.objective:>6.2f}")
    met = "met" if min(wall) >= 100 else "NOT met"
    print(f"{label}: PSO/exact wall min {min(wall):.0f}x, median {np.median(wall):.0f}x; "
          f"cpu min {min(cpu):.0f}x, median {np.median(cpu):.0f}x (target >= 100x wall on "
          f"every window: {met})")
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--hub", default="h5_split")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=7, help="timed solves per solver (median)")
    ap.add_argument("--no-busy", action="store_true", help="skip the busy-machine pass")
    ap.add_argument("--solvers-only", action="store_true", help="skip normals, registration")
    args = ap.parse_args()
    hub = load_hub(args.hub)
    windows = hub.windows[:2] if args.quick else hub.windows
    opts = OrientOptions()
    problems = []
    for edge in windows:
        cl, idx = cl_points_from_edge(edge, 2e-3)
        problems.append((edge, problem_for(cl, R_HL_from_normals(cl.t_H, edge.n_wall_H[idx]),
                                           "axis", options=opts)))
    print(f"## orientation: hub {args.hub}, axis model, exact vs PSO (same run, {os.cpu_count()} "
          f"cores, median of {args.repeats} interleaved solves, each from a fresh problem)")
    solve_problem(_fresh(problems[0][1]), "exact", opts)  # imports, not caches (emptied)
    passes = {"idle": compare_solvers(problems, opts, args.repeats, "idle")}
    if not args.no_busy:
        burner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        try:
            time.sleep(0.5)
            passes["busy"] = compare_solvers(problems, opts, args.repeats,
                                             "busy (one core saturated by a busy loop)")
        finally:
            burner.kill()
            burner.wait()
    print("\nsummary PSO/exact per window (min over windows): " + "; ".join(
        f"{k} wall {min(w):.0f}x cpu {min(c):.0f}x" for k, (w, c) in passes.items()))
    if args.solvers_only:
        return

    # normal estimation
    t0 = time.perf_counter()
    scan = simulate_scan(hub, ScannerModel(sigma=0.05e-3), seed=0, spacing=0.3e-3,
                         max_edge_distance=9e-3)
    t_scan = time.perf_counter() - t0
    print(f"\nnormals from a scan (sigma 0.05 mm, {len(scan.p_S)} points near the edges; "
          f"simulating it took {t_scan:.1f} s)")
    print(f"{'win':>3} {'kind':>5} {'M':>4} {'seconds':>8} {'ms/point':>9} {'median deg':>10} "
          f"{'p95 deg':>8} {'max deg':>8}")
    for edge in windows:
        cl, idx = cl_points_from_edge(edge, 2e-3)
        t0 = time.perf_counter()
        est = inner_normals_from_cloud(scan, cl)
        dt = time.perf_counter() - t0
        err = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", est.n_wall_H,
                                                     edge.n_wall_H[idx]), -1, 1)))
        print(f"{edge.index:>3} {edge.kind:>5} {len(cl):>4} {dt:>8.2f} {1e3 * dt / len(cl):>9.1f} "
              f"{np.median(err):>10.2f} {np.percentile(err, 95):>8.2f} {err.max():>8.2f}")

    # registration
    from pydrake.math import RigidTransform, RotationMatrix

    from drakedeburr.hub.registration import RegistrationOptions, points_in_world, register_hub
    from drakedeburr.hub.types import ScanCloud

    n = hub.spec.spoke_count
    rng = np.random.default_rng(0)
    X_true = RigidTransform(RotationMatrix.MakeZRotation(rng.uniform(-np.pi / n, np.pi / n)),
                            rng.uniform(-5e-3, 5e-3, 3))
    raw = simulate_scan(hub, ScannerModel(sigma=0.05e-3), seed=3, spacing=1.5e-3,
                        partial=(-2.0, 2.0))
    scan_W = ScanCloud(points_in_world(X_true, raw.p_S), source="scan")
    ropts = RegistrationOptions(symmetry_order=n, roi_radii=(0.07, 0.2))
    res = register_hub(scan_W, hub.trimesh, options=ropts)
    e = res.X_WH.inverse().multiply(X_true)
    print(f"\nregistration ({len(raw.p_S)} scan points, partial, turned and shifted): "
          f"{res.seconds:.1f} s, error {np.linalg.norm(e.translation()) * 1e3:.4f} mm / "
          f"{np.degrees(e.rotation().ToAngleAxis().angle()):.4f} deg, accepted {res.accepted}")
    if not args.quick:
        other = next(name for name in ("h5_straight", "h6_curved") if name != args.hub)
        wrong = register_hub(scan_W, load_hub(other).trimesh, options=ropts)
        print(f"wrong model ({other}): {wrong.seconds:.1f} s, accepted {wrong.accepted}, "
              f"fitness {wrong.fitness:.3f}")


if __name__ == "__main__":
    main()
