"""``drakedeburr hub ...``: generate the parametric hub models, a seeded random catalogue,
import a hub mesh, list and inspect hub models."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from drakedeburr.argcheck import number

__all__ = ["register"]

_POSITIVE_MM = number(0, lo_open=True, unit="mm")
_NONNEGATIVE_MM = number(0, unit="mm")
_SEED = number(0, integer=True)


def _check_hub_target(target: Path, spec_file) -> None:
    """Refuse a hub folder to generate into that holds files but is not a hub drakedeburr
    generated (its hub.yaml from ``spec_to_yaml``, or its summary's generator version)."""
    from drakedeburr.errors import InputError

    if not target.exists():
        return
    if not target.is_dir():
        raise InputError(f"{target}: exists and is a file; the hub's folder goes there")
    if not any(target.iterdir()):
        return
    try:
        ours = (target / "hub.yaml").read_text(errors="replace").startswith(
            "# drakedeburr parametric hub") or "generator_version" in json.loads(
            (target / "summary.json").read_text())
    except (OSError, ValueError, TypeError):
        ours = False
    same = spec_file is not None and Path(spec_file).resolve() == (target / "hub.yaml").resolve()
    if not (ours or same):
        raise InputError(f"{target}: an existing folder that drakedeburr did not generate; the "
                         "hub would be written into it (choose another --out or name)")


def _run_generate(args: argparse.Namespace) -> int:
    from drakedeburr import argcheck
    from drakedeburr._io import check_path_name
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.errors import InputError
    from drakedeburr.hub.catalogue import BUNDLED
    from drakedeburr.hub.generate import generate_hub
    from drakedeburr.hub.spec import load_spec
    from drakedeburr.resources import hubs_dir

    out_root = Path(args.out) if args.out else hubs_dir()
    argcheck.output_folder(out_root, "--out")
    if args.spec:
        argcheck.input_file(args.spec, "--spec hub.yaml")
    specs = []
    if args.spec:
        if args.names or args.all:
            raise InputError("hub generate: give either --spec FILE or hub names/--all")
        specs.append(load_spec(args.spec))
    elif args.all:
        specs.extend(BUNDLED[n] for n in sorted(BUNDLED))
    elif args.names:
        for name in args.names:
            check_path_name(name, "hub generate: hub name")
            if name in BUNDLED:
                specs.append(BUNDLED[name])
            elif (out_root / name / "hub.yaml").is_file():
                specs.append(load_spec(out_root / name / "hub.yaml"))
            else:
                raise InputError(f"hub generate: unknown hub {name!r}: not bundled "
                                 f"({', '.join(sorted(BUNDLED))}) and no "
                                 f"{out_root / name}/hub.yaml")
    else:
        raise InputError("hub generate: name a hub, or use --all or --spec FILE")
    for spec in specs:  # the files go into OUT/NAME: never into a folder we did not write
        _check_hub_target(out_root / spec.name, args.spec)
    for spec in specs:
        progress = None if args.no_progress else tqdm_progress(f"hub {spec.name}")
        res = generate_hub(spec, out_root / spec.name, progress=progress)
        coll = res.summary.get("collision", {})
        print(f"{spec.name}: {res.summary['window_count']} windows, "
              f"{res.summary['mesh']['triangles']} triangles, "
              f"{coll.get('piece_count', 0)} collision pieces, "
              f"{res.seconds:.1f} s -> {res.dir}")
    return 0


def _run_list(args: argparse.Namespace) -> int:
    from drakedeburr.resources import hubs_dir

    root = Path(args.dir) if args.dir else hubs_dir()
    if not root.is_dir():
        from drakedeburr.errors import InputError

        raise InputError(f"{root}: --dir is not a folder of hub folders")
    rows = []
    for d in sorted(p for p in root.iterdir() if (p / "hub.yaml").is_file()):
        summ = d / "summary.json"
        if summ.is_file():
            s = json.loads(summ.read_text())
            kinds = [w["kind"] for w in s["windows"]]
            rows.append(f"{d.name:<16} {s['window_count']:>2} windows "
                        f"({kinds.count('large')} large, {kinds.count('small')} small)  "
                        f"{s['mass_kg']:6.2f} kg")
        else:
            rows.append(f"{d.name:<16} (not generated)")
    print("\n".join(rows) if rows else f"no hub models in {root}")
    return 0


def _run_info(args: argparse.Namespace) -> int:
    from drakedeburr.hub.inputview import input_view_of_hub
    from drakedeburr.hub.model import load_hub, resolve_hub_dir

    if args.json:
        hub = load_hub(args.hub)
        json.dump({**hub.summary, "input": input_view_of_hub(hub)}, sys.stdout, indent=2)
        print()
        return 0
    d = resolve_hub_dir(args.hub)
    s = json.loads((d / "summary.json").read_text())
    print(f"hub {s['name']} ({d})")
    print(f"  mesh: {s['mesh']['vertices']} vertices, {s['mesh']['triangles']} triangles, "
          f"genus {s['mesh'].get('genus', '-')}, mass {s['mass_kg']} kg")
    c = s.get("collision", {})
    if c:
        print(f"  collision: {c['piece_count']} convex pieces, hull volume "
              f"{c['hull_volume_over_solid']:.3f} x solid, max reach into windows "
              f"{c['max_window_intrusion_mm']} mm")
    imp = s.get("import")
    if imp:
        front = imp.get("front") or {}
        print(f"  imported from {imp['source']} ({imp['unit']}); front side decided by "
              f"{front.get('decided_by', '?')}:")
        for e in front.get("evidence", []):
            print(f"    - {e}")
        for o in imp.get("not_windows", []) + imp.get("rejected", []):
            where = o.get("center_xy_mm")
            print(f"  not a window at {where} mm: {o.get('kind', 'rejected edge')}: "
                  f"{o['reason']}")
    print("  window kind   points length_mm width_mm radial_mm fillet_mm kappa_max_1/mm z_mm")
    for w in s["windows"]:
        print(f"  {w['index']:>6} {w['kind']:<6} {w['points']:>6} {w['length_mm']:>9.1f} "
              f"{w['width_mm']:>8.1f} {w['radial_size_mm']:>9.1f} {w['fillet_mm']:>9.1f} "
              f"{w['max_curvature_per_mm']:>14.3f} "
              f"{w['z_range_mm'][0]:.1f}..{w['z_range_mm'][1]:.1f}")
    return 0


def _run_scan(args: argparse.Namespace) -> int:
    import open3d as o3d

    from drakedeburr.argcheck import output_file
    from drakedeburr.hub.model import load_hub
    from drakedeburr.hub.scan import ScannerModel, simulate_scan
    from drakedeburr.units import m_from_mm

    output_file(args.output, "output point-cloud file")
    hub = load_hub(args.hub)
    cloud = simulate_scan(hub, ScannerModel(sigma=m_from_mm(args.sigma_mm)),
                          spacing=m_from_mm(args.spacing_mm), seed=args.seed)
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud.p_S))
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    if not o3d.io.write_point_cloud(str(args.output), pcd):
        raise OSError(f"could not write {args.output}")
    print(f"{len(cloud.p_S)} points (hub frame H, metres) -> {args.output}")
    return 0


def _run_import(args: argparse.Namespace) -> int:
    from drakedeburr import argcheck
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.errors import InputError
    from drakedeburr.hub.import_mesh import ImportOptions, import_mesh
    from drakedeburr.hub.mesh_io import MESH_TARGET_SUFFIXES
    from drakedeburr.units import m_from_mm

    # the formats not read reach load_hub_mesh, which says what to export instead
    argcheck.input_file(args.mesh, "hub mesh file", MESH_TARGET_SUFFIXES)
    argcheck.output_folder(args.out, "--out")
    if args.axis and not sum(a * a for a in args.axis) > 0:
        raise InputError(f"--axis {' '.join(map(str, args.axis))}: the hub axis needs a "
                         "direction (a non-zero vector)")
    options = ImportOptions(
        unit=args.unit, expected_windows=args.windows,
        axis_M=tuple(args.axis) if args.axis else None, front=args.front,
        burr_diameter=m_from_mm(args.burr_mm), clearance=m_from_mm(args.clearance_mm),
        min_window_width=None if args.min_window_width_mm is None
        else m_from_mm(args.min_window_width_mm),
        window_reach=m_from_mm(args.window_reach_mm),
        front_reach=m_from_mm(args.front_reach_mm),
        front_reach_far=m_from_mm(args.front_reach_far_mm), seed=args.seed)
    progress = None if args.no_progress else tqdm_progress(f"import {Path(args.mesh).name}")
    res = import_mesh(args.mesh, args.out, options=options, progress=progress)
    c = res.summary["collision"]
    imp = res.summary["import"]
    print(f"{res.name}: {res.window_count} windows, {res.piece_count} collision pieces "
          f"(max reach into a window {c['max_window_intrusion_mm']} mm), "
          f"{'cached' if res.cached else f'{res.seconds:.1f} s'} -> {res.dir}")
    front = imp.get("front") or {}
    print(f"  hub axis (file frame) {front.get('axis_in_file')}, front decided by "
          f"{front.get('decided_by')}")
    for o in imp.get("not_windows", []) + imp.get("rejected", []):
        print(f"  not a window: {o.get('kind', 'rejected edge')} at {o['center_xy_mm']} mm: "
              f"{o['reason']}")
    return 0


def _run_random(args: argparse.Namespace) -> int:
    from drakedeburr.argcheck import output_folder
    from drakedeburr.cli import tqdm_progress
    from drakedeburr.hub.randomhub import random_catalogue
    from drakedeburr.units import m_from_mm

    output_folder(args.out, "-o/--out")
    progress = None if args.no_progress else tqdm_progress(f"random hubs seed {args.seed}")
    results = random_catalogue(args.seed, args.count, args.out, start=args.start,
                               burr_diameter=m_from_mm(args.burr_mm),
                               with_collision=not args.no_collision,
                               export=not args.no_export, progress=progress)
    for res in results:
        s = res.summary
        kinds = [w["kind"] for w in s["windows"]]
        spec = res.dir / "hub.yaml"
        print(f"{res.dir.name}: {kinds.count('large')} large + {kinds.count('small')} small "
              f"windows, {s['mesh']['triangles']} triangles, "
              f"{s.get('collision', {}).get('piece_count', 0)} pieces, {res.seconds:.1f} s "
              f"-> {spec.parent}")
    return 0


def _burr_mm() -> float:
    from drakedeburr.cell.tools import BURR

    return round(BURR.head_diameter * 1e3, 6)


def add_front_and_burr(p) -> None:
    """--front, --burr-mm, --clearance-mm, --min-window-width-mm (every command taking a
    mesh)."""
    from drakedeburr.config import default_tolerances
    from drakedeburr.hub.front import FRONT_CHOICES

    p.add_argument("--front", choices=FRONT_CHOICES, default="auto",
                   help="which file axis the front face (the side the tool works on) looks "
                        "along; default auto: decided from lug seats, barrel, mounting face "
                        "and dish, with the evidence reported")
    p.add_argument("--burr-mm", type=_POSITIVE_MM, default=_burr_mm(),
                   help="burr diameter, > 0 (default %(default)s: the standard burr, and an "
                        "opening it does not fit is judged by the tool library's small burr "
                        "before it is refused; another value: that burr alone)")
    p.add_argument("--clearance-mm", type=_NONNEGATIVE_MM,
                   default=round(default_tolerances().min_clearance * 1e3, 6),
                   help="clearance the burr needs to the walls, >= 0 (default %(default)s)")
    p.add_argument("--min-window-width-mm", type=_POSITIVE_MM,
                   help="narrowest window, > 0; default the smallest need of the burrs "
                        "judged (head diameter + 2 x clearance)")


def register(subparsers) -> None:
    """Add ``drakedeburr hub {generate,random,import,list,info,scan}``."""
    hub = subparsers.add_parser(
        "hub", help="hub models: generate, random catalogue, import a mesh, list, info, scan")
    sub = hub.add_subparsers(dest="hub_command", metavar="HUB_COMMAND")
    sub.required = True

    p = sub.add_parser("generate", help="generate hub model assets (deterministic)")
    p.add_argument("names", nargs="*", help="bundled hub names (or folders under --out)")
    p.add_argument("--all", action="store_true", help="every bundled hub")
    p.add_argument("--spec", help="a hub.yaml to generate (into --out/<name>)")
    p.add_argument("--out", help="parent folder of the hub folders (default: bundled models/hubs)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(_run=_run_generate)

    p = sub.add_parser(
        "import", help="hub mesh file (STL, OBJ, PLY, OFF, DAE, GLB) -> hub model folder "
        "(edges, CoACD pieces)",
        description="Turn a closed hub mesh into a hub model folder OUT/<name>_<hash> that "
                    "`drakedeburr plan`/`verify` load like a bundled hub (docs/hub.md). "
                    "Re-importing the same file with the same options reuses the folder.")
    p.add_argument("mesh", help="mesh file: STL, OBJ, PLY, OFF, COLLADA (.dae) or binary glTF "
                   "(metres or millimetres)")
    p.add_argument("--out", required=True, help="parent folder of the hub folder")
    p.add_argument("--unit", choices=("m", "mm"), help="force the file's unit (default: by size)")
    p.add_argument("--axis", type=number(), nargs=3, metavar=("X", "Y", "Z"),
                   help="hub axis out of the visible face, in the file's frame (default: "
                        "estimated)")
    p.add_argument("--windows", type=number(1, integer=True),
                   help="expected number of windows, >= 1 (else any)")
    add_front_and_burr(p)
    p.add_argument("--window-reach-mm", type=_NONNEGATIVE_MM, default=1.0,
                   help="how far a collision piece may reach into a window opening [mm]")
    p.add_argument("--front-reach-mm", type=_POSITIVE_MM, default=1.0,
                   help="how far a collision piece may stand proud of the surface seen from "
                        "the front within 15 mm of a window, where the tool is low over the "
                        "face [mm] (before IMPORT_VERSION 4: everywhere, default 3)")
    p.add_argument("--front-reach-far-mm", type=_POSITIVE_MM, default=3.0,
                   help="the same further than 15 mm from every window, >= --front-reach-mm "
                        "[mm]")
    p.add_argument("--seed", type=_SEED, default=0, help="CoACD random seed, >= 0")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(_run=_run_import)

    p = sub.add_parser(
        "random", help="a seeded catalogue of realistic random hubs (docs/hub.md)",
        description="Write COUNT hub model folders DIR/r<SEED>_<index> (like `hub generate`: "
                    "hub.yaml, hub.obj, edges.npz, collision pieces, summary.json) and an STL "
                    "export of each in mm or m (export.json). The same seed gives the same "
                    "hubs on any machine.")
    p.add_argument("--seed", type=_SEED, required=True, help="catalogue seed (>= 0)")
    p.add_argument("--count", type=number(1, integer=True), default=1,
                   help="number of hubs, >= 1 (default 1)")
    p.add_argument("--start", type=_SEED, default=0, help="first hub index, >= 0 (default 0)")
    p.add_argument("-o", "--out", required=True, help="output folder")
    p.add_argument("--burr-mm", type=_POSITIVE_MM, default=_burr_mm(),
                   help="burr diameter the windows must admit (2.5 x), > 0 (default "
                        "%(default)s)")
    p.add_argument("--no-collision", action="store_true",
                   help="skip the collision pieces (mesh and edges only; fast)")
    p.add_argument("--no-export", action="store_true", help="no STL export")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(_run=_run_random)

    p = sub.add_parser("list", help="list hub models")
    p.add_argument("--dir", help="folder of hub folders (default: bundled models/hubs)")
    p.set_defaults(_run=_run_list)

    p = sub.add_parser("info", help="window table and model figures of one hub")
    p.add_argument("hub", help="bundled hub name or hub folder")
    p.add_argument("--json", action="store_true",
                   help="print summary.json plus 'input': the edge loops, hub axis and front "
                        "side in the input mesh's coordinates and unit")
    p.set_defaults(_run=_run_info)

    p = sub.add_parser("scan", help="write a simulated scan point cloud (PLY/PCD, metres, H)")
    p.add_argument("hub", help="bundled hub name or hub folder")
    p.add_argument("output", help="output point-cloud file (.ply, .pcd, .xyz)")
    p.add_argument("--sigma-mm", type=_NONNEGATIVE_MM, default=0.05,
                   help="noise sigma [mm], >= 0")
    p.add_argument("--spacing-mm", type=_POSITIVE_MM, default=1.0,
                   help="mean point spacing [mm], > 0")
    p.add_argument("--seed", type=_SEED, default=0, help="scan seed, >= 0")
    p.set_defaults(_run=_run_scan)
