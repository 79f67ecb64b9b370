"""Checks of command-line arguments and output paths, made before any work (the CLI layer).

Every check refuses with one line naming the argument or file, what is wrong and what is
allowed: numbers through argparse types (:func:`number`; argparse reports them as usage
errors, exit 2), paths and window numbers through :class:`~drakedeburr.errors.InputError`
(exit 2, :mod:`drakedeburr.cli`).
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path

from drakedeburr.errors import InputError

__all__ = ["number", "six_numbers", "input_file", "output_file", "output_folder", "free_space",
           "parse_windows", "check_windows", "hub_windows", "MB", "scheduler_address",
           "separate_outputs"]

MB = 1 << 20


def _range_text(lo, hi, lo_open, hi_open, unit) -> str:
    u = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        return (f"{lo:g} {'<' if lo_open else '<='} value {'<' if hi_open else '<='} "
                f"{hi:g}{u}")
    if lo is not None:
        return f"{'>' if lo_open else '>='} {lo:g}{u}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {hi:g}{u}"
    return f"a finite number{u}"


def number(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
           hi_open: bool = False, unit: str = "", integer: bool = False) -> Callable:
    """An argparse ``type``: a finite number (an integer with ``integer``) in the range; the
    refusal says which range is allowed."""
    allowed = _range_text(lo, hi, lo_open, hi_open, unit)

    def convert(text: str):
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if integer else 'a number'} {allowed}, "
                f"got {text!r}") from None
        bad = not math.isfinite(value)
        bad = bad or (lo is not None and (value <= lo if lo_open else value < lo))
        bad = bad or (hi is not None and (value >= hi if hi_open else value > hi))
        if bad:
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {text!r}")
        return value

    convert.__name__ = "integer" if integer else "number"
    return convert


def input_file(path: str | Path, what: str, suffixes: Iterable[str] | None = None) -> Path:
    """An existing, readable file (of one of ``suffixes``), else InputError naming it."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: {what} not found (no such file)")
    if p.is_dir():
        raise InputError(f"{p}: {what} is a folder, not a file")
    if suffixes is not None and p.suffix.lower() not in tuple(suffixes):
        raise InputError(f"{p}: {what} must be one of {', '.join(suffixes)} "
                         f"(got {p.suffix or 'no suffix'!r})")
    if not os.access(p, os.R_OK):
        raise InputError(f"{p}: {what} is not readable (permission denied)")
    return p


def _existing_parent(p: Path) -> Path:
    parent = p.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    return parent


def _writable_parent(p: Path, option: str) -> None:
    parent = _existing_parent(p)
    if not parent.is_dir():
        raise InputError(f"{p}: {option}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{p}: {option}: the folder {parent} is not writable")


def output_file(path: str | Path | None, option: str) -> Path | None:
    """A file the command will write: not a folder, in a folder that exists or can be made and
    is writable, itself writable if it exists. None passes (option not given)."""
    if path is None:
        return None
    p = Path(path)
    if str(path).endswith(os.sep) or p.is_dir():
        raise InputError(f"{p}: {option} is a folder; give a file name")
    if p.exists() and not os.access(p, os.W_OK):
        raise InputError(f"{p}: {option}: the file is not writable")
    _writable_parent(p, option)
    return p


def output_folder(path: str | Path | None, option: str, is_ours=None) -> Path | None:
    """A folder the command will write (whole, :func:`drakedeburr._io.atomic_folder`, or into):
    not a file; with ``is_ours`` an existing non-empty folder it does not recognise is
    refused; its parent writable. None passes."""
    if path is None:
        return None
    from drakedeburr._io import check_folder_target

    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(f"{p}: {option} exists and is a file; an output folder is needed")
    if is_ours is not None:
        check_folder_target(p, is_ours)
    if p.is_dir():
        if not os.access(p, os.W_OK | os.X_OK):
            raise InputError(f"{p}: {option}: the folder is not writable")
    else:
        _writable_parent(p, option)
    return p


def free_space(path: str | Path, need: int, option: str) -> None:
    """Refuse when the file system that will hold ``path`` has less than ``need`` bytes free
    (``need``: what the output is known to take at least)."""
    where = _existing_parent(Path(path) / "x")
    try:
        free = shutil.disk_usage(where).free
    except OSError:
        return
    if free < need:
        from drakedeburr._io import size_text

        raise InputError(f"{path}: {option}: {size_text(free)} free on {where}, the output "
                         f"needs about {size_text(need)}")


def six_numbers(text: str) -> list[float]:
    """An argparse type: ``x,y,z,rx,ry,rz`` (commas or semicolons) as numbers."""
    parts = [p for p in text.replace(";", ",").split(",") if p.strip()]
    try:
        return [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y,z,rx,ry,rz numbers, got {text!r}") from None


def parse_windows(text: str | None, option: str = "--windows") -> tuple[int, ...] | None:
    """Window numbers from ``"0,2,3"``: integers >= 0, no repeats (None: all windows)."""
    if text is None:
        return None
    parts = [x.strip() for x in text.split(",")]
    if not text.strip() or any(not p for p in parts):
        raise InputError(f"{option} {text!r}: expected comma-separated window numbers "
                         "(e.g. 0,2,3)")
    try:
        windows = tuple(int(p) for p in parts)
    except ValueError:
        raise InputError(f"{option} {text!r}: expected comma-separated window numbers "
                         "(integers >= 0, e.g. 0,2,3)") from None
    bad = [w for w in windows if w < 0]
    if bad:
        raise InputError(f"{option} {text!r}: window numbers are >= 0, got {bad[0]}")
    if len(set(windows)) != len(windows):
        raise InputError(f"{option} {text!r}: a window is named twice")
    return windows


def check_windows(windows: Iterable[int] | None, available: Iterable[int], hub: str,
                  option: str = "--windows") -> None:
    """Refuse window numbers the hub does not have, naming the ones it has."""
    if windows is None:
        return
    have = sorted(int(w) for w in available)
    unknown = [w for w in windows if w not in have]
    if unknown:
        raise InputError(f"{option}: hub {hub} has no window {', '.join(map(str, unknown))} "
                         f"(its windows: {', '.join(map(str, have)) or 'none'})")


def hub_windows(hub: str | Path) -> list[int]:
    """The window numbers of a hub model (bundled name or folder), from its summary."""
    import json

    from drakedeburr.resources import resolve_hub_dir

    d = resolve_hub_dir(hub)
    try:
        summary = json.loads((d / "summary.json").read_text())
        return [int(w["index"]) for w in summary["windows"]]
    except (OSError, ValueError, KeyError, TypeError):
        from drakedeburr.hub.model import load_hub

        return [w.index for w in load_hub(d).windows]


#: Dask's address schemes (distributed.comm: tcp, tls, ws, wss, ucx; inproc only in-process)
_SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


def scheduler_address(text: str | None, option: str = "--scheduler",
                      timeout: float = 3.0) -> str | None:
    """A Dask scheduler address ``SCHEME://HOST:PORT`` that answers: the form is checked, then
    one TCP connection is tried (``timeout`` seconds), so a wrong address fails at once
    naming the option instead of after Dask's 30 s connect timeout. None passes."""
    if text is None:
        return None
    import socket
    from urllib.parse import urlsplit

    try:
        u = urlsplit(text)
        host, port = u.hostname, u.port
    except ValueError:
        host = port = None
        u = None
    if u is None or u.scheme not in _SCHEDULER_SCHEMES or not host or port is None:
        raise InputError(f"{option} {text!r}: expected a Dask scheduler address "
                         f"SCHEME://HOST:PORT with SCHEME one of {', '.join(_SCHEDULER_SCHEMES)}"
                         " (e.g. tcp://127.0.0.1:8786)")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        what = exc.strerror or type(exc).__name__
        raise InputError(f"{option} {text}: no scheduler answers at {host}:{port} ({what}; "
                         f"tried for {timeout:g} s)") from None
    return text


def _real(p: str | Path) -> Path:
    return Path(os.path.realpath(os.path.abspath(os.fspath(p))))


def _within(inner: Path, outer: Path) -> bool:
    return inner == outer or outer in inner.parents


def separate_outputs(outputs: dict, *, inputs: dict | None = None,
                     input_folders: dict | None = None,
                     output_folders: dict | None = None) -> None:
    """Refuse (InputError, before any work) outputs that would replace an input or each
    other: an output file that is an input file, lies inside an input folder (e.g. the plan
    folder being verified) or inside an output folder (replaced whole), or is another output
    of the same command; an output folder that holds an input or the working directory (it is
    replaced by a rename). Each dict maps the option (or what the input is) to its path; None
    values (not given) are skipped. Paths are compared after resolving links."""
    def given(d):
        return [(k, Path(v), _real(v)) for k, v in (d or {}).items() if v is not None]

    outs, folders = given(outputs), given(output_folders)
    ins, in_folders = given(inputs), given(input_folders)
    seen: dict[Path, str] = {}
    for option, shown, real in outs:
        if real in seen:
            raise InputError(f"{shown}: {option} and {seen[real]} name the same file; give "
                             "each output its own file")
        seen[real] = option
        for what, ishown, ireal in ins:
            if real == ireal:
                raise InputError(f"{shown}: {option} is {what} {ishown}, an input of this "
                                 "command; outputs never replace inputs")
        for what, fshown, freal in in_folders:
            if _within(real, freal):
                raise InputError(f"{shown}: {option} is inside {what} {fshown}, an input of "
                                 "this command; write it elsewhere")
        for what, fshown, freal in folders:
            if _within(real, freal):
                raise InputError(f"{shown}: {option} is inside the output folder {fshown} "
                                 f"({what}), which is written whole; write it elsewhere")
    cwd = _real(".")
    for option, shown, real in folders:
        if _within(cwd, real):
            raise InputError(f"{shown}: {option} is the working folder or holds it; an output "
                             "folder is replaced whole, so choose a new folder (e.g. -o plan2)")
        for what, ishown, ireal in ins + in_folders:
            if _within(ireal, real):
                raise InputError(f"{shown}: {option} holds {what} {ishown}, an input of this "
                                 "command; outputs never replace inputs")
        for other, oshown, oreal in folders:
            if other != option and _within(oreal, real):
                raise InputError(f"{shown}: {option} holds {other} {oshown}; give each output "
                                 "its own folder")
