"""Study (issue 46): how far a saved plan is from the cycle, feed and wrist targets, and what two
cheap levers could move: the wrist spin and the timing of the moves off the cut.

Reads a plan folder (``drakedeburr plan ... -o DIR`` or ``demo -o DIR``'s ``plan/``) and its
verification report (``report.json`` beside it, with the ``time_budget`` item), plans nothing:

* **the least J6 range the plan's tool axes allow** (the spin about the axis is free: the burr
  is rotationally symmetric): at every CL target of a window its pose with the spin turned over
  a 5 deg grid, the analytic IK on the window's (shoulder, elbow, wrist) branch, inside the joint
  limits and |J5| >= 0.15 rad (the planner's wrist margin), the spin stepping at most
  ``--max-step`` grid steps between targets; a bisection on the range R with a reachability
  sweep over every lower end c (1 deg grid) finds the least R such that a spin path keeps J6 in
  [c, c + R]. No clearance query: a lower bound for these axes, not a plan (the spindle body
  may hit the hub at the spins it picks);
* **the J4-J6 trade of the spin**: the least-motion spin path (the planner's spin cost, no
  clearance, no smoothing) with J6's term weighted x1 ... x100, and its J4-J6 ranges;
* **the moves off the cut re-timed on their own joint path at the joint limits**: each home /
  transition / approach / retract move's joint path (the plan's trajectory sampled along it)
  timed rest to rest by the planner's own time-optimal construction
  (:func:`drakedeburr.plan.timing.time_path`) with no TCP speed or acceleration cap, at the
  planner's margins (95 % / 90 %) and at the full limits, then under each TCP cap alone (the
  move's programmed speed; the recipe's TCP path acceleration) and both (the planner's own
  timing, the reproduction to read the others against); beside the plan's time and the
  joint-displacement bound of ``time_budget``;
* **the window order at the bound**: the sum of the joint-displacement bounds of the moves
  between the cuts (home -> first approach, each retract -> next approach, last retract ->
  home; :func:`drakedeburr.verify.checks_process.joint_move_bound`, rest to rest) over every
  order of the windows, each window cut as planned (same start point, direction and joints).

Run:  PYTHONPATH=. python benchmarks/study_cycle_budget.py PLAN_DIR [--max-step 2] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

FULL_ARGS = ("/tmp/bench_verify_plans/tool_in_hand_h5_straight",)  # bench_verify.py's plan
QUICK_ARGS = (  # the window-0 plan bench_verify.py --quick leaves (run_all runs it first)
    "/tmp/bench_verify_plans/tool_in_hand_h5_straight_quick",)


def least_j6_range(kin, X_HT: np.ndarray, q_branch: np.ndarray, *, n_spin: int = 72,
                   max_step: int = 2, wrist_margin: float = 0.15) -> tuple[float, float, dict]:
    """(least J6 range over spin paths [rad], the share of (target, spin) states feasible, and
    on the least-motion spin path inside that range (each joint's step over its speed limit,
    squared, summed: the planner's spin cost) the J4-J6 ranges [rad] and the spin range)."""
    from drakedeburr.plan.spin import spin_frames

    n = len(X_HT)
    psi = np.arange(n_spin) * (2 * np.pi / n_spin)
    X = np.repeat(X_HT[:, None], n_spin, axis=1).reshape(-1, 4, 4).copy()
    X[:, :3, :3] = spin_frames(X[:, :3, :3], np.tile(psi, n))
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    b0 = kin.branch_of(q_branch)
    m = np.flatnonzero(np.all(branches == b0[None], axis=1))[0]
    q = q_all[:, m].reshape(n, n_spin, 6)
    ok = np.all(np.isfinite(q), axis=2)
    qq = np.where(np.isfinite(q), q, 0.0)
    for j in (3, 5):  # within half a turn of the branch's joints, as the spin search reads them
        qq[..., j] = q_branch[j] + np.mod(qq[..., j] - q_branch[j] + np.pi, 2 * np.pi) - np.pi
    ok &= np.all((qq >= kin.q_lower) & (qq <= kin.q_upper), axis=2)
    ok &= np.abs(qq[..., 4]) >= wrist_margin
    j6 = qq[..., 5]
    shifts = np.arange(-max_step, max_step + 1)
    P = (np.arange(n_spin)[:, None] - shifts[None, :]) % n_spin  # predecessor states

    lows = np.arange(j6[ok].min(), j6[ok].max() + 1e-9, np.radians(1.0))

    def feasible(R: float):
        """The lower ends c with a spin path keeping J6 in [c, c + R] (empty: none)."""
        c = lows[:, None, None]
        inside = ok[None] & (j6[None] >= c) & (j6[None] <= c + R)  # (C, n, n_spin)
        reach = inside[:, 0]
        for k in range(1, n):
            reach = reach[:, P].any(axis=2) & inside[:, k]
        return np.flatnonzero(reach.any(axis=1))

    lo, hi = 0.0, float(np.ptp(j6[ok])) + np.radians(2.0)
    if not len(feasible(hi)):
        return np.inf, float(ok.mean()), {}
    while hi - lo > np.radians(0.5):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if len(feasible(mid)) else (mid, hi)
    c = lows[feasible(hi)[0]]
    inside = ok & (j6 >= c) & (j6 <= c + hi)
    # the least-motion path among the states inside the band (dynamic programming)
    w = 1.0 / np.asarray(kin.v_max, float)
    cost = np.where(inside[0], 0.0, np.inf)
    back = np.zeros((n, n_spin), int)
    rows = np.arange(n_spin)
    for k in range(1, n):
        step = np.stack([np.sum(((qq[k] - qq[k - 1, P[:, i]]) * w) ** 2, axis=1)
                         for i in range(len(shifts))], axis=1)
        cand = cost[P] + step
        arg = np.argmin(cand, axis=1)
        cost = np.where(inside[k], cand[rows, arg], np.inf)
        back[k] = P[rows, arg]
    path = np.zeros(n, int)
    path[-1] = int(np.argmin(cost))
    for k in range(n - 1, 0, -1):
        path[k - 1] = back[k, path[k]]
    qp = qq[np.arange(n), path]
    figures = {"j4_range_rad": float(np.ptp(qp[:, 3])), "j5_range_rad": float(np.ptp(qp[:, 4])),
               "j6_range_rad": float(np.ptp(qp[:, 5])),
               "spin_range_rad": float(np.ptp(np.unwrap(psi[path])))}
    return hi, float(ok.mean()), figures


def spin_tradeoff(kin, X_HT: np.ndarray, q_branch: np.ndarray, weights=(1, 3, 10, 30, 100), *,
                  n_spin: int = 72, max_step: int = 2, wrist_margin: float = 0.15) -> list:
    """The J4-J6 ranges [rad] of the least-motion spin path (the planner's spin cost: each
    joint's step over its speed limit, squared, summed) with J6's term weighted by each of
    ``weights`` (1: the planner's cost, without its clearance and smoothing)."""
    from drakedeburr.plan.spin import spin_frames

    n = len(X_HT)
    psi = np.arange(n_spin) * (2 * np.pi / n_spin)
    X = np.repeat(X_HT[:, None], n_spin, axis=1).reshape(-1, 4, 4).copy()
    X[:, :3, :3] = spin_frames(X[:, :3, :3], np.tile(psi, n))
    q_all, branches = kin.ik_all(kin.X_WF_from_X_HT(X))
    m = np.flatnonzero(np.all(branches == kin.branch_of(q_branch)[None], axis=1))[0]
    q = q_all[:, m].reshape(n, n_spin, 6)
    ok = np.all(np.isfinite(q), axis=2)
    qq = np.where(np.isfinite(q), q, 0.0)
    for j in (3, 5):
        qq[..., j] = q_branch[j] + np.mod(qq[..., j] - q_branch[j] + np.pi, 2 * np.pi) - np.pi
    ok &= np.all((qq >= kin.q_lower) & (qq <= kin.q_upper), axis=2)
    ok &= np.abs(qq[..., 4]) >= wrist_margin
    shifts = np.arange(-max_step, max_step + 1)
    P = (np.arange(n_spin)[:, None] - shifts[None, :]) % n_spin
    rows = np.arange(n_spin)
    out = []
    for W in weights:
        w = 1.0 / np.asarray(kin.v_max, float)
        w[5] *= np.sqrt(W)
        cost = np.where(ok[0], 0.0, np.inf)
        back = np.zeros((n, n_spin), int)
        for k in range(1, n):
            step = np.stack([np.sum(((qq[k] - qq[k - 1, P[:, i]]) * w) ** 2, axis=1)
                             for i in range(len(shifts))], axis=1)
            cand = cost[P] + step
            arg = np.argmin(cand, axis=1)
            cost = np.where(ok[k], cand[rows, arg], np.inf)
            back[k] = P[rows, arg]
        if not np.isfinite(cost).any():
            out.append({"weight": W, "ok": False})
            continue
        path = np.zeros(n, int)
        path[-1] = int(np.argmin(cost))
        for k in range(n - 1, 0, -1):
            path[k - 1] = back[k, path[k]]
        qp = qq[np.arange(n), path]
        out.append({"weight": W, "ok": True,
                    "j4_j6_range_deg": np.degrees(np.ptp(qp[:, 3:6], axis=0)).tolist()})
    return out


def retime_air_moves(plan, kin, cell, tcp_acceleration: float) -> list[dict]:
    """Each home/transition move re-timed on its own joint path (module docstring)."""
    from drakedeburr.plan.timing import TimingLimits, time_path

    v = np.maximum(np.abs(cell.v_lower), np.abs(cell.v_upper))
    a = np.maximum(np.abs(cell.a_lower), np.abs(cell.a_upper))
    out = []
    for g in plan.segments:
        if g.kind == "cut":
            continue
        t = np.linspace(*g.t_range, 400)
        q = plan.trajectory.value(t)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
        keep = np.concatenate([[True], np.diff(s) > 1e-9])
        s, q = s[keep], q[keep]
        p = kin.p_HT(q)
        row = {"kind": g.kind, "window": int(g.window_index),
               "plan_s": g.t_range[1] - g.t_range[0]}
        v_prog = float(plan.targets[g.target_range[1] - 1].speed)
        a_tcp = float(tcp_acceleration)
        # (name, TCP speed cap, TCP acceleration cap, joint margins): without the TCP caps at
        # the planner's margins and at the full limits; then each TCP cap alone (margins), and
        # both (the planner's own timing of this path, to read the re-timing against)
        for name, v_cap, a_cap, vf, af in (
                ("margins", 1e3, 1e3, 0.95, 0.9), ("full", 1e3, 1e3, 1.0, 1.0),
                ("speed_cap_only", v_prog, 1e3, 0.95, 0.9),
                ("acceleration_cap_only", 1e3, a_tcp, 0.95, 0.9),
                ("both_caps", v_prog, a_tcp, 0.95, 0.9)):
            lim = TimingLimits(v_cap=v_cap, a_cap=a_cap, v_max=tuple(v), a_max=tuple(a),
                               velocity_fraction=vf, acceleration_fraction=af)
            row[f"retimed_{name}_s"] = float(time_path(s, q, p, lim, fk=kin.p_HT).t[-1])
        out.append(row)
    return out


def order_bounds(plan, cell) -> dict:
    """The moves between the cuts at their joint-displacement bound, for the plan's window
    order and for the best of every order (module docstring)."""
    from itertools import permutations

    from drakedeburr.verify.checks_process import joint_move_bound

    v = np.maximum(np.abs(cell.v_lower), np.abs(cell.v_upper))
    a = np.maximum(np.abs(cell.a_lower), np.abs(cell.a_upper))
    traj = plan.trajectory
    home = traj.value(np.array([0.0]))[0]
    end_home = traj.value(np.array([traj.t[-1]]))[0]
    start, stop, order = {}, {}, []
    for g in plan.segments:
        if g.kind == "approach":
            start[g.window_index] = traj.value(np.array([g.t_range[0]]))[0]
            order.append(g.window_index)
        if g.kind == "retract":
            stop[g.window_index] = traj.value(np.array([g.t_range[1]]))[0]
    z = np.zeros(6)

    def bound(q0, q1):
        return joint_move_bound(q0, q1, z, z, v, a)[0]

    def total(seq):
        t = bound(home, start[seq[0]]) + bound(stop[seq[-1]], end_home)
        return t + sum(bound(stop[x], start[y]) for x, y in zip(seq[:-1], seq[1:], strict=True))

    best = min(permutations(order), key=total)
    return {"plan_order": order, "plan_order_bound_s": total(order),
            "best_order": list(best), "best_order_bound_s": total(best)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plan_dir")
    ap.add_argument("--max-step", type=int, default=2, help="spin grid steps between targets")
    ap.add_argument("--json", help="write the figures here")
    args = ap.parse_args(argv)

    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.plan.io import load_plan
    from drakedeburr.plan.kinematics import cell_kinematics

    plan = load_plan(args.plan_dir)
    cell = load_plan_cell(plan)
    kin = cell_kinematics(cell)
    result = {"plan": str(args.plan_dir), "windows": {}, "air": []}
    report = Path(args.plan_dir) / "report.json"
    budget = None
    if report.exists():
        doc = json.loads(report.read_text())
        budget = next((i for i in doc["items"] if i["name"] == "time_budget"), None)
    for g in plan.segments:
        if g.kind != "cut":
            continue
        a, b = g.target_range
        ks = [k for k in range(a, b) if plan.targets[k].cl_index >= 0]
        X = np.array([plan.targets[k].X_HT for k in ks])
        qb = np.asarray(plan.targets[ks[0]].q, float)
        R, share, on_path = least_j6_range(kin, X, qb, max_step=args.max_step)
        q_t = np.array([plan.targets[k].q for k in ks])
        row = {"targets": len(ks),
               "plan_j4_j6_range_deg_at_targets": np.degrees(np.ptp(q_t[:, 3:6], axis=0)).tolist(),
               "least_j6_range_deg": float(np.degrees(R)), "feasible_state_share": share,
               "on_that_path_j4_j6_range_deg": [float(np.degrees(on_path.get(k, np.nan)))
                                                 for k in ("j4_range_rad", "j5_range_rad",
                                                           "j6_range_rad")],
               "on_that_path_spin_range_deg": float(np.degrees(on_path.get("spin_range_rad",
                                                                            np.nan)))}
        if budget is not None:
            rec = budget["per_window"].get(str(g.window_index))
            if rec:
                row["plan_j6_range_deg"] = float(np.degrees(rec["j6_range_rad"]))
        row["spin_tradeoff"] = spin_tradeoff(kin, X, qb, max_step=args.max_step)
        result["windows"][int(g.window_index)] = row
        pj = row["plan_j4_j6_range_deg_at_targets"]
        oj = row["on_that_path_j4_j6_range_deg"]
        print(f"window {g.window_index}: J4/J5/J6 ranges {pj[0]:.1f}/{pj[1]:.1f}/{pj[2]:.1f} deg "
              f"at the targets; least J6 with the spin free {row['least_j6_range_deg']:.1f} deg, "
              f"there J4/J5/J6 {oj[0]:.1f}/{oj[1]:.1f}/{oj[2]:.1f} deg, spin "
              f"{row['on_that_path_spin_range_deg']:.0f} deg ({100 * share:.0f} % of the spin "
              "states feasible)", flush=True)
        print("   J6 weighted in the spin cost: " + "; ".join(
            f"x{r['weight']}: " + ("none" if not r["ok"] else "/".join(
                f"{x:.0f}" for x in r["j4_j6_range_deg"])) for r in row["spin_tradeoff"])
              + " (J4/J5/J6 deg)", flush=True)
    from drakedeburr.verify.checks import config_for_plan

    a_tcp = config_for_plan(plan).process.tcp_acceleration
    result["air"] = retime_air_moves(plan, kin, cell, a_tcp)
    for r in result["air"]:
        print(f"{r['kind']:10s} plan {r['plan_s']:.3f} s; same joint path at the joint limits "
              f"without TCP caps: {r['retimed_margins_s']:.3f} s (95/90 % margins), "
              f"{r['retimed_full_s']:.3f} s (full); TCP speed cap alone "
              f"{r['retimed_speed_cap_only_s']:.3f} s, TCP acceleration cap alone "
              f"{r['retimed_acceleration_cap_only_s']:.3f} s, both "
              f"{r['retimed_both_caps_s']:.3f} s")
    for kinds in (("home", "transition"), ("approach", "retract")):
        rows = [r for r in result["air"] if r["kind"] in kinds]
        print(f"{'/'.join(kinds)}: " + ", ".join(
            f"{k} {sum(r[k] for r in rows):.3f} s" for k in (
                "plan_s", "retimed_margins_s", "retimed_full_s", "retimed_speed_cap_only_s",
                "retimed_acceleration_cap_only_s", "retimed_both_caps_s")))
    result["order"] = order_bounds(plan, cell)
    o = result["order"]
    print(f"moves between the cuts at their bound: order {o['plan_order']} "
          f"{o['plan_order_bound_s']:.3f} s, best order {o['best_order']} "
          f"{o['best_order_bound_s']:.3f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
