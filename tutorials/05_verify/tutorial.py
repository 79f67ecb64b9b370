"""Tutorial 05: verify a plan - the dense, independent certificate, and what it catches.

Steps:
1. get a plan: the planning stage's ``plan_hub`` when it is installed (``--planner plan_hub``),
   else the verifier's reference plan (fixed tool axis per window, analytic construction);
2. ``verify_plan``: re-check it with a freshly loaded cell, two forward kinematics (Drake and
   the analytic OPW model), pairwise distances with the closest pair named, every 0.5 mm of
   tool travel; both faces: the linear Cartesian program and the timed joint trajectory;
3. write ``report.json`` (versioned, deterministic) and a self-contained ``report.html``
   (pass/fail table, plots, Meshcat replay);
4. break the plan on purpose - a knot pushed into the hub, a transition run 4x too fast, a
   dropped window - and read which check names the fault;
5. between the samples: push the tool 0.1 mm past the clearance limit and back *between* two
   samples. The sampled ``clearance`` still passes; the ``clearance_certificate`` (a lower
   bound of the clearance over the whole trajectory, from how far any point of the robot,
   tool and hub can move between two samples) fails and names the reading between them.

Run:  python tutorials/05_verify/tutorial.py --out /tmp/verify  [--test-mode]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from drakedeburr.cell.station import load_cell
from drakedeburr.config import Config, ProcessParameters, Recipe, default_tolerances, load_config
from drakedeburr.hub.model import load_hub
from drakedeburr.verify import faults, reference_plan, verify_plan, write_report_json
from drakedeburr.verify.checks import QUICK_SAMPLING
from drakedeburr.verify.html import meshcat_replay_html, write_report_html


def show(title: str, report) -> None:
    print(f"\n== {title}: {'PASSED' if report.passed else 'FAILED'}")
    for it in report.items:
        if not it.passed:
            where = f"window {it.window}" if it.window is not None else ""
            if it.time is not None:
                where += f", t = {it.time:.3f} s"
            pair = f", pair {it.pair[0]} <-> {it.pair[1]}" if it.pair else ""
            value = "not measured" if it.value is None else f"{it.value:.4g} {it.unit}"
            print(f"   {'FAIL' if it.required else 'miss'} {it.name}: {value} "
                  f"(limit {it.comparison} {it.limit}) [{where}{pair}]")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="verify_out")
    ap.add_argument("--test-mode", action="store_true", help="one window, coarse fault runs")
    ap.add_argument("--hub", default="h5_straight")
    ap.add_argument("--planner", choices=("reference", "plan_hub"), default="reference")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    # 1. a plan. The reference plan runs at 75 mm/s: at 150 mm/s the hub's 10 mm fillets need
    # J3 accelerations above the robot model's (assumed) limit - verify would say so.
    params = ProcessParameters(grinding_speed=0.075)
    windows = [0] if args.test_mode else [0, 1]
    if args.planner == "plan_hub":
        from drakedeburr.plan.planner import PlanOptions, plan_hub

        params = ProcessParameters()
        plan = plan_hub(load_config("tool_in_hand", args.hub),
                        options=PlanOptions(windows=tuple(windows)))
    else:
        plan = reference_plan("tool_in_hand", args.hub, windows, params=params)
    print(f"plan: {len(plan.targets)} targets, {len(plan.trajectory.t)} knots, "
          f"{plan.trajectory.duration:.2f} s")

    # 2. verify (one cell and hub model shared by all runs below)
    cell, hub = load_cell(plan.scenario, plan.hub), load_hub(plan.hub)
    # one configuration: the recipe (here: the process at the plan's speed) and the tolerances
    config = Config("tool_in_hand", args.hub, Recipe(process=params), default_tolerances())
    common = {"expected_windows": windows, "cell": cell, "hub_model": hub}
    report = verify_plan(plan, config, **common)
    show("the plan", report)
    assert report.passed, f"the plan fails {report.failed}"  # the faults below start from a pass
    for name in ("path_deviation", "edge_deviation", "clearance", "tcp_speed_band",
                 "joint_acceleration", "wrist_singularity"):
        it = report.item(name)
        value = "not measured" if it.value is None else f"{it.value:.4g} {it.unit}"
        # process figures (the speed band) carry no pass limit: they are reported
        limit = "reported" if it.limit is None else f"limit {it.comparison} {it.limit:.4g}"
        print(f"   {name}: {value} ({limit})")

    # 3. reports
    write_report_json(report, out / "report.json")
    replay = meshcat_replay_html(plan, cell, hub, max_frames=100 if args.test_mode else 600)
    write_report_html(report, out / "report.html", replay_html=replay)
    print(f"wrote {out / 'report.json'} and {out / 'report.html'}")

    # 4. faults: each must fail with the right item named
    quick = Config("tool_in_hand", args.hub, Recipe(process=params),
                   default_tolerances(**QUICK_SAMPLING)) if args.test_mode else config
    k = faults.cut_knot_index(plan, windows[0])
    cases = {
        "knot pushed 5 mm into the hub": (faults.shift_knot_into_hub(plan, k, 0.005, cell),
                                         "burr_contact"),
        "transition 4x too fast": (faults.speed_up_segment(
            plan, next(i for i, s in enumerate(plan.segments) if s.kind == "transition"), 4.0),
            "joint_velocity"),
    }
    if len(windows) > 1:
        cases["window dropped"] = (faults.drop_window(plan, windows[-1]), "windows")
    caught = {}
    for title, (bad, expected) in cases.items():
        r = verify_plan(bad, quick, **common)
        show(title, r)
        caught[title] = {"expected": expected, "failed": r.failed,
                         "named": expected in r.failed}
    # 5. a graze between two samples: only the continuous certificate can see it
    t_near = report.item("clearance").time  # the plan's closest approach
    grazed, (ta, tb) = faults.graze_between_samples(plan, cell, config.tolerances, t_near,
                                                    depth=0.1e-3)
    # (a bump this short also breaks the joint limits, which are certified on every
    # polynomial piece too; what the samples' clearance misses, the certificate reads)
    r = verify_plan(grazed, config, **common)
    show(f"a graze between the samples at t = {ta:.4f}..{tb:.4f} s", r)
    sampled, cert = r.item("clearance"), r.item("clearance_certificate")
    print(f"   clearance at the samples: {sampled.value * 1e3:.3f} mm "
          f"({'passes' if sampled.passed else 'FAILS'})")
    print(f"   certificate: {'; '.join(cert.detail.split('; ')[:2])}")
    caught["graze between two samples"] = {
        "expected": "clearance_certificate", "failed": r.failed,
        "named": not cert.passed and sampled.passed}
    (out / "faults.json").write_text(json.dumps(caught, indent=2))
    assert all(c["named"] for c in caught.values()), caught


if __name__ == "__main__":
    main()
