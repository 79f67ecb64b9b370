"""Each window of an imported hub: targets (or the ToolPath refusal), then the window IK from the
best start seed until its first failed target (stop_at_failure): how far it gets and why."""

import logging
import os
import sys
import time

import numpy as np

from drakedeburr.cell.station import load_cell
from drakedeburr.config import load_config
from drakedeburr.hub import load_hub
from drakedeburr.plan.ik import IkOptions, seed_by_spin, solve_window_ik
from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
from drakedeburr.plan.planner import _window_targets
from drakedeburr.plan.targets import contact_geometry, tool_point_H

logging.basicConfig(level=logging.ERROR)

hub_dir = sys.argv[1]
TOOL = os.environ.get("TOOL")
hub = load_hub(hub_dir)
config = load_config("tool_in_hand", hub_dir)
cell = load_cell("tool_in_hand", hub_dir, tool=TOOL)
kin = cell_kinematics(cell)
checker = ClearanceChecker(cell, tolerances=config.tolerances)
opt = IkOptions()
r_c, lift = contact_geometry(1.6e-3)
for e in hub.windows:
    t0 = time.time()
    wt, why = _window_targets(e, "toolpath", hub.process)
    if wt is None:
        print(f"w{e.index} {e.kind}: no targets: {why[:200]}", flush=True)
        continue
    pQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    q0 = seed_by_spin(
        kin, checker, pQ[0] + lift * wt.retract_H[0], wt.retract_H[0], wt.t_H[0], kin.q_home, opt
    )
    res = solve_window_ik(
        cell,
        kin,
        checker,
        pQ,
        wt.retract_H,
        wt.cone_retract_H,
        wt.cone_half_angle,
        wt.t_H,
        kin.q_home,
        window_index=e.index,
        options=opt,
        q_first=q0,
        lift=lift,
        stop_at_failure=True,
    )
    f = res.failures[0] if res.failures else None
    sl = np.degrees(np.arcsin(abs(wt.tool_path.cl_path.t_H[f.point, 2]))) if f else 0
    dz = (wt.p_HC[:, 2].max() - wt.p_HC[f.point, 2]) * 1e3 if f else 0
    print(
        f"w{e.index} {e.kind}: {len(wt)} targets, IK reached {int(res.ok.sum())} "
        f"before the first failure"
        + (
            f" at CL {f.point} (edge slope {sl:.0f} deg, {dz:.0f} mm below the "
            f"loop's top): {f.reason[:160]}"
            if f
            else " (all)"
        )
        + f" [{time.time() - t0:.0f} s]",
        flush=True,
    )
