"""Hub stage benchmark: generation (mesh + edges vs collision pieces), loading, scan simulation.

    PYTHONPATH=. python benchmarks/bench_hub.py [--quick]

Baselines measured in the same run: generation without collision pieces (mesh + ground-truth
edges only) for the generator, and a visibility-free area sampling of the same mesh
(trimesh.sample.sample_surface) for the scan simulator.

Second table, mesh import (``drakedeburr hub import``: edges + CoACD pieces refined off the
windows): each hub's own mesh written as a millimetre STL and imported with the default
options; baseline = the generator's full run for the same hub (its own collision pieces).
``--import-only`` skips the first table (the generator then runs once for the baseline).

``--random N [--seed S]``: the random catalogue (``drakedeburr hub random``): N hubs generated
with their collision pieces, time per hub (median, p95) against the bundled h5_straight
generated in the same run (baseline).

``--real``: import of meshes as users bring them, timed against the closed-mesh import of the
same hub in the same run (baseline): the audibot game rim from shared/extdata (open, low-poly:
refused with its reasons, the time to that answer), and random catalogue hubs written as
millimetre files that are face-only and mirrored, or have holes in the barrel and unstitched
parts in a CAD pose (open meshes: surface-shell collision pieces).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--quick",)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="one hub only")
    ap.add_argument("--import-only", action="store_true", help="only the mesh-import table")
    ap.add_argument("--random", type=int, metavar="N", help="only the random catalogue table")
    ap.add_argument("--seed", type=int, default=2026, help="catalogue seed for --random/--real")
    ap.add_argument("--real", action="store_true", help="only the real-mesh import table")
    args = ap.parse_args()
    if args.random:
        _random_table(args.random, args.seed)
        return
    if args.real:
        _real_table(args.seed)
        return

    import trimesh

    from drakedeburr.hub import BUNDLED, generate_hub, load_hub, simulate_scan

    names = ["h5_straight"] if args.quick else sorted(BUNDLED)
    if args.import_only:
        _import_table(names)
        return
    print(f"{'hub':<12} {'tris':>6} {'pieces':>6} {'mesh+edges s':>12} {'full s':>7} "
          f"{'collision share':>15} {'load s':>6} {'scan 1mm s':>10} {'pts':>7} "
          f"{'vs plain sampling':>17}")
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            spec = BUNDLED[name]
            t0 = time.perf_counter()
            generate_hub(spec, Path(tmp) / "bare" / name, with_collision=False)
            t_bare = time.perf_counter() - t0
            t0 = time.perf_counter()
            res = generate_hub(spec, Path(tmp) / name)
            t_full = time.perf_counter() - t0
            t0 = time.perf_counter()
            hub = load_hub(Path(tmp) / name)
            t_load = time.perf_counter() - t0
            t0 = time.perf_counter()
            cloud = simulate_scan(hub, spacing=1e-3)
            t_scan = time.perf_counter() - t0
            t0 = time.perf_counter()
            trimesh.sample.sample_surface(hub.trimesh, len(cloud.p_S), seed=0)
            t_plain = time.perf_counter() - t0
            s = res.summary
            print(f"{name:<12} {s['mesh']['triangles']:>6} {s['collision']['piece_count']:>6} "
                  f"{t_bare:>12.1f} {t_full:>7.1f} {1 - t_bare / t_full:>15.0%} {t_load:>6.2f} "
                  f"{t_scan:>10.2f} {len(cloud.p_S):>7} {t_scan / max(t_plain, 1e-9):>16.1f}x")
    _import_table(names)


def _import_table(names: list[str]) -> None:
    import trimesh

    from drakedeburr.hub import BUNDLED, generate_hub, load_hub
    from drakedeburr.hub.import_mesh import import_mesh

    print(f"\n{'import':<12} {'tris':>6} {'generate s':>10} {'import s':>8} {'CoACD 1st s':>11} "
          f"{'1st pieces':>10} {'rounds':>6} {'pieces':>6} {'reach mm':>8} {'vs generate':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            t0 = time.perf_counter()
            generate_hub(BUNDLED[name], Path(tmp) / name)
            t_gen = time.perf_counter() - t0
            hub = load_hub(Path(tmp) / name)
            stl = Path(tmp) / f"{name}.stl"
            trimesh.Trimesh(hub.vertices_H * 1e3, hub.faces, process=False).export(stl)
            t0 = time.perf_counter()
            res = import_mesh(stl, Path(tmp) / "imported")
            t_imp = time.perf_counter() - t0
            c = res.summary["collision"]
            print(f"{name:<12} {len(hub.faces):>6} {t_gen:>10.1f} {t_imp:>8.1f} "
                  f"{c['coacd_first_pass_seconds']:>11.1f} {c['coacd_first_pass_pieces']:>10} "
                  f"{c['refine_rounds']:>6} {res.piece_count:>6} "
                  f"{c['max_window_intrusion_mm']:>8.2f} {t_imp / t_gen:>10.2f}x")


def _stats(t: list[float]) -> str:
    import numpy as np

    return f"median {np.median(t):.1f} s, p95 {np.percentile(t, 95):.1f} s, max {max(t):.1f} s"


def _random_table(n: int, seed: int) -> None:
    from drakedeburr.hub import BUNDLED, generate_hub
    from drakedeburr.hub.randomhub import random_catalogue

    print(f"{'hub':<10} {'style':<9} {'spokes':>6} {'windows':>7} {'tris':>7} {'pieces':>6} "
          f"{'s':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        generate_hub(BUNDLED["h5_straight"], Path(tmp) / "h5_straight")
        t_base = time.perf_counter() - t0
        times = []
        for i in range(n):
            t0 = time.perf_counter()
            (res,) = random_catalogue(seed, 1, Path(tmp) / "cat", start=i)
            times.append(time.perf_counter() - t0)
            s = res.summary
            spec = (res.dir / "hub.yaml").read_text()
            style = next(ln.split(": ")[1] for ln in spec.splitlines()
                         if ln.startswith("spoke_style"))
            style += "+tw" if "spoke_twist_deg" in spec else ""
            n_sp = next(ln.split(": ")[1] for ln in spec.splitlines()
                        if ln.startswith("spoke_count"))
            print(f"{res.dir.name:<10} {style:<9} {n_sp:>6} {s['window_count']:>7} "
                  f"{s['mesh']['triangles']:>7} {s['collision']['piece_count']:>6} "
                  f"{times[-1]:>6.1f}")
    print(f"\nrandom hubs (seed {seed}, {n}): {_stats(times)} per hub (generation incl. "
          f"collision pieces and STL export); baseline h5_straight {t_base:.1f} s in the same "
          f"run: median ratio {sorted(times)[len(times) // 2] / t_base:.2f}x")


def _real_table(seed: int) -> None:
    import numpy as np
    import trimesh

    from drakedeburr.errors import InputError
    from drakedeburr.hub import generate_hub, load_hub
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.hub.randomhub import random_spec
    from drakedeburr.resources import extdata_dir

    sys_path = str(Path(__file__).resolve().parent.parent / "tests")
    import sys

    sys.path.insert(0, sys_path)
    from hub_meshes import degraded_mesh

    print(f"{'mesh':<34} {'tris':>7} {'closed':>6} {'windows':>7} {'pieces':>6} {'s':>6} "
          f"{'vs closed':>9}  result")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rim = extdata_dir() / "wheel_models" / "audibot__wheel_rim_only_DERIVED_m.stl"
        t0 = time.perf_counter()
        try:
            import_mesh(rim, tmp / "imp")
            result = "imported"
        except InputError as exc:
            result = "refused: " + str(exc).split("; ")[1][:60] + " ..."
        print(f"{'audibot rim (extdata)':<34} {1048:>7} {'no':>6} {'-':>7} {'-':>6} "
              f"{time.perf_counter() - t0:>6.1f} {'-':>9}  {result}")
        for index in (0, 1):
            spec = random_spec(seed, index)
            generate_hub(spec, tmp / spec.name, with_collision=False)
            hub = load_hub(tmp / spec.name)
            rows = [("closed mm", dict()),
                    ("face-only mirrored mm", dict(mirror=True, no_barrel=True)),
                    ("holes+parts, CAD pose, mm", dict(holes=4, split=True, X_MH=_pose()))]
            base = None
            for label, kw in rows:
                V, F, _ = degraded_mesh(hub, np.random.default_rng(index), **kw)
                path = tmp / f"{spec.name}_{label.split()[0]}.stl"
                trimesh.Trimesh(V, F, process=False).export(path)
                t0 = time.perf_counter()
                res = import_mesh(path, tmp / "imp")
                dt = time.perf_counter() - t0
                base = base or dt
                print(f"{spec.name + ' ' + label:<34} {len(F):>7} "
                      f"{'yes' if res.summary['import']['closed_mesh'] else 'no':>6} "
                      f"{res.window_count:>7} {res.piece_count:>6} {dt:>6.1f} "
                      f"{dt / base:>8.2f}x  {res.window_count} of {len(hub.windows)} windows, "
                      f"reach {res.summary['collision']['max_window_intrusion_mm']} mm")


def _pose():
    import numpy as np

    X = np.eye(4)
    X[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    X[:3, 3] = [0.01, -0.05, 0.02]
    return X


if __name__ == "__main__":
    main()
