"""Hub stage benchmark: generation (mesh + edges vs collision pieces), loading, scan simulation.

    PYTHONPATH=. python benchmarks/bench_hub.py [--quick]

Baselines measured in the same run: generation without collision pieces (mesh + ground-truth
edges only) for the generator, and a visibility-free area sampling of the same mesh
(trimesh.sample.sample_surface) for the scan simulator.

Second table, mesh import (``drakedeburr hub import``: edges + CoACD pieces refined off the
windows): each hub's own mesh written as a millimetre STL and imported with the default
options; baseline = the generator's full run for the same hub (its own collision pieces).
``--import-only`` skips the first table (the generator then runs once for the baseline).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="one hub only")
    ap.add_argument("--import-only", action="store_true", help="only the mesh-import table")
    args = ap.parse_args()

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


if __name__ == "__main__":
    main()
