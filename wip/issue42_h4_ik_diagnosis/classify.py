"""Every target of one window: is there a clear pose (Drake cone probe, 2.05 mm) in the recipe's
cone, in a 45 deg cone about the same axis; which part blocks; by slope and depth."""

import logging
import os
import pickle
import sys
import time
from collections import Counter

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import load_config
from drakedeburr.plan.ik import IkOptions
from drakedeburr.plan.ik_seeds import cone_clearance_probe
from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
from drakedeburr.plan.targets import contact_geometry, tool_point_H

logging.basicConfig(level=logging.ERROR)

hub_dir, wtfile = sys.argv[1], sys.argv[2]
TOOL = os.environ.get("TOOL")
wt = pickle.load(open(wtfile, "rb"))
config = load_config("tool_in_hand", hub_dir)
cell = load_cell("tool_in_hand", hub_dir, tool=TOOL)
kin = cell_kinematics(cell)
checker = ClearanceChecker(cell, tolerances=config.tolerances)
opt = IkOptions()
r_c, lift = contact_geometry(1.6e-3)
pQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
slope = np.degrees(np.arcsin(np.abs(wt.tool_path.cl_path.t_H[:, 2])))
depth = (wt.p_HC[:, 2].max() - wt.p_HC[:, 2]) * 1e3
res = []
t0 = time.time()


def probe(i, half_angle, axis_H):
    """The Drake cone probe at target i: a cone of ``half_angle`` about the retract ``axis_H``."""
    return cone_clearance_probe(
        kin,
        checker,
        pQ[i],
        wt.cone_retract_H[i],
        half_angle,
        axis_H,
        wt.t_H[i],
        kin.q_home,
        lift=lift,
        bound=opt.min_distance_floor,
        min_wrist=opt.min_wrist,
    )


for i in range(len(wt)):
    a = probe(i, wt.cone_half_angle, wt.retract_H[i])
    b = a if a["feasible"] else probe(i, np.radians(45), wt.cone_retract_H[i])
    part = (a["pair"][0] or "").split("::")[-1].split("/")[0]
    res.append((i, slope[i], depth[i], a["feasible"], b["feasible"], a["best_clearance"], part))
pickle.dump(res, open(wtfile + f".{TOOL or 'std'}.cls", "wb"))
R = np.array([(r[1], r[2], r[3], r[4]) for r in res], float)
steep = R[:, 0] > 30
print(
    f"{len(res)} targets ({time.time() - t0:.0f} s), tool {TOOL or 'standard'}: "
    f"clear in the recipe cone {int(R[:, 2].sum())}, only in a 45 deg cone "
    f"{int((~R[:, 2].astype(bool) & R[:, 3].astype(bool)).sum())}, "
    f"in neither {int((~R[:, 3].astype(bool)).sum())}"
)
for nm, m in [("gentle (<=30 deg)", ~steep), ("steep (>30 deg, frame limited at 45)", steep)]:
    print(
        f"  {nm}: {int(m.sum())} targets: recipe cone {int(R[m, 2].sum())}, 45 "
        f"deg only {int((m & ~R[:, 2].astype(bool) & R[:, 3].astype(bool)).sum())}, "
        f"neither {int((m & ~R[:, 3].astype(bool)).sum())}"
    )
for lo, hi in [(0, 10), (10, 25), (25, 100)]:
    m = (R[:, 1] >= lo) & (R[:, 1] < hi)
    print(
        f"  depth below the loop's top {lo}-{hi} mm: {int(m.sum())} targets: recipe "
        f"cone {int(R[m, 2].sum())}, neither {int((m & ~R[:, 3].astype(bool)).sum())}"
    )

print("  blocking part in the recipe cone:", Counter(r[6] for r in res if not r[3]).most_common())
