"""What each window's cut is checked against (the plan's ToolPath, else the hub's ground-truth
edge), and how each program target is executed.

The fallback frames (a plan without a ToolPath) are built from the hub's edge samples: tangent
``t_H`` and wall normal ``n_wall_H``. On an imported mesh a sample beside a tessellated corner
may carry the wall normal of the corner's other side (the probe hit the neighbouring facet),
which turns its frame upside down. The verifier repairs that with the same function the
orientation stage uses (:func:`drakedeburr.orientation.corner_normals.side_consistent_normals`).
That does not make the check depend on the planner: the repair is a property of the mesh's
normals along the hub's own edge (which wall a sample belongs to), not a choice of the plan; it
is applied here to the hub's dense edge loop, independently of the plan's CL points, tangents
or axes, and without a reversal (every smooth loop) it returns the normals bit for bit.

On a steep stretch of the edge (slope to the face plane above
``OrientOptions.max_frame_slope``) the fallback frames follow the orientation stage's physical
rule (:func:`drakedeburr.frames.contact_frames.steep_contact_frames`: the source's frame turned
about the edge bisector by the conical burr's contact), applied to the hub's own dense edge
samples and the window class's box; on a flat loop they are the source's frames bit for bit.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.frames.contact_frames import steep_contact_frames
from drakedeburr.frames.local_frames import R_HL_from_normals
from drakedeburr.orientation.corner_normals import side_consistent_normals
from drakedeburr.orientation.orient import OrientOptions
from drakedeburr.verify.geometry import closed_polyline_distance

__all__ = ["LINEAR_KINDS", "WindowRef", "target_motion", "tool_paths_of", "via_anchors",
           "window_ref", "cone_half_angle", "edge_wall_normals"]

log = logging.getLogger(__name__)

#: the slope [rad] above which the orientation stage's frames follow the contact rule
MAX_FRAME_SLOPE = OrientOptions().max_frame_slope

#: segment kinds executed as linear Cartesian moves unless a target says otherwise
LINEAR_KINDS = ("approach", "cut", "retract")


def target_motion(target) -> str:
    """"linear" or "joint": the target's ``motion`` (plan contract), else by segment kind."""
    motion = getattr(target, "motion", None)
    if motion in ("linear", "joint"):
        return motion
    return "linear" if target.segment in LINEAR_KINDS else "joint"


def tool_paths_of(plan) -> dict:
    tp = plan.tool_path
    if tp is None:
        return {}
    if isinstance(tp, dict):
        return {int(k): v for k, v in tp.items()}
    return {int(t.window_index): t for t in tp}


@dataclass(frozen=True, eq=False)
class WindowRef:
    """What a window's cut is checked against: CL points, local frames, the box, and which
    CL point each target aims at. From the plan's ToolPath, or - when the plan carries none -
    from the hub's ground truth (nearest edge point to each target's tool point)."""

    p_HC: np.ndarray
    R_HL: np.ndarray
    bounds: object
    cl_of: dict
    tool_path: object = None
    source: str = "ToolPath"
    #: via targets (``cl_index`` -1 between CL targets): target -> (CL before, CL after,
    #: share of the travel between their targets), so a via stands for the edge chord point
    via_of: dict = field(default_factory=dict)

    def anchor(self, k: int) -> tuple[int, int, float] | None:
        """The CL point target ``k`` stands for, as (CL a, CL b, share from a to b)."""
        if k in self.cl_of:
            return self.cl_of[k], self.cl_of[k], 0.0
        return self.via_of.get(k)


def via_anchors(targets, w: int, cl_of: dict) -> dict:
    """Via targets of window ``w``: each between the CL targets before and after it, at its
    share of the target polyline's length between them (the verifier's own reading, from the
    targets' tool points; not the planner's ``p_HC``)."""
    out = {}
    ks = [k for k, t in enumerate(targets) if t.window_index == w and t.segment == "cut"
          and t.cl_index < 0]
    for k in ks:
        a = next((j for j in range(k - 1, -1, -1) if j in cl_of), None)
        b = next((j for j in range(k + 1, len(targets)) if j in cl_of), None)
        if a is None or b is None or targets[b].window_index != w:
            continue
        P = np.array([targets[j].X_HT[:3, 3] for j in range(a, b + 1)])
        run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
        out[k] = (cl_of[a], cl_of[b], float(run[k - a] / max(run[-1], 1e-15)))
    return out


def window_ref(w, targets, tool_path, edge, params) -> WindowRef | None:
    ks = [k for k, t in enumerate(targets) if t.window_index == w and t.segment == "cut"]
    if tool_path is not None:
        cl_of = {k: int(targets[k].cl_index) for k in range(len(targets))
                 if targets[k].window_index == w and targets[k].cl_index >= 0}
        bounds = getattr(tool_path, "bounds", None) or (
            params.bounds(edge.kind))
        return WindowRef(np.asarray(tool_path.p_HC, float), np.asarray(tool_path.R_HL, float),
                          bounds, cl_of, tool_path, via_of=via_anchors(targets, w, cl_of))
    if edge is None or edge.t_H is None or edge.n_wall_H is None or not ks:
        return None
    from scipy.spatial import cKDTree

    p_E = np.asarray(edge.p_HE, float)
    # the targets of the cut loop (the one before the first cut target starts the loop)
    loop = [ks[0] - 1] + ks if ks[0] >= 1 else ks
    p_T = np.array([targets[k].X_HT[:3, 3] for k in loop])
    _, C = closed_polyline_distance(p_T, p_E)
    _, v = cKDTree(p_E).query(C)
    n_E = edge_wall_normals(edge, w)
    # the project's one definition of the local frames (frames.local_frames, right-handed)
    # (row by row: built on the CL points' nearest edge samples only)
    bounds = params.bounds(edge.kind)
    t_v, n_v = np.asarray(edge.t_H, float)[v], n_E[v]
    R_HL = steep_contact_frames(R_HL_from_normals(t_v, n_v, name=f"window {w}"), t_v, n_v,
                                bounds.theta_min, bounds.theta_max, MAX_FRAME_SLOPE,
                                name=f"window {w}")
    # a closed loop ends on its first point: one CL point for both
    unique, cl_of = [], {}
    for i, k in enumerate(loop):
        j = next((u for u, c in enumerate(unique) if np.linalg.norm(C[c] - C[i]) < 1e-6), None)
        if j is None:
            unique.append(i)
            j = len(unique) - 1
        cl_of[k] = j
    sel = np.asarray(unique)
    return WindowRef(C[sel], R_HL[sel], bounds, cl_of, None,
                      "hub edge (the plan carries no ToolPath)")


def edge_wall_normals(edge, w: int) -> np.ndarray:
    """(N, 3) the hub edge's wall normals, a sample that took its normal from across a
    tessellated corner given its neighbour's (see the module docstring); the loop is closed."""
    n_E, fixed = side_consistent_normals(np.asarray(edge.t_H, float),
                                         np.asarray(edge.n_wall_H, float), closed=True)
    if fixed:
        log.debug("window %d: hub edge samples %s took the wall normal from across a corner: "
                  "the neighbour's carried over for the reference frames", w, fixed)
    return n_E


def cone_half_angle(plan, window: int, tool_path) -> float:
    """The cone half-angle the plan was made with (recorded per window by the planner), else
    the ToolPath's enclosing cone (the planner's default mapping)."""
    for st in (plan.meta or {}).get("windows", []):
        if (isinstance(st, dict) and int(st.get("window", -1)) == int(window)
                and "cone_half_angle_rad" in st):
            return float(st["cone_half_angle_rad"])
    return float(getattr(tool_path, "cone_outer_half_angle", tool_path.cone_half_angle))
