"""Tutorial 02: from a window edge to cutter-location (CL) points, four planners compared.

Run:  python tutorials/02_cl_points/tutorial.py [--out DIR] [--test-mode] [--mesh FILE]

1. get a window edge: from a hub mesh (``--mesh``) via edge-loop extraction, else a hub-like
   analytic window;
2. fit the closed NURBS curve (EdgeCurve) and look at its curvature;
3. plan CL points with the source's method, the two baselines and our adaptive planner;
4. print the Tab. 1-2 style figures and save a plot of the four plans.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from drakedeburr.hub.types import WindowEdge  # noqa: E402
from drakedeburr.path import METHODS, cl_table, fit_edge_curve, format_table, plan_all  # noqa: E402
from drakedeburr.path.synthetic import hub_like_window  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("--out", default="out_02", help="output folder")
ap.add_argument("--test-mode", action="store_true", help="smaller inputs (CI)")
ap.add_argument("--mesh", help="hub mesh (STL, OBJ, PLY, OFF, DAE, GLB) to extract the "
                "windows from")
args = ap.parse_args()
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)

# 1. window edges
if args.mesh:
    from drakedeburr.hub.extract import extract_window_edges
    from drakedeburr.hub.mesh_io import load_hub_mesh

    windows = extract_window_edges(load_hub_mesh(args.mesh).mesh, source=args.mesh).windows
else:
    # the source's windows 1 and 2 had 182 and 63 initial CL points
    windows = [WindowEdge(0, "large", hub_like_window("large", 182)),
               WindowEdge(1, "small", hub_like_window("small", 63, angle=1.2))]
w = windows[-1] if args.test_mode else windows[0]

# 2. the closed NURBS (periodic B-spline) fit
curve = fit_edge_curve(w.p_HE)
u = np.linspace(0, 1, 2000, endpoint=False)
print(f"window {w.index}: {len(w.p_HE)} initial points, length {curve.length * 1e3:.1f} mm, "
      f"max curvature {curve.curvature(u).max() / 1e3:.3f} 1/mm")

# 3. the four planners on one window
paths = plan_all(curve, kind=w.kind, window_index=w.index)

for name, path in paths.items():
    m = path.metrics
    print(f"{name:20s} {m['count']:4d} points  c_v {m['cv']:.3f} (all pairs "
          f"{m['cv_pairwise']:.3f})  max chord height {m['max_chord_height_m'] * 1e3:.4f} mm  "
          f"max chord {m['max_chord_length_m'] * 1e3:.2f} mm")

# 4. the Tab. 1-2 style table for all windows (library call = `drakedeburr cl`), and a plot
if not args.test_mode:
    print(format_table(cl_table(windows, methods=METHODS)))

fig, axes = plt.subplots(1, 4, figsize=(18, 5), sharex=True, sharey=True)
p = curve.position(u) * 1e3
for ax, (name, path) in zip(axes, paths.items(), strict=True):
    ax.plot(p[:, 0], p[:, 1], "-", color="0.6", lw=1)
    q = path.p_HC * 1e3
    sc = ax.scatter(q[:, 0], q[:, 1], c=path.kappa / 1e3, s=14, cmap="viridis", zorder=3)
    m = path.metrics
    ax.set_title(f"{name}\nn={m['count']}  c_v={m['cv']:.3f}  "
                 f"max δ={m['max_chord_height_m'] * 1e3:.3f} mm", fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlabel("x_H [mm]")
axes[0].set_ylabel("y_H [mm]")
fig.colorbar(sc, ax=axes, label="curvature [1/mm]", shrink=0.8)
fig.savefig(out / "cl_planners.png", dpi=110)
print(f"wrote {out / 'cl_planners.png'}")
