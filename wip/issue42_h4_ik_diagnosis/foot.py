"""Share of each loop lying at the foot of a flank: the surface seen from the front 1 mm outside
the loop (away from the opening) stands more than 3 mm above the loop point."""

import math
import sys

import numpy as np
import open3d as o3d

import drakedeburr.hub.edgeline as el
import drakedeburr.hub.extract as ex
from drakedeburr.hub.mesh_io import load_hub_mesh

name, ang = sys.argv[1], float(sys.argv[2])
el.WALL_ANGLE = math.radians(ang)
lm = load_hub_mesh(f"/work/shared/extdata/wheel_models/{name}")
res = ex.extract_window_edges(lm.mesh, source=name)
X = np.linalg.inv(res.X_MH)
V = (lm.mesh.vertices @ X[:3, :3].T + X[:3, 3]).astype(np.float32)
sc = o3d.t.geometry.RaycastingScene()
sc.add_triangles(o3d.core.Tensor(V), o3d.core.Tensor(np.asarray(lm.mesh.faces, np.uint32)))
top = V[:, 2].max() + 0.05
out = []
for w in res.windows:
    p, t0 = w.p_HE, w.t_H
    left = np.cross([0, 0, 1.0], t0)[:, :2]
    gentle = np.abs(t0[:, 2]) < np.sin(np.radians(45))
    h = left / np.maximum(np.linalg.norm(left, axis=1, keepdims=True), 1e-9)
    q = p[:, :2] - 1e-3 * h
    rays = np.c_[q, np.full(len(q), top), np.zeros((len(q), 2)), -np.ones(len(q))].astype(
        np.float32
    )
    t = sc.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()
    above = (top - t) - p[:, 2]
    seg = np.linalg.norm(np.roll(p, -1, 0) - p, axis=1)
    foot = gentle & np.isfinite(above) & (above > 3e-3)
    seg = seg * gentle
    out.append((w.index, w.kind, seg[foot].sum() / seg.sum(), np.ptp(p[:, 2])))
print(
    f"{name} WALL {ang}: share of the gently sloped loop length at a flank's foot "
    f"(surface 1 mm outside > 3 mm above):"
)
print(
    "  " + "; ".join(f"w{i} {k[0]} {s * 100:.0f} % (dz {dz * 1e3:.0f} mm)" for i, k, s, dz in out)
)
