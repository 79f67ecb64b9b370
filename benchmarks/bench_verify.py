"""Benchmark of the verification stage, on the planner's own plan of a whole hub.

1. Verification per hub, per stage: ``sample_plan`` (samples, program reading, distances,
   cut geometry) and the checks, with the distance stage of the previous implementation
   (commit BASELINE: the cell's broad-phase query, a Drake FK and a Jacobian per sample) run
   on the same samples as the baseline; the figures of both must agree. Wall time and CPU
   time of the process (the machine is shared: the CPU time is the steadier figure; parts of
   the distance sweep read by a pool worker, ``verify.sweep``, are in the wall time only).
2. The continuous clearance certificate of each hub (clearance_certificate) and what it read.
3. ``drakedeburr verify PLANFOLDER`` timed as a new user runs it (``--cli``), and against the
   tree of a previous commit on copies of the same plan (``--cli-baseline REF``: interleaved
   runs, medians, the two reports' items compared).

The plans are made with ``plan_hub`` defaults (tool-in-hand) into ``--plans DIR`` and reused
from there on later runs (planning a hub takes 20-40 s).

Run:  PYTHONPATH=. python benchmarks/bench_verify.py [--hubs h5_straight,...] [--cli]
      [--plans /tmp/bench_verify_plans] [--quick] [--cli-baseline REF [--repeat N]]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from drakedeburr.verify import cut_geometry, distances, program, sampling
from drakedeburr.verify.checks import config_for_plan, verify_sampled

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ("--cli",)
QUICK_ARGS = ("--quick",)

#: the previous implementation of the distance stage (main before the certificate)
BASELINE = "2de1f4b"
ROOT = Path(__file__).resolve().parent.parent


class Clock:
    """Wall and process CPU time of named stages."""

    def __init__(self) -> None:
        self.t: dict[str, tuple[float, float]] = {}

    def wrap(self, module, name: str, label: str) -> None:
        f = getattr(module, name)

        def timed(*a, **k):
            w, c = time.perf_counter(), time.process_time()
            out = f(*a, **k)
            dw, dc = time.perf_counter() - w, time.process_time() - c
            pw, pc = self.t.get(label, (0.0, 0.0))
            self.t[label] = (pw + dw, pc + dc)
            return out

        setattr(module, name, timed)


def _baseline_measure():
    """The previous ``measure_samples`` from git (else the kept dense reference method)."""
    from _baseline import module_at

    try:
        mod = module_at(BASELINE, "drakedeburr/verify/distances.py", "distances_baseline")
    except (subprocess.CalledProcessError, FileNotFoundError):
        return (lambda cell, s, tol, *a, **k: distances.measure_samples(
            cell, s, tol, method="dense")), "dense reference method (git unavailable)"
    from drakedeburr.verify import types

    # the baseline's measure_samples imports Distances from verify.sampling, where it lived at
    # that commit (it moved to verify.types since); give it the same class there
    if not hasattr(sampling, "Distances"):
        sampling.Distances = types.Distances
    return (lambda cell, s, tol, *a, **k: mod.measure_samples(cell, s, tol)), f"git {BASELINE}"


def _plan(hub: str, plans: Path, quick: bool):
    from drakedeburr.config import load_config
    from drakedeburr.plan.io import load_plan, save_plan
    from drakedeburr.plan.options import PlanOptions
    from drakedeburr.plan.planner import plan_hub

    folder = plans / f"tool_in_hand_{hub}{'_quick' if quick else ''}"
    if not (folder / "plan.json").exists():
        config = load_config("tool_in_hand", hub)
        options = PlanOptions(windows=[0]) if quick else None
        t0 = time.perf_counter()
        save_plan(plan_hub(config, options=options), folder)
        print(f"  planned {hub} in {time.perf_counter() - t0:.1f} s -> {folder}")
    return load_plan(folder), folder


def _stage_table(clock: Clock, total: tuple[float, float], base: tuple[float, float]) -> None:
    print(f"  {'stage':<34}{'wall s':>9}{'cpu s':>9}")
    for label, (w, c) in clock.t.items():
        print(f"  {label:<34}{w:>9.2f}{c:>9.2f}")
    print(f"  {'verify (library, new)':<34}{total[0]:>9.2f}{total[1]:>9.2f}")
    print(f"  {'distances, previous (baseline)':<34}{base[0]:>9.2f}{base[1]:>9.2f}")
    new = clock.t["distances (tracked + certificate)"]
    print(f"  distances speed-up vs baseline: {base[0] / new[0]:.1f}x wall, "
          f"{base[1] / new[1]:.1f}x cpu")


def _same_figures(old, new, label: str) -> str:
    bad = [f for f in ("clearance", "self_distance", "burr", "clearance_pair", "self_pair",
                       "burr_pair") if not np.array_equal(np.asarray(getattr(old, f)),
                                                          np.asarray(getattr(new, f)))]
    diff = {f: int(np.sum(np.asarray(getattr(old, f)) != np.asarray(getattr(new, f))))
            for f in bad}
    man = float(np.max(np.abs(old.manipulability - new.manipulability)))
    return (f"per-sample minima, {label}: identical {not bad} {diff or ''}; manipulability max "
            f"diff {man:.1e}; fk {old.fk_difference:.1e} vs {new.fk_difference:.1e} m")


def bench_hub(hub: str, plans: Path, quick: bool, baseline) -> None:
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.hub.model import load_hub

    plan, folder = _plan(hub, plans, quick)
    config = config_for_plan(plan)
    clock = Clock()
    w, c = time.perf_counter(), time.process_time()
    cell = load_plan_cell(plan)  # the cell the plan was made in (placement search's hub pose)
    hub_model = load_hub(plan.hub)
    clock.t["load cell + hub"] = (time.perf_counter() - w, time.process_time() - c)
    clock.wrap(sampling, "_samples", "samples")
    clock.wrap(program, "read_program", "program reading")
    clock.wrap(distances, "measure_samples", "distances (tracked + certificate)")
    clock.wrap(cut_geometry, "cut_geometry", "cut geometry")
    w, c = time.perf_counter(), time.process_time()
    sp = sampling.sample_plan(plan, config, cell=cell, hub_model=hub_model)
    w2, c2 = time.perf_counter(), time.process_time()
    report = verify_sampled(sp, config)
    clock.t["checks"] = (time.perf_counter() - w2, time.process_time() - c2)
    total = (time.perf_counter() - w + clock.t["load cell + hub"][0],
             time.process_time() - c + clock.t["load cell + hub"][1])
    w, c = time.perf_counter(), time.process_time()
    old = baseline(cell, sp.samples, config.tolerances)
    base = (time.perf_counter() - w, time.process_time() - c)
    print(f"\n## hub {hub}: {len(plan.targets)} targets, {sp.plan.trajectory.duration:.1f} s "
          f"cycle, {len(sp.samples)} samples, verdict "
          f"{'PASS' if report.passed else 'FAIL ' + ','.join(report.failed)}")
    _stage_table(clock, total, base)
    # the baseline reads Drake's distances as they are: the certified readings differ from it
    # wherever Drake reads too far (most samples near the hub); compared like for like below
    print("  " + _same_figures(old, sp.distances, "certified vs the baseline's uncertified "
                               "(differ where Drake reads too far)"))
    cert = sp.distances.certificate
    for name, k in (("clearance", cert.clearance), ("self", cert.self_distance)):
        print(f"  certificate {name:<9} certified {k.certified * 1e3:8.4f} mm, sampled "
              f"{k.sampled * 1e3:8.4f} mm, smallest read {k.observed * 1e3:8.4f} mm, limit "
              f"{k.limit * 1e3:.1f} mm -> {'PASS' if k.passed else 'FAIL'}")
    print(f"  readings: sweep {cert.sweep_readings} pair readings at {cert.samples_posed} "
          f"samples; refinement {cert.refined} intervals, {cert.refine_readings} readings, "
          f"{cert.depth} levels")
    print(f"  {cert.method.split('; ')[-1]}")
    _uncertified(cell, sp, config, clock.t["distances (tracked + certificate)"], old)
    return folder


def _uncertified(cell, sp, config, certified: tuple[float, float], old) -> None:
    """The distance stage again with Drake's readings taken as they are (what the verifier
    did before cell.narrowphase): its cost, the clearance it would have certified, and its
    per-sample minima against the baseline's ``old`` (both uncertified: like for like). In
    this process alone (one core): the patched reading is this process's."""
    import os

    from drakedeburr.verify.pair_scene import PairScene

    keep, workers = PairScene.certify, os.environ.get("DRAKEDEBURR_WORKERS")
    PairScene.certify = lambda self, p, d, *a: d
    os.environ["DRAKEDEBURR_WORKERS"] = "1"  # the patch is this process's: no worker reads
    try:
        w, c = time.perf_counter(), time.process_time()
        raw = distances.measure_samples(cell, sp.samples, config.tolerances,
                                        trajectory=sp.plan.trajectory)
        dt = (time.perf_counter() - w, time.process_time() - c)
    finally:
        PairScene.certify = keep
        if workers is None:
            os.environ.pop("DRAKEDEBURR_WORKERS", None)
        else:
            os.environ["DRAKEDEBURR_WORKERS"] = workers
    k, k0 = sp.distances.certificate.clearance, raw.certificate.clearance
    print(f"  Drake's readings as they are: distances {dt[0]:.2f} s wall / {dt[1]:.2f} s cpu "
          f"(certified readings: {certified[0]:.2f} / {certified[1]:.2f}, "
          f"{certified[1] / max(dt[1], 1e-9):.2f}x cpu); clearance certified "
          f"{k0.certified * 1e3:.4f} mm, sampled {k0.sampled * 1e3:.4f} mm (certified readings: "
          f"{k.certified * 1e3:.4f} / {k.sampled * 1e3:.4f} mm)")
    print("  " + _same_figures(old, raw, "uncertified tracked vs the baseline (like for like)"))


def bench_cli(folder: Path) -> None:
    exe = Path(sys.executable).with_name("drakedeburr")
    w = time.perf_counter()
    r = subprocess.run([str(exe), "verify", str(folder)], capture_output=True, text=True)
    print(f"  `drakedeburr verify {folder}`: {time.perf_counter() - w:.1f} s wall, exit "
          f"{r.returncode}")


def _report_items(folder: Path) -> list:
    import json
    import re

    items = json.loads((folder / "report.json").read_text())["items"]
    for it in items:  # the reading counts differ with how the sweep was split
        it["detail"] = re.sub(r"\d+ (positive readings|lowered|readings|intervals|solved)", r"N \1",
                              str(it.get("detail", "")))
    return items


def bench_cli_against(folder: Path, ref: str, repeat: int) -> None:
    """``python -m drakedeburr.cli verify`` of this tree and of the tree at ``ref`` on copies
    of the same plan, interleaved ``repeat`` times: median wall times, and whether the two
    reports' items agree (reading counts aside)."""
    import os
    import shutil
    import statistics

    from _baseline import tree_at

    trees = {"this tree": ROOT, ref: tree_at(ref, f"bench_verify_{ref}_")}
    for k, tree in trees.items():  # each run imports its own tree's package
        r = subprocess.run([sys.executable, "-c",
                            "import drakedeburr; print(drakedeburr.__file__)"],
                           capture_output=True, text=True, cwd=tree,
                           env={**os.environ, "PYTHONPATH": str(tree)})
        if not Path(r.stdout.strip()).resolve().is_relative_to(Path(tree).resolve()):
            raise RuntimeError(f"{k}: imports {r.stdout.strip()}, not {tree}")
    times: dict[str, list[float]] = {k: [] for k in trees}
    copies = {}
    for k in trees:
        copies[k] = Path(tempfile.mkdtemp(prefix="bench_verify_plan_")) / folder.name
        shutil.copytree(folder, copies[k])
    for _ in range(repeat):
        for k, tree in trees.items():
            env = {**os.environ, "PYTHONPATH": str(tree)}
            w = time.perf_counter()
            r = subprocess.run([sys.executable, "-m", "drakedeburr.cli", "verify",
                                str(copies[k]), "-q"], capture_output=True, text=True, env=env,
                               cwd=tree)  # "-m" puts the working folder first on the path
            times[k].append(time.perf_counter() - w)
            if r.returncode not in (0, 1):
                raise RuntimeError(f"{k}: verify exited {r.returncode}: {r.stderr[-500:]}")
    med = {k: statistics.median(v) for k, v in times.items()}
    same = _report_items(copies["this tree"]) == _report_items(copies[ref])
    print(f"  CLI verify, median of {repeat} interleaved: this tree {med['this tree']:.1f} s, "
          f"{ref} {med[ref]:.1f} s ({med[ref] / med['this tree']:.2f}x); report items the "
          f"same (reading counts aside): {same}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hubs", default="h5_straight", help="comma-separated bundled hubs")
    ap.add_argument("--plans", default=str(Path(tempfile.gettempdir()) / "bench_verify_plans"))
    ap.add_argument("--cli", action="store_true", help="also time the CLI on each plan")
    ap.add_argument("--quick", action="store_true", help="window 0 only")
    ap.add_argument("--cli-baseline", metavar="REF",
                    help="also time the CLI of the tree at git REF on the same plans")
    ap.add_argument("--repeat", type=int, default=3, help="CLI runs per tree (--cli-baseline)")
    args = ap.parse_args()
    baseline, label = _baseline_measure()
    print(f"## verification per hub (tool-in-hand, plan_hub defaults); baseline distances: "
          f"{label}")
    for hub in args.hubs.split(","):
        folder = bench_hub(hub, Path(args.plans), args.quick, baseline)
        if args.cli:
            bench_cli(folder)
        if args.cli_baseline:
            bench_cli_against(folder, args.cli_baseline, args.repeat)


if __name__ == "__main__":
    main()
