"""Atomic output: a half-written file or folder never replaces a good one."""

from __future__ import annotations

import contextlib
import glob
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["atomic_write_text", "atomic_write_bytes", "atomic_write_json", "atomic_folder",
           "atomic_write_files", "clean_leftovers", "check_folder_target", "temp_folder_beside",
           "umask"]

# Temporary names carry the writer's process id (``.NAME.tmp-PID-XXXX`` folders,
# ``.NAME.PID-XXXX.tmp`` files) so that the next run removes what a killed one left
# (:func:`clean_leftovers`) without touching the temporary files of a run still going.


def umask() -> int:
    """The process's umask (from /proc where it can be read without changing it: setting it
    to read it back races with other threads creating files)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True


_RANDOM = r"[a-z0-9_]{8}"  # tempfile's random part


def _stale(name: str, pattern: str) -> bool:
    """Is ``name`` a temporary left by a run that has ended? ``pattern`` (a regular
    expression) matches it with the writer's process id as group ``pid``, or without one
    (names written by earlier versions, always stale)."""
    m = re.fullmatch(pattern, name)
    if m is None:
        return False
    pid = m.groupdict().get("pid")
    return pid is None or not _pid_alive(int(pid))


def _file_pattern(name: str) -> str:
    return rf"\.{re.escape(name)}\.(?:(?P<pid>\d+)-{_RANDOM}|{_RANDOM})\.tmp"


def _mkstemp_beside(path: Path) -> tuple[int, str]:
    """A temporary file beside ``path`` (``.NAME.PID-XXXXXXXX.tmp``), after removing the ones
    killed runs left there."""
    pattern = _file_pattern(path.name)
    for old in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        if _stale(old.name, pattern) and old.is_file():
            with contextlib.suppress(OSError):
                old.unlink()
    return tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}-", suffix=".tmp",
                            dir=path.parent)


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _mkstemp_beside(path)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp creates 0600; give the file the permissions a normal open() would
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        _name_the_output(exc, path, Path(tmp))
        raise
    return path


def _name_the_output(exc: BaseException, path: Path, tmp: Path) -> None:
    """Let an OSError name the output being written, not its temporary (or nothing, as
    ``os.fsync`` raises it): ``path/inner`` for a file inside a temporary folder."""
    if not isinstance(exc, OSError):
        return
    name = exc.filename
    if name is None:
        exc.filename = str(path)
    elif str(name).startswith(str(tmp)):
        exc.filename = str(path) + str(name)[len(str(tmp)):]
    if exc.filename2 is not None and str(exc.filename2) == str(path):
        exc.filename2 = None  # the rename's target is the output itself


def atomic_write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    return atomic_write_bytes(path, text.encode(encoding))


def atomic_write_json(path: str | Path, obj: Any, **kwargs: Any) -> Path:
    kwargs.setdefault("indent", 2)
    kwargs.setdefault("sort_keys", True)
    return atomic_write_text(path, json.dumps(obj, **kwargs) + "\n")


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2(RENAME_EXCHANGE)``); False where the
    system or the file system cannot."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0


def clean_leftovers(path: str | Path) -> None:
    """Remove what a killed :func:`atomic_folder` left beside ``path`` (its temporary folders),
    and put back the previous version if the kill came between the two renames of the
    fallback (no ``path``, an ``.old`` copy beside it)."""
    path = Path(path)
    parent = path.parent
    if not parent.is_dir():
        return
    name, esc = re.escape(path.name), glob.escape(path.name)
    old_pattern = rf"\.{name}\.old-(?P<pid>\d+)(?:-\d+)?"
    tmp_pattern = rf"\.{name}\.tmp-(?:(?P<pid>\d+)-{_RANDOM}|{_RANDOM})"
    olds = sorted((p for p in parent.glob(f".{esc}.old-*") if _stale(p.name, old_pattern)),
                  key=lambda p: p.stat().st_mtime)
    if olds and not path.exists():
        os.rename(olds.pop(), path)
    tmps = [p for p in parent.glob(f".{esc}.tmp-*") if _stale(p.name, tmp_pattern)]
    for p in olds + tmps:
        shutil.rmtree(p, ignore_errors=True)


def check_folder_target(path: str | Path, is_ours=lambda p: True) -> Path:
    """Refuse (InputError) an output folder ``path`` that :func:`atomic_folder` could not
    replace: a file there, a folder that ``is_ours`` does not recognise, or a parent that is
    not a writable folder. Call it before the work whose result goes there."""
    from drakedeburr.errors import InputError

    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{path}: exists and is not a folder (an output folder is needed)")
    if path.is_dir() and any(path.iterdir()) and not is_ours(path):
        raise InputError(f"{path}: an existing folder that drakedeburr did not write; "
                         "choose another output folder")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{path}: {parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{path}: the folder {parent} is not writable")
    return path


def temp_folder_beside(path: str | Path) -> Path:
    """A new empty temporary folder beside ``path`` (``.NAME.tmp-PID-XXXX``, with the
    permissions the user's umask gives a new folder), after removing the ones killed runs
    left (:func:`clean_leftovers`). Rename it to ``path`` when complete."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_leftovers(path)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.tmp-{os.getpid()}-", dir=path.parent))
    os.chmod(tmp, 0o777 & ~umask())
    return tmp


@contextlib.contextmanager
def atomic_folder(path: str | Path, is_ours=lambda p: True):
    """Write a folder as one transaction: yields an empty temporary folder beside ``path``;
    when the block ends without an error it replaces ``path`` in one rename (the previous
    version stays whole until then, and is removed after); on an error or a kill nothing
    changes but a temporary folder, which the next call removes (:func:`clean_leftovers`).

    ``is_ours(path)`` guards an existing ``path``: a folder it does not recognise is not
    replaced (InputError), so a user's own folder is never swapped away.
    """
    path = Path(path)
    parent = path.parent
    check_folder_target(path, is_ours)
    tmp = temp_folder_beside(path)
    try:
        yield tmp
        if not path.exists():
            os.rename(tmp, path)
        elif _exchange(tmp, path):
            shutil.rmtree(tmp, ignore_errors=True)  # the previous version
        else:
            old = parent / f".{path.name}.old-{os.getpid()}-0"
            os.rename(path, old)
            os.rename(tmp, path)
            shutil.rmtree(old, ignore_errors=True)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        _name_the_output(exc, path, tmp)
        raise


def atomic_write_files(texts: dict) -> list[Path]:
    """Write several files together: every one is written to a temporary file first and only
    then are they renamed into place, so an error leaves none of them changed (``texts``: path
    -> text). Returns the paths in the given order."""
    temps = []
    mask = umask()
    try:
        for path, text in texts.items():
            path = Path(path)
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = _mkstemp_beside(path)
            temps.append((tmp, path))
            with os.fdopen(fd, "wb") as f:
                f.write(text.encode("utf-8"))
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, 0o666 & ~mask)
        for tmp, path in temps:
            os.replace(tmp, path)
    except BaseException as exc:
        for tmp, _ in temps:
            if os.path.exists(tmp):
                os.unlink(tmp)
        if temps:
            _name_the_output(exc, temps[-1][1], Path(temps[-1][0]))
        raise
    return [path for _, path in temps]
