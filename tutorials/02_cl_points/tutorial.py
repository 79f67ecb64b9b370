"""Tutorial 02: from a window edge to cutter-location (CL) points, four planners compared.

Run:  python tutorials/02_cl_points/tutorial.py [--out DIR] [--test-mode] [--mesh FILE]

1. get a window edge: from a hub mesh (``--mesh``) via edge-loop extraction, else a hub-like
   analytic window;
2. fit the closed NURBS curve (EdgeCurve) as the pipeline does (``fit_window_edge``: the
   interpolating fit of a smooth loop, the smoothing fit of a faceted low-poly one) and look
   at its curvature;
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
from drakedeburr.path import (  # noqa: E402
    METHODS,
    PlannerParams,
    cl_table,
    fit_window_edge,
    format_table,
    plan_all,
)
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

# 2. the closed NURBS (periodic B-spline) fit, chosen from the loop's points (a low-poly mesh's
# faceted loop gets the smoothing fit, which does not follow every facet corner)
curve = fit_window_edge(w.p_HE, chord_tolerance=PlannerParams().delta_max,
                        name=f"window {w.index}")
u = np.linspace(0, 1, 2000, endpoint=False)
print(f"window {w.index}: {len(w.p_HE)} initial points, length {curve.length * 1e3:.1f} mm, "
      f"max curvature {curve.curvature(u).max() / 1e3:.3f} 1/mm, {curve.fit['fit']} fit "
      f"({curve.fit['facets']} facets, chord error {curve.fit['chord_error_m'] * 1e3:.4f} mm)")

# 3. the four planners on one window
paths = plan_all(curve, kind=w.kind, window_index=w.index)

for name, path in paths.items():
    m = path.metrics
    print(f"{name:20s} {m['count']:4d} points  c_v {m['cv']:.3f} (all pairs "
          f"{m['cv_pairwise']:.3f})  max chord height {m['max_chord_height_m'] * 1e3:.4f} mm  "
          f"max chord {m['max_chord_length_m'] * 1e3:.2f} mm")

# 3b. the figures checked independently: every CL point on the curve, and each chord's height
# and length read here by sampling the curve between neighbouring CL points (not the planners'
# own metric), against the threshold each method promises
P = PlannerParams()
PROMISES = {"isoparametric": ("height", "length"), "adaptive": ("height", "length"),
            "equal_chord_height": ("height",), "proposed": ()}


def chords(path):
    """Per span of the closed CL sequence: (largest distance of the curve from the chord [m],
    chord length [m]), the curve sampled 400 times per span."""
    u0, u1 = path.u, np.append(path.u[1:], path.u[0] + 1.0)
    a, b = curve.position(u0), curve.position(u1)
    s = np.linspace(0.0, 1.0, 401)
    c = curve.position(u0[:, None] + s[None] * (u1 - u0)[:, None])  # (M, 401, 3)
    ab = b - a
    f = np.clip(np.einsum("mj,msj->ms", ab, c - a[:, None]) / np.sum(ab * ab, 1)[:, None], 0, 1)
    height = np.linalg.norm(c - (a[:, None] + f[..., None] * ab[:, None]), axis=2).max(axis=1)
    return height, np.linalg.norm(ab, axis=1)


for name, path in paths.items():
    np.testing.assert_allclose(curve.position(path.u), path.p_HC, atol=1e-9)
    assert np.all(np.diff(path.u) > 0) and 0 <= path.u[0] and path.u[-1] < 1, name
    height, length = chords(path)
    m = path.metrics
    # the planner's figure is the one read here (its own search is finer than 400 samples)
    assert height.max() <= m["max_chord_height_m"] + 1e-9, (name, height.max())
    assert height.max() >= 0.98 * m["max_chord_height_m"], (name, height.max())
    np.testing.assert_allclose(length.max(), m["max_chord_length_m"], rtol=1e-9)
    assert m["count"] == len(path.u)
    if "height" in PROMISES[name]:
        assert height.max() <= P.delta_max, (name, height.max())
    if "length" in PROMISES[name]:
        assert length.max() <= P.l_max + 1e-12, (name, length.max())
# the adaptive planner spends at most the proposed method's count (its budget) where that count
# is feasible, i.e. where the proposed plan itself keeps both thresholds
proposed = paths["proposed"].metrics
if proposed["max_chord_height_m"] <= P.delta_max and proposed["max_chord_length_m"] <= P.l_max:
    assert paths["adaptive"].metrics["count"] <= proposed["count"]
print(f"checked: every CL point on the curve; chord height <= {P.delta_max * 1e3:.2f} mm and "
      f"chord <= {P.l_max * 1e3:.0f} mm where the method promises it")

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
