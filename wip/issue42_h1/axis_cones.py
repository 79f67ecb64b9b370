"""Issue 42 (h1), deliverable 1: at each CL target of a window, is there ANY tool axis for
which the round tool parts (shank, collet, spindle body) clear the part by the 2 mm
clearance, with the burr's contact circle on the edge? Cones: the recipe's (about its cone
axis), 20/30/45 deg about the same axis, 20/30/45 deg about the inner normal tilted up
(the local frame's retract side: n + face normal, normalised) and 45/60 deg about +Z_H.
Drake (standalone SceneGraph of the cell's own tool parts and hub pieces, plan.clearance).
Usage: PYTHONPATH=$PWD python wip/issue42_h1/axis_cones.py HUB_DIR W [W ...] [TOOL=long_reach]"""

import logging
import os
import sys
import time

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import load_config
from drakedeburr.hub import load_hub
from drakedeburr.plan.clearance import tool_axis_clearance, tool_scene
from drakedeburr.plan.kinematics import ClearanceChecker
from drakedeburr.plan.planner import _window_targets
from drakedeburr.plan.targets import contact_geometry, tool_point_H

logging.basicConfig(level=logging.ERROR)

hub_dir, wins = sys.argv[1], [int(w) for w in sys.argv[2:]]
TOOL = os.environ.get("TOOL")
hub = load_hub(hub_dir)
config = load_config("tool_in_hand", hub_dir)
cell = load_cell("tool_in_hand", hub_dir, tool=TOOL)
checker = ClearanceChecker(cell, tolerances=config.tolerances)
scene = tool_scene(checker)
print("tool parts:", {scene.names[g]: round(r * 1e3) for g, r in scene.reach.items()})
r_c, lift = contact_geometry(1.6e-3)
bound = config.tolerances.min_clearance
for w in wins:
    wt, why = _window_targets(hub.windows[w], "toolpath", hub.process)
    if wt is None:
        print(f"w{w}: no targets: {why[:200]}")
        continue
    m = len(wt)
    pQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    slope = np.degrees(np.arcsin(np.clip(np.abs(wt.tool_path.cl_path.t_H[:, 2]), 0, 1)))
    z = np.tile([0, 0, 1.0], (m, 1))
    up_n = wt.n_H + z
    up_n /= np.linalg.norm(up_n, axis=1, keepdims=True)
    fams = (
        [("recipe", None, None)]
        + [(f"cone{a}", np.radians(a), None) for a in (20, 30, 45)]
        + [(f"n+z{a}", np.radians(a), up_n) for a in (20, 30, 45)]
        + [(f"Z{a}", np.radians(a), z) for a in (45, 60)]
    )
    print(
        f"w{w} ({wt.kind}, {m} targets, recipe cone {np.degrees(wt.cone_half_angle):.1f} deg, "
        f"{int((slope > 30).sum())} on stretches > 30 deg)"
    )
    res = {}
    for name, half, about in fams:
        t0 = time.time()
        s = tool_axis_clearance(
            scene, wt, pQ, lift, bound=bound, margin=0.2e-3, half_angle=half, about=about
        )
        res[name] = s
        ok = s.best >= bound
        worst = int(np.argmin(s.best))
        blocked = np.median(s.best[~ok]) * 1e3 if (~ok).any() else 0.0
        parts = sorted({p for p, o in zip(s.part, ok, strict=False) if not o})
        where = np.round(wt.p_HC[worst] * 1e3, 1).tolist()
        steep = slope > 30
        print(
            f"  {name:8s}: clear {int(ok.sum()):3d}/{m} (steep {int((ok & steep).sum())}/"
            f"{int(steep.sum())}); blocked best median {blocked:6.1f} mm; "
            f"worst {s.best[worst] * 1e3:6.1f} mm at CL {worst} {where} "
            f"slope {slope[worst]:.0f}; parts {parts} proven blocked {int(s.proven.sum())} "
            f"({int(s.reads.sum())} reads) [{time.time() - t0:.1f} s]",
            flush=True,
        )
    np.savez(
        f"/tmp/h1/axis_cones_w{w}_{TOOL or 'std'}.npz",
        slope=slope,
        p_HC=wt.p_HC,
        **{k: v.best for k, v in res.items()},
    )
