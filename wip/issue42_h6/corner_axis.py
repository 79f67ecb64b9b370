"""Issue 42 (h6): why the orientation stage's tool axis points into the hub on windows 0/3/5/9
of the audibot rim. Light: path + orientation stages only (no IK, no collision).

Per window: CL points where axis . Z_H <= 0; at each: edge slope (true tangent and the frame's
slope-limited one), the tangent's turn angle over +-1 CL point, n . Z_H (the inner normal's
tilt out of the face plane), n . t, the axis angle below the face plane, theta_A/theta_B, and
where the frame's -B (Z_L) points. Usage: corner_axis.py HUB_DIR [W ...]"""

import sys

import numpy as np

from drakedeburr.hub import load_hub
from drakedeburr.plan.tool_paths import tool_path

hub = load_hub(sys.argv[1])
ws = [int(a) for a in sys.argv[2:]] or [w.index for w in hub.windows]
Z = np.array([0.0, 0.0, 1.0])
for edge in hub.windows:
    if edge.index not in ws:
        continue
    tp = tool_path(edge, hub.process)
    ax = -tp.zT_H  # tip -> spindle
    t_true = tp.cl_path.t_H / np.linalg.norm(tp.cl_path.t_H, axis=1, keepdims=True)
    n = tp.R_HL[:, :, 0]
    t = tp.R_HL[:, :, 1]
    zl = tp.R_HL[:, :, 2]
    nraw = None
    bad = np.flatnonzero(ax @ Z <= 0.0)
    m = len(tp)
    print(f"window {edge.index} ({edge.kind}): {m} CL, {bad.size} into the hub; "
          f"z range {1e3 * tp.p_HC[:, 2].min():.1f}..{1e3 * tp.p_HC[:, 2].max():.1f} mm")
    runs = np.split(bad, np.flatnonzero(np.diff(bad) > 1) + 1) if bad.size else []
    for r in runs:
        for i in r[:: max(1, len(r) // 4)]:
            turn = np.degrees(np.arccos(np.clip(t_true[(i - 1) % m] @ t_true[(i + 1) % m], -1, 1)))
            sl = np.degrees(np.arcsin(abs(t_true[i, 2])))
            slf = np.degrees(np.arcsin(abs(t[i, 2])))
            below = np.degrees(np.arcsin(-ax[i] @ Z))
            print(f"  CL {i:3d} p={np.round(tp.p_HC[i] * 1e3, 1).tolist()} slope {sl:4.0f} "
                  f"(frame {slf:3.0f}) turn {turn:5.1f} n.Z {n[i] @ Z:+.3f} "
                  f"n.t_true {n[i] @ t_true[i]:+.3f} Z_L.Z {zl[i] @ Z:+.3f} "
                  f"axis {below:5.1f} deg below, thA {np.degrees(tp.theta_A[i]):5.1f} "
                  f"thB {np.degrees(tp.theta_B[i]):5.1f}")
    np.savez(f"/tmp/h6/w{edge.index}.npz", p=tp.p_HC, R=tp.R_HL, ax=ax, t=t_true,
             thA=tp.theta_A, thB=tp.theta_B)
