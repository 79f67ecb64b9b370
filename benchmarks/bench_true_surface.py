"""The burr head read against a hub's triangle mesh (``cell/true_surface.py``), as the planner's
burr-depth reading (``plan/burr_depth.py``) and the verifier's ``burr_contact`` call it: this
tree against a previous commit's module (``--baseline REF``, loaded from git into this
process), on the same poses, in the same run; the readings of both must agree bit for bit.

    .venv/bin/python benchmarks/bench_true_surface.py [--hubs h5_straight,h6_curved]
        [--baseline fb04ee7] [--repeat 5] [--windows 0,1]

The poses: the hub's planned windows (``--windows``, planned in the run by this tree): their
approach, cut and retract every 2 mm for the planner's coarse reading (``reach`` 0, settled at
the bound less 0.15 mm, 20 um), the first 8 mm of the first cut every 0.25 mm for its fine
reading (``reach`` 0, 2 um) and the verifier's (``reach`` 2 mm, 2 um). CPU seconds, the
median of ``--repeat`` calls after one warm-up call (which builds what the module keeps per
mesh).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--hubs", "h5_straight", "--repeat", "3", "--windows", "0")

MODULE = "drakedeburr/cell/true_surface.py"


def poses(hub_name: str, windows: tuple[int, ...]) -> dict[str, np.ndarray]:
    """Tool poses in H of the hub's planned windows (``plan_hub``, this tree, one process):
    the approach, cut and retract every 2 mm (the planner's coarse reading) and the first
    8 mm of the first cut every 0.25 mm (its fine reading near the bound)."""
    from drakedeburr.config import load_config
    from drakedeburr.plan.burr_depth import _thin
    from drakedeburr.plan.kinematics import cell_kinematics
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    config = load_config("tool_in_hand", hub_name)
    plan = plan_hub(config, options=PlanOptions(windows=windows, workers=1))
    from drakedeburr.cell.station import load_cell

    kin = cell_kinematics(load_cell("tool_in_hand", hub_name,
                                    hub_pose=np.array(plan.meta["hub_pose"])))
    coarse, fine = [], None
    for seg in plan.segments:
        if seg.kind not in ("approach", "cut", "retract"):
            continue
        t = np.arange(seg.t_range[0], seg.t_range[1], 1e-3)
        X = kin.X_HT_from_q(np.array([plan.trajectory.value(x).ravel() for x in t]))
        coarse.append(X[_thin(X, 2e-3)])
        if seg.kind == "cut" and fine is None:
            s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(X[:, :3, 3], axis=0),
                                                                axis=1))])
            first = X[s <= 8e-3]
            fine = first[_thin(first, 0.25e-3)]
    return {"coarse": np.concatenate(coarse), "fine": fine}


READINGS = {  # name: (poses, keyword arguments of true_surface_distances)
    "planner coarse (2 mm, reach 0, 20 um, settled)": ("coarse", dict(
        reach=0.0, tolerance=2e-5, shallow=1.49e-3)),
    "planner fine (0.25 mm, reach 0, 2 um)": ("fine", dict(reach=0.0, tolerance=2e-6)),
    "verifier (0.25 mm, reach 2 mm, 2 um)": ("fine", dict(reach=2e-3)),
}


def _cpu(fn, repeat: int) -> tuple[float, object]:
    out = fn()  # warm-up: what the module keeps per mesh is built here
    times = []
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        times.append(time.process_time() - t)
    return float(np.median(times)), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hubs", default="h5_straight,h6_curved")
    ap.add_argument("--baseline", default="fb04ee7")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--windows", default="0,1", help="windows planned per hub")
    args = ap.parse_args()
    from _baseline import module_at

    from drakedeburr.cell import true_surface as new
    from drakedeburr.hub import load_hub

    old = module_at(args.baseline, MODULE, "true_surface_baseline")
    print(f"## true-surface reading: this tree vs git {args.baseline}, CPU s (median of "
          f"{args.repeat})")
    print(f"{'hub':<13}{'reading':<48}{'poses':>6}{'pairs':>9}{'before':>8}{'now':>8}"
          f"{'speed-up':>9}  same")
    for name in args.hubs.split(","):
        hub = load_hub(name)
        sets = poses(name, tuple(int(w) for w in args.windows.split(",")))
        for label, (which, kw) in READINGS.items():
            X = sets[which]
            args_ = (hub, X, np.arange(len(X)))
            t_old, r_old = _cpu(lambda a=args_, kw=kw: old.true_surface_distances(*a, **kw),
                                args.repeat)
            t_new, r_new = _cpu(lambda a=args_, kw=kw: new.true_surface_distances(*a, **kw),
                                args.repeat)
            same = (np.array_equal(r_old.value, r_new.value)
                    and np.array_equal(r_old.engulfed, r_new.engulfed))
            print(f"{name:<13}{label:<48}{len(X):>6}{r_new.points:>9}{t_old:>8.3f}{t_new:>8.3f}"
                  f"{t_old / t_new:>8.2f}x  {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
