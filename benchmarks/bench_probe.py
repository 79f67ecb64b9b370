"""The IK's cone probe (``plan/ik_seeds.cone_clearance_probe``) on a blocked stretch of a deep
dish: this tree's search (axes a spin-invariant pair blocks are not searched past their first
pose) against the full search of every pose (the same code with that pruning off), in the same
run, target by target; verdicts and best clearances compared.

    .venv/bin/python benchmarks/bench_probe.py [--hub h5_deepdish] [--window 4] [--targets 16]

The targets are the source's tilt box (0.26-0.44 rad) on the hub's window, from the middle of
its loop on (where h5_deepdish's window 4 meets its dish wall). Each probe is searched afresh
(no memo).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--targets", "4")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hub", default="h5_deepdish")
    ap.add_argument("--window", type=int, default=4)
    ap.add_argument("--targets", type=int, default=16)
    args = ap.parse_args()

    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import ProcessParameters
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.ik import IkOptions
    from drakedeburr.plan.ik_seeds import IkTarget, _probe, unreachable
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, window_targets_for_hub
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    cell = load_cell("tool_in_hand", args.hub)
    kin, checker = cell_kinematics(cell), ClearanceChecker(cell)
    full = ClearanceChecker(cell)  # the baseline: no spin-invariant bound, every axis searched
    full.axis_reading = lambda q, cap: (ClearanceChecker.axis_reading(full, q, cap)[0], np.inf)
    wt = window_targets_for_hub(load_hub(args.hub), source="toolpath", windows=[args.window],
                                params=ProcessParameters())[0]
    _, lift = contact_geometry(PlanOptions().contact_radius)
    opt = IkOptions()
    p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut,
                        contact_geometry(PlanOptions().contact_radius)[0], 0.0)

    def probe(ch, i):
        t = time.perf_counter()
        r = _probe(kin, ch, cell.q_home, IkTarget(p_HQ[i], wt.cone_retract_H[i], wt.retract_H[i],
                                                  wt.t_H[i]), wt.cone_half_angle,
                   opt.probe_settings(lift))
        return r, time.perf_counter() - t

    def verdict(r):
        return "clear" if r.feasible else ("unreachable" if unreachable(r, opt) else "near")

    print(f"## cone probe: hub {args.hub}, window {args.window}, source box, "
          f"targets {len(wt) // 2}..{len(wt) // 2 + args.targets - 1}\n")
    print(f"{'CL':>4}  {'verdict':11}  {'best mm':>8}  {'full mm':>8}  {'queries':>7}  "
          f"{'full q':>6}  {'s':>6}  {'full s':>6}")
    times, same = {"now": [], "full": []}, True
    for i in range(len(wt) // 2, min(len(wt), len(wt) // 2 + args.targets)):
        (r, t), (b, tb) = probe(checker, i), probe(full, i)
        same &= verdict(r) == verdict(b)
        if not r.feasible:
            times["now"].append(t)
            times["full"].append(tb)
        print(f"{i:4d}  {verdict(r):11}  {1e3 * r.best_clearance:8.3f}  "
              f"{1e3 * b.best_clearance:8.3f}  {r.queries:7d}  {b.queries:6d}  "
              f"{t:6.3f}  {tb:6.3f}")
    if times["now"]:
        now, base = np.median(times["now"]), np.median(times["full"])
        print(f"\nblocked targets ({len(times['now'])}): median {now:.3f} s against "
              f"{base:.3f} s for the full search: {base / now:.1f}x; verdicts "
              f"{'identical' if same else 'DIFFER'}")


if __name__ == "__main__":
    main()
