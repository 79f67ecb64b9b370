"""The exact orientation solver against stored results of its previous implementation.

The fast rewrite of ``solve_exact`` (issue 19: no per-call overhead) must return the same
optimum as the version it replaced, not just *a* KKT point. tests/data/orientation_reference.npz
holds, for each case, the problem (CL points, local frames, box, second-difference weight,
start point) and the previous solver's angles and objective. It was written by

    python tests/test_orientation_reference.py --write

at commit 9ccafa3 (the banded projected-Newton solver before the rewrite). The cases are stored
whole, so this test depends on no hub model, planner or frame code: three synthetic windows of
tests/test_orientation.py (one with second differences), two windows of the bundled hub
h5_split (CL points every 2 mm, ground-truth normals; from the centre, a bound, a seeded random
start), the planner's CL points on h5_straight's dense window 0 (M = 481; the solves that take
the projected-gradient safeguard step), and seeded random hub-like window shapes
(drakedeburr.path.synthetic) with the planner's badly scaled ``proposed`` CL points (chords
0.01-10 mm).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from drakedeburr.config import OrientationBounds
from drakedeburr.orientation.exact import projected_gradient_norm, solve_exact
from drakedeburr.orientation.models import make_problem

DATA = Path(__file__).parent / "data" / "orientation_reference.npz"


def _cases_from_file() -> list[dict]:
    z = np.load(DATA)
    names = [str(s) for s in z["names"]]
    return [{key: z[f"{name}/{key}"] for key in ("p_HC", "R_HL", "box", "w2nd", "x0", "x",
                                                   "objective")} | {"name": name}
            for name in names]


CASES = _cases_from_file() if DATA.is_file() else []


def _problem(case):
    lo, hi = case["box"]
    return make_problem("axis", case["p_HC"], case["R_HL"], OrientationBounds(float(lo), float(hi)),
                        second_difference_weight=float(case["w2nd"]), name=case["name"])


def _x0(case):
    return None if np.isnan(case["x0"]).all() else case["x0"]


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_exact_solver_returns_the_previous_implementations_optimum(case):
    prob = _problem(case)
    rep = solve_exact(prob, x0=_x0(case))
    assert rep.success, rep.message
    # same optimum: objective and every angle within 1e-9 (the previous solver stopped at a
    # KKT point with residual <= 1e-6 of the gradient scale; both reach the same point, the
    # difference is rounding)
    assert rep.objective == pytest.approx(float(case["objective"]), rel=1e-9, abs=0.0)
    np.testing.assert_allclose(rep.x, case["x"], rtol=0.0, atol=1e-9)
    # independent re-check on the problem's own (dense) model
    assert rep.objective == pytest.approx(float(prob.objective(rep.x)), rel=1e-12)
    scale = np.abs(prob.gradient(0.5 * (prob.lower + prob.upper))).max()
    assert projected_gradient_norm(prob, rep.x) <= 1e-6 * scale


def test_reference_file_covers_the_cases():
    assert len(CASES) >= 8
    sizes = {len(c["p_HC"]) for c in CASES}
    assert max(sizes) >= 200 and min(sizes) <= 80
    assert any(float(c["w2nd"]) > 0 for c in CASES)
    assert any(not np.isnan(c["x0"]).all() for c in CASES)


# -------------------------------------------------------------------------------------------
# writing the reference (run by hand with the implementation to be preserved)
# -------------------------------------------------------------------------------------------
def _generate_cases() -> list[tuple[str, object, np.ndarray | None]]:
    sys.path.insert(0, str(Path(__file__).parent))
    from test_orientation import WINDOWS
    from test_orientation import _problem as window_problem

    from drakedeburr.frames.local_frames import R_HL_from_normals
    from drakedeburr.hub import load_hub
    from drakedeburr.orientation import OrientOptions, problem_for
    from drakedeburr.orientation.commands import cl_points_from_edge
    from drakedeburr.path import PlannerParams, fit_edge_curve, plan_cl
    from drakedeburr.path.synthetic import hub_like_window

    cases = []
    for k, (cl, n) in enumerate(WINDOWS):
        cases.append((f"synthetic{k}", window_problem(cl, n, "axis"), None))
    cl, n = WINDOWS[1]
    cases.append(("synthetic1_w2nd", window_problem(cl, n, "axis", 1e-5), None))
    hub = load_hub("h5_split")
    for edge in hub.windows[:2]:
        cl, idx = cl_points_from_edge(edge, 2e-3)
        prob = problem_for(cl, R_HL_from_normals(cl.t_H, edge.n_wall_H[idx]), "axis",
                           options=OrientOptions())
        cases.append((f"h5_split_w{edge.index}", prob, None))
        if edge.index == 1:
            cases.append((f"h5_split_w{edge.index}_lower", prob, prob.lower.copy()))
            x0 = np.random.default_rng(7).uniform(prob.theta_min, prob.theta_max, prob.n_vars)
            cases.append((f"h5_split_w{edge.index}_random", prob, x0))
    # the planner's CL points on a dense ground-truth loop: the projected-gradient safeguard
    # is used on these (a wrong active-set guess on badly scaled chords)
    from scipy.spatial import cKDTree

    edge = load_hub("h5_straight").windows[0]
    cl = plan_cl(fit_edge_curve(edge.p_HE), "proposed", window_index=0, kind=edge.kind)
    _, idx = cKDTree(edge.p_HE).query(cl.p_HC)
    prob = problem_for(cl, R_HL_from_normals(cl.t_H, edge.n_wall_H[idx]), "axis",
                       options=OrientOptions())
    cases.append(("h5_straight_w0_proposed", prob, None))
    cases.append(("h5_straight_w0_proposed_upper", prob, prob.upper.copy()))
    rng = np.random.default_rng(19)
    for k in range(3):
        kind = ("large", "small", "large")[k]
        p = hub_like_window(kind, int(rng.integers(120, 260)), angle=float(rng.uniform(0, 6)),
                            dome=float(rng.uniform(0.0, 0.4)))
        curve = fit_edge_curve(p, name=f"random window {k}")
        cl = plan_cl(curve, "proposed", PlannerParams(), window_index=k, kind=kind)
        n_in = np.cross([0.0, 0.0, 1.0], cl.t_H)  # CCW seen from +Z: left is inside
        prob = problem_for(cl, R_HL_from_normals(cl.t_H, n_in), "axis",
                           options=OrientOptions(second_difference_weight=1e-6 * (k == 2)))
        cases.append((f"random_window{k}", prob, None))
    return cases


def write_reference() -> None:
    arrays = {}
    names = []
    for name, prob, x0 in _generate_cases():
        rep = solve_exact(prob, x0=x0)
        assert rep.success, (name, rep.message)
        names.append(name)
        arrays.update({f"{name}/p_HC": prob.p_HC, f"{name}/R_HL": prob.R_HL,
                       f"{name}/box": np.array([prob.theta_min, prob.theta_max]),
                       f"{name}/w2nd": np.array(prob.second_difference_weight),
                       f"{name}/x0": (np.full(prob.n_vars, np.nan) if x0 is None else x0),
                       f"{name}/x": rep.x, f"{name}/objective": np.array(rep.objective)})
        print(f"{name}: M={prob.m} objective {rep.objective:.12g} it {rep.iterations} "
              f"safeguard {rep.info['safeguard_steps']} convex {rep.info['convex_model_steps']}")
    np.savez_compressed(DATA, names=np.array(names), **arrays)
    print(f"wrote {DATA}")


if __name__ == "__main__":
    if "--write" in sys.argv:
        write_reference()
