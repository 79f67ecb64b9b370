"""Study: how fast can a fillet be cut at all? (issue 5's speed band, planner-independent)

The planner cuts a window slower than the +-5 % band around each fillet (the joint
accelerations bind there). This study asks a joint-space optimiser the same question with every
freedom the planner has and none of its choices: around each slow stretch of a planned window,
one Drake KinematicTrajectoryOptimization (SNOPT) over the joints, warm-started from the plan,
with the tool point on the plan's executed path (+-0.02 mm every 1 mm), the tool axis inside
its cone (interpolated between the CL points, 2 mrad inside), 2 mm clearance (burr contact
excepted), the joint speed (95 %) and acceleration (90 %) limits the planner times to, and the
plan's joints and path velocity at both ends of the stretch. The speed along the stretch is
prescribed: 143 mm/s (inside the band) with a raised-cosine dip to 50 mm/s of a given width
centred on the plan's slowest point (no dip: constant 143 mm/s). The result is re-checked
densely with the cell's own FK and distance queries (not SNOPT's word) against the verifier's
own tolerances (``Tolerances``: the tool within ``path_deviation`` of the path, the axis inside
its cone to ``cone_slack``, clearance at least ``min_clearance`` at every one of 1500 points,
every joint acceleration within the model's limit): only then is a profile *held*. Where SNOPT's
solution leaks between its constraints, the stretch is solved once more with the constraints
twice as dense and the cone margin doubled. The looser verdict earlier versions printed (2 mrad
outside the cone, 1.98 mm clearance allowed) is shown beside it: a figure built on it is not
one a verified plan can reach.

The narrowest dip held at each fillet is how much of the window a (locally) optimal joint path
must still cut outside the band; it is evidence, not a proof (SNOPT is a local solver).

Run:  PYTHONPATH=. python benchmarks/study_fillet_speed.py [--hub NAME] [--window W]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drakedeburr.config import load_config

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ("--hub", "h5_straight", "--window", "0")
QUICK_ARGS = ("--hub", "h5_straight", "--window", "0")

V_BAND = 0.143  # [m/s] inside +-5 % of 150 mm/s
V_DIP = 0.050  # [m/s] the dip's slowest speed
HALF_SPAN = 0.05  # [m] optimised stretch: the slowest point +- this


def _profile(s, v_hi, dip):
    """Times t(s) of a speed profile along s: v_hi with a raised-cosine dip (centre, width,
    v_low) or none."""
    sg = np.linspace(s[0], s[-1], 4001)
    v = np.full_like(sg, v_hi)
    if dip is not None:
        c, w, v_lo = dip
        x = np.clip((sg - (c - w / 2)) / w, 0, 1)
        v = v_hi - (v_hi - v_lo) * 0.5 * (1 - np.cos(2 * np.pi * x))
    t = np.concatenate([[0], np.cumsum(np.diff(sg) / (0.5 * (v[1:] + v[:-1])))])
    return sg, t


def hold(cell, kin, checker, tol, s, q, p, cone_s, cones, half_angle, dip, targets,
         control_points=24, constraint_step=1e-3, cone_margin=2e-3, position_tolerance=0.02e-3):
    """One KTO over the stretch (s, q, p: the plan's samples) with the prescribed profile;
    returns (held to the verifier's tolerances ``tol``, held to the looser criterion, SNOPT
    success, max path deviation, least cone margin as the verifier reads the cone, least
    clearance, largest acceleration ratio, seconds). ``targets``: the window's CL points in
    program order and their cone axes, (K, 3) each."""
    from drakedeburr.plan.cut_path import axes_interp
    from drakedeburr.plan.fillets import CutSamples, FilletOptions, stretch_kto
    from drakedeburr.plan.program_reading import cone_axes_on_moves
    from drakedeburr.verify.geometry import point_segment

    sg, tg = _profile(s, V_BAND, dip)
    amax = np.asarray(kin.a_max)
    t0 = time.perf_counter()
    X = kin.X_HT_from_q(q)
    X[:, :3, 3] = p  # the plan's tool points (the KTO reads only these of the poses)
    res, traj = stretch_kto(
        cell, checker, CutSamples(s, q, X, axes_interp(cone_s, cones, s), half_angle),
        np.interp(s, sg, tg), amax, np.asarray(kin.v_max),
        FilletOptions(control_points=control_points, acceleration_share=0.9,
                      cone_margin=cone_margin, constraint_step=constraint_step, iterations=500,
                      position_tolerance=position_tolerance))
    sec = time.perf_counter() - t0
    tt = np.linspace(traj.start_time(), traj.end_time(), 1500)
    Q = np.array([traj.value(t).ravel() for t in tt])
    Qdd = np.array([traj.EvalDerivative(t, 2).ravel() for t in tt])
    X = kin.X_HT_from_q(Q)
    P = X[:, :3, 3]
    dev, k, f = point_segment(P, p[:-1], p[1:])  # the verifier's point-to-path reading
    s_at = s[k] + f * np.diff(s)[k]
    axis = -X[:, :3, 2]
    ang = np.arccos(np.clip(np.sum(axes_interp(cone_s, cones, s_at) * axis, 1), -1, 1))
    margin_interp = float(np.min(half_angle - ang))
    # the cone as the verifier reads it: on the program's moves between the CL points
    ang = np.arccos(np.clip(np.sum(cone_axes_on_moves(P, *targets) * axis, 1), -1, 1))
    margin = float(np.min(half_angle - ang))
    clear = float(checker.min_distances_along(Q, 0.01).min())
    acc = float(np.max(np.abs(Qdd) / amax))
    dmax = float(dev.max())
    strict = (dmax <= tol.path_deviation and margin >= -tol.cone_slack
              and clear >= tol.min_clearance and acc <= 1.0)
    loose = dmax <= 0.05e-3 and margin_interp >= -2e-3 and clear >= 1.98e-3 and acc <= 1.0
    return strict, loose, res.is_success(), dmax, margin, clear, acc, sec


def held_at(cell, kin, checker, tol, s, q, p, cone_s, cones, half_angle, dip, targets, **kw):
    """:func:`hold`, solved once more with denser constraints and twice the cone margin where
    the first solution holds only the looser criterion: (held, loosely held, cone margin)."""
    strict, loose, *_, margin, _clear, _acc, _sec = hold(cell, kin, checker, tol, s, q, p,
                                                         cone_s, cones, half_angle, dip,
                                                         targets, **kw)
    if loose and not strict:
        strict, _loose, *_, margin, _clear, _acc, _sec = hold(
            cell, kin, checker, tol, s, q, p, cone_s, cones, half_angle, dip, targets,
            constraint_step=0.5e-3, cone_margin=4e-3, **kw)
    return strict, loose, margin


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hub", default=None)
    ap.add_argument("--window", type=int, default=0)
    ap.add_argument("--position-tolerance-mm", type=float, default=0.02,
                    help="half-width of the tool point's box at each path constraint")
    args = ap.parse_args()

    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import plan_windows, window_targets_for_hub

    hub_name = args.hub or DEFAULT_HUB
    cell = load_cell("tool_in_hand", hub_name)
    kin = cell_kinematics(cell)
    checker = ClearanceChecker(cell)
    wt = window_targets_for_hub(load_hub(hub_name), source="toolpath",
                                windows=[args.window])[0]
    cfg = load_config("tool_in_hand", hub_name)
    plan = plan_windows(cell, [wt], cfg)
    seg = next(sg for sg in plan.segments if sg.kind == "cut")
    tr = plan.trajectory
    sel = (tr.t >= seg.t_range[0]) & (tr.t <= seg.t_range[1])
    q, t = tr.q[sel], tr.t[sel]
    p = kin.X_HT_from_q(q)[:, :3, 3]
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    v = np.concatenate([[0], np.diff(s) / np.diff(t)])
    # cone axes along the executed path: each CL target's at its nearest sample
    tg = [x for x in plan.targets[seg.target_range[0]:seg.target_range[1]] if x.cl_index >= 0]
    at = np.argmin(np.linalg.norm(np.array([x.X_HT[:3, 3] for x in tg])[:, None] - p[None],
                                  axis=2), axis=1)
    order = np.argsort(at)
    cone_s = s[at[order]]
    cl = np.array([x.cl_index for x in tg])
    cones = wt.cone_retract_H[cl[order]]
    targets = (np.array([x.X_HT[:3, 3] for x in tg]), wt.cone_retract_H[cl])
    L = s[-1]
    slow = (v < 0.95 * 0.150) & (s > 0.02) & (s < L - 0.02)
    runs = np.flatnonzero(np.diff(np.concatenate([[0], slow.astype(int), [0]])))
    runs = runs.reshape(-1, 2)
    merged = [list(runs[0])] if len(runs) else []
    for a, b in runs[1:]:  # one fillet: slow runs less than 20 mm apart
        if s[a] - s[merged[-1][1] - 1] < 0.02:
            merged[-1][1] = b
        else:
            merged.append([a, b])
    band = plan.meta["windows"][0]["speed_in_band_fraction"]
    print(f"## fillet speed study: hub {hub_name}, window {args.window} (tool in hand), "
          f"cut {1e3 * L:.0f} mm, planner {100 * band:.0f} % in band\n")
    print("fillet mm   planner: slow mm  slowest mm/s | constant 143  dip 10 mm  dip 20 mm  "
          "dip 40 mm  -> narrowest dip held")
    need, need_loose, widths = 0.0, 0.0, (None, 0.010, 0.020, 0.040)
    for a, b in merged:
        c_i = a + int(np.argmin(v[a:b]))
        lo = np.searchsorted(s, max(s[c_i] - HALF_SPAN, 0.01))
        hi = np.searchsorted(s, min(s[c_i] + HALF_SPAN, L - 0.01))
        cells, narrowest, loose_narrowest = [], None, None
        for width in widths:
            dip = None if width is None else (s[c_i], width, V_DIP)
            held, loose, margin = held_at(
                cell, kin, checker, cfg.tolerances, s[lo:hi + 1], q[lo:hi + 1], p[lo:hi + 1],
                cone_s, cones, wt.cone_half_angle, dip, targets,
                position_tolerance=1e-3 * args.position_tolerance_mm)
            loose_narrowest = (loose_narrowest if loose_narrowest is not None or not loose
                               else (0.0 if width is None else width))
            cells.append(f"{'held' if held else 'loose' if loose else 'no'} "
                         f"({1e3 * margin:+.1f} mrad)")
            if held:
                narrowest = 0.0 if width is None else width
                break
        need += widths[-1] if narrowest is None else narrowest
        need_loose += widths[-1] if loose_narrowest is None else loose_narrowest
        print(f"{1e3 * s[a]:5.0f}-{1e3 * s[b - 1]:3.0f}  {1e3 * (s[b - 1] - s[a]):14.0f}  "
              f"{1e3 * v[a:b].min():12.0f} | {'  '.join(cells)}  -> "
              f"{'none of these' if narrowest is None else f'{1e3 * narrowest:.0f} mm'}")
    ends = 2 * 0.150 ** 2 / (2 * 3.0)  # rest-to-rest ramps at the 3 m/s^2 TCP cap
    print(f"\nslow travel a locally optimal path still needs: the narrowest dip held at each "
          f"fillet (counted as {1e3 * widths[-1]:.0f} mm where none of them was) and the "
          f"rest-to-rest ends ({1e3 * ends:.1f} mm): {1e3 * (need + ends):.0f} mm of "
          f"{1e3 * L:.0f} -> at most {100 * (1 - (need + ends) / L):.0f} % of this window in "
          f"the band (planner: {100 * band:.0f} %); held only to the looser criterion: "
          f"{100 * (1 - (need_loose + ends) / L):.0f} %")


if __name__ == "__main__":
    main()
