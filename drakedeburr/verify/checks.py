"""Dense, independent re-check of a plan -> :class:`VerificationReport`.

Nothing the planner computed is trusted beyond the plan itself (targets, segments, joint
trajectory, tool paths): the cell is loaded afresh from the plan's scenario and hub, forward
kinematics is evaluated twice (the Drake plant and the analytic OPW model of the cell's arm,
which must agree to ``Tolerances.fk_match``), distances come from the scene graph's narrow
phase (:mod:`drakedeburr.verify.distances`), and the true window edges come from the hub
model's ground truth.

The plan is sampled once into a :class:`drakedeburr.verify.types.SampledPlan`; each check
is a small function over it, listed with its purpose in :mod:`drakedeburr.verify.registry`;
the report is rendered from their items.
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Callable
from pathlib import Path

from drakedeburr.config import Config
from drakedeburr.verify.gate import plan_identity
from drakedeburr.verify.registry import CHECKS, run_checks
from drakedeburr.verify.report import VerificationReport
from drakedeburr.verify.sampling import sample_plan
from drakedeburr.verify.types import KIND_CODE, SampledPlan

__all__ = ["verify_plan", "verify_sampled", "config_for_plan", "no_window_report",
           "QUICK_SAMPLING"]

log = logging.getLogger(__name__)

#: coarse sampling for a smoke test (``--quick``): Tolerances fields, not a certificate
QUICK_SAMPLING = {"dense_step": 2e-3, "time_step": 0.1, "joint_move_step": 10e-3}


def _series(sp: SampledPlan) -> dict:
    s, d, c, p = sp.samples, sp.distances, sp.cut, sp.program
    return {"t": s.t, "q": s.q, "qd": s.qd, "speed": s.speed, "clearance": d.clearance,
            "self": d.self_distance, "burr": d.burr, "kind": s.kind, "window": s.window,
            "path_dev": p.path_dev, "orient_dev": p.orient_dev, "edge_dev": c.edge_dev,
            "engagement": c.engagement, "theta_A": c.theta_A, "theta_B": c.theta_B,
            "s_cut": c.s_cut, "cone_margin": c.cone_margin,
            "manipulability": d.manipulability, "p_HT": s.p_HT, "contact_H": c.contact}


def verify_sampled(sp: SampledPlan, config: Config, *, elapsed: float = 0.0,
                   checks=CHECKS) -> VerificationReport:
    """Run the checks over a sampled plan and assemble the report."""
    import drakedeburr

    items = run_checks(sp, config, checks)
    passed = all(i.passed for i in items if i.required)
    plan, traj = sp.plan, sp.plan.trajectory
    plan_info = {"scenario": str(plan.scenario), "hub": str(plan.hub), "mode": plan.mode,
                 "expected_windows": sp.expected_windows,
                 "windows": sorted({t.window_index for t in plan.targets
                                    if t.window_index >= 0}),
                 "targets": len(plan.targets), "segments": len(plan.segments),
                 "knots": len(traj.t), "duration_s": traj.duration,
                 "planner": str(plan.meta.get("planner", "")),
                 "robot": (plan.meta or {}).get("robot"),
                 "identity": plan_identity(plan)}
    tol = config.tolerances
    settings = {"tolerances": _tolerance_record(tol),
                "samples": len(sp.samples), "grinding_speed": config.process.grinding_speed,
                "cut_samples": int((sp.samples.kind == KIND_CODE["cut"]).sum())}
    import datetime as _dt

    run = {"timestamp": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
           "elapsed_s": round(elapsed, 3),
           "versions": {"drakedeburr": getattr(drakedeburr, "__version__", "")}}
    log.info("verified plan for %s (%s): %s, %d samples", plan.hub, plan.scenario,
             "PASS" if passed else "FAIL " + ", ".join(i.name for i in items
                                                       if i.required and not i.passed),
             len(sp.samples))
    return VerificationReport(passed=passed, items=items, plan_info=plan_info,
                              settings=settings, series=_series(sp), run=run)


def _tolerance_record(tol) -> dict:
    """The report's record of the tolerances a run used (every field)."""
    return {k: getattr(tol, k) for k in tol.__dataclass_fields__}


def verify_plan(
    plan,
    config: Config,
    *,
    expected_windows: list[int] | None = None,
    cell=None,
    hub_model=None,
    progress: Callable[[int, int, str], None] | None = None,
) -> VerificationReport:
    """Re-check a plan densely and independently (see module docstring).

    Args:
        plan: a :class:`drakedeburr.plan.types.Plan`.
        config: the run's configuration: the recipe (speeds, depth of cut, boxes, acceptance
            thresholds) and the tolerances (limits and sampling).
        expected_windows: windows the plan must cut (default: every window of the hub); give
            a subset to verify a partial plan (e.g. one re-planned window).
        cell: an already loaded cell for the plan's scenario and hub (default: load afresh).
        hub_model: the hub's :class:`drakedeburr.hub.HubModel` (default: ``load_hub(plan.hub)``).
        progress: optional callback (done, total, label).

    Returns:
        The VerificationReport; ``passed`` is False if any required item failed.

    Raises:
        InputError: the plan is malformed (trajectory shapes, non-increasing knots, no targets).
    """
    started = _time.perf_counter()
    if len(plan.trajectory.t) < 2 and plan.failures and plan.targets:
        return _nothing_planned(plan, config, hub_model, expected_windows)
    sp = sample_plan(plan, config, cell=cell, hub_model=hub_model,
                     expected_windows=expected_windows, progress=progress)
    from drakedeburr.verify.html import warm_plotting

    warm_plotting()  # the sweep's workers are idle until the report's figures
    return verify_sampled(sp, config, elapsed=_time.perf_counter() - started)


def _nothing_planned(plan, config: Config, hub_model, expected_windows) -> VerificationReport:
    """The report of a plan in which no window could be planned (it holds only home): the
    planner's failure records say per window what failed and what was tried."""
    from drakedeburr.verify.checks_plan import failures_item
    from drakedeburr.verify.report import CheckItem

    if hub_model is None:
        from drakedeburr.hub.model import load_hub

        hub_model = load_hub(plan.hub)
    windows = expected_windows or [w.index for w in hub_model.windows]
    detail = "; ".join(str(f) for f in plan.failures[:8])
    items = (
        CheckItem("windows", False, float(len(windows)), 0.0, "count", "<=",
                  window=windows[0] if windows else None,
                  detail=f"no window of hub {hub_model.name} could be planned: {detail}",
                  per_window={w: {"cut": False} for w in windows}),
        failures_item(plan),
    )
    return VerificationReport(
        passed=False, items=items,
        plan_info={"scenario": str(plan.scenario), "hub": str(plan.hub), "mode": plan.mode,
                   "expected_windows": windows, "windows": [], "targets": len(plan.targets),
                   "segments": len(plan.segments), "knots": len(plan.trajectory.t),
                   "duration_s": 0.0, "planner": str(plan.meta.get("planner", "")),
                   "robot": (plan.meta or {}).get("robot"), "identity": plan_identity(plan)},
        settings={"tolerances": _tolerance_record(config.tolerances),
                  "samples": 0, "grinding_speed": config.process.grinding_speed},
        run={"elapsed_s": 0.0})


def no_window_report(exc, scenario: str, tolerances) -> VerificationReport:
    """The report of a hub mesh none of whose openings is a window the burr can cut
    (:class:`drakedeburr.errors.NoCuttableWindow`): one failed required item ``windows``
    naming every opening and outline and why it was not taken; ``plan_info["openings"]`` and
    ``plan_info["rejected_outlines"]`` hold them whole (for --json readers)."""
    from drakedeburr.verify.report import CheckItem

    reasons = [f"{o.get('kind', 'opening')} at r = {o.get('radius_mm', float('nan')):.0f} mm: "
               f"{o.get('reason', '')}" for o in exc.openings]
    reasons += [f"outline at {r.get('center_xy_mm')} mm: {r.get('reason', '')}"
                for r in exc.rejected]
    detail = (f"no window of {Path(exc.source).name} can be cut: {len(exc.openings)} openings "
              f"too small or not windows, {len(exc.rejected)} outlines rejected: "
              + "; ".join(reasons)
              + "".join(f" ({note})" for note in getattr(exc, "notes", [])))
    items = (CheckItem("windows", False, 0.0, 1.0, "count", ">=", detail=detail),)
    return VerificationReport(
        passed=False, items=items,
        plan_info={"scenario": str(scenario), "hub": str(exc.source), "mode": None,
                   "expected_windows": [], "windows": [], "targets": 0, "segments": 0,
                   "knots": 0, "duration_s": 0.0, "planner": "", "robot": None,
                   "hub_axis_file": exc.axis, "openings": exc.openings,
                   "rejected_outlines": exc.rejected,
                   "import_notes": list(getattr(exc, "notes", []))},
        settings={"tolerances": _tolerance_record(tolerances),
                  "samples": 0, "grinding_speed": None},
        run={"elapsed_s": 0.0})


def config_for_plan(plan, *, tolerances=None, grinding_speed: float | None = None) -> Config:
    """The configuration to verify a saved plan with: the recipe the plan was made with (its
    record in ``plan.meta["config"]``; for a plan without one, the hub's own recipe), the
    verifier's tolerances (``tolerances``, else the defaults - never the plan's), and an
    explicit ``grinding_speed`` [m/s] over the recipe's."""
    from drakedeburr.config import load_config, recipe_from_record

    record = (plan.meta or {}).get("config")
    recipe = recipe_from_record(record, f"plan of {plan.hub}") if record else None
    robot = record.get("robot") if record else None
    return load_config(plan.scenario, plan.hub, robot=robot, tolerances=tolerances,
                       recipe=recipe, grinding_speed=grinding_speed)
