"""Tutorial 01: the deburring cells and the hubs.

Steps:
1. load the tool-in-hand cell (robot carries the floating spindle, hub face-up in a chuck) and
   the workpiece-in-hand cell (robot carries the hub, spindle on a stand) with one hub;
2. the frames every later stage uses: W, F (flange), T (cutting point), H (hub);
3. home is collision-free (SceneGraph query with a positive clearance);
4. the burr geometry the planner and verifier share;
5. reachability of the window edges from both cells (Drake InverseKinematics, FK re-check);
6. show both cells and the hub's window edges in Meshcat and save static HTML files.

Run:  python tutorials/01_cell_and_hubs/tutorial.py --out /tmp/cells  [--hub h5_split] [--test-mode]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from drakedeburr.cell import (
    BURR,
    ReachOptions,
    ReachTarget,
    face_targets,
    load_cell,
    survey_reach,
)
from drakedeburr.resources import hub_names, models_dir
from drakedeburr.viz import (
    get_meshcat,
    publish_cell,
    publish_edge_loops,
    publish_frame,
    publish_model_file,
    write_static_html,
)


def pick_hub(requested: str | None) -> str:
    """The requested hub, else the default bundled one; a plain disc stand-in if none exist."""
    if requested:
        return requested
    if (models_dir() / "hubs").is_dir() and hub_names():
        from drakedeburr.cell import resolve_hub_sdf

        return str(resolve_hub_sdf(None).parent)
    stand_in = Path(__file__).resolve().parents[2] / "tests" / "data" / "stand_in_hub" / "hub.sdf"
    print(f"(no bundled hubs yet: using the stand-in disc {stand_in})")
    return str(stand_in)


def window_edges(hub: str) -> list:
    """Ground-truth window edge loops of a generated hub (empty for a plain SDF)."""
    try:
        from drakedeburr.hub import load_hub

        return list(load_hub(hub).windows)
    except (ImportError, FileNotFoundError):
        return []


def fmt(v) -> str:
    return np.array2string(np.asarray(v), precision=4, suppress_small=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("cells_out"))
    ap.add_argument("--hub", default=None, help="bundled hub name, folder or hub.sdf")
    ap.add_argument("--test-mode", action="store_true", help="fewer reachability targets")
    args = ap.parse_args()
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    hub = pick_hub(args.hub)
    windows = window_edges(hub)
    print(f"hub: {hub} ({len(windows)} windows)")

    # 1. the two cells ----------------------------------------------------------------------
    cells = {name: load_cell(name, hub=hub) for name in ("tool_in_hand", "workpiece_in_hand")}

    for name, cell in cells.items():
        q = cell.q_home
        print(f"\n== {name}: {cell.mode}-in-hand, {cell.plant.num_positions()} joints")
        # 2. frames -----------------------------------------------------------------------
        print(f"  q_home [deg]         {fmt(np.degrees(q))}")
        print(f"  flange F in W [m]    {fmt(cell.X_WF(q).translation())}")
        print(f"  tool T in W [m]      {fmt(cell.X_WT(q).translation())}, "
              f"+Z_T = {fmt(cell.X_WT(q).rotation().matrix()[:, 2])}")
        print(f"  hub H in W [m]       {fmt(cell.X_WH(q).translation())}, "
              f"+Z_H = {fmt(cell.X_WH(q).rotation().matrix()[:, 2])}")
        print(f"  T in H (process)     {fmt(cell.X_HT(q).translation())}")
        print(f"  v_max [deg/s]        {fmt(np.degrees(cell.v_upper))}")
        print(f"  a_max [rad/s^2]      {fmt(cell.a_upper)}  (assumed, see docs/cell.md)")
        # 3. home is collision-free -------------------------------------------------------
        pairs = cell.collision_pairs(q, ignore_burr_hub=False)
        clearance, closest = cell.min_distance(q, ignore_burr_hub=False)
        print(f"  home: {len(pairs)} contacts, clearance {clearance * 1e3:.1f} mm "
              f"({closest[0]} / {closest[1]})")
        assert not pairs and clearance > 0.0, f"{name}: home is not collision-free"

    # 4. the burr ---------------------------------------------------------------------------
    print(f"\nburr: {np.degrees(2 * BURR.cone_half_angle):.0f} deg cone, head "
          f"{BURR.head_diameter * 1e3:.1f} mm, contact circle r = {BURR.contact_radius * 1e3:.1f} "
          f"mm at T, apex {BURR.apex_offset * 1e3:.1f} mm ahead of T")

    # 5. reachability of the window edges ----------------------------------------------------
    # Targets: points of every window edge with the burr axis along the face normal (into the
    # face) and tilted 0.5 rad from it. Kinematic survey (no distance constraint: the hub's ~400
    # convex collision pieces make that slow); each solution's clearance is reported instead
    # (the burr body against the hub excepted: the survey puts T on the edge itself).
    per_window = 2 if args.test_mode else 8
    targets = []
    for w in windows:
        for k in np.linspace(0, len(w.p_HE), per_window, endpoint=False).astype(int):
            n = w.n_face_H[k] if w.n_face_H is not None else np.array([0.0, 0.0, 1.0])
            tilt_dir = np.cross(n, w.t_H[k]) if w.t_H is not None else np.array([1.0, 0, 0])
            for tilt in (0.0, 0.5):
                a = -np.cos(tilt) * n + np.sin(tilt) * tilt_dir / np.linalg.norm(tilt_dir)
                targets.append(ReachTarget(w.p_HE[k], a))
    if not targets:  # a plain SDF hub without edges: points of its face instead
        targets = face_targets(0.175, rings=1, per_ring=4, tilt=0.5, tilts=2)
    for name, cell in cells.items():
        survey = survey_reach(cell, targets, ReachOptions(min_distance=None))
        reached = [r for r in survey.results if r.success]
        worst = max(r.position_error for r in reached)
        print(f"{name}: {len(reached)}/{len(targets)} edge targets reached "
              f"(axis up to 0.5 rad off the face normal, 10 deg joint margin, |J5| >= "
              f"{survey.min_wrist:.2f} rad), FK error <= {worst * 1e6:.2f} um, clearance "
              f"(burr body vs hub excepted) >= {min(r.clearance for r in reached) * 1e3:.1f} mm")

    # 6. show -------------------------------------------------------------------------------
    meshcat = get_meshcat()
    for name, cell in cells.items():
        meshcat.Delete()
        publish_cell(meshcat, cell)
        X_WH = cell.X_WH(cell.q_home)
        publish_edge_loops(meshcat, windows, X_WH)
        publish_frame(meshcat, "/drakedeburr/frames/T", cell.X_WT(cell.q_home), length=0.08)
        publish_frame(meshcat, "/drakedeburr/frames/H", X_WH, length=0.15)
        path = write_static_html(meshcat, out / f"{name}.html")
        print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    meshcat.Delete()
    publish_model_file(meshcat, cells["tool_in_hand"].hub_sdf, path="/drakedeburr/hub")
    publish_edge_loops(meshcat, windows)
    path = write_static_html(meshcat, out / "hub.html")
    print(f"wrote {path}; live viewer: {meshcat.web_url()}")


if __name__ == "__main__":
    main()
