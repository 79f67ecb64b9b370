"""Tutorial 04: plan a hub - cone-constrained IK, smoothing and timing at 150 mm/s.

Steps:
1. the cell (tool in hand) and a bundled hub; the windows' targets (CL points, inner normals,
   preferred tool axes and the admissible cone);
2. where the tool point goes for a CL point (burr contact circle, depth of cut);
3. the plan: Drake IK at every CL target, the executed linear motion solved analytically,
   approach/retract/transitions, timing;
4. joint angles before and after smoothing (the source's Fig. 22/23), TCP speed, J4-J6 ranges;
   the opt-in fillet repair (a KTO's tool orientation where the cut slows at a fillet);
5. save the plan, joint CSV, a RAPID program, a Meshcat replay (static HTML);
6. the same window in the workpiece-in-hand cell (same code, other frames).

Run:  python tutorials/04_plan_a_hub/tutorial.py --out /tmp/plan  [--test-mode]
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from drakedeburr.cell.station import load_cell  # noqa: E402
from drakedeburr.config import load_config
from drakedeburr.hub import DEFAULT_HUB, load_hub  # noqa: E402
from drakedeburr.plan import (  # noqa: E402
    PlanOptions,
    contact_geometry,
    load_plan,
    plan_windows,
    save_plan,
    tool_point_H,
    window_targets_for_hub,
    write_joint_csv,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("plan_out"))
    ap.add_argument("--test-mode", action="store_true", help="a stretch of one window only")
    ap.add_argument("--hub", default=None, help="bundled hub (default: the first)")
    args = ap.parse_args()
    out = args.out
    out.mkdir(parents=True, exist_ok=True)

    # 1. cell + hub + targets ---------------------------------------------------------------
    hub_name = args.hub or DEFAULT_HUB
    cell = load_cell("tool_in_hand", hub_name)
    hub = load_hub(hub_name)
    print(f"cell: {cell.mode}-in-hand, hub {hub_name} with {len(hub.windows)} windows")
    if args.test_mode:
        # the real chain (path stage CL points + orientation stage ToolPath) for window 0,
        # planned on a 20-point stretch
        windows = [window_targets_for_hub(hub, windows=[0])[0].stretch(0, 20)]
    else:
        windows = window_targets_for_hub(hub)  # path + orientation stages (ToolPath)
    for w in windows:
        print(f"  window {w.window_index} ({w.kind}): {len(w)} CL points, cone half-angle "
              f"{np.degrees(w.cone_half_angle):.1f} deg, depth of cut {w.depth_of_cut * 1e3:.1f} mm"
              f" [{w.source}]")

    # 2. tool point for a CL point --------------------------------------------------------------
    w0 = windows[0]
    r_c, lift = contact_geometry(PlanOptions().contact_radius)
    p_HT = tool_point_H(w0.p_HC[:1], w0.n_H[:1], w0.retract_H[:1], w0.depth_of_cut, r_c, lift)
    offset = p_HT[0] - w0.p_HC[0]
    print(f"tool point offset from CL 0: {np.round(offset * 1e3, 3)} mm (cutting circle radius "
          f"{r_c * 1e3:.2f} mm, T lifted {lift * 1e3:.2f} mm along the axis; along the inner "
          f"normal {offset @ w0.n_H[0] * 1e3:+.3f} mm)")

    # 3. plan -------------------------------------------------------------------------------
    options = PlanOptions()
    plan = plan_windows(cell, windows, load_config("tool_in_hand", hub_name), options=options)
    m = plan.meta
    print(f"plan: {len(plan.targets)} targets, cycle {m['cycle_seconds']:.2f} s, cutting "
          f"{m['cutting_seconds']:.2f} s (physical limit {m['physical_cut_seconds']:.2f} s), "
          f"{len(plan.failures)} failures")
    assert not plan.failures, plan.failures[:3]

    # 4. joints before/after smoothing, speed, wrist ranges ------------------------------------
    ws = m["windows"][0]
    q_ik, q_sm = np.degrees(ws["q_ik_rad"]), np.degrees(ws["q_smoothed_rad"])
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for j in range(6):
        axes[0].plot(q_ik[:, j], label=f"J{j + 1}")
        axes[1].plot(q_sm[:, j], label=f"J{j + 1}")
        axes[2].plot(q_sm[:, j] - q_ik[:, j], label=f"J{j + 1}")
    axes[2].set_title("change made by smoothing")
    axes[0].set_title("joint angles at the CL targets: per-target IK (before smoothing)")
    axes[1].set_title("after orientation smoothing + analytic IK on one configuration")
    axes[2].set_xlabel("CL target")
    for a in axes:
        a.set_ylabel("deg")
        a.legend(ncol=6, fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "joints_before_after_smoothing.png", dpi=120)
    tr = plan.trajectory
    tt = np.linspace(0, tr.duration, 3000)
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(cell)
    p = kin.X_HT_from_q(tr.value(tt))[:, :3, 3]
    v = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(tt)
    fig, ax = plt.subplots(figsize=(8, 3))
    ax.plot(tt[1:], v * 1e3)
    for s in plan.segments:
        ax.axvspan(*s.t_range, alpha=0.08 if s.kind == "cut" else 0.0, color="r")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("TCP speed rel. hub [mm/s]")
    fig.tight_layout()
    fig.savefig(out / "tcp_speed.png", dpi=120)
    for w in m["windows"]:
        print(f"  window {w['window']}: J4 {w['j4_range_deg']:.1f} deg, J5 {w['j5_range_deg']:.1f}"
              f" deg, J6 {w['j6_range_deg']:.1f} deg range; speed in +-5 % band "
              f"{100 * w['speed_in_band_fraction']:.0f} % of cutting; min clearance "
              f"{w['min_clearance_m'] * 1e3:.2f} mm")

    # the fillet repair (on by default): where the timed cut slows at a fillet, the feed
    # program looks for a tool orientation that holds the feed (docs/plan.md, "Fillet
    # repair"); here the first window planned again without it, for comparison
    bare = plan_windows(cell, windows[:1], load_config("tool_in_hand", hub_name),
                        options=replace(options, fillets=None))
    assert not bare.failures, bare.failures[:3]
    a, b = bare.meta["windows"][0], m["windows"][0]
    print(f"fillet repair, window {a['window']}: cut {a['cut_seconds']:.2f} s without -> "
          f"{b['cut_seconds']:.2f} s with, in band {100 * a['speed_in_band_fraction']:.0f} % -> "
          f"{100 * b['speed_in_band_fraction']:.0f} %")

    # 5. files ------------------------------------------------------------------------------
    save_plan(plan, out / "plan")
    back = load_plan(out / "plan")
    assert np.array_equal(back.trajectory.q, plan.trajectory.q)
    write_joint_csv(plan, out / "plan" / "joints.csv")
    from drakedeburr.programs import program_from_plan, write_program

    # the tool data carry the spindle model's mass and centre of gravity (cell.flange_loads)
    program = program_from_plan(plan, "Deburr", loads=cell.flange_loads(), flag="UNVERIFIED",
                                flag_reason="tutorial plan, not verified")
    print("program:", [str(p) for p in write_program(program, out / "Deburr.mod", "rapid")])
    from drakedeburr.viz.playback import save_plan_html

    html = save_plan_html(plan, out / "replay.html", cell=cell, dt=0.2 if args.test_mode else 0.05)
    print(f"replay: {html} ({html.stat().st_size / 1e6:.1f} MB)")

    # 6. workpiece in hand ----------------------------------------------------------------------
    if args.test_mode:
        wp_windows = [replace(windows[0].stretch(0, 8))]
    else:
        wp_windows = windows
    wp_cell = load_cell("workpiece_in_hand", hub_name)
    wp = plan_windows(wp_cell, wp_windows, load_config("workpiece_in_hand", hub_name))
    print(f"workpiece in hand: cycle {wp.meta['cycle_seconds']:.2f} s, {len(wp.failures)} failures")
    assert not wp.failures, wp.failures[:3]


if __name__ == "__main__":
    main()
