"""Study (issue 46 item 1): the window order chosen for the cycle, before against after, read off
verification reports of the same hubs planned by two trees.

For each pair of reports (the same hub and cell, planned before and after the change) it prints
the cycle [s], the ``cycle_time`` ratio (the cycle over the edge length at the feed plus the
straight moves at their programmed speeds), the moves between the cuts (home and transitions)
against the least time of their joint displacement at the joint limits (``time_budget``'s
bound), the J6 range per window, the window order cut and the planning time where the catalogue
summary has it; then the medians over a seeded catalogue sample (``bench_catalogue.py``'s
output folders: ``OUT/verify/<cell>/<hub>/report.json`` and ``OUT/verify/summary.json``).
It plans nothing: make the folders with ``bench_catalogue.py --seed 1601 --count 6 -j 1 --cells
tool_in_hand --out DIR`` on each tree (the same hubs: copy ``DIR/hubs``), and the default hub's
reports with ``drakedeburr plan`` + ``drakedeburr verify --json``.

Run:  python benchmarks/study_window_order.py --catalogue BEFORE_DIR AFTER_DIR
          [--pair LABEL BEFORE.json AFTER.json ...]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

# the folders of the measurement behind RESULTS.md (made as the docstring says)
FULL_ARGS = ("--catalogue", "/tmp/h4_before", "/tmp/h4_after",
             "--pair", "default_hub/tool_in_hand", "/tmp/h4_plan_before_tool_in_hand.report.json",
             "/tmp/h4_plan_after_tool_in_hand.report.json",
             "--pair", "default_hub/workpiece_in_hand",
             "/tmp/h4_plan_before_workpiece_in_hand.report.json",
             "/tmp/h4_plan_after_workpiece_in_hand.report.json")

AIR_BETWEEN = ("home", "transition")


def figures(report: dict) -> dict:
    """One report's figures: cycle, ratio, the moves between cuts and their bound, J6 ranges,
    the window order."""
    items = {i["name"]: i for i in report["items"]}
    budget = items["time_budget"].get("per_window") or {}
    air = bound = 0.0
    for w in budget.values():
        for m in w.get("air_before", []) + w.get("air_after", []):
            if m["kind"] in AIR_BETWEEN:
                air += m["duration_s"]
                bound += m["bound_s"]
    j6 = {int(w): float(np.degrees(v["J6_range_rad"]))
          for w, v in (items["j4_j6_range"].get("per_window") or {}).items()}
    order = cutting_order(budget)
    return {"passed": bool(report["passed"]), "cycle_s": float(report["plan"]["duration_s"]),
            "ratio": float(items["cycle_time"]["value"]), "air_s": air, "air_bound_s": bound,
            "j6_deg": j6, "order": order}


def cutting_order(budget: dict) -> list[int]:
    """The windows in cutting order, read off ``time_budget``'s moves: the first window's moves
    start at home; each other's start with the retract of the window cut before it."""
    after = {}
    first = None
    for w, v in budget.items():
        moves = v.get("air_before", [])
        if int(w) < 0 or not moves:
            continue
        if moves[0]["kind"] == "home":
            first = int(w)
        elif moves[0]["kind"] == "retract":
            after[int(moves[0]["window"])] = int(w)
    order = []
    while first is not None and first not in order:
        order.append(first)
        first = after.get(first)
    return order


def _read(path: Path) -> dict | None:
    return figures(json.loads(path.read_text())) if path.is_file() else None


def _line(label: str, b: dict, a: dict, plan_s: tuple = (None, None)) -> str:
    def j6(f):
        return f"{max(f['j6_deg'].values()):.0f}" if f["j6_deg"] else "-"

    t = "" if None in plan_s else f"  plan {plan_s[0]:.0f} -> {plan_s[1]:.0f} s"
    return (f"{label:32s} cycle {b['cycle_s']:6.2f} -> {a['cycle_s']:6.2f} s  ratio "
            f"{b['ratio']:.3f} -> {a['ratio']:.3f}  home+transitions {b['air_s']:.2f} -> "
            f"{a['air_s']:.2f} s (bound {b['air_bound_s']:.2f} -> {a['air_bound_s']:.2f})  "
            f"max J6 {j6(b)} -> {j6(a)} deg  order {b['order']} -> {a['order']}  "
            f"{'pass' if b['passed'] else 'FAIL'} -> {'pass' if a['passed'] else 'FAIL'}{t}")


def _plan_seconds(folder: Path) -> dict:
    path = folder / "verify" / "summary.json"
    if not path.is_file():
        return {}
    rows = json.loads(path.read_text())["rows"]
    return {(r["scenario"], r["hub"]): r.get("plan_s") for r in rows}


def catalogue(before: Path, after: Path) -> list[str]:
    """Per hub of both samples a line, then the medians over the hubs both planned."""
    out, pairs = [], []
    tb, ta = _plan_seconds(before), _plan_seconds(after)
    for rb in sorted((before / "verify").glob("*/*/report.json")):
        cell, hub = rb.parent.parent.name, rb.parent.name
        ra = after / "verify" / cell / hub / "report.json"
        b, a = _read(rb), _read(ra)
        if a is None:
            out.append(f"{cell}/{hub}: no report after")
            continue
        pairs.append((b, a))
        out.append(_line(f"{cell}/{hub}", b, a, (tb.get((cell, hub)), ta.get((cell, hub)))))
    if pairs:
        def med(key, k):
            return float(np.median([p[k][key] for p in pairs]))

        def med_j6(k):
            return float(np.median([v for p in pairs for v in p[k]["j6_deg"].values()]))

        out.append(f"median over {len(pairs)} hubs: cycle ratio {med('ratio', 0):.3f} -> "
                   f"{med('ratio', 1):.3f}, cycle {med('cycle_s', 0):.2f} -> "
                   f"{med('cycle_s', 1):.2f} s, home+transitions {med('air_s', 0):.2f} -> "
                   f"{med('air_s', 1):.2f} s; J6 range per window (median over every window) "
                   f"{med_j6(0):.1f} -> {med_j6(1):.1f} deg; passed "
                   f"{sum(p[0]['passed'] for p in pairs)} -> {sum(p[1]['passed'] for p in pairs)}")
        t = [(tb[k], ta[k]) for k in tb if k in ta and tb[k] and ta[k]]
        if t:
            out.append(f"planning time per hub (median): {np.median([x for x, _ in t]):.0f} -> "
                       f"{np.median([y for _, y in t]):.0f} s (shared 2-core machine)")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", nargs=2, metavar=("BEFORE", "AFTER"))
    ap.add_argument("--pair", nargs=3, action="append", default=[],
                    metavar=("LABEL", "BEFORE", "AFTER"))
    args = ap.parse_args()
    for label, b, a in args.pair:
        fb, fa = _read(Path(b)), _read(Path(a))
        print(_line(label, fb, fa) if fb and fa else f"{label}: a report is missing")
    if args.catalogue:
        print(f"\ncatalogue sample: {args.catalogue[0]} -> {args.catalogue[1]}")
        for line in catalogue(Path(args.catalogue[0]), Path(args.catalogue[1])):
            print(line)


if __name__ == "__main__":
    main()
