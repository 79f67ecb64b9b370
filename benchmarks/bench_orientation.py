"""Orientation benchmark: exact solver vs the source's PSO on the same `axis` model, per window
of a bundled hub, plus normal-estimation and registration time.

    python benchmarks/bench_orientation.py [--hub h5_split] [--quick]

Both solvers see the same problem (CL points every 2 mm, ground-truth normals). PSO uses the
source's settings (50 particles, 200 iterations, inertia 0.8, c1 = c2 = 2, seed 0) and its
Gaussian smoothing; its objective is reported after smoothing (the pipeline's output) and
raw. --quick: two windows, no registration of the wrong model.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drakedeburr.frames.local_frames import R_HL_from_normals
from drakedeburr.frames.normals import inner_normals_from_cloud
from drakedeburr.hub import load_hub, simulate_scan
from drakedeburr.orientation import OrientOptions, problem_for, solve_problem
from drakedeburr.orientation.commands import cl_points_from_edge


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--hub", default="h5_split")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    hub = load_hub(args.hub)
    windows = hub.windows[:2] if args.quick else hub.windows
    opts = OrientOptions()
    print(f"## orientation: hub {args.hub}, axis model, exact vs PSO (same run)")
    print(f"{'win':>3} {'kind':>5} {'M':>4} {'exact obj':>10} {'exact ms':>9} {'PSO obj':>10} "
          f"{'PSO raw':>10} {'PSO ms':>8} {'speed-up':>8} {'obj ratio':>9}")
    speed, ratio = [], []
    for edge in windows:
        cl, idx = cl_points_from_edge(edge, 2e-3)
        prob = problem_for(cl, R_HL_from_normals(cl.t_H, edge.n_wall_H[idx]), "axis", options=opts)
        solve_problem(prob, "exact", opts)  # warm-up (imports, first Drake solve)
        ex = solve_problem(prob, "exact", opts)
        ps = solve_problem(prob, "pso", opts)
        speed.append(ps.solve_seconds / ex.solve_seconds)
        ratio.append(ps.objective / ex.objective)
        print(f"{edge.index:>3} {edge.kind:>5} {prob.m:>4} {ex.objective:>10.4f} "
              f"{1e3 * ex.solve_seconds:>9.1f} {ps.objective:>10.4f} "
              f"{ps.info['objective_raw']:>10.4f} {1e3 * ps.solve_seconds:>8.1f} "
              f"{speed[-1]:>7.1f}x {ratio[-1]:>9.2f}")
    print(f"speed-up PSO/exact: min {min(speed):.1f}x, median {np.median(speed):.1f}x; "
          f"PSO objective / exact objective: min {min(ratio):.2f} (exact never worse: "
          f"{'yes' if min(ratio) >= 1.0 else 'NO'})")

    # normal estimation
    t0 = time.perf_counter()
    scan = simulate_scan(hub, sigma=0.05e-3, seed=0, spacing=0.3e-3, max_edge_distance=9e-3)
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
    raw = simulate_scan(hub, sigma=0.05e-3, seed=3, spacing=1.5e-3, partial=(-2.0, 2.0))
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
