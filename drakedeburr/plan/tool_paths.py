"""A window's ToolPath by the path and orientation stages: its CL points (the path stage's
adaptive segmentation) and tool axes (the orientation stage), as the planner's targets
(:func:`drakedeburr.plan.planner.window_targets_for_hub`) and the recipe relaxation's milder
variants (:mod:`drakedeburr.plan.relax`) are made."""

from __future__ import annotations

from drakedeburr.config import ProcessParameters

__all__ = ["CL_DELTA", "CL_COUNT_BUDGET", "tool_path", "oriented"]

# CL targets of the real chain: the path stage's ``adaptive`` segmentation at 0.03 mm chord
# height (the executed linear moves stay within it of the edge curve), with the FEWEST points
# that meet it and L_max (count budget 1): long chords on straight edges, short ones in fillets.
# The default budget (the proposed method's count) spreads ~2.3x as many points evenly; the
# robot gains nothing from them (every move is linear and blended), and each costs an IK solve.
CL_DELTA = 0.03e-3
CL_COUNT_BUDGET = 1


def oriented(edge, cl, params: ProcessParameters):
    """The ToolPath of ``edge`` from its CL points ``cl`` (a ClPath) in the box of ``params``:
    the orientation stage alone, its face normals the wall normals nearest to the CL points."""
    from scipy.spatial import cKDTree

    from drakedeburr.orientation.orient import orient_window

    nearest = cKDTree(edge.p_HE).query(cl.p_HC)[1]
    return orient_window(cl, edge.n_wall_H[nearest], params=params)


def tool_path(edge, params: ProcessParameters):
    """CL points and tool axes of one window by the path and orientation stages."""
    from drakedeburr.path import fit_window_edge, plan_cl
    from drakedeburr.path.cl_planning import PlannerParams

    # the interpolating NURBS of a smooth loop, the smoothing fit of a faceted one (a low-poly
    # mesh's edge: facets of >= 3 point spacings joined at tessellation corners, sagitta above
    # the CL chord height), chosen from the points (drakedeburr.path.window_fit)
    # held within the configured chord-height bound of the edge points the verifier reads
    curve = fit_window_edge(edge.p_HE, chord_tolerance=CL_DELTA, edge_tolerance=params.delta_max,
                            name=f"window {edge.index}")
    cl = plan_cl(curve, method="adaptive", params=PlannerParams(delta_max=CL_DELTA,
                                                            count_budget=CL_COUNT_BUDGET),
                 window_index=edge.index, kind=edge.kind)
    return oriented(edge, cl, params)
