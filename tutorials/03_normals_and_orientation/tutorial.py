"""Tutorial 03: inner-side normals, local frames and tool orientation on a bundled hub.

Run:  python tutorial.py [--hub h5_split] [--out DIR] [--test-mode]

1. load a bundled hub and simulate a noisy scan of its window edges (sigma = 0.05 mm);
2. estimate the inner-side normals at the CL points of one large and one small window
   (the source's procedure: radius search, k-means, RANSAC plane / quadric fit) and compare
   them with the model's ground truth;
   (CL points from the path stage: the pipeline's NURBS fit, ``fit_window_edge``, + the
   source's planner);
3. build the local frames [N, T, -B] and optimise the tool axis with the `axis` model
   (exact solver) - and, for comparison, the source's eq. 11 with its PSO;
4. write a meshcat scene as static HTML (normals = green, tool axes = red, source's
   eq. 11 axes = blue) and a PNG with the angle sequences.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.frames import inner_normals_from_cloud
from drakedeburr.hub import ScannerModel, load_hub, simulate_scan
from drakedeburr.orientation import OrientOptions, PsoOptions, orient_window
from drakedeburr.path import PlannerParams, fit_window_edge, plan_cl


def check_figures(edge, cl, err, tp, tp_paper) -> None:
    """The tutorial's key figures, re-read here from the vectors (not from the solvers' stats):
    the estimated normals near the model's, the local frames right-handed with Y_L along the
    feed, and each tool axis's angles (docs/orientation.md's formulas) inside the box."""
    # normals: the source's procedure on a 0.05 mm scan; docs/orientation.md states a median of
    # 0.13-0.20 deg and a 95th percentile of 0.6-0.9 deg on h5_split, CL points every 2 mm
    assert np.median(err) < 0.5 and np.percentile(err, 95) < 2.0, (edge.index, err)
    t_H = cl.t_H / np.linalg.norm(cl.t_H, axis=1, keepdims=True)
    for t in (tp, tp_paper):
        R = t.R_HL
        np.testing.assert_allclose(np.einsum("mji,mjk->mik", R, R), np.broadcast_to(
            np.eye(3), R.shape), atol=1e-9)
        np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-9)  # not the printed reflection
        np.testing.assert_allclose(R[:, :, 1], t_H, atol=1e-9)  # Y_L = feed direction
        z = t.zT_H
        np.testing.assert_allclose(np.linalg.norm(z, axis=1), 1.0, atol=1e-9)
        N, T, Z = R[:, :, 0], R[:, :, 1], R[:, :, 2]
        theta_A = np.arctan2(-np.einsum("ij,ij->i", z, N), np.einsum("ij,ij->i", z, Z))
        theta_B = np.arcsin(np.clip(-np.einsum("ij,ij->i", z, T), -1, 1))
        np.testing.assert_allclose(theta_A, t.theta_A, atol=1e-9)
        np.testing.assert_allclose(theta_B, t.theta_B, atol=1e-9)
        lo, hi = t.bounds.theta_min, t.bounds.theta_max
        for theta in (theta_A, theta_B):
            assert np.all((theta >= lo - 1e-9) & (theta <= hi + 1e-9)), (t.model, lo, hi)
    assert tp.success, tp.message


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hub", default="h5_split")
    ap.add_argument("--out", default="out_03")
    ap.add_argument("--test-mode", action="store_true",
                    default=os.environ.get("DRAKEDEBURR_TEST_MODE") == "1")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    hub = load_hub(args.hub)
    large = next(w for w in hub.windows if w.kind == "large")
    small = next((w for w in hub.windows if w.kind == "small"), None)
    windows = [large] if small is None else [large, small]
    method = "equal_chord_height" if args.test_mode else "proposed"  # CL planner (path stage)

    # 1. a dense scan near the window edges only (cheap); restricted to the two windows' sector
    ang = np.concatenate([np.arctan2(w.p_HE[:, 1], w.p_HE[:, 0]) for w in windows])
    mid = np.angle(np.exp(1j * ang).mean())
    d = np.angle(np.exp(1j * (ang - mid)))  # polar angles relative to their mean, no wrap
    sector = (mid + d.min() - 0.15, mid + d.max() + 0.15)
    scan = simulate_scan(hub, ScannerModel(sigma=0.05e-3), seed=0, spacing=0.3e-3,
                         max_edge_distance=9e-3, partial=sector)
    print(f"scan: {len(scan.p_S)} points near the edges of windows "
          f"{[w.index for w in windows]}")

    results = []
    pso = OrientOptions(pso=PsoOptions(iterations=50 if args.test_mode else 200))
    for edge in windows:
        # the pipeline's fit (path.window_fit): interpolating on a smooth loop, smoothing on a
        # faceted low-poly one
        curve = fit_window_edge(edge.p_HE, chord_tolerance=PlannerParams().delta_max,
                                name=f"window {edge.index}")
        cl = plan_cl(curve, method, window_index=edge.index, kind=edge.kind)
        # 2. normals from the cloud vs ground truth (at the nearest point of the model's loop)
        est = inner_normals_from_cloud(scan, cl)
        nearest = np.argmin(np.linalg.norm(cl.p_HC[:, None] - edge.p_HE[None], axis=2), axis=1)
        n_true = edge.n_wall_H[nearest]
        err = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", est.n_wall_H, n_true), -1, 1)))
        print(f"window {edge.index} ({edge.kind}, {len(cl)} CL points): normal error "
              f"median {np.median(err):.2f} deg, 95 % {np.percentile(err, 95):.2f} deg; "
              f"fits: {est.method.count('plane')} planes, "
              f"{len(cl) - est.method.count('plane')} curved")
        # 3. orientation: the axis model (exact) and the source's eq. 11 (PSO + smoothing)
        tp = orient_window(cl, est.n_wall_H)
        tp_paper = orient_window(cl, est.n_wall_H, model="paper", solver="pso", options=pso)
        for t in (tp, tp_paper):
            s = t.stats
            print(f"  {t.model:5s}/{t.solver:5s}: theta_A {s['theta_A']['min']:.3f}.."
                  f"{s['theta_A']['max']:.3f} rad, theta_B {s['theta_B']['min']:.3f}.."
                  f"{s['theta_B']['max']:.3f} rad, tool-axis turning max "
                  f"{s['axis_turn_deg_per_mm']['max']:.2f} deg/mm, total "
                  f"{s['axis_turn_total_deg']:.0f} deg, {1e3 * t.solve_seconds:.0f} ms")
        check_figures(edge, cl, err, tp, tp_paper)
        results.append((edge, cl, est, tp, tp_paper))

    # 4a. angle plots
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(results), 2, figsize=(11, 3.2 * len(results)), squeeze=False)
    for row, (edge, cl, _, tp, tp_paper) in enumerate(results):
        s_mm = cl.arc_length * 1e3
        ax = axes[row, 0]
        ax.plot(s_mm, tp.theta_A, "r-", label="theta_A, axis model (exact)")
        ax.plot(s_mm, tp.theta_B, "r--", label="theta_B, axis model (exact)")
        ax.plot(s_mm, tp_paper.theta_A, "b-", lw=0.8, label="theta_A, eq. 11 (PSO + smoothing)")
        ax.plot(s_mm, tp_paper.theta_B, "b--", lw=0.8, label="theta_B, eq. 11 (PSO + smoothing)")
        ax.axhline(tp.bounds.theta_min, color="k", lw=0.5)
        ax.axhline(tp.bounds.theta_max, color="k", lw=0.5)
        ax.set(xlabel="arc length [mm]", ylabel="angle [rad]",
               title=f"window {edge.index} ({edge.kind}): angles in the local frame")
        ax.legend(fontsize=7)
        ax = axes[row, 1]
        for t, c in ((tp, "r"), (tp_paper, "b")):
            turn = np.degrees(np.arccos(np.clip(np.einsum(
                "ij,ij->i", t.zT_H, np.roll(t.zT_H, -1, axis=0)), -1, 1)))
            ds = np.linalg.norm(np.roll(cl.p_HC, -1, axis=0) - cl.p_HC, axis=1) * 1e3
            ax.plot(s_mm, turn / ds, c, label=f"{t.model}/{t.solver}")
        ax.set(xlabel="arc length [mm]", ylabel="tool-axis turn [deg/mm]",
               title="what the robot feels: the axis turning in the hub frame")
        ax.legend(fontsize=7)
    fig.tight_layout()
    png = out / "angles.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")

    # 4b. meshcat scene as static HTML
    from pydrake.geometry import Rgba, SurfaceTriangle, TriangleSurfaceMesh

    from drakedeburr.viz import get_meshcat

    meshcat = get_meshcat(new=True)  # on 127.0.0.1 only (Drake's Meshcat() listens everywhere)
    V, F = hub.vertices_H, hub.faces
    mesh = TriangleSurfaceMesh([SurfaceTriangle(*f) for f in F.tolist()], V.tolist())
    meshcat.SetObject("hub", mesh, Rgba(0.75, 0.75, 0.78, 0.6))
    step = 1
    for edge, cl, est, tp, tp_paper in results:
        p = cl.p_HC[::step].T
        L = 0.012  # arrow length [m]
        meshcat.SetLineSegments(f"window{edge.index}/normals", p, p + L * est.n_wall_H[::step].T,
                                2.0, Rgba(0.1, 0.7, 0.1, 1))
        # tool axes drawn from the tip back toward the spindle (-Z_T) so they stand over the edge
        meshcat.SetLineSegments(f"window{edge.index}/axis_model", p,
                                p - 2 * L * tp.zT_H[::step].T,
                                2.0, Rgba(0.9, 0.1, 0.1, 1))
        meshcat.SetLineSegments(f"window{edge.index}/paper_model", p,
                                p - 2 * L * tp_paper.zT_H[::step].T, 1.0,
                                Rgba(0.1, 0.2, 0.9, 1))
        meshcat.SetLine(f"window{edge.index}/edge", np.c_[cl.p_HC.T, cl.p_HC[:1].T], 2.0,
                        Rgba(0, 0, 0, 1))
    html = out / "normals_and_axes.html"
    atomic_write_text(html, meshcat.StaticHtml())
    print(f"wrote {html} (open it in a browser)")


if __name__ == "__main__":
    main()
