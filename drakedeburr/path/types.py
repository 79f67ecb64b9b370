"""Data passed out of the path stage: cutter-location points on one window edge."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drakedeburr.hub.types import WindowKind

__all__ = ["ClPath"]


@dataclass(frozen=True, eq=False)
class ClPath:
    """Cutter-location points planned on one closed window edge.

    Attributes:
        window_index: which window of the hub.
        kind: "large" or "small".
        method: planner name ("proposed", "isoparametric", "equal_chord_height", ...).
        u: (M,) curve parameters of the CL points, increasing, in [0, 1).
        p_HC: (M, 3) CL points in hub frame H [m], in edge order (closed: M-1 -> 0 wraps).
        t_H: (M, 3) unit tangents (feed direction) at the CL points.
        kappa: (M,) curvature at the CL points [1/m].
        arc_length: (M,) arc length from the curve start to each point [m].
        total_length: length of the closed edge [m].
        metrics: count, cv, max_chord_height_m, max_chord_length_m, ... (see path.metrics).
    """

    window_index: int
    kind: WindowKind
    method: str
    u: np.ndarray
    p_HC: np.ndarray
    t_H: np.ndarray
    kappa: np.ndarray
    arc_length: np.ndarray
    total_length: float
    metrics: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.u)
