"""``drakedeburr`` command line: one sub-command per pipeline job.

Each stage package may hold a ``commands`` module (``drakedeburr/<stage>/commands.py``) that
defines ``register(subparsers)``: it adds its sub-parsers and sets ``_run`` on each with
``parser.set_defaults(_run=function)``, where ``function(args) -> int``. Command modules import
heavy libraries (pydrake, open3d) only inside the run functions so that ``drakedeburr --help``
stays fast. Exit codes: 0 success, 1 the job ran
and its result failed (e.g. verification), 2 bad input.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import logging
import sys
from collections.abc import Callable, Sequence

from drakedeburr.errors import InputError

__all__ = ["main", "tqdm_progress", "STAGES"]

# stage packages in pipeline order; each may provide a ``commands`` module
STAGES: tuple[str, ...] = (
    "hub", "path", "frames", "orientation", "robots", "programs", "cell", "plan", "verify", "post",
    "laser", "viz",
)

log = logging.getLogger("drakedeburr")


def tqdm_progress(desc: str) -> Callable[[int, int, str], None]:
    """A progress callback ``(done, total, label)`` that drives a tqdm bar on stderr."""
    from tqdm import tqdm

    bar: dict[str, tqdm] = {}

    def update(done: int, total: int, label: str = "") -> None:
        if "bar" not in bar:
            bar["bar"] = tqdm(total=total, desc=desc, unit="step", file=sys.stderr,
                              disable=None, leave=True)
        b = bar["bar"]
        b.total = total
        b.n = done
        if label:
            b.set_postfix_str(label, refresh=False)
        b.refresh()
        if done >= total:
            b.close()

    return update


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="drakedeburr",
        description="Plan and verify robot deburring paths for wheel-hub windows.",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more log output (-vv for debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="warnings and errors only")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for stage in STAGES:
        module_name = f"drakedeburr.{stage}.commands"
        if importlib.util.find_spec(module_name) is not None:
            importlib.import_module(module_name).register(sub)
    importlib.import_module("drakedeburr.demo").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = _build_parser()
    args = parser.parse_args(argv)
    level = logging.WARNING if args.quiet else (logging.DEBUG if args.verbose > 1 else logging.INFO)
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S", stream=sys.stderr)
    # the solvers' own messages (e.g. IPOPT stopping at its iteration cap on a retried IK
    # point, which the planner handles) only with -vv
    logging.getLogger("drake").setLevel(level if args.verbose > 1 else logging.ERROR)
    try:
        return int(args._run(args) or 0)
    except (InputError, FileNotFoundError) as exc:
        log.error("%s", exc)
        print(f"drakedeburr {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
