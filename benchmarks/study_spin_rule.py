"""Study: which warm-start spin rule should a window be planned with first?

Every window of each hub is planned with both rules (``IkOptions.seed_spin`` = "frame" and
"joint_cost", :func:`drakedeburr.plan.window._plan_window_once`), in the planner's own run
(placement, relaxation, one process). The window planner's policy (the first rule; the other
when the first fails or holds less than ``retry_in_band`` of its cut in the band; the better
kept: :func:`drakedeburr.plan.window.needs_other_rule`, :func:`~drakedeburr.plan.window.better_of`)
is then read off the two results for either order: a rule's plan of a window does not depend on
which rule went first, so both orders' outcome and planning CPU come from the same run. The run
itself goes on with the default order's choice, as ``plan_hub`` would.

Run (unseen hubs first made with ``drakedeburr hub random --seed 112930 --count 6 -o DIR``):
    PYTHONPATH=. python benchmarks/study_spin_rule.py [--hubs h5_straight,DIR/r112930_000,...]
        [--cells tool_in_hand,workpiece_in_hand] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from types import SimpleNamespace

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--hubs", "h5_straight", "--cells", "tool_in_hand")

RULES = ("frame", "joint_cost")


def _summary(result, seconds: float) -> dict:
    st = result.stats if result.status.planned else None
    return dict(status=result.status.name, clean=bool(result.status.planned
                                                      and not result.failures),
                failures=len(result.failures), seconds=seconds,
                band=st.speed_in_band_fraction if st else None,
                cut=st.cut_seconds if st else None)


def study_hub(hub: str, scenario: str) -> list[dict]:
    """Both rules' plan of every window planning pass of ``hub`` in ``scenario``: a list of
    {"window", "results": {rule: summary}, "retry_in_band"}."""
    from dataclasses import replace

    from drakedeburr.config import load_config
    from drakedeburr.plan import window as W
    from drakedeburr.plan.options import PlanOptions
    from drakedeburr.plan.planner import plan_hub

    records: list[dict] = []
    original = W.plan_window

    def both(ctx, wt, mode=W.RunMode.FULL):
        q_from = W.window_reference(ctx, wt)
        if mode is W.RunMode.REPORT_ONLY:
            return W._plan_window_once(ctx, wt, q_from, mode)
        plans, rec = {}, {}
        for rule in RULES:
            c = replace(ctx, options=replace(ctx.options,
                                             ik=replace(ctx.options.ik, seed_spin=rule)))
            t0 = time.process_time()
            plans[rule] = W._plan_window_once(c, wt, q_from, mode)
            rec[rule] = _summary(plans[rule], time.process_time() - t0)
        records.append(dict(window=wt.window_index, results=rec,
                            retry_in_band=ctx.options.retry_in_band))
        first = plans[ctx.options.ik.seed_spin]
        if not W.needs_other_rule(first, ctx.options.retry_in_band):
            return first
        return W.better_of(first, plans[W._other_rule(ctx)[0]])

    W.plan_window = both
    try:
        plan_hub(load_config(scenario, hub), options=PlanOptions(workers=1))
    finally:
        W.plan_window = original
    return records


class _Plan:
    """The few fields of a WindowPlan the policy reads, from a summary."""

    def __init__(self, s: dict, window: int) -> None:
        from drakedeburr.plan.results import WindowStatus

        self.s, self.window, self.failures = s, window, [None] * s["failures"]
        self.status = WindowStatus[s["status"]]
        self.stats = (None if s["cut"] is None else SimpleNamespace(
            speed_in_band_fraction=s["band"], cut_seconds=s["cut"]))


def policy(rec: dict, first_rule: str) -> tuple[dict, float]:
    """(the kept plan's summary, CPU seconds spent) with ``first_rule`` first."""
    from drakedeburr.plan.window import better_of, needs_other_rule

    other = RULES[1] if first_rule == RULES[0] else RULES[0]
    a = _Plan(rec["results"][first_rule], rec["window"])
    b = _Plan(rec["results"][other], rec["window"])
    if not needs_other_rule(a, rec["retry_in_band"]):
        return a.s, a.s["seconds"]
    kept = better_of(a, b)
    s = kept.s if isinstance(kept, _Plan) else dict(a.s, status=kept.status.name, clean=False)
    return s, a.s["seconds"] + b.s["seconds"]


def main() -> None:
    from drakedeburr.resources import hub_names

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hubs", default=",".join(hub_names()))
    ap.add_argument("--cells", default="tool_in_hand,workpiece_in_hand")
    ap.add_argument("--json", default=None, help="write every window's both results here")
    args = ap.parse_args()
    os.environ["DRAKEDEBURR_WORKERS"] = "1"
    out = {}
    for cell in args.cells.split(","):
        print(f"{cell}: hub | clean windows | planning CPU [s] | cut time of the clean [s] "
              f"({' first | '.join(RULES)} first)")
        total = {r: [0, 0, 0.0, 0.0] for r in RULES}
        for hub in args.hubs.split(","):
            recs = study_hub(hub, cell)
            out[f"{cell}/{hub}"] = recs
            row = {}
            for r in RULES:
                kept = [policy(rec, r) for rec in recs]
                row[r] = [sum(k["clean"] for k, _ in kept), len(kept),
                          sum(c for _, c in kept),
                          sum(k["cut"] for k, _ in kept if k["clean"])]
                total[r] = [x + y for x, y in zip(total[r], row[r], strict=True)]
            print(f"  {Path(hub).name:14s} " + " | ".join(
                f"{c}/{n} {cpu:6.1f} {cut:6.2f}" for c, n, cpu, cut in row.values()))
        print(f"  {'all':14s} " + " | ".join(
            f"{c}/{n} {cpu:6.1f} {cut:6.2f}" for c, n, cpu, cut in total.values()))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
