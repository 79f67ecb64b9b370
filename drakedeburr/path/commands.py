"""``drakedeburr cl``: CL-point planning table for all windows of a hub."""

from __future__ import annotations

import argparse

__all__ = ["register"]


def register(subparsers) -> None:
    from drakedeburr.config import ProcessParameters

    pp = ProcessParameters()
    p = subparsers.add_parser(
        "cl",
        help="plan CL points on every window edge of a hub and compare the planners",
        description="Extract the window edges of a hub (mesh file, hub model folder or bundled "
        "hub name), fit each with a closed NURBS curve and plan cutter-location points with "
        "each method; prints a table like the source's Tab. 1-2.",
    )
    p.add_argument("source", help="hub model folder, bundled hub name, or STL/OBJ/PLY file")
    p.add_argument("--method", action="append", default=None,
                   help="planner (repeatable): proposed, isoparametric, equal_chord_height, "
                   "adaptive; default all")
    p.add_argument("--l-max-mm", type=float, default=pp.l_max * 1e3,
                   help="max chord length [mm] (default %(default)s)")
    p.add_argument("--delta-max-mm", type=float, default=pp.delta_max * 1e3,
                   help="max chord-height error [mm] (default %(default)s)")
    p.add_argument("--json", metavar="FILE", help="write the table as JSON")
    p.set_defaults(_run=_run_cl)


def _run_cl(args: argparse.Namespace) -> int:
    from drakedeburr._io import atomic_write_json
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.path.cl_planning import METHODS, PlannerParams
    from drakedeburr.path.table import cl_table, format_table
    from drakedeburr.units import m_from_mm

    methods = args.method or list(METHODS)
    params = PlannerParams(l_max=m_from_mm(args.l_max_mm), delta_max=m_from_mm(args.delta_max_mm))
    for m in methods:
        if m not in METHODS:
            from drakedeburr.errors import InputError

            raise InputError(f"--method {m!r}: choose from {', '.join(METHODS)}")
    table = cl_table(args.source, methods, params, progress=tqdm_progress("windows"))
    print(format_table(table))
    if args.json:
        atomic_write_json(args.json, table)
    return 0
