"""How far the collision pieces stand proud of the true mesh seen from the front (-Z_H rays),
against the plan distance to the nearest opening (rays that miss the mesh) and to the nearest
window loop. Usage: proud.py HUB_DIR [STEP_MM]"""

import sys

import numpy as np
import open3d as o3d
import trimesh
from matplotlib.path import Path as MP
from scipy.spatial import cKDTree

from drakedeburr.hub import load_hub

hub = load_hub(sys.argv[1])
h = float(sys.argv[2]) * 1e-3 if len(sys.argv) > 2 else 1e-3


def scene_of(V, F):
    sc = o3d.t.geometry.RaycastingScene()
    sc.add_triangles(
        o3d.core.Tensor(np.asarray(V, np.float32)), o3d.core.Tensor(np.asarray(F, np.uint32))
    )
    return sc


true = scene_of(hub.vertices_H, hub.faces)
PV, PF, pid = [], [], []
for k, p in enumerate(hub.collision_paths):
    m = trimesh.load(p, force="mesh", process=False)
    PF.append(np.asarray(m.faces) + sum(len(v) for v in PV))
    PV.append(np.asarray(m.vertices))
    pid += [k] * len(m.faces)
pieces = scene_of(np.concatenate(PV), np.concatenate(PF))
pid = np.array(pid)
r = np.hypot(hub.vertices_H[:, 0], hub.vertices_H[:, 1]).max()
g = np.arange(-r, r, h)
gx, gy = np.meshgrid(g, g, indexing="ij")
xy = np.c_[gx.ravel(), gy.ravel()]
xy = xy[np.hypot(xy[:, 0], xy[:, 1]) < r]
z0 = hub.vertices_H[:, 2].max() + 0.05
rays = np.zeros((len(xy), 6), np.float32)
rays[:, :2] = xy
rays[:, 2] = z0
rays[:, 5] = -1
a = true.cast_rays(o3d.core.Tensor(rays))
b = pieces.cast_rays(o3d.core.Tensor(rays))
ta, tb = a["t_hit"].numpy(), b["t_hit"].numpy()
miss = ~np.isfinite(ta)
opening = cKDTree(xy[miss])
loops = np.concatenate([w.p_HE[:, :2] for w in hub.windows])
loop_tree = cKDTree(loops)
hit = np.isfinite(ta) & np.isfinite(tb)
# the piece's first hit point's 3-D distance to the true mesh (a steep wall's 0.5 mm shell
# would read as a tall step along the ray)
ph = (rays[hit, :3] + tb[hit, None] * rays[hit, 3:]).astype(np.float32)
proud = true.compute_distance(o3d.core.Tensor(ph)).numpy() * 1e3
above = (ta - tb)[hit] * 1e3
d_open = opening.query(xy[hit])[0] * 1e3
d_loop = loop_tree.query(xy[hit])[0] * 1e3
# inside each window loop's plan polygon? (between loop and the opening)

inside = np.zeros(hit.sum(), bool)
for w in hub.windows:
    inside |= MP(w.p_HE[:, :2]).contains_points(xy[hit])
print(f"grid {h * 1e3:.1f} mm, {hit.sum()} rays hitting both; {len(hub.collision_paths)} pieces")
print(
    "plan distance to opening [mm] | rays | proud median / p95 / max [mm] | share > 1 mm | > 2 mm"
)
for lo, hi in [
    (0, 5),
    (5, 10),
    (10, 15),
    (15, 20),
    (20, 25),
    (25, 30),
    (30, 40),
    (40, 60),
    (60, 999),
]:
    m = (d_open >= lo) & (d_open < hi) & ~inside
    if m.sum():
        p = proud[m]
        print(
            f"  {lo:3.0f}-{hi:3.0f} outside loops | {m.sum():6d} | {np.median(p):5.2f} "
            f"/ {np.quantile(p, 0.95):5.2f} / {p.max():5.2f} | {np.mean(p > 1):5.1%} "
            f"| {np.mean(p > 2):5.1%}"
        )
print("plan distance to nearest loop (outside the loops) [mm]")
for lo, hi in [(0, 2), (2, 5), (5, 10), (10, 20), (20, 40)]:
    m = (d_loop >= lo) & (d_loop < hi) & ~inside
    if m.sum():
        p = proud[m]
        print(
            f"  {lo:3.0f}-{hi:3.0f} | {m.sum():6d} | {np.median(p):5.2f}"
            f" / {np.quantile(p, 0.95):5.2f} "
            f"/ {p.max():5.2f} | {np.mean(p > 1):5.1%} | {np.mean(p > 2):5.1%}"
        )
m = inside
p = proud[m]
print(
    f"  inside loops (between loop and opening) | {m.sum()} | {np.median(p):5.2f} "
    f"/ {np.quantile(p, 0.95):5.2f} / {p.max():5.2f} | {np.mean(p > 1):5.1%}"
)
np.savez(
    "/tmp/h6/proud.npz",
    xy=xy[hit],
    proud=proud,
    above=above,
    d_open=d_open,
    d_loop=d_loop,
    inside=inside,
    pid=pid[b["primitive_ids"].numpy()[hit].astype(np.int64)],
)
