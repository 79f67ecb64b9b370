"""A robot program read back from its files: the types the strict readers return.

The readers (:func:`drakedeburr.programs.rapid.read_rapid`, ``krl.read_krl``, ``ls.read_ls``)
accept the straight-line motion programs the writers produce and the same subset written by
hand or by other tools (comments, data declarations, motion instructions, the settings that
go with them). Anything else is refused with a :class:`ProgramFormatError` naming the file,
the line and the construct, never skipped: a program that does more than move cannot be
checked against a plan.

All values are SI (m, rad, m/s) in the controller's own frames:

* ``X_FT``: the frame the flange carries (tool TCP, or the held work object with a
  stationary tool), in the flange frame F;
* ``X_RO``: the fixed frame (work object, or the stationary TCP) in the controller's robot
  frame R (ABB base, KUKA $ROBROOT, FANUC world);
* each move's ``X_OT``: the flange-carried frame in the fixed frame (the KUKA/FANUC point;
  ABB robtargets are converted: with a stationary tool the robtarget is its inverse).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.programs.common import ProgramFormatError

__all__ = ["ReadMove", "ReadProgram", "parse_number", "split_top_level"]


@dataclass(frozen=True, eq=False)
class ReadMove:
    """One motion instruction as read.

    Attributes:
        file: the file holding the instruction.
        line: 1-based line of the instruction.
        move_type: "linear" or "joint".
        name: the target's name (``p12``, ``XP12``, ``P[12]``).
        X_OT: (4, 4) pose of the flange-carried frame in the fixed frame [m].
        configuration: ABB ``(cf1, cf4, cf6, cfx)``, KUKA ``(S, T)`` or FANUC ``'N U T, 0, 0, 0'``.
        speed: TCP speed [m/s] (None where the format gives joint moves a % instead).
        joint_percent: KRL/LS joint moves: % of the axes' top speed (None otherwise).
        zone: zone radius [m] (0 = fine); LS: the nominal radius of the CNT value.
        target_file, target_line: where the target's pose and configuration are written.
        speed_line, zone_line: where the move's speed and zone are set (file = ``file``).
        options: other motion options as written (e.g. ``"RTCP"``).
        orientation_line, config_line: where the target's orientation / configuration are
            written when not on ``target_line`` (FANUC /POS blocks); 0 = ``target_line``.
    """

    file: str
    line: int
    move_type: str
    name: str
    X_OT: np.ndarray
    configuration: object
    speed: float | None
    joint_percent: int | None
    zone: float
    target_file: str
    target_line: int
    speed_line: int
    zone_line: int
    options: tuple[str, ...] = ()
    orientation_line: int = 0
    config_line: int = 0


@dataclass(frozen=True, eq=False)
class ReadProgram:
    """A program as read (module docstring for the frames).

    Attributes:
        format: "rapid", "krl" or "ls".
        files: the files read (KRL: .src then .dat).
        name: module / DEF / /PROG name.
        moves: motion instructions in program order.
        stationary_tool: written for a stationary tool (ABB robhold FALSE tooldata, KUKA
            ``$IPO_MODE = #TCP``, FANUC RTCP moves).
        X_FT, X_RO: (4, 4) frames [m] (None where the program does not state them).
        frame_lines: item -> (file, line) where the tool / work object / load are written.
        load_mass: total carried mass [kg] (tool + workpiece; None if not stated).
        load_cog: (3,) its centre of gravity in F [m] (None if not stated).
        declarations: other data the reader understood (name -> value), for the record.
        header: comment lines of the header.
        io: outputs set, in order: (line, "do"|"ao", port number (KRL, LS) or signal name
            (RAPID), value (DO 0/1, AO as written)).
    """

    format: str
    files: tuple[str, ...]
    name: str
    moves: tuple[ReadMove, ...]
    stationary_tool: bool
    X_FT: np.ndarray | None
    X_RO: np.ndarray | None
    frame_lines: dict = field(default_factory=dict)
    load_mass: float | None = None
    load_cog: np.ndarray | None = None
    declarations: dict = field(default_factory=dict)
    header: tuple[str, ...] = ()
    io: tuple[tuple[int, str, int | str, float], ...] = ()


_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def parse_number(text: str, file: str, line: int, what: str) -> float:
    """A finite number, or a ProgramFormatError naming file, line and item."""
    t = text.strip()
    if not _NUM.fullmatch(t):
        raise ProgramFormatError(f"{file}:{line}: {what}: expected a number, got {t!r}")
    value = float(t)
    if not np.isfinite(value):
        raise ProgramFormatError(f"{file}:{line}: {what}: not finite ({t!r})")
    return value


def split_top_level(text: str, opening: str = "[{(", closing: str = "]})") -> list[str]:
    """Split ``text`` at commas outside brackets and quotes."""
    parts, depth, quote, start = [], 0, False, 0
    for i, ch in enumerate(text):
        if ch == '"':
            quote = not quote
        elif quote:
            continue
        elif ch in opening:
            depth += 1
        elif ch in closing:
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts]
