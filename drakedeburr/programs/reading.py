"""Read a robot program from its files: the format from the suffix, the file checked as UTF-8
text, then the strict reader of that format (:func:`drakedeburr.programs.rapid.read_rapid`,
``krl.read_krl``, ``ls.read_ls``), each returning a
:class:`~drakedeburr.programs.read_types.ReadProgram`."""

from __future__ import annotations

from pathlib import Path

from drakedeburr.programs.common import SUFFIXES, ProgramFormatError
from drakedeburr.programs.read_types import ReadProgram

__all__ = ["read_program", "format_of"]


def format_of(path: str | Path) -> str:
    """Program format from a file suffix (.mod/.modx/.prg, .src/.dat, .ls)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".dat":
        return "krl"
    for fmt, suffixes in SUFFIXES.items():
        if suffix in suffixes:
            return fmt
    raise ProgramFormatError(f"{path}: unknown program file type {suffix!r} (RAPID .mod/.modx/"
                             ".prg, KRL .src (+ .dat), FANUC .ls)")


def _check_utf8(path: Path) -> None:
    """Refuse a file that is not UTF-8 text, naming the line (a missing file is left to the
    reader)."""
    from drakedeburr._io import read_bounded

    try:  # a regular file of at most READ_LIMITS["program"] (never /dev/zero read to the end)
        data = read_bounded(path, "program file", "program")
    except FileNotFoundError:
        return
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ProgramFormatError(f"{path}:{line}: not UTF-8 text (byte "
                                 f"0x{data[exc.start]:02x})") from None


def read_program(path: str | Path, fmt: str | None = None, check_name: bool = True
                 ) -> ReadProgram:
    """Read a program file strictly (RAPID module, KRL .src with its .dat, FANUC .ls).

    Args:
        path: the file (for KRL the .src or the .dat; the other is found beside it).
        fmt: "rapid", "krl" or "ls"; default from the suffix.
        check_name: KRL/LS: the program's name must be the file's (as the controllers need).

    Raises:
        FileNotFoundError: missing file. ProgramFormatError: a line the reader does not accept.
    """
    path = Path(path)
    fmt = fmt or format_of(path)
    for f in (path.with_suffix(".src"), path.with_suffix(".dat")) if fmt == "krl" else (path,):
        _check_utf8(f)
    if fmt == "rapid":
        from drakedeburr.programs.rapid import read_rapid

        return read_rapid(path)
    if fmt == "krl":
        from drakedeburr.programs.krl import read_krl

        return read_krl(path, check_name=check_name)
    if fmt == "ls":
        from drakedeburr.programs.ls import read_ls

        return read_ls(path, check_name=check_name)
    raise ProgramFormatError(f"{path}: unknown program format {fmt!r}")
