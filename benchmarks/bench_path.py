"""Benchmark of the path stage: CL planning time per window and planner, counts and c_v.

    python benchmarks/bench_path.py [--quick]

Windows: the hub-like analytic windows (large 182 / small 63 initial points, as the source's
windows 1 and 2), every bundled hub's windows, and (full run) the 5 windows extracted from
the audibot rim in ../shared/extdata. Ratios are against the isoparametric baseline measured
in the same run. The source needed 8.4-15.3 s per window (MATLAB, proposed method).
"""

import argparse
import time
from pathlib import Path

import sklearn.cluster  # noqa: F401  (import once before timing: 2-6 s cold)

from drakedeburr.hub.types import WindowEdge
from drakedeburr.path import METHODS, cl_table
from drakedeburr.path.synthetic import hub_like_window

ap = argparse.ArgumentParser()
ap.add_argument("--quick", action="store_true", help="analytic windows only")
args = ap.parse_args()

sets = {"analytic": [WindowEdge(0, "large", hub_like_window("large", 182)),
                     WindowEdge(1, "small", hub_like_window("small", 63, angle=1.2))]}
if not args.quick:
    try:
        from drakedeburr.resources import hub_names

        for name in hub_names():
            sets[f"hub {name}"] = name
    except FileNotFoundError:
        pass
    for parent in Path(__file__).resolve().parents:
        rim = parent / "shared/extdata/wheel_models/audibot__wheel_rim_only_DERIVED_m.stl"
        if rim.is_file():
            sets["audibot rim"] = rim
            break

print(f"{'set':14s}{'win':>4s}{'init':>6s} " + "".join(f"{m[:12]:>26s}" for m in METHODS))
print(f"{'':24s} " + "".join(f"{'n  c_v  c_v(pairs) t[s]':>26s}" for _ in METHODS))
tot = {m: 0.0 for m in METHODS}
nwin = 0
for name, src in sets.items():
    t0 = time.perf_counter()
    table = cl_table(src, METHODS)
    for w in table["windows"]:
        nwin += 1
        row = f"{name:14s}{w['index']:>4d}{w['initial_count']:>6d} "
        for m in METHODS:
            e = w["methods"][m]
            tot[m] += e["time_s"]
            row += f"{e['count']:>6d} {e['cv']:5.3f} {e['cv_pairwise']:6.4f} {e['time_s']:6.2f} "
        print(row)
print("\nmean planning time per window [s] (ratio to isoparametric):")
for m in METHODS:
    print(f"  {m:20s} {tot[m] / nwin:7.3f}  ({tot[m] / tot['isoparametric']:.2f}x)")
print("source (MATLAB, proposed): 8.4-15.3 s per window")
