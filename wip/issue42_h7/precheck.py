"""Blocked CL points per window from the planner's tool pre-check (plan.window.tool_refusal),
targets by the path + orientation stages of THIS checkout (run with PYTHONPATH=<worktree>).

usage: python precheck.py HUB_DIR [OUT.json]    (tool_in_hand cell, standard burr)
Per window: CL points, blocked points, the tool part and depth of the worst, the box centre's
angle to +Z_H (median / max over the CL points), steep points (slope > 45 deg)."""

import json
import logging
import sys
import time

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import load_config
from drakedeburr.hub import load_hub
from drakedeburr.plan.options import PlanOptions
from drakedeburr.plan.planner import _context, _window_targets
from drakedeburr.plan.window import tool_refusal

logging.basicConfig(level=logging.ERROR)
hub_dir = sys.argv[1]
hub = load_hub(hub_dir)
config = load_config("tool_in_hand", hub_dir)
cell = load_cell("tool_in_hand", hub_dir)
ctx = _context(cell, config, PlanOptions(), None)
rows = []
for e in hub.windows:
    t0 = time.time()
    wt, why = _window_targets(e, "toolpath", hub.process)
    if wt is None:
        rows.append({"window": e.index, "targets": None, "why": why[:160]})
        print(f"w{e.index}: no targets: {why[:160]}", flush=True)
        continue
    tp = wt.tool_path
    spindle = -np.asarray(tp.cone_zT_H)
    centre = np.degrees(np.arccos(np.clip(spindle[:, 2], -1, 1)))
    slope = np.degrees(np.arcsin(np.clip(np.abs(tp.cl_path.t_H[:, 2]), 0, 1)))
    ref = tool_refusal(ctx, wt)
    blocked = ref.where["blocked_points"] if ref is not None else []
    row = {"window": e.index, "targets": len(wt), "blocked": len(blocked),
           "steep": int((slope > 45).sum()), "blocked_steep": int((slope[blocked] > 45).sum()),
           "centre_to_Z_deg_median": float(np.median(centre)),
           "centre_to_Z_deg_max": float(centre.max()),
           "worst_mm": float(ref.value * 1e3) if ref is not None else None,
           "part": ref.where["pair"][0] if ref is not None else None,
           "seconds": round(time.time() - t0, 1)}
    rows.append(row)
    print(json.dumps(row), flush=True)
tot = sum(r.get("blocked", 0) for r in rows)
npts = sum(r["targets"] or 0 for r in rows)
print(f"TOTAL blocked {tot} of {npts} CL points; windows with none blocked: "
      f"{sum(1 for r in rows if r.get('targets') and r['blocked'] == 0)} of {len(rows)}")
if len(sys.argv) > 2:
    with open(sys.argv[2], "w") as f:
        json.dump(rows, f, indent=1)
