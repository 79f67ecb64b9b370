"""The statement interpreter behind :mod:`drakedeburr.post.cl_reader`.

One :class:`ClInterpreter` keeps the modal state of a CL file (units, feed, tool axis, MSYS,
active CIRCLE or drilling cycle, tool paths) and turns each statement into zero or more
:class:`~drakedeburr.post.cl_types.ClMove`. See the reader's docstring for the words it knows.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import NamedTuple

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.post.cl_cycles import FEED_UNITS, DrillCycle, hole_moves, parse_cycle
from drakedeburr.post.cl_types import (
    LENGTH_M,
    ClMove,
    ClParseError,
    ClToolPath,
    Notes,
    number,
    unit_vector,
)
from drakedeburr.units import INCH_M, MM_PER_M

__all__ = ["ClInterpreter", "ClCircle", "arc_points"]


class ClCircle(NamedTuple):
    """A CIRCLE statement waiting for its end GOTO: its CL ``line``, ``center`` (3,) [m], unit
    normal ``n`` (3,), ``radius`` [m] and the radius token as written (for messages)."""

    line: int
    center: np.ndarray
    n: np.ndarray
    radius: float
    r_token: str

_ORTHO_TOL = 1e-3  # MSYS axes: unit length and orthogonality as printed with ~7 digits

# words that say nothing about the robot's motion (titles, display, tolerances, tool data):
# read and counted (ClProgram.read_words, logged by post), not listed as "not applied"
_TOOL_DATA = "tool geometry for the CAM display; the robot's TCP comes from --tool"
_INFO = {
    "PARTNO": "part title", "MACHIN": "NC machine selection", "TLDATA": _TOOL_DATA,
    "PAINT": "CAM display colour/speed", "CUTTER": _TOOL_DATA, "CLRSRF": "clearance plane",
    "DISPLY": "CAM display", "SEQNO": "NC sequence numbers", "TPRINT": "tool list print",
    "INTOL": "CAM tolerance", "OUTOL": "CAM tolerance", "TOLER": "CAM tolerance",
    "MODE": "NC mode", "TOOLNO": "tool number for the NC", "REWIND": "NC tape rewind",
    "END": "NC program end", "AUTOPS": "APT part surface", "MULTAX": "multi-axis flag (the "
    "GOTO arity is read)", "OPERATION NAME": "CAM operation name", "SELECT": "NC selection",
    "INDIRV": "APT direction hint", "ARCSLP": "arc slope flag",
}
# machine functions a robot program does not carry: read, then listed as not written
_MACHINE = {
    "SPINDL": "spindle on/off and speed: written only to the outputs of the post's I/O "
              "settings (--io)",
    "COOLNT": "coolant: written only to the output of the post's I/O settings (--io)",
    "AIR": "air blast is not written to the robot program",
    "DELAY": "a dwell is not written (the robot programs carry no waits)",
    "DWELL": "a dwell is not written (the robot programs carry no waits)",
    "OPSTOP": "an optional stop is not written",
    "STOP": "a program stop is not written",
    "AUXFUN": "an auxiliary (M) function is not written",
    "PREFUN": "a preparatory (G) function is not written",
    "INSERT": "literal NC text is not written",
    "ORIGIN": "the NC machine origin does not apply (give the work object instead)",
    "PITCH": "the thread pitch is not used",
    "OPSKIP": "block skip is not written",
    "SELCTL": "tool preselection is not written",
    "CLAMP": "axis clamping is not written",
}
# motion words whose moves this reader cannot compute: refused, never dropped
_MOTION = frozenset({
    "GOFWD", "GOLFT", "GORGT", "GOBACK", "GOUP", "GODOWN", "TLON", "TLLFT", "TLRGT", "TLOFPS",
    "TLONPS", "PSIS", "ROTABL", "ROTATE", "ROTHED", "TRACUT", "COPY", "INDEX",
})
_NX_BANNER = ("INFORMATION LISTING CREATED BY", "DATE", "CURRENT WORK PART", "NODE NAME",
              "TOOL PATH LISTING HAS")


class ClInterpreter:
    """The modal state of a CL file; :meth:`statement` turns one statement into moves.

    Args:
        source: file name for messages.
        units: length unit until a UNITS statement: 'mm' or 'inch'.
        arc_tolerance: chord-height error of CIRCLE expansion [m].
        notes: collects warnings and the words not applied.
        on_comment: called with (line, text) of each ``$$`` comment and PPRINT.
        cutcom: 'refuse' (cutter compensation is an error) or 'ignore' (the CL points are the
            tool centre; CUTCOM is listed as not applied).
    """

    def __init__(self, source: str, units: str = "mm", arc_tolerance: float = 1e-5,
                 notes: Notes | None = None,
                 on_comment: Callable[[int, str], None] | None = None,
                 cutcom: str = "refuse") -> None:
        if units not in LENGTH_M:
            raise InputError(f"{source}: units must be 'mm' or 'inch', got {units!r}")
        if not arc_tolerance > 0:
            raise InputError(f"arc_tolerance must be > 0, got {arc_tolerance!r}")
        if cutcom not in ("refuse", "ignore"):
            raise InputError(f"cutcom must be 'refuse' or 'ignore', got {cutcom!r}")
        self.source, self.units, self.scale = source, units, LENGTH_M[units]
        self.arc_tolerance, self.cutcom = arc_tolerance, cutcom
        self.notes = notes if notes is not None else Notes()
        self.on_comment = on_comment
        self.axis = (0.0, 0.0, 1.0)
        self.feed, self.rpm, self.tool = math.nan, 0.0, 0
        self.rapid_next = False
        self.p_prev: tuple[float, float, float] | None = None
        self.p_from: tuple[float, float, float] | None = None
        self.circle: ClCircle | None = None
        self.cycle: DrillCycle | None = None
        self.cycle_last: DrillCycle | None = None
        self.cycle_start: np.ndarray | None = None
        self.msys: tuple[np.ndarray, np.ndarray] | None = None  # (R (3, 3), origin [m])
        self.ended = 0
        self.paths: list[ClToolPath] = []
        self.path_open = False
        self.unit_changes: list[tuple[int, str, int]] = []  # (line, unit, moves before)
        # SPINDL / COOLNT state changes: (line, word, value, moves before); SPINDL value =
        # signed rpm (0 = off, NaN = on at an unknown speed), COOLNT 1 = on (ON, FLOOD, MIST,
        # THRU, AIR...), 0 = off
        self.machine_events: list[tuple[int, str, float, int]] = []
        self.coolant = 0.0
        self.n_moves = 0
        self._handlers = {
            "GOTO": self._goto, "GODLTA": self._godlta, "FROM": self._from,
            "GOHOME": self._gohome, "RAPID": self._rapid, "FEDRAT": self._fedrat,
            "SPINDL": self._spindl, "CIRCLE": self._circle, "TLAXIS": self._tlaxis,
            "UNITS": self._units, "INCHES": self._units, "MM": self._units,
            "LOADTL": self._loadtl, "LOAD": self._loadtl, "PPRINT": self._pprint,
            "FINI": self._fini, "END-OF-PATH": self._end_of_path, "TOOL PATH": self._tool_path,
            "MSYS": self._msys, "CYCLE": self._cycle, "CUTCOM": self._cutcom,
            "TLCOMP": self._cutcom, "COOLNT": self._coolnt,
        }

    # ---- dispatch
    def statement(self, line: int, stmt: str) -> Iterable[ClMove]:
        """Moves of one (joined) statement; most statements give none."""
        if self.ended:
            self.notes.skip(line, "(after FINI)", "statements after FINI are not read")
            return ()
        if stmt.startswith("$$"):
            self._comment(line, stmt[2:].lstrip("-> ").strip())
            return ()
        word, sep, rest = stmt.partition("/")
        word = " ".join(word.split()).upper()
        args = [a.strip() for a in rest.split(",")] if sep else []
        handler = self._handlers.get(word)
        if handler is not None:
            return handler(line, word, args) or ()
        self._other(line, word, stmt)
        return ()

    def _fail(self, line: int, token: str, message: str):
        raise ClParseError(self.source, line, token, message)

    def _other(self, line: int, word: str, stmt: str) -> None:
        parts = {p.strip() for p in word.split(",")}
        if parts & _MOTION:
            self._fail(line, word, f"motion statement {word} is not supported (its moves "
                                   "cannot be computed here): output GOTO points instead")
        if word[:6] == "CYCLE8" and word[6:7].isdigit() and word[7:8] in ("", "(", " "):
            self._fail(line, word[:12], "NC drilling cycle call in a CL file is not supported: "
                                        "post the CYCLE/DRILL or CYCLE/DEEP form instead")
        if word in _INFO:
            self.notes.read(line, word, _INFO[word])
            return
        if word in _MACHINE:
            self.notes.skip(line, word, _MACHINE[word])
        elif word.startswith(_NX_BANNER):
            self._comment(line, stmt)  # NX information listing banner / footer
        else:
            self.notes.skip(line, word.split(" ")[0][:40] or "?", "unknown word, not applied")

    # ---- tool paths
    def _path(self, line: int) -> ClToolPath:
        if not self.path_open:
            self.paths.append(ClToolPath(len(self.paths), start_line=line))
            self.path_open = True
        return self.paths[-1]

    def _close_path(self, line: int) -> None:
        if self.path_open:
            self.paths[-1].end_line = line
            self.path_open = False

    def _tool_path(self, line: int, word: str, args: list[str]) -> None:
        if self.path_open and self.paths[-1].n_moves:
            self.notes.warn(line, word, f"new TOOL PATH before END-OF-PATH of "
                                        f"{self.paths[-1].label!r}")
        self._close_path(line - 1)
        path = self._path(line)
        path.name = args[0] if args else ""
        upper = [a.upper() for a in args]
        if "TOOL" in upper[1:] and upper.index("TOOL") + 1 < len(args):
            path.tool_name = args[upper.index("TOOL") + 1]

    def _end_of_path(self, line: int, word: str, args: list[str]) -> None:
        if self.circle is not None:
            self._fail(line, word, f"CIRCLE on line {self.circle[0]} has no end GOTO")
        if not self.path_open:
            self.notes.warn(line, word, "END-OF-PATH without an open tool path")
        self._close_path(line)
        self.cycle = None

    def _fini(self, line: int, word: str, args: list[str]) -> None:
        self._close_path(line)
        self.ended = line

    def _comment(self, line: int, text: str) -> None:
        key = text.upper().replace(" ", "")
        if key.startswith("FEATNO/"):  # Creo: an NC sequence starts
            if self.path_open and self.paths[-1].n_moves:
                self._close_path(line - 1)
            self._path(line).name = "FEATNO " + text.partition("/")[2].strip()
        elif key == "END/" or key == "END":  # Creo: the NC sequence ends
            self._close_path(line)
        if self.on_comment is not None:
            self.on_comment(line, text)

    # ---- frames and units
    def _point(self, line: int, args: list[str]) -> tuple[float, float, float]:
        """x, y, z of the statement in the CL frame [m] (units and MSYS applied)."""
        sc = self.scale
        x, y, z = (number(self.source, line, a) * sc for a in args[:3])
        if self.msys is None:
            return (x, y, z)
        R, o = self.msys
        p = R @ (x, y, z) + o
        return (float(p[0]), float(p[1]), float(p[2]))

    def _direction(self, line: int, args: list[str], word: str) -> tuple[float, float, float]:
        v = unit_vector(self.source, line, [number(self.source, line, a) for a in args[:3]],
                         self.notes, word)
        if self.msys is None:
            return v
        w = self.msys[0] @ v
        return (float(w[0]), float(w[1]), float(w[2]))

    def _msys(self, line: int, word: str, args: list[str]) -> None:
        if len(args) not in (9, 12):
            self._fail(line, ",".join(args), "MSYS needs 9 numbers (origin, X axis, Y axis) or "
                                             "12 (a 3 x 4 matrix, row by row)")
        v = np.array([number(self.source, line, a) for a in args])
        if v.size == 9:
            o, x, y = v[:3], v[3:6], v[6:9]
        else:
            M = v.reshape(3, 4)
            o, x, y = M[:, 3], M[:, 0], M[:, 1]
        if (abs(np.linalg.norm(x) - 1) > _ORTHO_TOL or abs(np.linalg.norm(y) - 1) > _ORTHO_TOL
                or abs(x @ y) > _ORTHO_TOL):
            self._fail(line, ",".join(args[3:9] if v.size == 9 else args),
                       "MSYS axes are not orthonormal")
        x = x / np.linalg.norm(x)
        y = y - (y @ x) * x
        y = y / np.linalg.norm(y)
        R = np.column_stack([x, y, np.cross(x, y)])
        o = o * self.scale
        identity = np.allclose(R, np.eye(3), atol=1e-12) and not np.any(o)
        self.msys = None if identity else (R, o)

    def _units(self, line: int, word: str, args: list[str]) -> None:
        u = word if word in ("INCHES", "MM") else (args[0].upper() if args else "")
        if u in ("MM", "MILLIMETERS", "METRIC"):
            units = "mm"
        elif u in ("INCHES", "INCH", "IN"):
            units = "inch"
        else:
            self._fail(line, u, "UNITS must be MM or INCHES")
        if units != self.units:
            self.unit_changes.append((line, units, self.n_moves))
            if self.n_moves:
                self.notes.warn(line, "UNITS", f"units switched from {self.units} to {units} "
                                               f"after {self.n_moves} moves: the following "
                                               f"coordinates are read in {units}")
        self.units, self.scale = units, LENGTH_M[units]

    # ---- modal settings
    def _rapid(self, line: int, word: str, args: list[str]) -> None:
        self.rapid_next = True

    def _tlaxis(self, line: int, word: str, args: list[str]) -> None:
        if len(args) < 3:
            self._fail(line, ",".join(args) or word, "TLAXIS needs i,j,k")
        self.axis = self._direction(line, args, "TLAXIS")

    def _loadtl(self, line: int, word: str, args: list[str]) -> None:
        if word == "LOAD":
            if not args or args[0].upper() != "TOOL":
                self.notes.skip(line, "LOAD", "unknown word, not applied")
                return
            args = args[1:]
        if not args or not args[0]:
            self._fail(line, word, "tool change without a tool number")
        self.tool = int(number(self.source, line, args[0]))

    def _pprint(self, line: int, word: str, args: list[str]) -> None:
        if self.on_comment is not None:
            self.on_comment(line, ",".join(args).strip())

    def _cutcom(self, line: int, word: str, args: list[str]) -> None:
        mode = args[0].upper() if args else ""
        if mode in ("OFF", "NOMORE"):
            return
        if self.cutcom == "ignore":
            self.notes.skip(line, word, "cutter compensation ignored: the CL points are used "
                                        "as the tool centre")
            return
        self._fail(line, f"{word}/{','.join(args)}",
                   "cutter compensation is not supported by the robot programs: output the "
                   "path on the tool centre, or accept the CL points as the tool centre "
                   "(--ignore-cutcom)")

    def feed_from(self, value: float, mode: str | None) -> float:
        """Feed [m/s] of a value in ``mode`` (IPM, MMPM, IPR, MMPR, PERMIN, PERREV or None =
        file units per minute)."""
        if mode in ("IPM", "IPR"):
            length = INCH_M
        elif mode in ("MMPM", "MMPR"):
            length = 1.0 / MM_PER_M
        else:
            length = self.scale
        if mode in ("IPR", "MMPR", "PERREV"):
            return value * length * abs(self.rpm) / 60.0
        return value * length / 60.0

    def _fedrat(self, line: int, word: str, args: list[str]) -> None:
        value = mode = None
        for a in args:
            u = a.upper()
            if u in FEED_UNITS:
                mode = u
            elif u:
                value = number(self.source, line, a)
        if value is None:
            self._fail(line, ",".join(args), "FEDRAT without a value")
        if value < 0:
            self._fail(line, f"{value:g}", "negative feed")
        if mode in ("IPR", "MMPR", "PERREV") and self.rpm == 0:
            self.notes.warn(line, "FEDRAT", "feed per revolution with the spindle off: feed 0")
        self.feed = self.feed_from(value, mode)
        if mode == "IPM" and self.units == "mm":
            self.notes.warn(line, "FEDRAT", "feed in inch/min but coordinates read as mm (no "
                                            "UNITS statement?): check the units argument")

    def _event(self, line: int, word: str, value: float) -> None:
        self.machine_events.append((line, word, float(value), self.n_moves))

    def _spindl(self, line: int, word: str, args: list[str]) -> None:
        self.notes.skip(line, word, _MACHINE[word])
        words = [a.upper() for a in args if a]
        if "OFF" in words:
            self.rpm = 0.0
            self._event(line, word, 0.0)
            return
        sign = -1.0 if "CCLW" in words else 1.0
        nums = [a for a in args if a and a.upper() not in (
            "RPM", "SFM", "SMM", "CLW", "CCLW", "ON", "RANGE", "HIGH", "LOW", "MEDIUM")]
        if nums:
            self.rpm = sign * abs(number(self.source, line, nums[0]))
        elif "ON" not in words:
            self._fail(line, ",".join(args), "SPINDL without a speed")
        # SPINDL/ON before any speed: on, speed unknown (NaN)
        self._event(line, word, self.rpm if self.rpm != 0 else math.nan)

    def _coolnt(self, line: int, word: str, args: list[str]) -> None:
        self.notes.skip(line, word, _MACHINE[word])
        words = {a.upper() for a in args if a}
        if words & {"OFF", "NOMORE"}:
            value = 0.0
        elif words & {"ON", "FLOOD", "MIST", "THRU", "TAPKUL", "AIR", "SPRAY"} or not words:
            value = 1.0
        else:
            self._fail(line, ",".join(args), "COOLNT must be ON, FLOOD, MIST, THRU, AIR or OFF")
        self.coolant = value
        self._event(line, word, value)

    # ---- motion
    def _move(self, line: int, p: tuple[float, float, float], rapid: bool, *,
              circle: bool = False, cycle: bool = False, feed: float | None = None) -> ClMove:
        path = self._path(line)
        path.n_moves += 1
        self.n_moves += 1
        return ClMove(line, rapid, p, self.axis, self.feed if feed is None else feed,
                      self.rpm, self.tool, circle, path.index, cycle)

    def _goto(self, line: int, word: str, args: list[str]) -> Iterator[ClMove]:
        if len(args) not in (3, 6):
            self._fail(line, ",".join(args), f"GOTO needs 3 or 6 numbers, got {len(args)}")
        p = self._point(line, args)
        if len(args) == 6:
            self.axis = self._direction(line, args[3:], "GOTO")
        self._path(line).n_goto += 1
        if self.cycle is not None:
            yield from self._hole(line, p)
            return
        rapid, self.rapid_next = self.rapid_next, False
        if self.circle is not None:
            yield from self._arc(line, p, rapid)
        self.p_prev = p
        yield self._move(line, p, rapid)

    def _godlta(self, line: int, word: str, args: list[str]) -> Iterator[ClMove]:
        if self.p_prev is None:
            self._fail(line, word, "GODLTA before any position")
        if self.cycle is not None or self.circle is not None:
            self._fail(line, word, "GODLTA inside a drilling cycle or after CIRCLE")
        if len(args) == 1:
            d = number(self.source, line, args[0]) * self.scale
            delta = (d * self.axis[0], d * self.axis[1], d * self.axis[2])
        elif len(args) == 3:
            delta = tuple(number(self.source, line, a) * self.scale for a in args)
            if self.msys is not None:
                delta = tuple(float(v) for v in self.msys[0] @ delta)
        else:
            self._fail(line, ",".join(args), f"GODLTA needs 1 or 3 numbers, got {len(args)}")
        p = tuple(a + b for a, b in zip(self.p_prev, delta, strict=True))
        self._path(line).n_goto += 1
        rapid, self.rapid_next = self.rapid_next, False
        self.p_prev = p
        yield self._move(line, p, rapid)

    def _from(self, line: int, word: str, args: list[str]) -> Iterator[ClMove]:
        if len(args) not in (3, 6):
            self._fail(line, ",".join(args), f"FROM needs 3 or 6 numbers, got {len(args)}")
        self.p_from = self._point(line, args)
        if len(args) == 6:
            self.axis = self._direction(line, args[3:], "FROM")
        self._path(line).n_goto += 1
        self.rapid_next = False
        self.p_prev = self.p_from
        yield self._move(line, self.p_from, True)  # the start point: reached by positioning

    def _gohome(self, line: int, word: str, args: list[str]) -> Iterator[ClMove]:
        if self.p_from is None:
            self._fail(line, word, "GOHOME without a FROM point")
        self._path(line).n_goto += 1
        self.rapid_next = False
        self.p_prev = self.p_from
        yield self._move(line, self.p_from, True)

    def _circle(self, line: int, word: str, args: list[str]) -> None:
        if len(args) < 7:
            self._fail(line, ",".join(args), "CIRCLE needs xc,yc,zc,i,j,k,r")
        if self.cycle is not None:
            self._fail(line, word, "CIRCLE inside a drilling cycle")
        center = np.array(self._point(line, args))
        v = [number(self.source, line, a) for a in args[3:7]]
        n = np.array(v[:3])
        nn = np.linalg.norm(n)
        if nn < 1e-9 or v[3] <= 0:
            self._fail(line, ",".join(args), "CIRCLE axis must be non-zero and radius > 0")
        n = n / nn if self.msys is None else self.msys[0] @ (n / nn)
        self.circle = ClCircle(line, center, n, v[3] * self.scale, args[6])

    def _arc(self, line: int, p: tuple[float, float, float], rapid: bool) -> Iterator[ClMove]:
        circle, c_line = self.circle, self.circle.line
        self.circle = None
        if self.p_prev is None:
            self._fail(c_line, "CIRCLE", "CIRCLE before any position")
        for q in arc_points(self.source, circle, np.array(self.p_prev), np.array(p),
                            self.arc_tolerance):
            yield self._move(c_line, (float(q[0]), float(q[1]), float(q[2])), rapid,
                             circle=True)

    def _cycle(self, line: int, word: str, args: list[str]) -> None:
        if self.circle is not None:
            self._fail(line, word, f"CYCLE after the CIRCLE on line {self.circle[0]}")
        cyc = parse_cycle(
            args, line, self.scale, self.feed_from,
            lambda tok: number(self.source, line, tok),
            lambda tok, msg: self._fail(line, tok, msg),
            lambda msg: self.notes.warn(line, "CYCLE", msg))
        if cyc == "OFF":
            self.cycle = None
            return
        if cyc == "ON":
            if self.cycle_last is None:
                self._fail(line, "ON", "CYCLE/ON before any cycle was defined")
            cyc = self.cycle_last
        self.cycle = self.cycle_last = cyc
        self.cycle_start = None if self.p_prev is None else np.array(self.p_prev)

    def _hole(self, line: int, p_top: tuple[float, float, float]) -> Iterator[ClMove]:
        cyc = self.cycle
        self.rapid_next = False
        feed = cyc.feed if math.isfinite(cyc.feed) else self.feed
        prev = None if self.p_prev is None else np.array(self.p_prev)
        self._path(line).n_holes += 1
        for q, rapid in hole_moves(cyc, np.array(p_top), np.array(self.axis), prev,
                                   self.cycle_start):
            p = (float(q[0]), float(q[1]), float(q[2]))
            self.p_prev = p
            yield self._move(line, p, rapid, cycle=True, feed=feed)


def arc_points(source: str, circle: ClCircle, p0: np.ndarray, p1: np.ndarray,
               tol: float) -> np.ndarray:
    """(K, 3) interior points of the arc p0 -> p1 [m] on ``circle``, right-handed about its
    unit normal n (a helix along n is allowed), at most ``tol`` chord-height error."""
    line, center, n, radius, r_token = circle
    r0, r1 = p0 - center, p1 - center
    h0, h1 = r0 @ n, r1 @ n
    r0p, r1p = r0 - h0 * n, r1 - h1 * n
    rad_tol = max(1e-3 * radius, 10 * tol)
    for rp, name in ((r0p, "start"), (r1p, "end")):
        if abs(np.linalg.norm(rp) - radius) > rad_tol:
            raise ClParseError(source, line, r_token,
                               f"CIRCLE {name} point is {np.linalg.norm(rp):.6g} m from the "
                               f"centre, radius {radius:.6g} m")
    e1 = r0p / np.linalg.norm(r0p)
    e2 = np.cross(n, e1)
    ang = math.atan2(float(r1p @ e2), float(r1p @ e1)) % (2 * math.pi)
    if ang < 1e-12:
        ang = 2 * math.pi  # end point = start point: full circle
    step = 2 * math.acos(max(-1.0, 1 - tol / radius)) if tol < radius else math.pi / 2
    k = max(1, math.ceil(ang / max(step, 1e-6)))
    t = np.arange(1, k) / k
    th = ang * t
    return (center[None] + radius * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2)
            + (h0 + (h1 - h0) * t)[:, None] * n)
