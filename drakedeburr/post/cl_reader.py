"""Streaming reader for APT-style cutter-location files (NX CLSF, Creo Pro/CLfile, generic APT).

The file is read line by line (never loaded whole): physical lines ending in ``$`` continue on
the next line; ``$$`` starts a comment that runs to the end of the line, also after a statement
(``GOTO/1,2,3 $$ 4,5,6`` is the GOTO to 1,2,3; the comment is kept). Statements are
``WORD / arg, arg, ...`` or a bare ``WORD``. What the reader does with each word:

- moves: ``GOTO/x,y,z[,i,j,k]`` (tool tip and tool axis, tip -> spindle), ``GODLTA/dx,dy,dz``
  or ``GODLTA/d`` (along the tool axis), ``FROM`` (start point, reached by positioning),
  ``GOHOME`` (back to FROM); ``RAPID`` makes the next move a rapid (one-shot, as in APT);
  ``CIRCLE/xc,yc,zc,i,j,k,r`` makes the next GOTO run on the circle (right-handed about
  (i, j, k), helix allowed), expanded within ``arc_tolerance``;
- drilling cycles: ``CYCLE/DRILL|FACE|DEEP|BRKCHP|BORE|REAM, ...`` ... ``CYCLE/OFF``: every
  GOTO in between is a hole, expanded into its moves (:mod:`drakedeburr.post.cl_cycles`);
  other cycles and NC cycle calls (``CYCLE81(...)``) are refused with the line named;
- frames and units: ``MSYS/x,y,z,xi,xj,xk,yi,yj,yk`` (or a 12-number 3 x 4 matrix): the
  following coordinates are in that system, ``p = origin + [X Y Z] p_file``; ``UNITS/MM|INCHES``
  (a switch after moves is reported); ``TLAXIS/i,j,k``; ``FEDRAT``; ``SPINDL``; ``LOADTL`` /
  ``LOAD/TOOL``;
- tool paths: ``TOOL PATH/name,...`` ... ``END-OF-PATH`` (NX; the file goes on to the next
  path), Creo's ``$$-> FEATNO / n`` ... ``$$-> END /``; ``FINI`` ends the data;
- cutter compensation ``CUTCOM`` / ``TLCOMP`` (other than OFF) is refused unless
  ``cutcom="ignore"`` (the CL points are then the tool centre);
- motion words whose moves cannot be computed here (GOFWD, TLON, ROTABL, TRACUT, ...) are
  refused;
- machine functions (SPINDL, COOLNT, DELAY, STOP, AUXFUN, INSERT, ...) and unknown words are
  listed once each with their count and first lines (:attr:`ClProgram.not_applied`); titles,
  display and tool data (PARTNO, PAINT, TLDATA, ...) are read and counted with the reason they
  are not needed (:attr:`ClProgram.read_words`, logged by ``post``), the NX listing banner is
  read as a comment; ``$$`` comments and PPRINT are kept.

Malformed data raise :class:`ClParseError` (an :class:`~drakedeburr.errors.InputError`) naming
the file, line and token. Output is SI: positions [m], feeds [m/s]; tool axes are unit vectors
in the CAM convention (i, j, k) = tip -> spindle = -Z_T (DESIGN.md).
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.post.cl_interpreter import ClInterpreter
from drakedeburr.post.cl_types import (
    ClMove,
    ClParseError,
    ClToolPath,
    ClWarning,
    ClWordCount,
    Notes,
)

__all__ = [
    "ClParseError",
    "ClWarning",
    "ClMove",
    "ClToolPath",
    "ClWordCount",
    "ClProgram",
    "ClReadOptions",
    "ClReadState",
    "iter_cl_moves",
    "read_cl",
    "parse_cl_text",
]

log = logging.getLogger(__name__)

_CHUNK = 65536  # moves per column block while reading
_COMMENTS_KEPT = 10000
_PROGRESS_LINES = 65536  # progress callback every this many lines


@dataclass(frozen=True)
class ClReadOptions:
    """How a CL file is read.

    Attributes:
        units: length unit until a UNITS statement says otherwise: 'mm' or 'inch' (NX CLSF
            files usually carry no UNITS statement; inch files say FEDRAT/IPM).
        arc_tolerance: maximum chord-height error of CIRCLE expansion [m].
        require_end: raise if the file ends without FINI or a closing END-OF-PATH (truncated).
        cutcom: 'refuse' cutter compensation (default) or 'ignore' it (CL = tool centre).
    """

    units: str = "mm"
    arc_tolerance: float = 1e-5
    require_end: bool = True
    cutcom: str = "refuse"


@dataclass
class ClReadState:
    """What a streaming read found besides the moves (filled while reading, complete at the
    end). See :class:`ClProgram` for the attributes."""

    units: str = "mm"
    end_line: int = 0
    paths: list[ClToolPath] = field(default_factory=list)
    unit_changes: list[tuple[int, str, int]] = field(default_factory=list)
    machine_events: list[tuple[int, str, float, int]] = field(default_factory=list)
    warnings: list[ClWarning] = field(default_factory=list)
    warning_counts: dict[str, int] = field(default_factory=dict)
    not_applied: tuple[ClWordCount, ...] = ()
    read_words: tuple[ClWordCount, ...] = ()
    lines_read: int = 0


_TEXT_WORDS = ("PPRINT", "PARTNO", "INSERT", "TPRINT")  # the rest of the line is literal text


def _split_comment(text: str, continued: bool) -> tuple[str, str]:
    """(statement text, ``$$`` comment) of one physical line: in APT ``$$`` starts a comment
    that runs to the end of the line, also after a statement (``GOTO/1,2,3 $$ note``); a
    line that is only a comment is returned whole as the comment. The text of PPRINT, PARTNO,
    INSERT and TPRINT is literal and never split."""
    at = text.find("$$")
    if at < 0 or (not continued and text[:at].lstrip().upper().startswith(_TEXT_WORDS)):
        return text, ""
    if at == 0 or not text[:at].strip():
        return ("", text.strip()) if continued else (text, "")
    return text[:at].rstrip(), text[at:].strip()


def _statements(lines: Iterable[str], source: str, counter: list[int],
                progress: Callable[[int, int], None] | None) -> Iterator[tuple[int, str]]:
    """(first line number, joined text) per statement; ``$`` continues a line.
    ``counter`` follows [physical line number, characters read]."""
    buf: list[str] = []
    start = lineno = chars = 0
    for lineno, raw in enumerate(lines, start=1):
        chars += len(raw)
        if progress is not None and lineno % _PROGRESS_LINES == 0:
            counter[0], counter[1] = lineno, chars
            progress(lineno, chars)
        text = raw.rstrip("\r\n").strip()
        if not buf:
            start = lineno
        text, comment = _split_comment(text, bool(buf))
        if buf and not text and comment:  # a comment line inside a continuation
            yield lineno, comment
            continue
        if text.endswith("$") and text != "$":
            buf.append(text[:-1])
            if comment:
                yield lineno, comment
            continue
        if comment:  # before the statement it follows: a comment on the FINI line is read
            yield lineno, comment
        if buf:
            buf.append(text)
            text = " ".join(buf).strip()
            buf = []
        if text:
            yield start, text
    counter[0], counter[1] = lineno, chars
    if buf:
        raise ClParseError(source, lineno, buf[-1][-20:] + "$",
                           "file ends inside a '$' continuation (truncated?)")


def iter_cl_moves(
    lines: Iterable[str],
    source: str = "<cl>",
    options: ClReadOptions = ClReadOptions(),
    on_warning: Callable[[ClWarning], None] | None = None,
    on_comment: Callable[[int, str], None] | None = None,
    state_out: dict | ClReadState | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Iterator[ClMove]:
    """Yield the moves of a CL file as it is read (streaming).

    Args:
        lines: the file's lines (an open text file works).
        source: name used in messages.
        options: units, arc tolerance, end required, cutter compensation
            (:class:`ClReadOptions`).
        on_warning: called with each :class:`ClWarning` (at most 20 per word).
        on_comment: called with (line, text) of each comment / PPRINT.
        state_out: a :class:`ClReadState` (or a dict, which receives 'units' and 'end_line')
            filled at the end.
        progress: called with (lines read, characters read) every 65536 lines.

    Raises:
        ClParseError: malformed or unsupported statement, non-finite number, truncated file.
    """
    notes = Notes(on_warning)
    interp = ClInterpreter(source, options.units, options.arc_tolerance, notes, on_comment,
                           options.cutcom)
    counter = [0, 0]
    for line, stmt in _statements(lines, source, counter, progress):
        yield from interp.statement(line, stmt)
    last_line = max(counter[0], 1)
    if interp.circle is not None:
        raise ClParseError(source, last_line, "CIRCLE",
                           f"CIRCLE on line {interp.circle[0]} has no end GOTO (truncated?)")
    closed = interp.paths and not interp.path_open and interp.paths[-1].end_line > 0
    if options.require_end and not (interp.ended or closed):
        raise ClParseError(source, last_line, "EOF",
                           "file ends without FINI or END-OF-PATH (truncated?)"
                           if counter[0] else "empty file")
    end_line = interp.ended or (interp.paths[-1].end_line if closed else 0)
    if isinstance(state_out, dict):
        state_out.update(units=interp.units, end_line=end_line)
    elif state_out is not None:
        state_out.units, state_out.end_line = interp.units, end_line
        state_out.paths = interp.paths
        state_out.unit_changes = interp.unit_changes
        state_out.machine_events = interp.machine_events
        state_out.warnings, state_out.warning_counts = notes.warnings, notes.warning_counts
        state_out.not_applied = notes.word_counts()
        state_out.read_words = notes.word_counts(read=True)
        state_out.lines_read = counter[0]


class _Columns:
    """Moves collected into numpy blocks (bounded memory: ~90 bytes per move)."""

    def __init__(self) -> None:
        self.rows: list[tuple] = []
        self.blocks: list[np.ndarray] = []

    def add(self, m: ClMove) -> None:
        self.rows.append((m.line, m.rapid, *m.p_C, *m.axis_C, m.feed, m.spindle_rpm, m.tool,
                          m.from_circle, m.path, m.cycle))
        if len(self.rows) == _CHUNK:
            self.blocks.append(np.array(self.rows, float))
            self.rows = []

    def columns(self) -> dict[str, np.ndarray]:
        if self.rows or not self.blocks:
            self.blocks.append(np.array(self.rows, float).reshape(-1, 14))
            self.rows = []
        a = np.concatenate(self.blocks) if len(self.blocks) > 1 else self.blocks[0]
        self.blocks = []
        return dict(lines=a[:, 0].astype(np.int64), rapid=a[:, 1] != 0,
                    p_C=np.ascontiguousarray(a[:, 2:5]), axis_C=np.ascontiguousarray(a[:, 5:8]),
                    feed=a[:, 8].copy(), spindle_rpm=a[:, 9].copy(),
                    tool=a[:, 10].astype(np.int32), from_circle=a[:, 11] != 0,
                    path=a[:, 12].astype(np.int32), cycle=a[:, 13] != 0)


@dataclass(frozen=True, eq=False)
class ClProgram:
    """A read CL file (see :func:`read_cl`), moves stored as arrays.

    Attributes:
        source: file name (for messages).
        p_C: (N, 3) tool tip positions in the CL frame [m].
        axis_C: (N, 3) unit tool axes tip -> spindle, CL frame.
        rapid: (N,) bool, rapid moves.
        lines: (N,) int, CL line of each move.
        feed: (N,) feed [m/s] (NaN before the first FEDRAT).
        spindle_rpm: (N,) spindle speed [1/min] (+ CLW).
        tool: (N,) tool numbers.
        from_circle: (N,) bool, points from CIRCLE expansion.
        path: (N,) int, index into ``paths``.
        cycle: (N,) bool, moves of an expanded drilling cycle.
        paths: the tool paths, in file order.
        warnings: statements acted on with a caveat (at most 20 per word; all are counted in
            ``warning_counts``).
        warning_counts: word -> number of warnings.
        not_applied: words not turned into robot motion, each listed once with its count.
        read_words: words read that say nothing about the motion (PAINT, TLDATA, PARTNO, ...),
            each once with its count and why it is not needed (``post`` logs them).
        comments: (line, text) of ``$$`` comments and PPRINT (the first 10000).
        units: length unit in effect at the end ('mm' or 'inch').
        unit_changes: (line, new unit, moves read before) of each UNITS statement that changed
            the unit; a switch with moves before it is a mid-file switch.
        end_line: line of FINI (or of the last END-OF-PATH).
        machine_events: (line, word, value, moves read before) of each SPINDL (value =
            signed rpm, 0 = off, NaN = on before any speed) and COOLNT (1 on, 0 off)
            statement, in file order.
    """

    source: str
    p_C: np.ndarray
    axis_C: np.ndarray
    rapid: np.ndarray
    lines: np.ndarray
    feed: np.ndarray
    spindle_rpm: np.ndarray
    tool: np.ndarray
    from_circle: np.ndarray
    path: np.ndarray
    cycle: np.ndarray
    paths: tuple[ClToolPath, ...] = ()
    warnings: tuple[ClWarning, ...] = ()
    warning_counts: dict[str, int] = field(default_factory=dict)
    not_applied: tuple[ClWordCount, ...] = ()
    read_words: tuple[ClWordCount, ...] = ()
    comments: tuple[tuple[int, str], ...] = ()
    units: str = "mm"
    unit_changes: tuple[tuple[int, str, int], ...] = ()
    end_line: int = 0
    machine_events: tuple[tuple[int, str, float, int], ...] = ()

    def __len__(self) -> int:
        return int(self.lines.shape[0])

    @functools.cached_property
    def moves(self) -> tuple[ClMove, ...]:
        """Every move as a :class:`ClMove`, in order (built on first use)."""
        return tuple(
            ClMove(int(ln), bool(r), tuple(map(float, p)), tuple(map(float, a)), float(f),
                   float(s), int(t), bool(c), int(k), bool(y))
            for ln, r, p, a, f, s, t, c, k, y in zip(
                self.lines, self.rapid, self.p_C, self.axis_C, self.feed, self.spindle_rpm,
                self.tool, self.from_circle, self.path, self.cycle, strict=True))

    @property
    def mid_file_unit_changes(self) -> tuple[tuple[int, str, int], ...]:
        """UNITS switches that came after moves had been read in the other unit."""
        return tuple(u for u in self.unit_changes if u[2] > 0)

    def summary(self) -> list[str]:
        """Short lines describing the file: paths, units, words not applied."""
        out = [f"{Path(self.source).name}: {len(self)} moves in {len(self.paths)} tool "
               f"path(s), units {self.units}"]
        for p in self.paths:
            holes = f", {p.n_holes} holes drilled" if p.n_holes else ""
            name = f" {p.name!r}" if p.name else ""
            out.append(f"path {p.index + 1}{name}: lines {p.start_line}-{p.end_line}, "
                       f"{p.n_goto} GOTOs -> {p.n_moves} moves{holes}")
        for line, unit, before in self.mid_file_unit_changes:
            out.append(f"UNITS switched to {unit} at line {line} after {before} moves")
        out += [f"not applied: {w.describe()}" for w in self.not_applied]
        return out


def _program(source: str, moves: Iterable[ClMove], state: ClReadState,
             comments: list[tuple[int, str]]) -> ClProgram:
    cols = _Columns()
    for m in moves:
        cols.add(m)
    return ClProgram(source=source, **cols.columns(), paths=tuple(state.paths),
                     warnings=tuple(state.warnings), warning_counts=dict(state.warning_counts),
                     not_applied=state.not_applied, read_words=state.read_words,
                     comments=tuple(comments),
                     units=state.units, unit_changes=tuple(state.unit_changes),
                     end_line=state.end_line, machine_events=tuple(state.machine_events))


def _comment_sink(comments: list[tuple[int, str]]) -> Callable[[int, str], None]:
    def add(line: int, text: str) -> None:
        if len(comments) < _COMMENTS_KEPT:
            comments.append((line, text))
    return add


def read_cl(
    path: str | Path,
    units: str = "mm",
    arc_tolerance: float = 1e-5,
    require_end: bool = True,
    cutcom: str = "refuse",
    progress: Callable[[int, int, str], None] | None = None,
) -> ClProgram:
    """Read a CL/APT file into a :class:`ClProgram` (see :func:`iter_cl_moves`).

    Args:
        path: the file.
        units: length unit until a UNITS statement ('mm' or 'inch').
        arc_tolerance: chord-height error of CIRCLE expansion [m].
        require_end: a file without FINI / END-OF-PATH is an error (truncated).
        cutcom: 'refuse' cutter compensation, or 'ignore' it (CL points = tool centre).
        progress: optional callback (characters read, file size, "read CL").

    Raises:
        ClParseError: malformed data (file, line, token named).
        InputError: no such file, or not a readable file.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: CL file not found")
    from drakedeburr._io import check_regular_file

    size = check_regular_file(path, "CL file", "cl")  # READ_LIMITS["cl"], regular files only
    state = ClReadState()
    comments: list[tuple[int, str]] = []
    tick = None if progress is None else (lambda n, chars: progress(min(chars, size), size,
                                                                    "read CL"))
    with path.open("r", encoding="utf-8", errors="replace", newline="") as f:
        prog = _program(str(path), iter_cl_moves(
            f, str(path), ClReadOptions(units, arc_tolerance, require_end, cutcom), None,
            _comment_sink(comments), state, tick), state, comments)
    if progress is not None:
        progress(size, size, "read CL")
    for w in prog.warnings:
        log.info("%s:%d: %s: %s", path.name, w.line, w.word, w.message)
    return prog


def parse_cl_text(text: str, source: str = "<text>", units: str = "mm",
                  arc_tolerance: float = 1e-5, require_end: bool = True,
                  cutcom: str = "refuse") -> ClProgram:
    """Like :func:`read_cl` for a string."""
    state = ClReadState()
    comments: list[tuple[int, str]] = []
    return _program(source, iter_cl_moves(
        text.splitlines(), source, ClReadOptions(units, arc_tolerance, require_end, cutcom),
        None, _comment_sink(comments), state), state, comments)
