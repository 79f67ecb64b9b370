"""Drilling cycles of CL files (the APT ``CYCLE`` statement), expanded into their moves.

A CL file does not spell out a drilling cycle's moves: ``CYCLE/...`` sets the cycle up and
every following ``GOTO`` (until ``CYCLE/OFF``) is a hole. A robot has no canned cycles, so each
hole becomes explicit moves, all on the hole axis ``a`` (the tool axis, tip -> spindle) through
the GOTO point ``P``, the top of the hole (ISO 4343; Creo and NX write it so):

- ``R = P + r a``: where the rapid approach ends and feeding starts (``RAPTO r``, else
  ``CLEAR r``; 0 when neither is given);
- ``B = P - d a``: the bottom (``DEPTH d``, or NX's ``FEDTO -d``);
- ``T = P + t a``: where the tool goes after the hole (``RTRCTO t``; ``RTRCTO, AUTO`` is the
  level the tool came from, as G98; ``CLEAR c`` when ``RAPTO`` gave R; else R).

Cycles (and the NC cycle each stands for):

- ``DRILL`` (G81), ``FACE`` (spot drill, G82): rapid to R, feed to B, rapid to T;
- ``DEEP`` / ``DRILL,DEEP`` (G83, peck drilling): feed ``STEP`` (``INCR``) deeper each peck,
  rapid out to R after each peck, rapid back in to :data:`PECK_GAP_M` above the last depth;
- ``BRKCHP`` / ``DRILL,BRKCHP`` (G73, chip breaking): as DEEP, but each peck only backs off by
  :data:`PECK_GAP_M`;
- ``BORE``, ``REAM`` (G85): feed to B, feed back out to R, rapid to T.

Before the first move of a hole the tool is brought over the hole at its current level along
``a`` (never dropping below R), so the approach runs above the part as on an NC machine. Every
rapid of a cycle is a straight move (the CL post writes it as a linear move at rapid speed):
the tool is in or right above a hole. ``TAP`` (spindle-synchronised), ``BORE,BACK``, ``CSINK``,
``THRU``, ``MANUAL`` and other cycles are refused with the line named; a dwell (``DWELL``,
``FACE``) is reported, since the robot programs carry no waits.

Parameters come as keyword couplets (``DEPTH, 3.5, STEP, 1, MMPM, 50, CLEAR, 1``) or in the
older positional form ``CYCLE/DRILL, depth, [unit,] feed, [unit,] clearance`` (a feed unit
takes the number after it, or the one before it when two numbers precede it); a positional
reading is reported with the values it took.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["DrillCycle", "parse_cycle", "hole_moves", "PECK_GAP_M", "FEED_UNITS"]

# Clearance kept above the last peck depth when the tool rapids back into the hole (G83) and
# the back-off of a chip-breaking peck (G73). NC controls keep this in a machine parameter; 0.5
# mm is a common setting. [m]
PECK_GAP_M = 0.5e-3
FEED_UNITS = ("IPM", "MMPM", "IPR", "MMPR", "PERMIN", "PERREV")
_EXPANDED = ("DRILL", "FACE", "DEEP", "BRKCHP", "BORE", "REAM")
_REFUSED = {
    "TAP": "tapping needs a spindle synchronised with the feed",
    "CSINK": "countersinking needs the tool's point angle to find the depth",
    "THRU": "THRU needs the part thickness",
    "MANUAL": "a manual cycle has no moves to expand",
    "BACK": "back boring needs an oriented spindle stop",
    "AVOID": "AVOID moves are machine specific",
}
_VALUE_WORDS = ("DEPTH", "FEDTO", "STEP", "INCR", "CLEAR", "RAPTO", "RTRCTO", "RETURN",
                "DWELL")
_EPS = 1e-9  # [m] positions closer than this are the same point
_MAX_PECKS = 10_000  # more pecks per hole than this is a data error (DEPTH / STEP)


@dataclass(frozen=True)
class DrillCycle:
    """A drilling cycle, lengths in metres.

    Attributes:
        kind: 'DRILL', 'FACE', 'DEEP', 'BRKCHP', 'BORE' or 'REAM'.
        depth: hole depth below the GOTO point along the tool axis [m] (> 0).
        step: peck depth [m] (DEEP, BRKCHP), else 0.
        rapto: R level above the GOTO point [m] (feeding starts there).
        retract: level above the GOTO point the tool leaves to [m]; None = the level the tool
            came from (``RTRCTO, AUTO``).
        feed: feed rate [m/s] of the feed moves; NaN = the file's current FEDRAT.
        dwell: dwell at the bottom [s] or [rev] (reported, not written).
        line: line of the CYCLE statement.
        text: the statement's parameters as written (for messages).
    """

    kind: str
    depth: float
    step: float
    rapto: float
    retract: float | None
    feed: float
    dwell: float
    line: int
    text: str


def _split(args: list[str]) -> tuple[str, list[str]]:
    tokens = [a.strip().upper() for a in args if a.strip()]
    if not tokens:
        return "", []
    kind, rest = tokens[0], tokens[1:]
    if kind in ("DRILL", "TAP", "BORE") and rest and rest[0] in ("DEEP", "BRKCHP", "BACK"):
        kind, rest = rest[0], rest[1:]
    return kind, rest


def _is_number(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _couplets(tokens: list[str], number: Callable[[str], float], fail: Callable[[str, str], None]
              ) -> tuple[dict[str, float | str], list[float], str | None, float | None]:
    """Keyword values, positional numbers, feed unit and feed value of a CYCLE statement."""
    named: dict[str, float | str] = {}
    positional: list[tuple[int, float]] = []
    unit = feed = None
    i = 0
    while i < len(tokens):
        tok = tokens[i]
        nxt = tokens[i + 1] if i + 1 < len(tokens) else ""
        if tok in _VALUE_WORDS:
            if tok == "RTRCTO" and nxt == "AUTO":
                named[tok] = "AUTO"
            elif not nxt:
                fail(tok, f"{tok} without a value")
            else:
                named[tok] = number(nxt)
            i += 2
            if tok == "DWELL" and i < len(tokens) and tokens[i] in ("REV", "SEC"):
                i += 1
            continue
        if tok in FEED_UNITS:
            unit = tok
            before_two = len(positional) >= 2 and positional[-1][0] == i - 1
            if before_two or not _is_number(nxt):
                if not positional or positional[-1][0] != i - 1:
                    fail(tok, f"feed unit {tok} without a feed value")
                feed = positional.pop()[1]
                i += 1
            else:
                feed = number(nxt)
                i += 2
            continue
        if _is_number(tok):
            positional.append((i, number(tok)))
            i += 1
            continue
        fail(tok, f"unknown CYCLE parameter {tok!r}")
    return named, [v for _, v in positional], unit, feed


def parse_cycle(
    args: list[str],
    line: int,
    scale: float,
    feed_from: Callable[[float, str | None], float],
    number: Callable[[str], float],
    fail: Callable[[str, str], None],
    warn: Callable[[str], None],
) -> DrillCycle | str:
    """Read a CYCLE statement.

    Args:
        args: the comma-separated arguments after ``CYCLE/``.
        line: its line number.
        scale: metres per CL length unit.
        feed_from: (value, unit or None) -> feed [m/s] (the reader's FEDRAT rules).
        number: token -> finite float (raises with the line named).
        fail: (token, message) -> raises the reader's parse error.
        warn: message -> records a warning for this line.

    Returns:
        A :class:`DrillCycle`, or 'OFF' / 'ON' for ``CYCLE/OFF`` (``NOMORE``) and ``CYCLE/ON``.
    """
    kind, rest = _split(args)
    text = ",".join(a.strip() for a in args)
    if kind in ("OFF", "NOMORE"):
        return "OFF"
    if kind == "ON" and not rest:
        return "ON"
    if kind in _REFUSED:
        fail(kind, f"drilling cycle CYCLE/{text} is not supported: {_REFUSED[kind]}; "
                   "output its moves from the CAM system instead")
    if kind not in _EXPANDED:
        fail(kind or "CYCLE", f"unknown drilling cycle CYCLE/{text} (supported: "
                              f"{', '.join(_EXPANDED)})")
    named, positional, unit, feed = _couplets(rest, number, fail)
    deep = kind in ("DEEP", "BRKCHP")
    if "DEPTH" in named:
        depth = float(named["DEPTH"])
    elif "FEDTO" in named:
        depth = -float(named["FEDTO"])
        if depth < 0:
            warn(f"FEDTO {named['FEDTO']:g} above the hole top read as a depth of "
                 f"{-depth:g}")
            depth = -depth
    elif positional:
        depth = positional.pop(0)
    else:
        fail(kind, f"CYCLE/{kind} without a depth (DEPTH or FEDTO)")
    step = float(named.get("STEP", named.get("INCR", 0.0)))
    clear = named.get("CLEAR")
    if clear is None and positional:
        clear = positional.pop(0)
        warn(f"positional CYCLE parameters read as depth {depth:g}, clearance {clear:g}"
             + (f", feed {feed:g} {unit}" if feed is not None else ""))
    if positional:
        fail(f"{positional[0]:g}", f"CYCLE/{kind}: {len(positional)} parameter(s) left over "
                                   "(expected depth, feed, clearance)")
    rapto = named.get("RAPTO", clear if clear is not None else 0.0)
    if "RTRCTO" in named or "RETURN" in named:
        r = named.get("RTRCTO", named.get("RETURN"))
        retract = None if r == "AUTO" else float(r)
    else:
        retract = float(clear) if ("RAPTO" in named and clear is not None) else float(rapto)
    if not depth > 0:
        fail(f"{depth:g}", f"CYCLE/{kind}: the depth must be > 0")
    if deep and not step > 0:
        fail(kind, f"CYCLE/{kind} needs a peck depth STEP (or INCR) > 0")
    if deep and depth / step > _MAX_PECKS:
        fail(f"{step:g}", f"CYCLE/{kind}: {depth:g} / {step:g} is more than {_MAX_PECKS} pecks")
    if float(rapto) < 0:
        fail(f"{rapto:g}", f"CYCLE/{kind}: the clearance (RAPTO/CLEAR) must be >= 0")
    if retract is not None and retract < float(rapto):
        warn(f"retract level {retract:g} below the R level {float(rapto):g}: retracting to R")
        retract = float(rapto)
    dwell = float(named.get("DWELL", 0.0))
    if dwell > 0 or kind == "FACE":
        warn(f"CYCLE/{kind}: the dwell at the hole bottom is not written (the robot programs "
             "carry no waits)")
    return DrillCycle(
        kind=kind, depth=depth * scale, step=(step if deep else 0.0) * scale,
        rapto=float(rapto) * scale, retract=None if retract is None else retract * scale,
        feed=math.nan if feed is None else feed_from(feed, unit), dwell=dwell, line=line,
        text=text)


def _peck_depths(depth: float, step: float) -> list[float]:
    n = max(1, math.ceil(depth / step - 1e-9))
    return [min((k + 1) * step, depth) for k in range(n)]


def hole_moves(
    cycle: DrillCycle,
    p_top: np.ndarray,
    axis: np.ndarray,
    p_prev: np.ndarray | None,
    p_initial: np.ndarray | None,
) -> list[tuple[np.ndarray, bool]]:
    """The moves of one hole.

    Args:
        cycle: the active cycle.
        p_top: (3,) GOTO point, the top of the hole [m].
        axis: (3,) unit hole axis = tool axis, tip -> spindle.
        p_prev: (3,) tool tip before this hole [m] (None: start of the file).
        p_initial: (3,) tool tip when the cycle started [m] (for ``RTRCTO, AUTO``).

    Returns:
        [(p (3,) [m], rapid)] in order; feed moves run at the cycle's feed.
    """
    P, a = np.asarray(p_top, float), np.asarray(axis, float)
    r = cycle.rapto
    moves: list[tuple[np.ndarray, bool]] = []
    if p_prev is not None:
        h = float((p_prev - P) @ a)
        if h > r + _EPS:
            over = P + h * a  # over the hole at the current level, then down to R
            if np.linalg.norm(over - p_prev) > _EPS:
                moves.append((over, True))
        elif h < r - _EPS:
            moves.append((p_prev + (r - h) * a, True))  # up to the R level first
    R = P + r * a
    moves.append((R, True))
    if cycle.kind in ("DEEP", "BRKCHP"):
        depths = _peck_depths(cycle.depth, cycle.step)
        for k, d in enumerate(depths):
            if k > 0 and cycle.kind == "DEEP":
                level = min(r, PECK_GAP_M - depths[k - 1])  # back in, short of the last depth
                moves.append((P + level * a, True))
            moves.append((P - d * a, False))
            if k < len(depths) - 1:
                if cycle.kind == "DEEP":
                    moves.append((R, True))  # out of the hole: chips cleared
                else:
                    moves.append((P + min(r, PECK_GAP_M - d) * a, True))  # break the chip
    else:
        moves.append((P - cycle.depth * a, False))
        if cycle.kind in ("BORE", "REAM"):
            moves.append((R, False))  # fed back out
    if cycle.retract is not None:
        t = cycle.retract
    else:
        t = r if p_initial is None else max(r, float((np.asarray(p_initial) - P) @ a))
    T = P + t * a
    if np.linalg.norm(T - moves[-1][0]) > _EPS:
        moves.append((T, True))
    return moves

