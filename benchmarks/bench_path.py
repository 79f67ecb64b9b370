"""Benchmark of the path stage: CL planning time per window and planner, counts and c_v.

    python benchmarks/bench_path.py [--quick] [--hubs h5_straight]

Windows: two hub-like analytic windows (182 / 63 initial points, as the source's windows 1
and 2), every window of every bundled hub (ground-truth loops resampled at 2 mm), and (full
run) the 5 windows extracted from the audibot rim in ../shared/extdata. Times are compared
with the isoparametric baseline measured in the same run; the source needed 8.4-15.3 s per
window (MATLAB, proposed method). Every plan is checked against the thresholds its method
promises (true chord height <= delta_max; chord <= L_max for isoparametric and adaptive).
Last, the wall and process-CPU time of each set's ``cl_table`` call (the CL stage of
``drakedeburr demo``, which runs it on its default hub h5_straight: ``--hubs h5_straight``).
"""

import argparse
import time
from pathlib import Path

import sklearn.cluster  # noqa: F401  (import once before timing: 2-6 s cold)

from drakedeburr.errors import InputError
from drakedeburr.hub.types import WindowEdge
from drakedeburr.path import METHODS, PlannerParams, cl_table
from drakedeburr.path.synthetic import hub_like_window

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--quick",)

ap = argparse.ArgumentParser()
ap.add_argument("--quick", action="store_true", help="analytic windows and one hub only")
ap.add_argument("--hubs", default="", help="comma-separated bundled hubs only (e.g. the demo's "
                "h5_straight: times drakedeburr demo's CL stage), no analytic windows or rim")
args = ap.parse_args()

sets = {} if args.hubs else {
    "analytic": [WindowEdge(0, "large", hub_like_window("large", 182)),
                 WindowEdge(1, "small", hub_like_window("small", 63, angle=1.2))]}
try:
    from drakedeburr.resources import hub_names

    names = hub_names()
except FileNotFoundError:
    names = []
for name in args.hubs.split(",") if args.hubs else names[:1] if args.quick else names:
    sets[name] = name
if not args.quick and not args.hubs:
    for parent in Path(__file__).resolve().parents:
        rim = parent / "shared/extdata/wheel_models/audibot__wheel_rim_only_DERIVED_m.stl"
        if rim.is_file():
            sets["audibot rim"] = rim
            break

P = PlannerParams()
PROMISE = {"isoparametric": (True, True), "adaptive": (True, True),
           "equal_chord_height": (True, False), "proposed": (False, False)}
print(f"{'set':13s}{'win':>4s}{'init':>5s} " + "".join(f"{m[:18]:>27s}" for m in METHODS))
print(f"{'':22s} " + "".join(f"{'n   c_v  c_v(pairs)  t[s]':>27s}" for _ in METHODS))
tot = {m: 0.0 for m in METHODS}
nwin, violations, wins = 0, [], {"count": 0, "cv_pairs": 0, "both": 0, "cv_vs_proposed": 0}
table_times = {}
for name, src in sets.items():
    c0, t0 = time.process_time(), time.perf_counter()
    try:
        table = cl_table(src, METHODS, P)
    except InputError as exc:  # e.g. the audibot rim: refused by the hub import (issue 16)
        print(f"{name}: skipped: {exc}")
        continue
    table_times[name] = (time.perf_counter() - t0, time.process_time() - c0, len(table["windows"]))
    for w in table["windows"]:
        nwin += 1
        row = f"{name[:13]:13s}{w['index']:>4d}{w['initial_count']:>5d} "
        for m in METHODS:
            e = w["methods"][m]
            tot[m] += e["time_s"]
            row += f"{e['count']:>5d} {e['cv']:6.3f} {e['cv_pairwise']:7.4f} {e['time_s']:6.2f} "
            dmax, lmax = PROMISE[m]
            if dmax and e["max_chord_height_m"] > P.delta_max:
                violations.append(f"{name} w{w['index']} {m}: chord height "
                                  f"{e['max_chord_height_m'] * 1e3:.4f} mm")
            if lmax and e["max_chord_length_m"] > P.l_max + 1e-12:
                violations.append(f"{name} w{w['index']} {m}: chord "
                                  f"{e['max_chord_length_m'] * 1e3:.3f} mm")
        a, p, i = (w["methods"][k] for k in ("adaptive", "proposed", "isoparametric"))
        c1 = a["count"] <= p["count"]
        c2 = a["cv_pairwise"] <= i["cv_pairwise"]
        wins["count"] += c1
        wins["cv_pairs"] += c2
        wins["both"] += c1 and c2
        wins["cv_vs_proposed"] += a["cv"] < p["cv"]
        print(row)
print(f"\n{nwin} windows. Threshold violations of methods that promise them: "
      f"{len(violations) or 'none'}")
for v in violations:
    print("  ", v)
print(f"adaptive vs the source: count <= proposed on {wins['count']}/{nwin}; all-pairs c_v <= "
      f"isoparametric on {wins['cv_pairs']}/{nwin}; both on {wins['both']}/{nwin}; "
      f"neighbour c_v < proposed on {wins['cv_vs_proposed']}/{nwin}")
print("mean planning time per window [s] (ratio to isoparametric):")
for m in METHODS:
    print(f"  {m:20s} {tot[m] / nwin:7.3f}  ({tot[m] / tot['isoparametric']:.2f}x)")
print("source (MATLAB, proposed): 8.4-15.3 s per window")
print("cl_table (all four planners, every window; the CL stage of `drakedeburr demo`):")
for name, (wall, cpu, n) in table_times.items():
    print(f"  {name:13s} {n:3d} windows  wall {wall:6.2f} s  cpu {cpu:6.2f} s")
