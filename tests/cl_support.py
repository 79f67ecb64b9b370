"""Helpers for the CL tests: a 15-path NX CLSF listing built from the two real NX files, and
plain line scans of a CL file that do not use the reader (the independent check)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from drakedeburr.units import INCH_M

NX_FILES = ("MECH491_NX_CLSF__APT_code.txt", "MECH491_NX_CLSF__APT_Variable_Axis.txt")
# MCS variants (origin [inch], X axis, Y axis): identity, shifted, turned 90 and 30 deg about z
_C30, _S30 = math.cos(math.radians(30)), math.sin(math.radians(30))
MSYS_VARIANTS = (
    "MSYS/0.0000,0.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000",
    "MSYS/3.0000,3.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000",
    "MSYS/1.0000,-2.0000,0.5000,0.0000000,1.0000000,0.0000000,-1.0000000,0.0000000,0.0000000",
    f"MSYS/-1.0000,0.5000,0.0000,{_C30:.7f},{_S30:.7f},0.0000000,{-_S30:.7f},{_C30:.7f},0.0000000",
)


def _one_path(extdata: Path, name: str) -> list[str]:
    lines = (extdata / "cl_files" / name).read_text().splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("TOOL PATH/"))
    end = next(i for i, ln in enumerate(lines) if ln.strip() == "END-OF-PATH")
    return lines[start:end + 1]


def nx_multipath(extdata: Path, out: Path, n_paths: int = 15) -> Path:
    """An NX information listing with ``n_paths`` tool paths (the real paths alternately, each
    renamed and given one of :data:`MSYS_VARIANTS`), banner and footer as NX writes them."""
    bodies = [_one_path(extdata, name) for name in NX_FILES]
    text = ["", "Information listing created by\ttester", "Date\t25-Nov-2026 10:00:00",
            "Current work part\tC:\\parts\\hub.prt", "Node name\tcell", ""]
    for k in range(n_paths):
        body = list(bodies[k % 2])
        body[0] = re.sub(r"^TOOL PATH/[^,]*", f"TOOL PATH/OP{k + 1:02d}", body[0])
        body = [MSYS_VARIANTS[k % len(MSYS_VARIANTS)] if ln.startswith("MSYS/") else ln
                for ln in body]
        text += body
    text.append(f"Tool Path Listing has {len(text) + 1} lines.")
    out.write_text("\r\n".join(text) + "\r\n")
    return out


def scan_nx_paths(path: Path) -> list[dict]:
    """Per TOOL PATH: name and GOTO statements (line, numbers, MSYS numbers in force), by a
    plain scan of the lines (no continuation lines in NX listings)."""
    paths: list[dict] = []
    current: dict | None = None
    msys = None
    for n, raw in enumerate(path.read_text().splitlines(), start=1):
        s = raw.strip()
        if s.startswith("TOOL PATH/"):
            current = {"name": s[len("TOOL PATH/"):].split(",")[0], "gotos": [], "start": n}
            paths.append(current)
        elif s.startswith("MSYS/"):
            msys = [float(v) for v in s[5:].split(",")]
        elif s.startswith("GOTO/"):
            current["gotos"].append((n, [float(v) for v in s[5:].split(",")], msys))
        elif s == "END-OF-PATH":
            current["end"] = n
            current = None
    return paths


def msys_point_inch(msys: list[float] | None, xyz: list[float]) -> np.ndarray:
    """Absolute position [m] of an MCS point given in inch: o + x X + y Y + z (X x Y)."""
    p = np.asarray(xyz[:3], float)
    if msys is None:
        return p * INCH_M
    o, X, Y = np.array(msys[:3]), np.array(msys[3:6]), np.array(msys[6:9])
    return (o + p[0] * X + p[1] * Y + p[2] * np.cross(X, Y)) * INCH_M


def goto_lines(path: Path) -> list[int]:
    """Line numbers of GOTO statements (plain scan)."""
    return [n for n, raw in enumerate(path.read_text().splitlines(), start=1)
            if raw.lstrip().upper().startswith("GOTO")]
