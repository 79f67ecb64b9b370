"""``drakedeburr demo``: the main job on the bundled default hub.

Runs every pipeline stage that exists on the default hub and writes its outputs to a folder.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

__all__ = ["DEFAULT_HUB", "register", "run_demo"]

log = logging.getLogger(__name__)

DEFAULT_HUB = "h5_straight"


def run_demo(out_dir: Path, hub: str = DEFAULT_HUB, test_mode: bool = False) -> dict:
    """Run the chain on ``hub``; returns a summary mapping of what was written."""
    out_dir.mkdir(parents=True, exist_ok=True)
    summary: dict = {"hub": hub, "outputs": {}}
    log.info("demo: hub %s -> %s", hub, out_dir)
    return summary


def _run(args: argparse.Namespace) -> int:
    summary = run_demo(Path(args.out), hub=args.hub, test_mode=args.test_mode)
    for name, path in summary["outputs"].items():
        print(f"{name}: {path}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("demo", help="run the whole chain on the bundled default hub")
    p.add_argument("--hub", default=DEFAULT_HUB, help="bundled hub name (default %(default)s)")
    p.add_argument("--out", default="out/demo", help="output folder (default %(default)s)")
    p.add_argument("--test-mode", action="store_true", help="shrink the work (CI)")
    p.set_defaults(_run=_run)
