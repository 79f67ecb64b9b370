"""``drakedeburr orient <hub>``: inner-side normals + tool orientation for every window."""

from __future__ import annotations

import argparse
import logging
from dataclasses import dataclass

from drakedeburr.argcheck import number

__all__ = ["register", "OrientRun", "run_orient", "cl_points_from_edge", "cl_points_planned"]

log = logging.getLogger(__name__)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "orient", help="tool orientation along every window edge of a hub",
        description="Estimate the inner-side normals (from a simulated scan, the mesh or the "
                    "model's ground truth), build the local frames and optimise the tool axis "
                    "per window; print a table and optionally write JSON.")
    p.add_argument("hub", help="bundled hub name or hub.yaml path (drakedeburr.hub.load_hub)")
    p.add_argument("--solver", choices=["exact", "pso"], default="exact")
    p.add_argument("--model", choices=["axis", "paper"], default="axis",
                   help="axis: world-axis smoothness (default); paper: eq. 11 as printed")
    p.add_argument("--normals", choices=["cloud", "mesh", "truth"], default="cloud",
                   help="normal source: simulated scan (default), mesh, or the model's truth")
    p.add_argument("--sigma-mm", type=number(0, unit="mm"), default=0.05,
                   help="scan noise [mm] (cloud), >= 0")
    p.add_argument("--seed", type=number(0, integer=True), default=0, help="scan seed, >= 0")
    p.add_argument("--cl", default="proposed",
                   choices=["proposed", "isoparametric", "equal_chord_height", "adaptive",
                            "loop"],
                   help="CL planner of the path stage (default: the source's proposed method); "
                        "'loop': points of the edge loop every --spacing-mm")
    p.add_argument("--spacing-mm", type=number(0, lo_open=True, unit="mm"), default=2.0,
                   help="CL point spacing [mm] for --cl loop, > 0")
    p.add_argument("--json", metavar="FILE", help="write the per-window results as JSON")
    p.set_defaults(_run=_run)


def cl_points_from_edge(edge, spacing: float):
    """Isoparametric CL points on a WindowEdge loop (stand-in for the path stage's planners).

    Picks loop points at equal arc-length stations ``spacing`` [m] apart; tangents from the
    edge (or central differences), curvature from the turning of the tangent per arc length.

    Returns:
        (ClPath, indices into the edge's loop points).
    """
    import numpy as np

    from drakedeburr.errors import InputError
    from drakedeburr.path.types import ClPath

    p = np.asarray(edge.p_HE, float)
    seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    total = float(seg.sum())
    n = max(int(round(total / spacing)), 8)
    stations = np.linspace(0, total, n, endpoint=False)
    idx = np.unique(np.searchsorted(s, stations).clip(0, len(p) - 1))
    if len(idx) < 8:
        raise InputError(f"window {edge.index}: edge loop too short for CL points ({total:.4g} m)")
    if edge.t_H is not None:
        t_all = np.asarray(edge.t_H, float)
    else:
        t_all = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
        t_all /= np.linalg.norm(t_all, axis=1)[:, None]
    # curvature: turning angle of the loop tangent over +-1 sample per arc length
    t_prev, t_next = np.roll(t_all, 1, axis=0), np.roll(t_all, -1, axis=0)
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", t_prev, t_next), -1.0, 1.0))
    kappa_all = turn / np.maximum(seg + np.roll(seg, 1), 1e-12)
    cl = ClPath(edge.index, edge.kind, "isoparametric-standin", s[idx] / total, p[idx],
                t_all[idx], kappa_all[idx], s[idx], total)
    return cl, idx


def cl_points_planned(edge, method: str):
    """CL points from the path stage (NURBS fit + planner) and, for each, the index of the
    nearest edge-loop point (for ground-truth comparisons). The fit is the pipeline's
    (:func:`drakedeburr.path.window_fit.fit_window_edge`: the smoothing fit of a faceted
    low-poly loop, the interpolating one otherwise, at the planner's chord tolerance); its
    record is in ``cl.metrics["edge_fit"]``."""
    from scipy.spatial import cKDTree

    from drakedeburr.path import PlannerParams, fit_window_edge, plan_cl

    params = PlannerParams()
    curve = fit_window_edge(edge.p_HE, chord_tolerance=params.delta_max,
                            name=f"window {edge.index}")
    cl = plan_cl(curve, method, params, window_index=edge.index, kind=edge.kind)
    _, idx = cKDTree(edge.p_HE).query(cl.p_HC)
    return cl, idx


@dataclass(frozen=True)
class OrientRun:
    """What ``orient`` runs on each window.

    Attributes:
        solver: the orientation solver ("exact", ...); model: the orientation model.
        normals: "cloud" (estimated from a simulated scan), "mesh" or "truth".
        sigma: the simulated scan's noise [m]; seed: its seed.
        spacing: CL point spacing of the "loop" CL method [m]; cl_method: "proposed", "loop"
            or another CL planner's method.
    """

    solver: str = "exact"
    model: str = "axis"
    normals: str = "cloud"
    sigma: float = 0.05e-3
    seed: int = 0
    spacing: float = 2e-3
    cl_method: str = "proposed"


def run_orient(hub, run: OrientRun = OrientRun(), progress=None) -> list[dict]:
    """Orient every window of ``hub`` (a drakedeburr.hub HubModel) as ``run`` says; JSON-ready
    rows.

    Returns:
        One dict per window: tool_path_summary(...) plus normal-error figures when the model
        has ground-truth normals, and the ToolPath under key "_tool_path".
    """
    import numpy as np

    from drakedeburr.frames.normals import inner_normals_from_cloud, inner_normals_from_mesh
    from drakedeburr.orientation.orient import orient_window, tool_path_summary

    solver, model, normals, sigma, seed, spacing, cl_method = (
        run.solver, run.model, run.normals, run.sigma, run.seed, run.spacing, run.cl_method)
    scan = None
    if normals == "cloud":
        from drakedeburr.hub import ScannerModel, simulate_scan

        scan = simulate_scan(hub, ScannerModel(sigma=sigma), seed=seed, spacing=0.3e-3,
                             max_edge_distance=1.5 * 6e-3)
    rows = []
    for w, edge in enumerate(hub.windows):
        if cl_method == "loop":
            cl, idx = cl_points_from_edge(edge, spacing)
        else:
            cl, idx = cl_points_planned(edge, cl_method)
        if normals == "truth":
            if edge.n_wall_H is None:
                from drakedeburr.errors import InputError

                raise InputError(f"window {edge.index}: the hub model has no ground-truth normals")
            n_H = np.asarray(edge.n_wall_H)[idx]
        elif normals == "mesh":
            n_H = inner_normals_from_mesh(hub.trimesh, cl).n_wall_H
        else:
            n_H = inner_normals_from_cloud(scan, cl).n_wall_H
        tp = orient_window(cl, n_H, model=model, solver=solver, params=hub.process)
        row = tool_path_summary(tp)
        row["normals"] = normals
        if "edge_fit" in cl.metrics:  # which NURBS fit the CL points lie on (path.window_fit)
            row["edge_fit"] = dict(cl.metrics["edge_fit"])
        if edge.n_wall_H is not None:
            err = np.degrees(np.arccos(np.clip(
                np.einsum("ij,ij->i", n_H, np.asarray(edge.n_wall_H)[idx]), -1.0, 1.0)))
            row["normal_error_deg"] = {"median": float(np.median(err)),
                                       "p95": float(np.percentile(err, 95)),
                                       "max": float(err.max())}
        row["_tool_path"] = tp
        rows.append(row)
        if progress is not None:
            progress(w + 1, len(hub.windows), f"window {edge.index}")
    return rows


def _run(args: argparse.Namespace) -> int:
    from drakedeburr._io import atomic_write_json
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.errors import InputError

    try:
        from drakedeburr.hub import load_hub
    except ImportError as exc:  # the hub stage is not in this build
        raise InputError(f"cannot load hubs: {exc}") from exc
    from drakedeburr.argcheck import output_file

    output_file(args.json, "--json")
    hub = load_hub(args.hub)
    rows = run_orient(hub, OrientRun(solver=args.solver, model=args.model, normals=args.normals,
                                     sigma=args.sigma_mm * 1e-3, seed=args.seed,
                                     spacing=args.spacing_mm * 1e-3, cl_method=args.cl),
                      progress=tqdm_progress("orient"))
    print(f"{'window':>6} {'kind':>5} {'pts':>4} {'objective':>12} {'ms':>8} "
          f"{'thA min..max':>14} {'thB min..max':>14} {'turn deg/mm max':>16} ok")
    for r in rows:
        print(f"{r['window']:>6} {r['kind']:>5} {r['n_points']:>4} {r['objective']:>12.5g} "
              f"{1e3 * r['solve_seconds']:>8.1f} "
              f"{r['theta_A']['min']:>6.3f}..{r['theta_A']['max']:<6.3f} "
              f"{r['theta_B']['min']:>6.3f}..{r['theta_B']['max']:<6.3f} "
              f"{r['axis_turn_deg_per_mm']['max']:>16.3f} {'yes' if r['success'] else 'NO'}")
    if args.json:
        out = {"hub": args.hub, "solver": args.solver, "model": args.model,
               "normals": args.normals, "cl": args.cl,
               "windows": [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows]}
        atomic_write_json(args.json, out)
        log.info("wrote %s", args.json)
    return 0 if all(r["success"] for r in rows) else 1
