"""CLI: ``drakedeburr robots``: the registered arms (``--robot NAME`` on plan, demo, export;
``--robot FILE`` takes an arm file of the same schema, docs/robots.md)."""

from __future__ import annotations

import argparse
import json

__all__ = ["register", "robots_table"]


def robots_table() -> list[dict]:
    """One row per registered arm: name, title, controller, program format, reach [m] (axis 1
    to the wrist centre, the data sheets' figure), payload [kg] and wrist ratings (J4-J6 [N m],
    [kg m^2], None where not published), cells with a mount, model, arm file."""
    import numpy as np

    from drakedeburr.resources import arm_file_path
    from drakedeburr.robots import ROBOTS

    rows = []
    for spec in ROBOTS.values():
        p = spec.opw
        reach = p.a1 + p.c2 + float(np.hypot(p.a2, p.c3))  # arm stretched, to the wrist centre
        rows.append(dict(name=spec.name, title=spec.title, controller=spec.controller_model,
                         format=spec.program_format, reach_m=round(reach, 3),
                         payload_kg=spec.payload_kg, wrist_moment_Nm=spec.wrist_moment_Nm,
                         wrist_inertia_kgm2=spec.wrist_inertia_kgm2, cells=list(spec.cells),
                         model=spec.model_url, arm_file=str(arm_file_path(spec.name))))
    return rows


def _run(args: argparse.Namespace) -> int:
    rows = robots_table()
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"{'name':<12} {'arm':<22} {'controller':<22} {'format':<6} {'reach':>7} "
          f"{'payload':>8}  cells")
    for r in rows:
        print(f"{r['name']:<12} {r['title']:<22} {r['controller']:<22} {r['format']:<6} "
              f"{r['reach_m']:>6.3f}m {r['payload_kg']:>6.1f}kg  {', '.join(r['cells']) or '-'}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "robots", help="list the registered arms (--robot NAME on plan, demo, export)",
        description="The arm registry (drakedeburr.robots): OPW kinematics, joint limits, vendor "
                    "conventions, controller and program format, Drake model, and the cells it "
                    "has a mount in (docs/cell.md).")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(_run=_run)
