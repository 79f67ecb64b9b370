"""Per target of one window: the round tool parts (shank, collet, spindle body) at the preferred
axis and over the recipe's cone, clearance to the REAL mesh and to the convex collision pieces;
how much the pieces overstate (true - pieces) at the pieces' closest point, and where that
point lies (plan distance to the opening, to the loop). Targets from mkwt.py (/tmp/h4x/wtW.pkl).
Usage: tool_vs_pieces.py HUB W [long]"""

import pickle
import sys
from collections import Counter

import numpy as np
import open3d as o3d
import trimesh
from scipy.spatial import ConvexHull, cKDTree

from drakedeburr.cell.tools import BURR
from drakedeburr.hub import load_hub
from drakedeburr.plan.ik_seeds import cone_ring
from drakedeburr.plan.targets import contact_geometry, tool_point_H

hub = load_hub(sys.argv[1])
w = int(sys.argv[2])
stick = 75e-3 if "long" in sys.argv[3:] else 25e-3
wt = pickle.load(open(f"/tmp/h4x/wt{w}.pkl", "rb"))


def scene_of(V, F):
    sc = o3d.t.geometry.RaycastingScene()
    sc.add_triangles(
        o3d.core.Tensor(np.asarray(V, np.float32)), o3d.core.Tensor(np.asarray(F, np.uint32))
    )
    return sc


true = scene_of(hub.vertices_H, hub.faces)
PV, PF, EQ, pid = [], [], [], []
n0 = 0
for k, p in enumerate(hub.collision_paths):
    v = np.asarray(trimesh.load(p, force="mesh", process=False).vertices)
    hull = ConvexHull(v)
    PV.append(v)
    PF.append(hull.simplices + n0)
    n0 += len(v)
    EQ.append(hull.equations)
    pid += [k] * len(hull.simplices)
pieces = scene_of(np.concatenate(PV), np.concatenate(PF))
pid = np.array(pid)


def d_pieces(q):
    ans = pieces.compute_closest_points(o3d.core.Tensor(q.astype(np.float32)))
    cp = ans["points"].numpy().astype(float)
    d = np.linalg.norm(q - cp, axis=1)
    for eq in EQ:  # inside a hull: distance 0 (a lower bound of the signed distance)
        inside = np.all(q @ eq[:, :3].T + eq[:, 3] <= 0, axis=1)
        d[inside] = 0.0
    return d, cp, pid[ans["primitive_ids"].numpy().astype(np.int64)]


r_c, lift = contact_geometry(1.6e-3)
pQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
hb = (BURR.head_radius - BURR.contact_radius) / np.tan(BURR.cone_half_angle)
u = np.arange(hb + 1e-3, hb + stick + 20e-3 + 250e-3, 1e-3)
rad = np.where(
    u < hb + stick,
    BURR.shank_diameter / 2,
    np.where(u < hb + stick + 20e-3, BURR.collet_diameter / 2, 0.04),
)
part = np.where(u < hb + stick, "shank", np.where(u < hb + stick + 20e-3, "collet", "spindle"))
miss_xy = None
# opening in plan: vertical rays that miss the mesh, 0.5 mm grid around the window
lo = hub.windows[w].p_HE[:, :2].min(0) - 0.03
hi = hub.windows[w].p_HE[:, :2].max(0) + 0.03
gx, gy = np.meshgrid(np.arange(lo[0], hi[0], 5e-4), np.arange(lo[1], hi[1], 5e-4), indexing="ij")
rays = np.zeros((gx.size, 6), np.float32)
rays[:, 0], rays[:, 1] = gx.ravel(), gy.ravel()
rays[:, 2] = hub.vertices_H[:, 2].max() + 0.05
rays[:, 5] = -1
miss = ~np.isfinite(true.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy())
opening = cKDTree(rays[miss, :2].astype(float))
loop = cKDTree(hub.windows[w].p_HE[:, :2])


def clear(p, a):
    pts = p[None] + (lift + u)[:, None] * a[None]
    dt = true.compute_distance(o3d.core.Tensor(pts.astype(np.float32))).numpy() - rad
    dp, cp, pk = d_pieces(pts)
    dp = dp - rad
    k = int(np.argmin(dp))
    j = int(np.argmin(dt))
    return dict(
        true=dt[j],
        pieces=dp[k],
        over=dt[k] - dp[k],
        part=part[k],
        piece=int(pk[k]),
        cp=cp[k],
        u=u[k],
    )


rows = []
for i in range(len(wt)):
    c = wt.cone_retract_H[i]
    axes = (
        [c]
        + cone_ring(c, 0.66 * wt.cone_half_angle, 8)
        + cone_ring(c, 0.98 * wt.cone_half_angle, 12)
    )
    pref = clear(pQ[i], wt.retract_H[i])
    cone = [clear(pQ[i], a) for a in axes]
    best_p = max(cone, key=lambda r: r["pieces"])
    best_t = max(cone, key=lambda r: r["true"])
    slope = np.degrees(np.arcsin(abs(wt.t_H[i, 2])))
    rows.append(
        (
            i,
            slope,
            pref["true"],
            pref["pieces"],
            pref["over"],
            best_t["true"],
            best_p["pieces"],
            best_p["over"],
            best_p["part"],
            best_p["piece"],
            opening.query(best_p["cp"][:2])[0],
            loop.query(best_p["cp"][:2])[0],
            best_p["cp"][2] - wt.p_HC[i, 2],
            best_p["u"],
        )
    )
R = np.array([r[:8] for r in rows], float) * np.r_[1, 1, [1e3] * 6]
need = 2.05
print(f"window {w}, {len(rows)} targets, stick {stick * 1e3:.0f} mm; clearance need {need} mm")
print(
    f"  preferred axis: pieces >= need {int((R[:, 3] >= need).sum())}, true >= "
    f"need {int((R[:, 2] >= need).sum())}; median pieces {np.median(R[:, 3]):.2f} "
    f"true {np.median(R[:, 2]):.2f}"
)
print(
    f"  best in cone:   pieces >= need {int((R[:, 6] >= need).sum())}, true >= "
    f"need {int((R[:, 5] >= need).sum())}; median pieces {np.median(R[:, 6]):.2f} "
    f"true {np.median(R[:, 5]):.2f}"
)
print(
    f"  overstatement at the pieces' closest point (best cone axis): median "
    f"{np.median(R[:, 7]):.2f} "
    f"p90 {np.quantile(R[:, 7], 0.9):.2f} max {R[:, 7].max():.2f} mm"
)
fail_p = R[:, 6] < need
print(
    "  targets failing on the pieces but clear on the mesh (best in cone): "
    f"{int((fail_p & (R[:, 5] >= need)).sum())}"
)

print(
    "  blocking part (pieces, best cone axis, failing):",
    Counter(r[8] for r, f in zip(rows, fail_p, strict=False) if f).most_common(),
)
print(" i slope truePref pcsPref over | trueCone pcsCone over | part piece dOpen dLoop dz u  [mm]")
for r in rows[:: max(1, len(rows) // 40)]:
    print(
        f"{r[0]:3d} {r[1]:5.1f} {r[2] * 1e3:6.2f} {r[3] * 1e3:6.2f} {r[4] * 1e3:5.2f} "
        f"| {r[5] * 1e3:6.2f} {r[6] * 1e3:6.2f} {r[7] * 1e3:5.2f} | {r[8]:7s} "
        f"{r[9]:3d} {r[10] * 1e3:5.1f} {r[11] * 1e3:5.1f} {r[12] * 1e3:6.1f} {r[13] * 1e3:5.1f}"
    )
pickle.dump(rows, open(f"/tmp/h6/tvp{w}_{int(stick * 1e3)}.pkl", "wb"))
