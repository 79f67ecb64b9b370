"""Per CL point of chosen windows: edge slope, climb sign, box centre angle to +Z_H, blocked
flag and best clearance from the tool pre-check. usage: perpoint.py HUB_DIR W[,W..] OUT.json"""
import json
import logging
import sys

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import load_config
from drakedeburr.hub import load_hub
from drakedeburr.plan.options import PlanOptions
from drakedeburr.plan.planner import _context, _window_targets
from drakedeburr.plan.window import tool_refusal

logging.basicConfig(level=logging.ERROR)
hub_dir, wins, out = sys.argv[1], [int(x) for x in sys.argv[2].split(",")], sys.argv[3]
hub = load_hub(hub_dir)
config = load_config("tool_in_hand", hub_dir)
cell = load_cell("tool_in_hand", hub_dir)
ctx = _context(cell, config, PlanOptions(), None)
res = {}
for e in hub.windows:
    if e.index not in wins:
        continue
    wt, why = _window_targets(e, "toolpath", hub.process)
    tp = wt.tool_path
    ref = tool_refusal(ctx, wt)
    sp = -np.asarray(tp.cone_zT_H)
    slope = np.degrees(np.arcsin(np.clip(np.abs(tp.cl_path.t_H[:, 2]), 0, 1)))
    res[e.index] = {"slope": slope.tolist(),
                    "climb": np.sign(tp.cl_path.t_H[:, 2]).tolist(),
                    "centre": np.degrees(np.arccos(np.clip(sp[:, 2], -1, 1))).tolist(),
                    "blocked": ref.where["blocked_points"] if ref else [],
                    "best": ref.where["best_clearance_mm"] if ref else [],
                    "half": float(wt.cone_half_angle),
                    "p": (np.asarray(wt.p_HC) * 1e3).tolist()}
json.dump(res, open(out, "w"))
