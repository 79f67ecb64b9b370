"""How far the collision pieces named in near-miss IK records stand off the real mesh surface.

Usage: python proud.py HUB_FOLDER PIECE [PIECE ...] (unsigned distance: see the README)."""
import sys

import numpy as np
import trimesh
from trimesh.triangles import closest_point

hub = sys.argv[1]
mesh = trimesh.load(f"{hub}/hub.obj", force="mesh")
tri = mesh.triangles
for name in sys.argv[2:]:
    p = trimesh.load(f"{hub}/collision/{name}.obj", force="mesh")
    s = np.vstack([p.vertices, p.sample(1500, seed=0)])
    lo, hi = s.min(0) - 0.01, s.max(0) + 0.01
    near = tri[((tri.min(1) <= hi) & (tri.max(1) >= lo)).all(1)]
    d = np.array([np.linalg.norm(closest_point(near, np.repeat(q[None], len(near), 0)) - q,
                                 axis=1).min() for q in s])
    print(name, f"{len(near)} tris; hull samples off the real surface: max {d.max() * 1e3:.2f} "
                f"mm, 99 % {np.percentile(d, 99) * 1e3:.2f} mm, median {np.median(d) * 1e3:.3f} mm")
