"""``drakedeburr cl``: CL-point planning table for all windows of a hub."""

from __future__ import annotations

import argparse

from drakedeburr.argcheck import number

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
    p.add_argument("source", help="hub model folder, bundled hub name, or mesh file "
                   "(STL, OBJ, PLY, OFF, DAE, GLB)")
    p.add_argument("--method", action="append", default=None,
                   help="planner (repeatable): proposed, isoparametric, equal_chord_height, "
                   "adaptive; default all")
    p.add_argument("--l-max-mm", type=number(0, lo_open=True, unit="mm"),
                   default=pp.l_max * 1e3, help="max chord length [mm], > 0 (default %(default)s)")
    p.add_argument("--delta-max-mm", type=number(0, lo_open=True, unit="mm"),
                   default=pp.delta_max * 1e3,
                   help="max chord-height error [mm], > 0 (default %(default)s)")
    p.add_argument("--json", metavar="FILE",
                   help="write the table as JSON, with 'input': each window's edge loop, the "
                        "hub axis and the front side in the input mesh's coordinates and unit")
    p.add_argument("--unit", choices=("m", "mm"), help="force a mesh file's unit")
    from drakedeburr.hub.commands import add_front_and_burr

    add_front_and_burr(p)
    p.set_defaults(_run=_run_cl)


def _windows_and_view(args: argparse.Namespace):
    """(windows for the planners, the input view for --json, source description)."""
    from pathlib import Path

    from drakedeburr.hub.extract import extract_window_edges, resample_loop
    from drakedeburr.hub.inputview import input_view, input_view_of_hub
    from drakedeburr.hub.mesh_io import CAD_SUFFIXES, MESH_TARGET_SUFFIXES, load_hub_mesh
    from drakedeburr.hub.model import load_hub
    from drakedeburr.hub.openings import OpeningSearch
    from drakedeburr.hub.types import WindowEdge
    from drakedeburr.units import m_from_mm

    path = Path(args.source)
    if path.suffix.lower() in CAD_SUFFIXES:  # STEP/IGES: the B-rep's exact edges
        return _cad_windows_and_view(path, args)
    if path.suffix.lower() in MESH_TARGET_SUFFIXES:  # read, or refused by name
        lm = load_hub_mesh(path, unit=args.unit)
        search = OpeningSearch.of(
            m_from_mm(args.burr_mm), clearance=m_from_mm(args.clearance_mm),
            min_window_width=None if args.min_window_width_mm is None
            else m_from_mm(args.min_window_width_mm))
        res = extract_window_edges(lm.mesh, source=str(path), spacing=2.0e-3,
                                   front=args.front, search=search)
        view = input_view(res.windows, res.X_MH, lm.unit, front=res.notes["front"],
                          not_windows=res.notes["not_windows"] + res.notes["rejected"],
                          source=str(path))
        return res.windows, view, str(path)
    hub = load_hub(args.source)
    # the ground truth is dense (mesh vertices); the planners start from equidistant
    # "initial CL points" as in the source
    windows = [WindowEdge(index=w.index, kind=w.kind, p_HE=resample_loop(w.p_HE, 2.0e-3))
               for w in hub.windows]
    return windows, input_view_of_hub(hub), f"hub {hub.name}"


def _cad_windows_and_view(path, args: argparse.Namespace):
    """:func:`_windows_and_view` of a STEP/IGES file: the B-rep's window loops, resampled at
    the planners' 2 mm like a mesh's."""
    from drakedeburr.hub.extract import resample_loop
    from drakedeburr.hub.import_cad import read_cad_windows
    from drakedeburr.hub.import_mesh import ImportOptions
    from drakedeburr.hub.inputview import input_view
    from drakedeburr.hub.types import WindowEdge
    from drakedeburr.units import m_from_mm

    width = args.min_window_width_mm
    options = ImportOptions(front=args.front, burr_diameter=m_from_mm(args.burr_mm),
                            clearance=m_from_mm(args.clearance_mm),
                            min_window_width=None if width is None else m_from_mm(width))
    cw = read_cad_windows(path, options)
    windows = [WindowEdge(index=w.index, kind=w.kind, p_HE=resample_loop(w.p_HE, 2.0e-3))
               for w in cw["windows"]]
    notes = cw["notes"]
    view = input_view(windows, cw["X_MH"], "mm", front=notes["front"],
                      not_windows=notes["not_windows"] + notes["rejected"], source=str(path))
    return windows, view, str(path)


def _check_source(source: str) -> None:
    """A mesh file that exists, or a hub (bundled name or folder), before any work."""
    from pathlib import Path

    from drakedeburr import argcheck
    from drakedeburr.hub.mesh_io import MESH_TARGET_SUFFIXES
    from drakedeburr.resources import resolve_hub_dir

    if Path(source).suffix.lower() in MESH_TARGET_SUFFIXES:
        argcheck.input_file(source, "hub mesh file")
    else:
        resolve_hub_dir(source)


def _run_cl(args: argparse.Namespace) -> int:
    from drakedeburr import argcheck
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
    _check_source(args.source)
    argcheck.output_file(args.json, "--json")
    from pathlib import Path

    src = Path(args.source)
    argcheck.separate_outputs({"--json": args.json},
                              inputs={"the mesh": src if src.is_file() else None},
                              input_folders={"the hub folder": src if src.is_dir() else None})
    windows, view, desc = _windows_and_view(args)
    table = cl_table(windows, methods, params, progress=tqdm_progress("windows"))
    table["source"] = desc
    print(format_table(table))
    if args.json:
        atomic_write_json(args.json, {**table, "input": view})
    return 0
