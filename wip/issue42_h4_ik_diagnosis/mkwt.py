import pickle
import sys

import numpy as np

from drakedeburr.hub import load_hub
from drakedeburr.plan.tool_paths import tool_path as _tool_path
from drakedeburr.plan.window_targets import WindowTargets

hub = load_hub(sys.argv[1])
w = int(sys.argv[2])
tp = _tool_path(hub.windows[w], hub.process)


def u(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


wt = WindowTargets(
    window_index=w,
    kind=tp.kind,
    p_HC=tp.p_HC,
    t_H=u(tp.R_HL[:, :, 1]),
    n_H=u(tp.R_HL[:, :, 0]),
    retract_H=-u(tp.zT_H),
    cone_retract_H=-u(tp.cone_zT_H),
    cone_half_angle=float(tp.cone_outer_half_angle),
    depth_of_cut=float(tp.depth_of_cut),
    tool_path=tp,
)
pickle.dump(wt, open(f"/tmp/h4x/wt{w}.pkl", "wb"))
print(len(wt), "targets; cone", np.degrees(wt.cone_half_angle))
