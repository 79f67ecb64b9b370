"""Median distance of gentle loop stretches to mesh creases / borders, per window (as the test)."""

import math
import sys

import numpy as np

import drakedeburr.hub.edgeline as el
import drakedeburr.hub.extract as ex
from drakedeburr.hub.mesh_io import load_hub_mesh

name, ang, reach = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
el.WALL_ANGLE = math.radians(ang)
orig = el.deburr_line


def patched(scene, outline, z0, **kw):
    kw.setdefault("reach", reach * 1e-3)
    return orig(scene, outline, z0, **kw)


ex.deburr_line = patched
lm = load_hub_mesh(f"/work/shared/extdata/wheel_models/{name}")
mesh = lm.mesh
res = ex.extract_window_edges(mesh, source=name)

adj = mesh.face_adjacency
ang_e = mesh.face_adjacency_angles
sharp = mesh.face_adjacency_edges[ang_e >= np.radians(10)]
e, count = np.unique(np.sort(mesh.edges, axis=1), axis=0, return_counts=True)
edges = np.vstack([sharp, e[count == 1]])
a, b = mesh.vertices[edges[:, 0]], mesh.vertices[edges[:, 1]]


def segd(p, a, b):
    out = np.full(len(p), np.inf)
    ab = b - a
    L2 = np.maximum((ab * ab).sum(1), 1e-30)
    for i in range(0, len(p), 64):
        q = p[i : i + 64, None, :]
        t = np.clip(((q - a) * ab).sum(-1) / L2, 0, 1)
        out[i : i + 64] = np.linalg.norm(q - (a + t[..., None] * ab), axis=-1).min(1)
    return out


X = res.X_MH
meds = []
for w in res.windows:
    p = w.p_HE @ X[:3, :3].T + X[:3, 3]
    gentle = np.abs(w.t_H[:, 2]) < np.sin(np.radians(45.0))
    d = segd(p[gentle], a, b)
    meds.append(np.median(d) * 1e3)
print(
    f"{name} wall {ang} reach {reach}: {len(res.windows)} windows, rejected "
    f"{len(res.notes['rejected'])}; "
    f"crease median mm max {max(meds):.2f}: {np.round(meds, 2).tolist()}; z ranges "
    f"{[round(np.ptp(w.p_HE[:, 2]) * 1e3) for w in res.windows]}"
)
