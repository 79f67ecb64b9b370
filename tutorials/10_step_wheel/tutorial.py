"""Tutorial 10: a STEP wheel - a CAD solid in, a verified robot program out.

A wheel plant's design office sends the wheel as STEP (or IGES). The import reads the B-rep
through OpenCASCADE, so the window loops are the model's own edges (lines, arcs, B-splines,
one NURBS per loop) and, on a rounded window edge, the line where the face meets the round;
the collision geometry is the B-rep tessellated at a stated chordal tolerance.

1. the wheel: a parametric STEP wheel built with a CAD kernel (build123d, the test wheels of
   ``tests/cad_wheels.py``: drafted windows with 7 mm corners and a 1 mm edge round that
   open into the rim's lip, pockets behind the spokes); bring your own file instead;
2. ``drakedeburr verify WHEEL.step -o PLAN``: import (units from the file, front side and its
   evidence, every opening that is no window with the reason), plan and verify;
3. ``drakedeburr export PLAN -o Deburr.mod``: the program, only when the report passed (the
   straight wheel passes every required check: docs/hub.md "CAD wheels, measured"; a report
   that fails makes export refuse, which this step then shows instead);
4. a window the burr cannot reach: the same wheel on a chuck 1.6 m from the robot; the report
   says per window what failed (out of the arm's reach) and ``export`` refuses.

Run:  python tutorials/10_step_wheel/tutorial.py --out /tmp/stepwheel  [--test-mode] [--kind y]
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "tests"))
import cad_wheels  # noqa: E402  (the CAD-kernel test wheels)


def _tutorial_08():
    """Tutorial 08's helpers (run a command line, show a report, the far cell)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "tutorial_08", HERE.parent / "08_bring_your_own_hub" / "tutorial.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_t08 = _tutorial_08()
far_cell, run, show_report = _t08.far_cell, _t08.run, _t08.show_report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("step_wheel_out"))
    ap.add_argument("--test-mode", action="store_true", help="one window of the wheel (CI)")
    ap.add_argument("--kind", choices=cad_wheels.KINDS, default="straight")
    args = ap.parse_args()
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    logging.basicConfig(level=logging.WARNING, format="  %(levelname)s %(name)s: %(message)s")
    windows = ["--windows", "0"] if args.test_mode else []

    # 1. your wheel: a STEP file from a CAD kernel --------------------------------------------
    wheel = cad_wheels.make_wheel(args.kind, out / "cad", formats=("step",))
    print(f"  your CAD file: {wheel.step.name} ({wheel.step.stat().st_size // 1024} kB), "
          f"{wheel.windows} through-openings between the spokes by construction")

    # 2. import + plan + verify in one command ------------------------------------------------
    plan = out / "plan"
    code = run("verify", str(wheel.step), "-o", str(plan), "--no-replay", *windows)
    imported = next((out / "plan_hub_import").iterdir())
    summary = json.loads((imported / "summary.json").read_text())
    info = summary["import"]
    cad = info["cad"]
    print(f"  import: {cad['format']}, file unit {cad['file_unit']}, {cad['faces']['total']} "
          f"B-rep faces ({cad['faces']['blend']} rounds/chamfers), collision mesh at "
          f"{cad['chordal_tolerance_mm']} mm chordal tolerance; front along "
          f"{info['front']['axis_in_file']} ({info['front']['decided_by']})")
    for loop in info["loops"]:
        print(f"    window {loop['index']}: {loop['edges']} B-rep edges "
              f"({loop['rounded_edges']} on a round), z {loop['z_range_mm']} mm, "
              f"{loop['width_mm']} mm wide")
    for opening in info["not_windows"] + info["rejected"]:
        print(f"    not a window: {opening.get('kind', 'rejected')}: {opening.get('reason')}")
    show_report(plan)
    assert code in (0, 1), "a readable wheel ends in a report (pass or fail)"

    # 3. the program: only from a plan whose report passed ------------------------------------
    program = out / "Deburr.mod"
    exported = run("export", str(plan), "-o", str(program))
    if code == 0:
        assert exported == 0
        head = [ln for ln in program.read_text().splitlines() if ln.strip().startswith("!")]
        print("  " + "\n  ".join(head[:4]))
    else:
        assert exported == 1 and not program.exists(), "no program from a failed report"
        print("  the report failed: no program written (fix what it names, then export)")

    # 4. a window the burr cannot reach: the chuck out of the arm's reach ---------------------
    plan_far = out / "plan_far"
    code = run("verify", str(wheel.step), "--scenario", str(far_cell(out)), "-o",
               str(plan_far), "--hub-cache", str(out / "plan_hub_import"), "--no-replay",
               "--windows", "0")
    show_report(plan_far)
    report = json.loads((plan_far / "report.json").read_text())
    failures = next(i for i in report["items"] if i["name"] == "planner_failures")
    assert code == 1 and "0" in failures.get("per_window", {}), "out of reach: must fail"
    assert run("export", str(plan_far), "-o", str(out / "Far.mod")) == 1
    assert not (out / "Far.mod").exists()


if __name__ == "__main__":
    main()
