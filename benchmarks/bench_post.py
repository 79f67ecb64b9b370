"""Benchmark of the post stage: CL parsing, analytic IK, 5-axis spin resolution.

    python benchmarks/bench_post.py [--quick]

Baselines measured in the same run: a naive pure-Python GOTO-only parser (regex per line), and
Drake's numerical InverseKinematics (one solve per pose, same joint chain) for the IK rate.
The spin comparison reports the joint travel of the paper's theta6 = 0 rule against our
minimum-travel rule on the NX variable-axis file.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from drakedeburr.post.cl_reader import parse_cl_text, read_cl  # noqa: E402
from drakedeburr.post.tool_axis import path_travel, solve_tool_axis_path  # noqa: E402
from drakedeburr.resources import extdata_dir  # noqa: E402
from drakedeburr.robots import IRB1600_10_120, fk_opw  # noqa: E402
from drakedeburr.robots import IRB1600_10_120_ROBOT as ROBOT  # noqa: E402
from drakedeburr.robots.opw_ik import ik_opw  # noqa: E402

GOTO = re.compile(r"^\s*GOTO\s*/\s*([^,]+),([^,]+),([^,\s]+)")


def naive_parse(text: str) -> int:
    """Baseline: GOTO x,y,z only, no continuation, no checks."""
    n = 0
    for line in text.splitlines():
        m = GOTO.match(line)
        if m:
            [float(v) for v in m.groups()]
            n += 1
    return n


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def drake_ik_rate(n: int) -> tuple[float, float]:
    """Poses per second and success rate of Drake's numerical IK on the same chain."""
    from pydrake.math import RigidTransform, RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.solvers import Solve

    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(REPO / "tests" / "data" / "irb1600_6_12_reference.urdf"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link"))
    plant.Finalize()
    tool0 = plant.GetFrameByName("tool0")
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    qs = rng.uniform(lo * 0.6, hi * 0.6, size=(n, 6))
    ok = 0
    t0 = time.perf_counter()
    for q in qs:
        X = RigidTransform(fk_opw(IRB1600_10_120, q))
        ik = InverseKinematics(plant)
        ik.AddPositionConstraint(tool0, np.zeros(3), plant.world_frame(), X.translation(),
                                 X.translation())
        ik.AddOrientationConstraint(tool0, RotationMatrix(), plant.world_frame(),
                                    X.rotation(), 1e-6)
        prog = ik.get_mutable_prog()
        prog.SetInitialGuess(ik.q(), q + rng.normal(0, 0.2, 6))
        res = Solve(prog)
        ok += int(res.is_success())
    dt = time.perf_counter() - t0
    return n / dt, ok / n


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shrink the work")
    args = ap.parse_args()
    quick = args.quick
    ext = extdata_dir()
    if ext is None:
        print("extdata not found (set DRAKEDEBURR_EXTDATA)")
        return 2
    rows: list[tuple[str, str, str, str]] = []

    # --- CL parsing
    src = (ext / "cl_files" / "MECH491_NX_CLSF__APT_code.txt").read_text()
    body = [ln for ln in src.splitlines() if ln.startswith("GOTO") or ln.startswith("FEDRAT")]
    reps = 20 if quick else 200
    text = "\n".join(body * reps + ["FINI"])
    n_lines = text.count("\n") + 1
    t_ours = best_of(lambda: parse_cl_text(text, units="inch"), 3)
    t_naive = best_of(lambda: naive_parse(text), 3)
    rows.append(("CL parse (streaming reader)", f"{n_lines / t_ours:,.0f} lines/s",
                 f"naive regex GOTO-only {n_lines / t_naive:,.0f} lines/s",
                 f"{t_naive / t_ours:.2f}x"))
    creo = ext / "cl_files" / "CreoPost__profilfraesen_2.ncl.2"
    t_creo = best_of(lambda: read_cl(creo), 5)
    rows.append(("CL read of the Creo file (CIRCLE expansion)",
                 f"{len(creo.read_text().splitlines()) / t_creo:,.0f} lines/s", "-", "-"))

    # --- analytic IK
    n_pose = 2000 if quick else 20000
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    X = fk_opw(IRB1600_10_120, rng.uniform(lo, hi, size=(n_pose, 6)))
    t_vec = best_of(lambda: ik_opw(IRB1600_10_120, X), 3)
    n_sol = int(ik_opw(IRB1600_10_120, X).valid.sum())
    n_single = 200 if quick else 1000
    t_single = best_of(lambda: [ik_opw(IRB1600_10_120, x) for x in X[:n_single]], 3)
    n_drake = 10 if quick else 50
    drake_rate, drake_ok = drake_ik_rate(n_drake)
    rows.append(("analytic IK, vectorised", f"{n_sol / t_vec:,.0f} solutions/s "
                 f"({n_pose / t_vec:,.0f} poses/s)",
                 f"Drake IK {drake_rate:,.1f} poses/s ({drake_ok:.0%} solved, 1 sol. each)",
                 f"{(n_pose / t_vec) / drake_rate:,.0f}x poses"))
    rows.append(("analytic IK, one pose per call", f"{n_single / t_single:,.0f} poses/s",
                 f"Drake IK {drake_rate:,.1f} poses/s",
                 f"{(n_single / t_single) / drake_rate:,.0f}x"))

    # --- spin resolution and the theta6 = 0 comparison
    prog = read_cl(ext / "cl_files" / "MECH491_NX_CLSF__APT_Variable_Axis.txt", units="inch")
    n_pts = 60 if quick else len(prog.moves)
    p_W = prog.p_C[:n_pts] + np.array([0.75, 0.0, 0.25])
    axis = prog.axis_C[:n_pts]
    for label, X_FT in (("straight tool", _tool(0.0)), ("tool tilted 30 deg", _tool(30.0))):
        res, secs = {}, {}
        for mode in ("min_travel", "greedy", "theta6_zero"):
            t = time.perf_counter()
            out = solve_tool_axis_path(ROBOT, p_W, axis, X_FT, mode)
            secs[mode] = time.perf_counter() - t
            res[mode] = path_travel(ROBOT, out.q)
        ta = res["min_travel"]
        for base in ("theta6_zero", "greedy"):
            tb = res[base]
            rows.append((f"spin {label}, {n_pts} pts: min travel vs {base}",
                         f"travel {ta['weighted']:.3f} m (J4-6 {ta['wrist']:.2f} rad), "
                         f"{n_pts / secs['min_travel']:,.0f} pts/s",
                         f"{base} {tb['weighted']:.3f} m (J4-6 {tb['wrist']:.2f} rad), "
                         f"{n_pts / secs[base]:,.0f} pts/s",
                         f"{tb['weighted'] / ta['weighted']:.3f}x travel"))

    w = [max(len(r[i]) for r in rows) for i in range(4)]
    head = ("case", "ours", "baseline", "ratio")
    w = [max(w[i], len(head[i])) for i in range(4)]
    print(" | ".join(h.ljust(w[i]) for i, h in enumerate(head)))
    print("-|-".join("-" * x for x in w))
    for r in rows:
        print(" | ".join(c.ljust(w[i]) for i, c in enumerate(r)))
    return 0


def _tool(tilt_deg: float) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("Y", tilt_deg, degrees=True).as_matrix()
    X[:3, 3] = [0.05 if tilt_deg else 0.0, 0.0, 0.15]
    return X


if __name__ == "__main__":
    sys.exit(main())
