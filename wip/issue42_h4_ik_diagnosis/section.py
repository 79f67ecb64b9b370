import pickle
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import trimesh

from drakedeburr.hub import load_hub

hub = load_hub(sys.argv[1])
w = int(sys.argv[2])
idx = [int(x) for x in sys.argv[3].split(",")]
wt = pickle.load(open(f"/tmp/h4x/wt{w}.pkl", "rb"))
tm = hub.trimesh
fig, axs = plt.subplots(1, len(idx), figsize=(6 * len(idx), 6))
for ax, i in zip(np.atleast_1d(axs), idx, strict=False):
    p, t = wt.p_HC[i], wt.tool_path.cl_path.t_H[i]
    # section plane normal = the horizontal part of the edge tangent
    # (a vertical section across the edge)
    th = t.copy()
    th[2] = 0
    th /= np.linalg.norm(th)
    segs = trimesh.intersections.mesh_plane(tm, th, p)
    e1 = np.cross([0, 0, 1.0], th)  # horizontal across the edge
    for s in segs:
        d = s - p
        if np.linalg.norm(d, axis=1).min() > 0.08:
            continue
        ax.plot(d @ e1 * 1e3, d[:, 2] * 1e3, "k-", lw=1)
    a = wt.retract_H[i]
    n = wt.n_H[i]
    ax.plot([0, 60 * a @ e1], [0, 60 * a[2]], "r-", lw=2, label="pref axis 60 mm")
    ax.plot([0, 8 * n @ e1], [0, 8 * n[2]], "b-", lw=2, label="n_H 8 mm")
    ax.plot(0, 0, "go")
    ax.set_xlim(-60, 60)
    ax.set_ylim(-50, 70)
    ax.set_aspect("equal")
    ax.grid(True)
    ax.set_title(f"CL {i} z {p[2] * 1e3:.1f} edge slope {np.degrees(np.arcsin(abs(t[2]))):.0f}")
    ax.legend(fontsize=7)
plt.savefig(sys.argv[4], dpi=60)
