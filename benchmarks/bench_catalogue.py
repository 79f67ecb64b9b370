"""Issue 16's catalogue benchmark: seeded random hubs nobody tuned for, planned and verified in
both cells on a process pool; prints the pass rate per cell, a histogram of the failure reasons
and the time per hub (median, p95).

    .venv/bin/python benchmarks/bench_catalogue.py --seed 1601 --count 60 -j 2 --out /tmp/cat

Hubs are generated once into OUT/hubs (reused when there); every (cell, hub) gets its report
(and, when it fails, its plan folder ``plan/``) under OUT/verify/<cell>/<hub>/ and one row in
OUT/verify/summary.json.
"""

from __future__ import annotations

import argparse
import collections
import json
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ("--seed", "1601", "--count", "60", "-j", "2", "--out", "{tmp}")
QUICK_ARGS = (
    "--seed", "1601", "--count", "1", "-j", "1", "--cells", "tool_in_hand", "--out", "{tmp}",
)


def _one_hub(args: tuple[int, int, str]) -> str:
    from drakedeburr.hub.randomhub import random_catalogue

    seed, index, out = args
    return str(random_catalogue(seed, 1, out, start=index)[0].dir)


def generate(seed: int, count: int, out: Path, workers: int) -> list[Path]:
    """The catalogue's hub folders (generated in parallel where missing)."""
    out.mkdir(parents=True, exist_ok=True)
    from drakedeburr.hub.randomhub import random_spec

    names = [random_spec(seed, i).name for i in range(count)]
    todo = [(seed, i, str(out)) for i, n in enumerate(names)
            if not (out / n / "hub.yaml").is_file()]
    if todo:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            list(pool.map(_one_hub, todo))
    return [out / n for n in names]


def reasons(row: dict) -> list[str]:
    """The failure reasons of one row: an error, else each failed required check (a planner
    failure by the kind of its records)."""
    if row.get("error"):
        return [f"error: {row['error'].split(':')[0]}"]
    out = []
    for name in row["failed"]:
        if name == "planner_failures" and row.get("failure_kinds"):
            out += [f"planner: {k}" for k in row["failure_kinds"]]
        else:
            out.append(name)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1601)
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("-j", "--workers", type=int, default=2)
    ap.add_argument("--out", default="catalogue_bench")
    ap.add_argument("--cells", default="tool_in_hand,workpiece_in_hand")
    ap.add_argument("--start", type=int, default=0,
                    help="first hub of the catalogue to run (the hubs before it are skipped)")
    args = ap.parse_args()
    out = Path(args.out)
    t0 = time.perf_counter()
    hubs = generate(args.seed, args.count, out / "hubs", args.workers)[args.start:]
    t_gen = time.perf_counter() - t0
    from drakedeburr.verify.batch import JobSettings, verify_all

    def progress(done: int, total: int, label: str) -> None:  # a long run shows each job
        print(f"[{done}/{total}] {label} done at {time.perf_counter() - t0:.0f} s", flush=True)

    summary = verify_all([str(h) for h in hubs], out / "verify",
                         scenarios=args.cells.split(","), workers=args.workers,
                         progress=progress, settings=JobSettings(keep_failed_plans=True))
    print(f"catalogue seed {args.seed}: {len(hubs)} hubs (generated/reused in {t_gen:.0f} s), "
          f"{summary['jobs']} jobs in {summary['elapsed_s']:.0f} s on {summary['executor']}")
    for cell in args.cells.split(","):
        rows = [r for r in summary["rows"] if r["scenario"] == cell]
        n_pass = sum(r["passed"] for r in rows)
        times = np.array([r.get("plan_s", np.nan) + r.get("verify_s", np.nan) for r in rows])
        times = times[np.isfinite(times)]
        print(f"\n{cell}: {n_pass}/{len(rows)} pass ({100 * n_pass / max(len(rows), 1):.0f} %); "
              f"plan + verify per hub median {np.median(times):.0f} s, "
              f"p95 {np.percentile(times, 95):.0f} s" if len(times) else f"\n{cell}: no times")
        hist = collections.Counter(x for r in rows if not r["passed"] for x in reasons(r))
        for reason, n in hist.most_common():
            print(f"  {n:3d}  {reason}")
        for r in rows:
            if not r["passed"]:
                print(f"    {r['hub']}: {'; '.join(r.get('failure_notes', [])[:2]) or reasons(r)}")
    (out / "bench_summary.json").write_text(json.dumps(
        {"seed": args.seed, "count": args.count, "rows": summary["rows"]}, indent=1))


if __name__ == "__main__":
    main()
