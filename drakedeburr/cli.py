"""``drakedeburr`` command line: one sub-command per pipeline job.

Each stage package may hold a ``commands`` module (``drakedeburr/<stage>/commands.py``) that
defines ``register(subparsers)``: it adds its sub-parsers and sets ``_run`` on each with
``parser.set_defaults(_run=function)``, where ``function(args) -> int``. Command modules import
heavy libraries (pydrake, open3d) only inside the run functions so that ``drakedeburr --help``
stays fast.

Exit codes, the same for every command (:data:`EXIT_CODES`, shown by every ``--help``):
0 done / passed; 1 the job ran and its result failed, a report or the messages say why;
2 bad input or usage, one line on stderr naming the file or argument, what is wrong and what
is allowed; 130 interrupted (Ctrl-C or SIGTERM), earlier outputs untouched. Commands check
their arguments and output paths before any work and raise
:class:`~drakedeburr.errors.InputError`; :func:`main` turns that, a file that cannot be read or
written (``OSError``: missing, a folder, permission, no space) and a usage error into one line
and exit 2. Any other exception is a bug: one line ``internal error`` and exit 1; ``-vv``
prints the traceback of every error.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import importlib.util
import logging
import signal
import sys
import threading
from collections.abc import Callable, Sequence

from drakedeburr.errors import InputError, NoCuttableWindow

__all__ = ["main", "tqdm_progress", "STAGES", "EXIT_CODES"]

# stage packages in pipeline order; each may provide a ``commands`` module
STAGES: tuple[str, ...] = (
    "hub", "path", "frames", "orientation", "robots", "programs", "cell", "plan", "verify", "post",
    "laser", "viz",
)

log = logging.getLogger("drakedeburr")

EXIT_CODES = """exit codes:
  0    done / passed
  1    ran, but the result failed (verification failed, points unreachable, export refused,
       a hub mesh none of whose openings is a window the burr can cut):
       the report or the messages say why; also an internal error (a bug), reported in one
       line "internal error: ..." (-vv prints the traceback)
  2    bad input or usage: one line on stderr naming the file or argument, what is wrong and
       what is allowed; checked before any work, nothing is written
  130  interrupted (Ctrl-C, SIGTERM): outputs written before are untouched, nothing
       half-written is left (a killed run's leftovers are removed by the next run)
no traceback unless -vv."""


class _Parser(argparse.ArgumentParser):
    """Every (sub-)parser: the exit codes as epilog (kept as written), usage errors in one
    line, and its own name recorded for the error line (``args._prog``)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("epilog", EXIT_CODES)
        super().__init__(*args, **kwargs)
        self.set_defaults(_prog=self.prog)

    def format_help(self) -> str:
        epilog, self.epilog = self.epilog, None
        try:
            text = super().format_help()
        finally:
            self.epilog = epilog
        return text + ("\n" + epilog + "\n" if epilog else "")

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {_one_line(message)} (see {self.prog} --help)\n")


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
    parser = _Parser(
        prog="drakedeburr",
        description="Plan and verify robot deburring paths for wheel-hub windows.",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more log output (-vv: debug, and the traceback of an error)")
    parser.add_argument("-q", "--quiet", action="store_true", help="warnings and errors only")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for stage in STAGES:
        module_name = f"drakedeburr.{stage}.commands"
        if importlib.util.find_spec(module_name) is not None:
            importlib.import_module(module_name).register(sub)
    importlib.import_module("drakedeburr.demo").register(sub)
    _verbosity_everywhere(parser)
    return parser


def _verbosity_everywhere(parser: argparse.ArgumentParser) -> None:
    """-v/-vv/-q also after the command (``drakedeburr verify X -vv``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in set(action.choices.values()):
                sub.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                                 help="more log output (-vv: debug, and the traceback of an "
                                      "error)")
                sub.add_argument("-q", "--quiet", action="store_true",
                                 default=argparse.SUPPRESS, help="warnings and errors only")
                _verbosity_everywhere(sub)


#: the longest error line printed (a message quoting a hostile file could be megabytes)
MAX_LINE = 2000


def _one_line(text: str) -> str:
    line = " ".join(str(text).split("\n")).strip()
    return line if len(line) <= MAX_LINE else line[:MAX_LINE - 20] + " ... (cut short)"


_OS_WHAT = {
    errno.ENOENT: "no such file or folder", errno.EISDIR: "is a folder, a file is needed",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.EACCES: "permission denied", errno.EPERM: "not permitted",
    errno.ENOSPC: "no space left on the device (nothing was written)",
    errno.EDQUOT: "disk quota exceeded (nothing was written)",
    errno.EROFS: "read-only file system", errno.EEXIST: "exists already",
    errno.ENAMETOOLONG: "file name too long",
}


def _os_message(exc: OSError) -> str:
    """One line for an OSError: the file (the target of a rename), what is wrong."""
    if exc.filename is None and exc.errno is None:
        return str(exc)  # raised by our own code with a message naming the file
    where = exc.filename2 if exc.filename2 is not None else exc.filename
    what = _OS_WHAT.get(exc.errno, exc.strerror or str(exc))
    return f"{where}: {what}" if where is not None else f"{what} ({exc})"


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """SIGTERM raises KeyboardInterrupt (like Ctrl-C), so that outputs being written are
    cleaned up the same way (main thread only; the previous handler is restored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(signal.Signals(signum).name)

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _run(args: argparse.Namespace) -> int:
    """Run the command under the exit-code contract (module docstring)."""
    prog = getattr(args, "_prog", "drakedeburr")
    trace = args.verbose > 1

    def say(kind: str, text: str) -> None:
        if trace:
            import traceback

            traceback.print_exc(file=sys.stderr)
        print(f"{prog}: {kind}{_one_line(text)}", file=sys.stderr, flush=True)

    try:
        with _sigterm_as_interrupt():
            return int(args._run(args) or 0)
    except KeyboardInterrupt as exc:
        how = f" by {exc}" if str(exc).startswith("SIG") else ""
        say("", f"interrupted{how}: outputs written before are untouched, nothing "
                "half-written left")
        return 130
    except NoCuttableWindow as exc:  # a readable hub with nothing to cut: a result, not bad input
        say("", f"no window can be cut: {exc}")
        return 1
    except InputError as exc:
        say("error: ", str(exc))
        return 2
    except OSError as exc:
        say("error: ", _os_message(exc))
        return 2
    except Exception as exc:  # a bug: one line, the traceback with -vv
        say("internal error: ", f"{type(exc).__name__}: {exc} (a bug in drakedeburr; run "
                                "with -vv for the traceback)")
        return 1


def main(argv: Sequence[str] | None = None) -> int:
    """The ``drakedeburr`` command; returns the exit code (module docstring)."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage error (2, one line) or --help (0)
        return exc.code if isinstance(exc.code, int) else 2
    configure_logging(args.verbose, args.quiet)
    return _run(args)


def configure_logging(verbose: int, quiet: bool) -> None:
    """Log records to stderr: warnings with -q, debug with -vv, else info. The solvers' own
    messages (e.g. IPOPT stopping at its iteration cap on a retried IK point, which the
    planner handles) only with -vv."""
    level = logging.WARNING if quiet else (logging.DEBUG if verbose > 1 else logging.INFO)
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S", stream=sys.stderr)
    _quiet_drake(level if verbose > 1 else logging.ERROR)


class _AtLeast(logging.Filter):
    def __init__(self, level: int) -> None:
        super().__init__()
        self.level = level

    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= self.level


def _quiet_drake(level: int) -> None:
    """Drop Drake's own log records (the ``drake`` logger, fed by its C++ spdlog) below
    ``level``, whether pydrake is imported before or after this. A filter, not the logger's
    level: importing pydrake sets that logger's level to INFO (``pydrake.common`` ties it to
    spdlog), and the CLI imports pydrake only once a command runs (so ``--help`` stays fast)."""
    logger = logging.getLogger("drake")
    for f in [f for f in logger.filters if isinstance(f, _AtLeast)]:
        logger.removeFilter(f)
    logger.addFilter(_AtLeast(level))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
