"""``drakedeburr show``: publish a cell or a hub to Meshcat, optionally as a static HTML file."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from drakedeburr.argcheck import number

log = logging.getLogger(__name__)


def _window_loops(hub_source):
    """The hub's ground-truth window edges, or [] when the hub has none (e.g. a plain SDF)."""
    try:
        from drakedeburr.hub import load_hub
    except ImportError:
        log.warning("drakedeburr.hub.load_hub is not available: no window edges shown")
        return []
    try:
        return list(load_hub(hub_source).windows)
    except FileNotFoundError as exc:
        log.warning("no window edges for %s: %s", hub_source, exc)
        return []


def _host(text: str) -> str:
    """An argparse ``type``: a host name or address to bind (``*``: every interface)."""
    import re

    if text == "*" or re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9.:-]{0,252}", text or ""):
        return text
    raise argparse.ArgumentTypeError(f"expected a host name or address (e.g. 127.0.0.1, "
                                     f"localhost, '*' for every interface), got {text!r}")


def _is_scenario(target: str) -> bool:
    from drakedeburr.resources import scenario_names

    path = Path(target)
    return (path.suffix in (".yaml", ".yml") and path.is_file()) or target in scenario_names()


def _run_show(args: argparse.Namespace) -> int:
    import time

    import numpy as np

    from drakedeburr.argcheck import output_file
    from drakedeburr.errors import InputError
    from drakedeburr.units import rad_from_deg
    from drakedeburr.viz import scene

    output_file(args.html, "--html")
    from drakedeburr.cell import resolve_hub_sdf

    if not _is_scenario(args.target):
        resolve_hub_sdf(args.target)
    elif args.hub is not None:
        resolve_hub_sdf(args.hub)
    meshcat = scene.get_meshcat(host=args.host)
    role = "proximity" if args.collision else "illustration"
    if _is_scenario(args.target):
        from drakedeburr.cell import load_cell

        cell = load_cell(args.target, hub=args.hub, robot=args.robot)
        q = None
        if args.q is not None:
            if len(args.q) != cell.num_joints:
                raise InputError(
                    f"--q needs {cell.num_joints} joint values [deg], got {len(args.q)}")
            q = rad_from_deg(np.asarray(args.q, float))
        scene.publish_cell(meshcat, cell, q, role=role)
        q_used = cell.q_home if q is None else q
        X_WH = cell.X_WH(q_used)
        scene.publish_frame(meshcat, f"{scene.ROOT}/frames/T", cell.X_WT(q_used), length=0.08)
        scene.publish_frame(meshcat, f"{scene.ROOT}/frames/H", X_WH, length=0.15)
        loops = _window_loops(cell.hub_sdf.parent if args.hub is None else args.hub)
        label = (f"cell {cell.scenario.stem} ({cell.mode}-in-hand) "
                 f"with hub {cell.hub_sdf.parent.name}")
    else:
        if args.q is not None:
            raise InputError("--q applies to a scenario, not to a hub")
        from pydrake.math import RigidTransform

        from drakedeburr.cell import resolve_hub_sdf

        hub_sdf = resolve_hub_sdf(args.target)
        scene.publish_model_file(meshcat, hub_sdf, path=f"{scene.ROOT}/hub", role=role)
        X_WH = RigidTransform()
        loops = _window_loops(args.target)
        label = f"hub {hub_sdf.parent.name}"
    scene.publish_edge_loops(meshcat, loops, X_WH)
    log.info("showing %s with %d window edge loops at %s", label, len(loops), meshcat.web_url())
    if args.html:
        out = scene.write_static_html(meshcat, args.html)
        log.info("wrote %s", out)
        print(out)
    if args.html is None or args.wait:
        print(f"{label}: open {meshcat.web_url()} (Ctrl-C to quit)")
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "show",
        help="show a cell (scenario) or a hub with its window edges in Meshcat",
        description="Publish a scenario's cell (robot, tool, fixture, hub) or a hub on its own, "
                    "with the hub's window edge loops, to Drake's Meshcat; optionally write a "
                    "self-contained static HTML file.",
    )
    p.add_argument("target", help="scenario name or YAML file (tool_in_hand, workpiece_in_hand), "
                                  "or a hub name / folder / hub.sdf")
    p.add_argument("--hub", default=None,
                   help="hub for a scenario: bundled name, folder or hub.sdf (default: the "
                        "default bundled hub)")
    p.add_argument("--robot", default=None, metavar="NAME|FILE",
                   help="registered arm (drakedeburr robots) or an arm file (*.yaml) for a "
                        "bundled cell")
    p.add_argument("--html", type=Path, default=None, help="write a static HTML snapshot here")
    p.add_argument("--q", type=number(), nargs="+", default=None, metavar="DEG",
                   help="robot joints J1..J6 in degrees (default: the scenario's home)")
    p.add_argument("--collision", action="store_true", help="draw collision geometry instead")
    p.add_argument("--host", type=_host, default=None, metavar="ADDRESS",
                   help="interface Meshcat listens on (default 127.0.0.1: this machine only; "
                        "'*' or 0.0.0.0 exposes the viewer to the network, where anyone who "
                        "can reach the port sees the cell)")
    p.add_argument("--wait", action="store_true",
                   help="keep serving Meshcat after writing --html (default without --html)")
    p.set_defaults(_run=_run_show)
