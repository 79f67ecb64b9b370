"""The one place where SI meets the industry's millimetres and degrees.

Inside drakedeburr everything is metres, radians and seconds. Robot programs, CL files and
reports speak millimetres and degrees; convert with these functions at those boundaries only.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "MM_PER_M",
    "INCH_M",
    "m_from_mm",
    "mm_from_m",
    "rad_from_deg",
    "deg_from_rad",
    "m_from_inch",
    "mm_s_from_m_s",
    "m_s_from_mm_s",
]

MM_PER_M = 1000.0
INCH_M = 0.0254


def m_from_mm(x):
    """Millimetres -> metres (scalars or arrays)."""
    return np.asarray(x, dtype=float) / MM_PER_M if not np.isscalar(x) else float(x) / MM_PER_M


def mm_from_m(x):
    """Metres -> millimetres (scalars or arrays)."""
    return np.asarray(x, dtype=float) * MM_PER_M if not np.isscalar(x) else float(x) * MM_PER_M


def rad_from_deg(x):
    return np.deg2rad(x) if not np.isscalar(x) else float(np.deg2rad(x))


def deg_from_rad(x):
    return np.rad2deg(x) if not np.isscalar(x) else float(np.rad2deg(x))


def m_from_inch(x):
    return np.asarray(x, dtype=float) * INCH_M if not np.isscalar(x) else float(x) * INCH_M


def mm_s_from_m_s(v):
    return mm_from_m(v)


def m_s_from_mm_s(v):
    return m_from_mm(v)
