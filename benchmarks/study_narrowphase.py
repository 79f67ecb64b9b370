"""How exact is Drake's narrow phase on the cell's near pairs? (what the verifier trusts)

On the planner's plan of a hub, every k-th reading of the verifier's sweep below ``--below``
mm is checked against a rigorous lower bound: the separation of the two shapes along the
normal Drake returns (support functions of the shapes: ``min_A n.a - max_B n.b`` is at most
the true distance for any unit n). The gap ``Drake - bound`` is at least Drake's
overestimate; the largest gaps are re-solved independently (SLSQP on the cylinder/convex-hull
distance problem).

Run:  PYTHONPATH=. python benchmarks/study_narrowphase.py [--plan DIR] [--every 5]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from drakedeburr.cell.narrowphase import ShapeSupport, exact_distance
from drakedeburr.cell.station import load_plan_cell
from drakedeburr.plan.io import load_plan
from drakedeburr.verify.checks import config_for_plan
from drakedeburr.verify.distances import pair_scene_of
from drakedeburr.verify.kinematics import VerifyKinematics
from drakedeburr.verify.sampling import _samples
from drakedeburr.verify.sweep import sweep

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = (  # the window-0 plan bench_verify.py --quick leaves (run_all runs it first)
    "--plan", "/tmp/bench_verify_plans/tool_in_hand_h5_straight_quick", "--every", "20",
)


def support(shape, X: np.ndarray, n: np.ndarray, hull: dict, key) -> float:
    """max over the shape (pose X in world) of n . x (:class:`ShapeSupport`, cached)."""
    if key not in hull:
        hull[key] = ShapeSupport(shape)
    return hull[key].support(X, n)


def independent(cyl, X_c, V_W) -> float:
    """Cylinder (pose X_c) to the hull of points V_W: SLSQP from several starts [m]."""
    from scipy.optimize import minimize

    r, half = cyl.radius(), cyl.length() / 2

    def f(z):
        return float(np.sum((X_c[:3, :3] @ z[:3] + X_c[:3, 3] - z[3:] @ V_W) ** 2))

    cons = [{"type": "ineq", "fun": lambda z: r * r - z[0] ** 2 - z[1] ** 2},
            {"type": "eq", "fun": lambda z: z[3:].sum() - 1.0}]
    best, rng = np.inf, np.random.default_rng(0)
    for _ in range(6):
        z0 = np.concatenate([[0, 0, rng.uniform(-half, half)], rng.dirichlet(np.ones(len(V_W)))])
        res = minimize(f, z0, method="SLSQP", constraints=cons,
                       bounds=[(-r, r), (-r, r), (-half, half)] + [(0, 1)] * len(V_W),
                       options={"ftol": 1e-16, "maxiter": 3000})
        best = min(best, float(np.sqrt(max(res.fun, 0.0))))
    return best


def main() -> None:
    from pydrake.geometry import Convex, Cylinder

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plan", default="/tmp/bench_verify_plans/tool_in_hand_h5_straight",
                    help="a saved plan (bench_verify.py plans one there)")
    ap.add_argument("--every", type=int, default=5)
    ap.add_argument("--below", type=float, default=6.0, help="readings below this [mm]")
    args = ap.parse_args()
    if not (Path(args.plan) / "plan.json").is_file():
        raise SystemExit(f"study_narrowphase: no plan at {args.plan}: run "
                         "benchmarks/bench_verify.py (--quick for the _quick folder) first")
    plan = load_plan(args.plan)
    config = config_for_plan(plan)
    cell = load_plan_cell(plan)
    s = _samples(plan, VerifyKinematics(cell), config.tolerances, None)
    scene = pair_scene_of(cell)
    sw = sweep(scene, plan.trajectory, s.t, s.q, config.tolerances)
    # separated pairs only (penetrating ones are the burr's contact, not clearance)
    sel = np.flatnonzero((sw.rec_value < args.below * 1e-3) & (sw.rec_value > 0))[::args.every]
    inspector, hull = cell.scene_graph.model_inspector(), {}
    gaps, kinds, worst = [], [], []
    for j in sel:
        i, p = int(sw.rec_sample[j]), int(sw.rec_pair[j])
        scene.set_configuration(s.q[i])
        scene.distance(p)
        q = scene._query
        r = q.ComputeSignedDistancePairClosestPoints(scene._A[p], scene._B[p])
        ga, gb = scene.ids[scene.a[p]], scene.ids[scene.b[p]]
        X_a = q.GetPoseInWorld(scene._A[p]).GetAsMatrix4()
        X_b = q.GetPoseInWorld(scene._B[p]).GetAsMatrix4()
        n = np.asarray(r.nhat_BA_W)
        sa, sb = inspector.GetShape(ga), inspector.GetShape(gb)
        bound = -support(sa, X_a, -n, hull, ga) - support(sb, X_b, n, hull, gb)
        gaps.append(r.distance - bound)
        kinds.append(f"{type(sa).__name__}/{type(sb).__name__}")
        worst.append((r.distance - bound, i, p, sa, sb, X_a, X_b, r.distance))
    gaps = np.array(gaps)
    print(f"{len(sel)} readings below {args.below} mm (every {args.every}th of the sweep's)")
    print("gap Drake - separating-plane bound [um]: median/90/99/max "
          + "/".join(f"{v * 1e6:.2f}" for v in np.percentile(gaps, [50, 90, 99, 100])))
    for kind in sorted(set(kinds)):
        g = gaps[np.array(kinds) == kind]
        print(f"  {kind:<20} {len(g):>6} readings, > 1 um: {np.mean(g > 1e-6):5.1%}, "
              f"> 10 um: {np.sum(g > 1e-5)}, max {g.max() * 1e6:.1f} um")
    worst = sorted((w for w in worst if isinstance(w[3], Cylinder)
                    and isinstance(w[4], Convex)), key=lambda w: -w[0])
    print("largest cylinder/convex gaps, re-solved independently:")
    for gap, i, p, sa, _, X_a, X_b, d in worst[:3]:
        V = hull[scene.ids[scene.b[p]]].V @ X_b[:3, :3].T + X_b[:3, 3]
        exact, _ = exact_distance(hull[scene.ids[scene.a[p]]], X_a, hull[scene.ids[scene.b[p]]],
                                  X_b)
        print(f"  sample {i} {scene.pair_names(p)}: Drake {d * 1e3:.4f} mm, independent "
              f"{independent(sa, X_a, V) * 1e3:.4f} mm (SLSQP), {exact * 1e3:.4f} mm "
              f"(cell.narrowphase SOCP bound; gap to the bound {gap * 1e6:.1f} um)")


if __name__ == "__main__":
    main()
