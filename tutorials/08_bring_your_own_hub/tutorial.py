"""Tutorial 08: bring your own hub - a mesh file in, a verified robot program out.

A cell engineer arrives with a CAD export of a hub nobody here has seen. This tutorial runs the
same commands they would, through ``drakedeburr.cli.main`` (what the ``drakedeburr`` command
calls), and reads what each one says:

1. the hub: here a seeded random hub written as an STL in metres, in a CAD pose (stand-in for
   your file; ``drakedeburr hub random``);
2. ``drakedeburr verify MESH -o PLAN``: import (unit detected, front side decided from the mesh's
   own cues and stated, openings that are not windows listed with the reason), plan (hub placed
   on the chuck by a reachability + clearance search, one arm configuration per window,
   recorded recipe relaxations) and the independent verification; the plan folder holds the
   plan and its report;
3. ``drakedeburr export PLAN -o Deburr.mod``: the program, written only because the report in
   the folder passed for this very plan and cell;
4. a window that cannot be cut: the same hub in a cell whose chuck stands out of the arm's
   reach. ``verify`` exits 1 and the report names, per window, what failed and what was tried;
   ``export`` then refuses (exit 1, nothing written).

Run:  python tutorials/08_bring_your_own_hub/tutorial.py --out /tmp/byoh  [--test-mode]
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from drakedeburr.cli import main as drakedeburr


def run(*args: str) -> int:
    """One ``drakedeburr`` command line, echoed with its exit code."""
    print("\n$ drakedeburr " + " ".join(args))
    code = drakedeburr(list(args))
    print(f"  -> exit {code}")
    return code


def show_report(folder: Path) -> None:
    """The report's verdict, the failed required checks and, per window, what the planner
    could not do and what it tried (the ``planner_failures`` item) and any recipe deviation."""
    report = json.loads((folder / "report.json").read_text())
    print(f"  report: {'PASSED' if report['passed'] else 'FAILED'}")
    for item in report["items"]:
        if item["required"] and not item["passed"]:
            print(f"    FAIL {item['name']}: {item['detail'][:120]}")
        if item["name"] == "planner_failures":
            for w, entry in item.get("per_window", {}).items():
                for kind, text in entry["reasons"].items():
                    print(f"    window {w}, {kind}: {text[:200]}")
                print(f"    window {w}, tried: {', '.join(entry['tried'])}")
        if item["name"] == "recipe_deviations" and item.get("value"):
            print(f"    recipe deviations: {item['detail'][:200]}")


def far_cell(out: Path) -> Path:
    """A cell file like the bundled tool-in-hand cell with the chuck 1.6 m from the robot
    (0.85 m further than the bundled cell's 0.75 m): the arm reaches no window."""
    from drakedeburr.resources import scenario_path

    text = scenario_path("tool_in_hand").read_text()
    moved = text.replace("translation: [0.75, 0.0, -0.46]", "translation: [1.60, 0.0, -0.46]")
    assert moved != text, "the bundled cell's chuck pose changed: update this tutorial"
    path = out / "far_cell.yaml"
    path.write_text(moved)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("byoh_out"))
    ap.add_argument("--test-mode", action="store_true", help="one window of the hub (CI)")
    ap.add_argument("--seed", type=int, default=2608, help="random hub seed")
    args = ap.parse_args()
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    logging.basicConfig(level=logging.WARNING, format="  %(levelname)s %(name)s: %(message)s")
    windows = ["--windows", "0"] if args.test_mode else []

    # 1. your hub: a random hub's STL export (mm or m, in a CAD pose) -------------------------
    assert run("hub", "random", "--seed", str(args.seed), "--count", "1", "-o",
               str(out / "catalogue"), "--no-collision", "--no-progress") == 0
    folder = next((out / "catalogue").iterdir())
    export = json.loads((folder / "export.json").read_text())
    mesh = folder / export["file"]
    print(f"  your mesh: {mesh.name}, written in {export['unit']}, front face along "
          f"{export['front']} of the file")

    # 2. import + plan + verify in one command ------------------------------------------------
    plan = out / "plan"
    code = run("verify", str(mesh), "-o", str(plan), "--no-replay", *windows)
    imported = next((out / "plan_hub_import").iterdir())
    summary = json.loads((imported / "summary.json").read_text())
    info = summary["import"]
    front = info["front"]
    print(f"  import: read as {info['unit']}, front along {front['axis_in_file']} of the file "
          f"({front['decided_by']}), {summary['window_count']} windows (narrowest allowed "
          f"{info['min_window_width_mm']} mm for the burr)")
    for line in front.get("evidence", []):
        print(f"    evidence: {line}")
    for opening in info["not_windows"] + info["rejected"]:
        print(f"    not a window: {opening.get('kind', 'rejected')}: {opening.get('reason')}")
    show_report(plan)
    assert code == 0, "the hub should plan and verify in the bundled cell"

    # 3. the program: only from a plan whose report passed ------------------------------------
    program = out / "Deburr.mod"
    assert run("export", str(plan), "-o", str(program)) == 0
    head = [ln for ln in program.read_text().splitlines() if ln.strip().startswith("!")][:6]
    print("  " + "\n  ".join(head))

    # 4. a window that cannot be cut ----------------------------------------------------------
    plan_far = out / "plan_far"
    code = run("verify", str(mesh), "--scenario", str(far_cell(out)), "-o", str(plan_far),
               "--hub-cache", str(out / "plan_hub_import"), "--no-replay", "--windows", "0")
    show_report(plan_far)
    assert code == 1, "out of reach: the report must fail"
    assert run("export", str(plan_far), "-o", str(out / "Far.mod")) == 1
    assert not (out / "Far.mod").exists()


if __name__ == "__main__":
    main()
