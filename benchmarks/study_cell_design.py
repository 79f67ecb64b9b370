"""Study (issue 46): which spindle mount and fixture height give the shortest cycle and the least
wrist travel on the default hub, every required verification check passing.

Each candidate tool-in-hand cell (:mod:`drakedeburr.cell.study`: the bundled 45 deg spindle on
a wedge adapter giving the mount angle, a stand-off, the fixture moved up or down) is planned
and verified on the hub (``drakedeburr cell study``'s evaluator), then ranked: passing first,
cycle time, the worst window's J4 + J5 + J6 travel, name. Printed: the ranking; the bundled
45 deg cell's figures and the recommended one's against the issue's targets (cycle <= 1.15x
its physical bound, feed held on >= 85 % of each cut, J6 <= 30 deg per window).

Run:  PYTHONPATH=. python benchmarks/study_cell_design.py [--angles 30,45,60|none] [--coaxial]
          [--offsets 0,50]
          [--fixture-heights -50,0,50] [--hub NAME] [--windows 0,1] [--out DIR]
      (--quick: the 45 and 60 deg mounts, window 0)
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
import time
from pathlib import Path

FULL_ARGS = ("--angles", "30,45,60", "--offsets", "0,50", "--fixture-heights=0,50,-50",
             "--out", "{tmp}/study")
# the grid is the study (--quick, two candidates on one window, is for tests)
QUICK_ARGS = ("--angles", "30,45,60", "--offsets", "0,50", "--fixture-heights=0,50,-50",
              "--out", "{tmp}/study")

TARGETS = {"cycle_ratio": 1.15, "feed_held_worst": 0.85, "worst_j6_deg": 30.0}


def _against_targets(row: dict) -> str:
    def show(key, fmt, good):
        v = row.get(key)
        if v is None:
            return f"{key} -"
        return f"{key} {format(v, fmt)} ({'met' if good(v) else 'not met'})"

    return "; ".join([
        show("cycle_ratio", ".3f", lambda v: v <= TARGETS["cycle_ratio"]),
        show("feed_held_worst", ".3f", lambda v: v >= TARGETS["feed_held_worst"]),
        show("worst_j6_deg", ".1f", lambda v: v <= TARGETS["worst_j6_deg"])])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--angles", default="30,45,60", help="wedge mount angles [deg] or none")
    ap.add_argument("--coaxial", action="store_true",
                    help="add the coaxial straight bracket at each fixture height")
    ap.add_argument("--offsets", default="0,50")
    ap.add_argument("--fixture-heights", default="-50,0,50")
    ap.add_argument("--hub", default=None)
    ap.add_argument("--windows", default=None)
    ap.add_argument("--quick", action="store_true", help="45 and 60 deg, window 0")
    ap.add_argument("--out", default=None, help="output folder (default: a temporary one)")
    ap.add_argument("--json", default=None, help="write the study's JSON here too")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, stream=sys.stderr,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")

    from drakedeburr.cell.commands import evaluate_candidate, study_setup, study_table
    from drakedeburr.cell.study import run_study

    hub, windows, candidates = study_setup(args)
    out = Path(args.out or tempfile.mkdtemp(prefix="study_cell_design_"))
    t0 = time.perf_counter()
    print("as evaluated (candidate, passed, cycle s, ratio, feed held, worst J6 deg, "
          "worst J4+J5+J6 deg, failing):", flush=True)

    def evaluate(c, f):
        r = evaluate_candidate(c, f, hub, windows)
        print(f"  {c.name} {r['passed']} {r.get('cycle_s')} {r.get('cycle_ratio')} "
              f"{r.get('feed_held_worst')} {r.get('worst_j6_deg')} "
              f"{r.get('worst_wrist_travel_deg')} {r.get('failing')}", flush=True)
        return r

    result = run_study(candidates, evaluate, out)
    took = time.perf_counter() - t0
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
    ranking = result["ranking"]
    print()
    print(f"## cell design study: hub {hub}, windows "
          f"{'all' if windows is None else ','.join(map(str, windows))}, tool in hand, "
          f"{len(candidates)} candidates in {took:.0f} s")
    print()
    print("mount: burr axis from the flange axis [deg]; offset: wedge stand-off [mm]; "
          "fixture: height change [mm]; ratio: cycle / physical bound; feed held: worst "
          "window's share in the band; J6 [deg] per window (max, mean); J4+J5+J6: worst "
          "window's travel [deg]")
    print()
    print(study_table(ranking))
    print()
    for r in ranking:
        per = r.get("j4_j6_deg_per_window") or {}
        if per:
            print(f"{r['name']}: J4/J5/J6 per window " + ", ".join(
                f"w{w} {a:.0f}/{b:.0f}/{c:.0f}" for w, (a, b, c) in per.items()))
    print()
    bundled = next((r for r in ranking if r["name"] == "m45_o000_f+000"), None)
    if bundled is not None:
        print(f"45 deg mount (the bundled cell): {_against_targets(bundled)}")
    best = next((r for r in ranking if r["name"] == result["recommended"]), None)
    if best is None:
        print("recommended: none (no candidate passes every required check)")
    else:
        print(f"recommended {best['name']}: cycle {best['cycle_s']:.3f} s; "
              f"{_against_targets(best)}")
        if bundled is not None and bundled.get("cycle_s") and best.get("cycle_s"):
            print(f"recommended vs 45 deg: cycle {best['cycle_s'] / bundled['cycle_s']:.3f}x, "
                  f"worst J6 {best['worst_j6_deg']:.1f} vs {bundled['worst_j6_deg']:.1f} deg")
    failed = [r for r in ranking if not r.get("passed")]
    print(f"{len(failed)} of {len(ranking)} candidates fail a required check"
          + ("" if not failed else ": " + "; ".join(
              f"{r['name']} ({', '.join(r.get('failing') or [])})" for r in failed)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
