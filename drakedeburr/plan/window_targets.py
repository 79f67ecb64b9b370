"""What the planner needs of one window: CL points, inner normals, axes, cone, depth of cut.

The planner reads only these fields, so it can be fed by the orientation stage's ``ToolPath``
(:meth:`WindowTargets.from_tool_path`) or, without the upstream stages, straight from a hub's
ground-truth window edge with a fixed tilt (:meth:`WindowTargets.from_window_edge`; used by
tests, benchmarks and as a fallback).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from drakedeburr.config import ProcessParameters
from drakedeburr.errors import InputError

__all__ = ["WindowTargets"]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True, eq=False)
class WindowTargets:
    """One window's process targets, all in the hub frame H.

    Attributes:
        window_index: window number; kind: "large" | "small".
        p_HC: (M, 3) CL (edge) points [m], in loop order (closed: M-1 -> 0).
        t_H: (M, 3) unit feed tangents.
        n_H: (M, 3) unit inner normals (out of the material into the opening).
        retract_H: (M, 3) preferred unit tool axes, tip -> spindle (-Z_T: the way the tool
            is pulled out of the cut; the ToolPath's ``zT_H`` is +Z_T).
        cone_retract_H: (M, 3) admissible cone axes (tip -> spindle); cone_half_angle: [rad].
        depth_of_cut: [m].
        source: what these came from (for the plan's metadata).
        tool_path: the ToolPath they came from, if any.
        closed: the edge is a closed loop (the cut returns to the first point); an open
            stretch (e.g. a part of a window, :meth:`stretch`) ends at its last point.
    """

    window_index: int
    kind: str
    p_HC: np.ndarray
    t_H: np.ndarray
    n_H: np.ndarray
    retract_H: np.ndarray
    cone_retract_H: np.ndarray
    cone_half_angle: float
    depth_of_cut: float
    source: str = ""
    tool_path: object = field(default=None, repr=False)
    closed: bool = True

    def __len__(self) -> int:
        return len(self.p_HC)

    def __post_init__(self) -> None:
        m = len(self.p_HC)
        for name in ("p_HC", "t_H", "n_H", "retract_H", "cone_retract_H"):
            arr = np.asarray(getattr(self, name), float)
            if arr.shape != (m, 3) or not np.all(np.isfinite(arr)):
                raise InputError(f"window {self.window_index}: {name} must be finite ({m}, 3), "
                                 f"got {arr.shape}")
        if m < 3:
            raise InputError(f"window {self.window_index}: needs at least 3 CL points, got {m}")
        if not 0.0 < self.cone_half_angle < np.pi / 2:
            raise InputError(f"window {self.window_index}: cone_half_angle must be in (0, pi/2) "
                             f"rad, got {self.cone_half_angle}")
        # the tool must come from the visible side: the axis points out of the material
        # (toward the spindle), i.e. away from the side wall's material and up from the face
        bad = np.flatnonzero(np.sum(self.retract_H * self.cone_retract_H, axis=1)
                             < np.cos(np.pi / 3))
        if bad.size:
            raise InputError(f"window {self.window_index}: preferred axis more than 60 deg from "
                             f"the cone axis at CL point {int(bad[0])}")

    def stretch(self, start: int, stop: int) -> WindowTargets:
        """The open stretch of CL points ``start..stop-1`` (for partial plans and tests)."""
        return self.points(np.arange(len(self))[start:stop])  # slice semantics

    def points(self, indices) -> WindowTargets:
        """The open stretch of the CL points ``indices``, in that order (a stretch of a closed
        loop may wrap past M-1 -> 0)."""
        idx = np.asarray(indices, int)
        return replace(self, p_HC=self.p_HC[idx], t_H=self.t_H[idx], n_H=self.n_H[idx],
                       retract_H=self.retract_H[idx], cone_retract_H=self.cone_retract_H[idx],
                       closed=False, source=f"{self.source} [CL {int(idx[0])}..{int(idx[-1])}]")

    @classmethod
    def from_tool_path(cls, tool_path, *, face_normal_H: np.ndarray | None = None,
                       cone_mapping: str = "outer") -> WindowTargets:
        """From the orientation stage's ToolPath (``drakedeburr.orientation.ToolPath``).

        Args:
            tool_path: has ``window_index, kind, p_HC, R_HL, zT_H, cone_zT_H,
                cone_half_angle, depth_of_cut``; ``zT_H``/``cone_zT_H`` are +Z_T
                (spindle -> tip, the ToolPath convention) and are flipped here.
            face_normal_H: (3,) outward normal of the visible face (default +Z_H): the tool
                axes must point to that side (the burr comes from the front).
            cone_mapping: which cone stands for the (theta_A, theta_B) box in the IK and in the
                verification (both use the same one): "outer" (default) the smallest cone about
                the box centre containing the whole box (``cone_outer_half_angle``), "inner"
                the largest cone inside it (``cone_half_angle``). See docs/plan.md, "From the
                theta box to the IK cone".

        Raises:
            InputError: axes pointing into the hub (names the window and point).
        """
        tp = tool_path
        face = (np.array([0.0, 0.0, 1.0]) if face_normal_H is None
                else _unit(np.asarray(face_normal_H, float)))
        # the ToolPath's zT_H / cone_zT_H are +Z_T (spindle -> tip); ours point tip -> spindle
        axis = -_unit(np.asarray(tp.zT_H, float))
        cone = -_unit(np.asarray(tp.cone_zT_H, float))
        if cone_mapping not in ("outer", "inner"):
            raise InputError(f"cone_mapping must be 'outer' or 'inner', got {cone_mapping!r}")
        half = float(tp.cone_outer_half_angle if cone_mapping == "outer" else tp.cone_half_angle)
        bad = np.flatnonzero(axis @ face <= 0.0)
        if bad.size:
            where = np.round(np.asarray(tp.p_HC)[bad[0]] * 1e3, 1).tolist()
            raise InputError(f"ToolPath of window {tp.window_index}: tool axis (tip -> spindle) "
                             f"points into the hub at CL point {int(bad[0])} at {where} mm "
                             f"(axis {np.round(axis[bad[0]], 3).tolist()}, face normal "
                             f"{face.tolist()}){_why_into_hub(tp, int(bad[0]), axis, face)}")
        return cls(window_index=int(tp.window_index), kind=str(tp.kind),
                   p_HC=np.asarray(tp.p_HC, float), t_H=_unit(np.asarray(tp.R_HL)[:, :, 1]),
                   n_H=_unit(np.asarray(tp.R_HL)[:, :, 0]), retract_H=axis, cone_retract_H=cone,
                   cone_half_angle=half, depth_of_cut=float(tp.depth_of_cut),
                   source=f"ToolPath ({getattr(tp, 'model', '')}/{getattr(tp, 'solver', '')})",
                   tool_path=tp)

    @classmethod
    def from_window_edge(cls, edge, *, spacing: float = 1.5e-3, tilt: float | None = None,
                         cone_half_angle: float = 0.08,
                         params: ProcessParameters | None = None) -> WindowTargets:
        """Stand-in targets from a hub's ground-truth window edge (``WindowEdge``).

        CL points every ``spacing`` of arc length; the preferred axis is the face normal tilted
        by ``tilt`` toward the opening (default: the middle of the window kind's theta bounds),
        which is also the cone axis.

        Args:
            edge: ``drakedeburr.hub.types.WindowEdge`` with ``t_H``, ``n_wall_H``, ``n_face_H``.
            spacing: arc length between CL points [m].
            tilt: theta_A [rad]; cone_half_angle: [rad].
        """
        params = params or ProcessParameters()
        if edge.n_wall_H is None or edge.n_face_H is None:
            raise InputError(f"window {edge.index}: the edge has no wall/face normals")
        p = np.asarray(edge.p_HE, float)
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        total = s[-1]
        m = max(int(np.ceil(total / spacing)), 8)
        s_cl = np.linspace(0.0, total, m, endpoint=False)
        idx = np.searchsorted(s, s_cl, side="right") - 1
        frac = ((s_cl - s[idx]) / np.maximum(seg[idx], 1e-15))[:, None]
        nxt = (idx + 1) % len(p)
        p_HC = (1 - frac) * p[idx] + frac * p[nxt]

        def lerp(v):
            v = np.asarray(v, float)
            return _unit((1 - frac) * v[idx] + frac * v[nxt])

        t = lerp(edge.t_H) if edge.t_H is not None else _unit(p[nxt] - p[idx])
        n_wall, n_face = lerp(edge.n_wall_H), lerp(edge.n_face_H)
        bounds = params.bounds_large if edge.kind == "large" else params.bounds_small
        th = 0.5 * (bounds.theta_min + bounds.theta_max) if tilt is None else float(tilt)
        n_perp = _unit(n_wall - np.sum(n_wall * n_face, axis=1, keepdims=True) * n_face)
        axis = _unit(np.cos(th) * n_face + np.sin(th) * n_perp)
        depth = params.depth_of_cut_large if edge.kind == "large" else params.depth_of_cut_small
        return cls(window_index=int(edge.index), kind=str(edge.kind), p_HC=p_HC, t_H=t,
                   n_H=n_wall, retract_H=axis, cone_retract_H=axis.copy(),
                   cone_half_angle=float(cone_half_angle), depth_of_cut=float(depth),
                   source=f"window edge, fixed tilt {th:.3f} rad")


def _why_into_hub(tp, i: int, axis: np.ndarray, face: np.ndarray) -> str:
    """What the geometry at CL point ``i`` is where the ToolPath's axis points into the hub:
    a steep stretch (slope > 45 deg) or a corner (the tangent's turn over the neighbouring CL
    points, the inner normal's angle to the face plane there and on either side, and by how
    much the recipe's box about that frame leaves the axis below the face plane)."""
    R = np.asarray(tp.R_HL)
    p = np.asarray(tp.p_HC)
    m = len(p)
    t = _unit(R[:, :, 1])
    slope = float(np.degrees(np.arcsin(min(1.0, abs(float(t[i] @ face))))))
    if slope > 45.0:
        return (f": the edge there runs at {slope:.0f} deg to the face plane (down a flank, "
                f"along the hub axis): an axis across the edge is at least {slope:.0f} deg "
                f"off the face normal, beyond the recipe's tilt and lead, so a burr coming "
                f"from the front cannot follow it")
    a, b = (i - 1) % m, (i + 1) % m
    turn = float(np.degrees(np.arccos(np.clip(t[a] @ t[b], -1.0, 1.0))))
    span = 1e3 * float(np.linalg.norm(p[i] - p[a]) + np.linalg.norm(p[b] - p[i]))
    tilt = np.degrees(np.arcsin(np.clip(_unit(R[[a, i, b], :, 0]) @ face, -1.0, 1.0)))
    below = float(np.degrees(np.arcsin(min(1.0, -float(axis[i] @ face)))))
    return (f": a corner of the loop (the edge turns {turn:.0f} deg within {span:.1f} mm, "
            f"slope {slope:.0f} deg) where the inner normal is {tilt[1]:+.0f} deg to the face "
            f"plane ({tilt[0]:+.0f} and {tilt[2]:+.0f} deg at the CL points on either side); "
            f"the recipe's tilt/lead box about that frame leaves the axis {below:.1f} deg below "
            f"the face plane: the box would have to tilt more than {below:.1f} deg toward the "
            f"face normal there")
