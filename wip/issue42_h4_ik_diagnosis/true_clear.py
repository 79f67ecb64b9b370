"""Spin-invariant clearance of the round tool (shank, collet, spindle body) against the REAL
hub mesh (not the convex pieces), per target and axis family."""

import pickle
import sys

import numpy as np
import open3d as o3d

from drakedeburr.cell.tools import BURR
from drakedeburr.hub import load_hub
from drakedeburr.plan.ik_seeds import cone_ring
from drakedeburr.plan.targets import contact_geometry, tool_point_H

hub = load_hub(sys.argv[1])
w = int(sys.argv[2])
wt = pickle.load(open(f"/tmp/h4x/wt{w}.pkl", "rb"))
sc = o3d.t.geometry.RaycastingScene()
sc.add_triangles(
    o3d.core.Tensor(hub.vertices_H.astype(np.float32)), o3d.core.Tensor(hub.faces.astype(np.uint32))
)
r_c, lift = contact_geometry(1.6e-3)
pQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)


def profile(stick):
    hb = (BURR.head_radius - BURR.contact_radius) / np.tan(BURR.cone_half_angle)
    u = np.arange(hb + 1e-3, hb + stick + 20e-3 + 250e-3, 1e-3)
    r = np.where(
        u < hb + stick,
        BURR.shank_diameter / 2,
        np.where(u < hb + stick + 20e-3, BURR.collet_diameter / 2, 0.04),
    )
    return u, r


def clear(p, a, prof):
    u, r = prof
    pts = p[None] + (lift + u)[:, None] * a[None]
    d = sc.compute_distance(o3d.core.Tensor(pts.astype(np.float32))).numpy()
    k = np.argmin(d - r)
    return float((d - r)[k]), float(u[k])


z = np.array([0, 0, 1.0])
profs = {"std": profile(25e-3), "long": profile(75e-3)}
axes_z = (
    [z]
    + cone_ring(z, np.radians(15), 12)
    + cone_ring(z, np.radians(30), 16)
    + cone_ring(z, np.radians(45), 20)
)
out = []
for i in range(len(wt)):
    a_pref, c = wt.retract_H[i], wt.cone_retract_H[i]
    cone_axes = (
        [c]
        + cone_ring(c, 0.66 * wt.cone_half_angle, 8)
        + cone_ring(c, 0.98 * wt.cone_half_angle, 12)
    )
    row = [i, wt.p_HC[i, 2] * 1e3, np.degrees(np.arcsin(abs(wt.t_H[i, 2])))]
    for _name, prof in profs.items():
        row.append(clear(pQ[i], a_pref, prof)[0] * 1e3)
        row.append(max(clear(pQ[i], a, prof)[0] for a in cone_axes) * 1e3)
        row.append(max(clear(pQ[i], a, prof)[0] for a in axes_z) * 1e3)
    out.append(row)
out = np.array(out)
np.save(f"/tmp/h4x/trueclear{w}.npy", out)
names = ["pref", "cone", "z45"]
for j, tool in enumerate(["std", "long"]):
    for k, nm in enumerate(names):
        col = out[:, 3 + 3 * j + k]
        print(
            f"{tool:4s} {nm:4s}: targets with >= 2.05 mm true clearance: "
            f"{int((col >= 2.05).sum()):3d}/{len(out)}; "
            f">=0: {int((col >= 0).sum()):3d}; median {np.median(col):6.2f} mm"
        )
for r in out[::5]:
    print(" ".join(f"{v:7.2f}" for v in r))
