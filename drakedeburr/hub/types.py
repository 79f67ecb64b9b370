"""Data passed out of the hub stage (shared contract of every later stage).

Frames: H is the hub frame: origin on the hub axis at the front (visible) face, +Z along the
axle out of the visible face. Window edge loops are ordered counter-clockwise seen from +Z_H.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

__all__ = ["WindowKind", "WindowEdge", "ScanCloud"]

WindowKind = Literal["large", "small"]


@dataclass(frozen=True, eq=False)
class WindowEdge:
    """The closed edge where the hub's front face meets one window (through-opening).

    Attributes:
        index: window number, 0-based, counter-clockwise about +Z_H from +X_H.
        kind: "large" or "small" (sets depth of cut and orientation bounds).
        p_HE: (N, 3) loop points in H [m], counter-clockwise seen from +Z_H; the first point is
            not repeated at the end.
        t_H: (N, 3) unit tangents in loop order, or None when unknown.
        n_wall_H: (N, 3) unit normal of the window's side wall at each point, pointing out of the
            material into the opening (the source's "inner-side normal"), or None when unknown.
        n_face_H: (N, 3) unit outward normal of the front face at each point, or None.
    """

    index: int
    kind: WindowKind
    p_HE: np.ndarray
    t_H: np.ndarray | None = None
    n_wall_H: np.ndarray | None = None
    n_face_H: np.ndarray | None = None

    def __post_init__(self) -> None:
        p = np.asarray(self.p_HE, float)
        if p.ndim != 2 or p.shape[1] != 3 or len(p) < 4:
            raise ValueError(f"window {self.index}: p_HE must be (N>=4, 3), got {p.shape}")
        if self.kind not in ("large", "small"):
            raise ValueError(f"window {self.index}: kind must be 'large' or 'small', "
                             f"got {self.kind!r}")


@dataclass(frozen=True, eq=False)
class ScanCloud:
    """A (simulated or real) scan of a hub.

    Attributes:
        p_S: (N, 3) points [m] in the scan's frame S (H for a simulated scan in place).
        n_S: (N, 3) unit normals, or None when the scanner gives none.
        source: where it came from (file path or description), for messages.
    """

    p_S: np.ndarray
    n_S: np.ndarray | None = None
    source: str = ""
    meta: dict = field(default_factory=dict)
