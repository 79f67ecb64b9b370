"""Atomic output: a half-written file or folder never replaces a good one."""

from __future__ import annotations

import contextlib
import glob
import json
import os
import re
import shutil
import stat
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["atomic_write_text", "atomic_write_bytes", "atomic_write_json", "atomic_folder",
           "atomic_write_files", "clean_leftovers", "check_folder_target", "temp_folder_beside",
           "umask", "READ_LIMITS", "YAML_LIMITS", "check_regular_file", "read_bounded",
           "read_text_bounded", "load_yaml", "PATH_NAME", "check_path_name",
           "size_text", "FILE_DIGITS", "round_numbers", "check_npz_members"]

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


def _remove(p: Path) -> None:
    """Remove a temporary folder, or the link that took its place (an output that was a
    symbolic link is replaced, not followed: the exchange leaves the link under the
    temporary name, and ``shutil.rmtree`` refuses links)."""
    if p.is_symlink() or p.is_file():
        with contextlib.suppress(OSError):
            p.unlink()
    else:
        shutil.rmtree(p, ignore_errors=True)


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
        _remove(p)


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
            _remove(tmp)  # the previous version (or the link that was there)
        else:
            old = parent / f".{path.name}.old-{os.getpid()}-0"
            os.rename(path, old)
            os.rename(tmp, path)
            _remove(old)
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


# --------------------------------------------------------------------------- bounded reading

#: the largest file each reader takes (bytes); a larger one is refused before it is read, the
#: limit named in the message. Far above any real input (a bundled hub's recipe is < 2 kB, a
#: 2-million-triangle binary STL 100 MB, a whole-hub program < 2 MB), far below what would
#: exhaust a workstation's memory.
READ_LIMITS: dict[str, int] = {
    "recipe": 1 << 20,  # process.yaml, hub specs, scenario files: YAML documents
    "program": 64 << 20,  # RAPID / KRL / FANUC LS robot programs
    "cl": 1 << 30,  # APT CL files (read line by line)
    "mesh": 1 << 30,  # hub meshes (STL, OBJ, PLY, ...)
    "json": 256 << 20,  # plan.json, report.json, summary.json
}


def size_text(n: int) -> str:
    """A byte count for a message: ``1.5 MiB``, ``980 KiB``, ``512 bytes`` (never "0.0 MB")."""
    for unit, size in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= size:
            return f"{n / size:.4g} {unit}"
    return f"{int(n)} bytes"


def check_regular_file(path: str | Path, what: str, limit: str | int) -> int:
    """Refuse (InputError, naming ``path``, ``what`` it is and the limit) anything but a
    regular file of at most ``limit`` bytes (a :data:`READ_LIMITS` name or a number): a
    device (``/dev/zero``), a pipe, a socket or a folder is never read. Returns its size.
    FileNotFoundError for a missing file."""
    from drakedeburr.errors import InputError

    path = Path(path)
    name, limit_bytes = (limit, READ_LIMITS[limit]) if isinstance(limit, str) else (
        "limit", int(limit))
    st = os.stat(path)  # follows a link: its target is what would be read
    if stat.S_ISDIR(st.st_mode):
        raise InputError(f"{path}: {what} is a folder, a file is needed")
    if not stat.S_ISREG(st.st_mode):
        kind = ("a character device" if stat.S_ISCHR(st.st_mode) else "a block device"
                if stat.S_ISBLK(st.st_mode) else "a pipe" if stat.S_ISFIFO(st.st_mode)
                else "a socket" if stat.S_ISSOCK(st.st_mode) else "not a regular file")
        raise InputError(f"{path}: {what} is {kind}; only regular files are read")
    if st.st_size > limit_bytes:
        raise InputError(f"{path}: {what} is {size_text(st.st_size)}, more than the "
                         f"{name} read limit of {size_text(limit_bytes)}")
    return int(st.st_size)


def read_bounded(path: str | Path, what: str, limit: str | int) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (:func:`check_regular_file`);
    a file that grows while read is cut at the limit and refused, so memory stays bounded."""
    from drakedeburr.errors import InputError

    path = Path(path)
    check_regular_file(path, what, limit)
    limit_bytes = READ_LIMITS[limit] if isinstance(limit, str) else int(limit)
    with open(path, "rb") as f:
        data = f.read(limit_bytes + 1)
    if len(data) > limit_bytes:
        name = limit if isinstance(limit, str) else "limit"
        raise InputError(f"{path}: {what} is more than the {name} read limit of "
                         f"{size_text(limit_bytes)}")
    return data


def read_text_bounded(path: str | Path, what: str, limit: str | int) -> str:
    """:func:`read_bounded` decoded as UTF-8 (a BOM allowed); other encodings (Latin-1,
    UTF-16) are refused naming the file, the line and the byte."""
    from drakedeburr.errors import InputError

    data = read_bounded(path, what, limit)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        hint = " (it looks like UTF-16)" if data[:2] in (b"\xff\xfe", b"\xfe\xff") else ""
        raise InputError(f"{path}:{line}: {what} is not UTF-8 text (byte "
                         f"0x{data[exc.start]:02x}){hint}; save it as UTF-8") from None


#: bounds on a YAML document beyond its size (:data:`READ_LIMITS`): how many nodes its
#: aliases may expand to (a "billion laughs" document of nested aliases expands
#: exponentially), and how deep its collections may nest
YAML_LIMITS = {"alias_expansion": 10_000, "depth": 64}

_FLOAT_12 = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9][0-9_]*(?:\.[0-9_]*)?)[eE][-+]?[0-9]+$")


def _local_tag(loader, suffix, node):
    """A local tag (``!Rpy``, Drake's model directives): its node as plain data."""
    import yaml

    if isinstance(node, yaml.MappingNode):
        return loader.construct_mapping(node, deep=True)
    if isinstance(node, yaml.SequenceNode):
        return loader.construct_sequence(node, deep=True)
    return loader.construct_scalar(node)


def _yaml_loader(where: str, local_tags: bool = False):
    """A yaml.SafeLoader subclass for one document: duplicate keys refused, alias expansion
    and nesting bounded (:data:`YAML_LIMITS`), and ``1.0e6`` / ``1e6`` read as numbers (YAML
    1.2; PyYAML's YAML 1.1 resolver wants ``1.0e+6``)."""
    import yaml

    from drakedeburr.errors import InputError

    class Loader(yaml.SafeLoader):
        yaml_implicit_resolvers = {k: list(v) for k, v in
                                   yaml.SafeLoader.yaml_implicit_resolvers.items()}

        def __init__(self, stream):
            super().__init__(stream)
            self._expanded = 0
            self._depth = 0
            self._sizes: dict[int, int] = {}

        def _size(self, node) -> int:
            key = id(node)
            if key not in self._sizes:
                self._sizes[key] = 1  # a recursive alias counts once
                if isinstance(node, yaml.MappingNode):
                    n = 1 + sum(self._size(k) + self._size(v) for k, v in node.value)
                elif isinstance(node, yaml.SequenceNode):
                    n = 1 + sum(self._size(v) for v in node.value)
                else:
                    n = 1
                self._sizes[key] = n
            return self._sizes[key]

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                anchor = self.peek_event().anchor
                if anchor in self.anchors:
                    self._expanded += self._size(self.anchors[anchor])
                    limit = YAML_LIMITS["alias_expansion"]
                    if self._expanded > limit:
                        mark = self.peek_event().start_mark
                        raise InputError(
                            f"{where}:{mark.line + 1}: its aliases expand to more than the "
                            f"YAML alias expansion limit of {limit} nodes")
            self._depth += 1
            try:
                if self._depth > YAML_LIMITS["depth"]:
                    mark = self.peek_event().start_mark
                    raise InputError(f"{where}:{mark.line + 1}: nested deeper than the YAML "
                                     f"depth limit of {YAML_LIMITS['depth']}")
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1

        def construct_mapping(self, node, deep=False):
            seen: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                try:
                    key = self.construct_object(key_node, deep=True)
                    hash(key)
                except (TypeError, yaml.YAMLError):
                    continue  # the base class refuses an unhashable key
                if key in seen:
                    raise InputError(
                        f"{where}:{key_node.start_mark.line + 1}: key {str(key)[:60]!r} is "
                        f"given twice (first on line {seen[key]}); each key once")
                seen[key] = key_node.start_mark.line + 1
            return super().construct_mapping(node, deep=deep)

    Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12,
                                 list("-+0123456789."))
    if local_tags:
        Loader.yaml_multi_constructors = dict(yaml.SafeLoader.yaml_multi_constructors)
        Loader.add_multi_constructor("!", _local_tag)
    return Loader


def load_yaml(path: str | Path, what: str, limit: str | int = "recipe", *,
              local_tags: bool = False):
    """One YAML document read safely (no Python tags) and bounded: at most ``limit`` bytes of
    a regular file (:func:`read_bounded`), UTF-8, no duplicate keys, bounded alias expansion
    and nesting (:data:`YAML_LIMITS`). An empty document is None. Every refusal is an
    InputError of one line naming the file (and the line) and the limit. ``local_tags``:
    accept local tags (``!Rpy`` of Drake's model directives) as plain data; ``!!python``
    tags are refused either way."""
    import yaml

    from drakedeburr.errors import InputError

    path = Path(path)
    text = read_text_bounded(path, what, limit)
    try:
        loader = _yaml_loader(str(path), local_tags)
        return yaml.load(text, Loader=loader)  # noqa: S506 - a SafeLoader
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f":{mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise InputError(f"{path}{at}: {what} is not valid YAML ({str(problem)[:160]})") \
            from None
    except RecursionError:
        raise InputError(f"{path}: {what} is nested too deeply to read") from None


# --------------------------------------------------------------------------- names of paths

#: a name that becomes a file or folder name (a hub, a spec, a scenario, an output): letters,
#: digits, ``_``, ``-`` and ``.``, starting with a letter or digit, at most 100 characters, no
#: ``..``: no separator, no parent folder, no hidden file, no control or shell character
PATH_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")


def check_path_name(name, what: str) -> str:
    """``name`` if it is safe as one path component (:data:`PATH_NAME`), else InputError
    naming ``what`` and the name (shown escaped, so a newline or a control character is
    visible on the one line)."""
    from drakedeburr.errors import InputError

    if not isinstance(name, str) or not PATH_NAME.fullmatch(name) or ".." in name:
        shown = repr(name)[:80] if isinstance(name, str) else type(name).__name__
        raise InputError(f"{what} {shown} cannot be a file name: use letters, digits, _ - "
                         "and . (starting with a letter or digit, at most 100 characters, "
                         "no '..', no '/' or spaces)")
    return name


# --------------------------------------------------------------------------- generated files

#: significant digits a generated model file keeps of a number: far below a double's 17,
#: so the last-bit differences of another machine's libm or BLAS (seen: a committed arm SDF
#: reading ...69689661813 where another machine generated ...69689661815) do not reach the
#: file; far above any model's precision (1e-12 of a metre is a picometre)
FILE_DIGITS = 12

_FLOAT_LITERAL = re.compile(r"(?<![\w.])-?\d+\.\d+(?:[eE][-+]?\d+)?(?![\w.])")


def round_numbers(text: str, digits: int = FILE_DIGITS) -> str:
    """``text`` with every decimal literal of more than ``digits`` significant digits rounded
    to ``digits`` (and written as Python writes that float: ``3.0``, ``0.048``); shorter
    literals stay as written. For generated files
    that must be identical on every machine (models, meshes)."""
    def short(m: re.Match) -> str:
        lit = m.group(0)
        mantissa = re.split(r"[eE]", lit)[0].lstrip("-").replace(".", "").lstrip("0")
        if len(mantissa) <= digits:
            return lit
        return repr(float(f"{float(lit):.{digits}g}"))  # 3.0000000000000013 -> 3.0

    return _FLOAT_LITERAL.sub(short, text)


# --------------------------------------------------------------------------- .npz archives

def check_npz_members(path: str | Path, names: re.Pattern, limit: int, what: str,
                      known: str, kinds: str = "biuf") -> None:
    """Refuse (InputError naming the file, the member and the limit) an ``.npz`` archive
    before anything in it is decompressed: each member read only from its zip entry and its
    ``.npy`` header (a few bytes) must have a name ``names`` matches (``known`` lists them
    for the message), a dtype of ``kinds`` (never objects), at most 4 dimensions, as many
    bytes as the header's shape says, and all together at most ``limit`` bytes. A 4 MB file
    that decompresses to 3 GB is refused by its declared sizes."""
    import zipfile

    import numpy as np

    from drakedeburr.errors import InputError

    path = Path(path)
    check_regular_file(path, what, limit)
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise InputError(f"{path}: not a readable .npz archive ({type(exc).__name__}: "
                         f"{str(exc)[:120]})") from None
    total = 0
    fmt = np.lib.format
    readers = {(1, 0): fmt.read_array_header_1_0, (2, 0): fmt.read_array_header_2_0}
    with zf:
        for info in zf.infolist():
            name = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
            if not names.fullmatch(name):
                raise InputError(f"{path}: member {info.filename[:60]!r} is not one of the "
                                 f"{what} ({known})")
            total += info.file_size
            if total > limit:
                raise InputError(f"{path}: member {name!r} takes the arrays past the {what} "
                                 f"limit of {size_text(limit)} decompressed")
            try:
                with zf.open(info) as f:
                    read = readers.get(fmt.read_magic(f))
                    if read is None:
                        raise ValueError("an .npy format version not read here")
                    shape, _, dtype = read(f)
                    header = f.tell()
            except Exception as exc:  # zlib, a bad header: numpy and zipfile raise many kinds
                raise InputError(f"{path}: member {name!r} has no readable .npy header "
                                 f"({type(exc).__name__}: {str(exc)[:80]})") from None
            if dtype.kind not in kinds or dtype.hasobject:
                raise InputError(f"{path}: array {name!r}: dtype {dtype}, expected numbers")
            if len(shape) > 4 or any(n < 0 for n in shape):
                raise InputError(f"{path}: array {name!r}: shape {shape}: at most 4 "
                                 "dimensions")
            if header + int(np.prod(shape, dtype=object)) * dtype.itemsize != info.file_size:
                raise InputError(f"{path}: array {name!r}: its header says shape {shape} "
                                 f"{dtype}, which does not match its {info.file_size} bytes")
