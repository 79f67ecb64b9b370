"""Distance [mm] of the loops the mesh extraction finds on a CAD wheel's STL export to the
B-rep's window loop edges (the method of tests/test_cad_import.py
``test_mesh_export_loops_near_the_brep_edges``: extract_window_edges at 2 mm spacing, every
2nd loop point, BRepExtrema_DistShapeShape against the edges of the STEP import's kept loops).

Run: PYTHONPATH=$PWD python wip/issue42_hD7_cad/mesh_loop_distance.py WHEEL.step WHEEL_x.stl
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from test_cad_import import _distances_mm, _loop_edges_compound  # noqa: E402

from drakedeburr.hub.extract import extract_window_edges  # noqa: E402
from drakedeburr.hub.import_cad import read_cad_windows  # noqa: E402
from drakedeburr.hub.import_mesh import ImportOptions  # noqa: E402
from drakedeburr.hub.mesh_io import load_hub_mesh  # noqa: E402


def main(step: str, stl: str) -> None:
    t0 = time.time()
    cw = read_cad_windows(Path(step), ImportOptions())
    edges = _loop_edges_compound(cw)
    res = extract_window_edges(load_hub_mesh(Path(stl)).mesh, source="stl", spacing=2e-3)
    X = res.X_MH
    print(f"{stl}: {len(res.windows)} windows from the mesh, {len(cw['windows'])} from the STEP")
    all_d = []
    for w in res.windows:
        d = _distances_mm(edges, (w.p_HE[::2] @ X[:3, :3].T + X[:3, 3]) * 1e3)
        all_d.append(d)
        print(f"  window {w.index}: {len(d)} points, median {np.median(d):.3f} "
              f"95% {np.percentile(d, 95):.3f} max {d.max():.3f} mm")
    d = np.concatenate(all_d)
    print(f"  all: {len(d)} points, median {np.median(d):.3f} 95% {np.percentile(d, 95):.3f} "
          f"max {d.max():.3f} mm; > 0.15 mm: {100 * np.mean(d > 0.15):.1f} %; "
          f"{time.time() - t0:.0f} s")


if __name__ == "__main__":
    main(*sys.argv[1:3])
