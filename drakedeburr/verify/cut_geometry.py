"""What the burr does to the edge along each cut, recomputed from the executed tool poses.

Per cut sample: the executed contact point C (the tool pose times the target's tool-to-CL
offset, interpolated along the move), its distance to the hub's ground-truth edge, the edge
point's depth inside the burr cone (engagement), the executed axis' theta_A/theta_B in the
interpolated local frame (the source's box) and its margin to the IK's cone. theta_A =
atan2(a.N, a.B), theta_B = asin(-a.T) for the axis a in the local frame [N, T, B]
(docs/orientation.md), recomputed from :mod:`drakedeburr.frames.local_frames`.

Apart from the dense samples, :func:`target_cones` reads the program's own targets: the axis of
each target from the forward kinematics of the joints the program is written with, against the
cone of the CL point the target cuts (a via target: the chord point's cone, as the samples read
it). A target outside its cone fails the ``cone`` check whatever the interpolation between the
targets reads.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from drakedeburr.frames.local_frames import angles_from_zT_H
from drakedeburr.verify.geometry import closed_polyline_distance, lerp_frames, point_segment
from drakedeburr.verify.refs import cone_half_angle

__all__ = ["cut_geometry", "stretch_coverage", "target_cones", "axis_angle"]


def _anchored(ref, k0: np.ndarray, k1: np.ndarray, f: np.ndarray) -> dict | None:
    """The CL point each move end stands for (a via target: the chord point between its CL
    points) -> the arrays of the moves ``k0 -> k1`` at shares ``f``; None if a target has no
    anchor."""
    anchors = {int(k): ref.anchor(int(k)) for k in np.unique(np.concatenate([k0, k1]))}
    if any(a is None for a in anchors.values()):
        return None
    an0 = np.array([anchors[int(k)] for k in k0])
    an1 = np.array([anchors[int(k)] for k in k1])
    out = {"ca0": an0[:, 0].astype(int), "cb0": an0[:, 1].astype(int), "g0": an0[:, 2],
           "ca1": an1[:, 0].astype(int), "cb1": an1[:, 1].astype(int), "g1": an1[:, 2], "f": f}
    p = ref.p_HC
    out["P0"] = (1 - out["g0"])[:, None] * p[out["ca0"]] + out["g0"][:, None] * p[out["cb0"]]
    out["P1"] = (1 - out["g1"])[:, None] * p[out["ca1"]] + out["g1"][:, None] * p[out["cb1"]]
    return out


def _contact(targets, k0, k1, a: dict, X_HT: np.ndarray) -> np.ndarray:
    """(n, 3) executed contact points: the tool-to-CL offset of the move's two targets,
    interpolated at the move's share and carried by the executed tool pose."""
    def p_TC(k, p):
        X = np.asarray(targets[k].X_HT)
        return X[:3, :3].T @ (p - X[:3, 3])

    off = np.array([(1 - fi) * p_TC(ka, pa) + fi * p_TC(kb, pb)
                    for ka, kb, pa, pb, fi in zip(k0, k1, a["P0"], a["P1"], a["f"], strict=True)])
    return np.einsum("nij,nj->ni", X_HT[:, :3, :3], off) + X_HT[:, :3, 3]


def _engagement(X_HT: np.ndarray, E: np.ndarray) -> np.ndarray:
    """Depth of the true edge points ``E`` inside the burr's cone, normal to its flank [m]."""
    from drakedeburr.cell.tools import BURR

    R = X_HT[:, :3, :3]
    p_TE = np.einsum("nji,nj->ni", R, E - X_HT[:, :3, 3])
    r = np.linalg.norm(p_TE[:, :2], axis=1)
    alpha = BURR.cone_half_angle
    return ((BURR.apex_offset - p_TE[:, 2]) * np.tan(alpha) - r) * np.cos(alpha)


def axis_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle [rad] between the directions ``a`` and ``b`` (n, 3), by atan2 (exact near 0)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _chord_axes(c_H: np.ndarray, ca: np.ndarray, cb: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Unit cone axes at chord points: the CL points ``ca``/``cb``'s axes ``c_H`` mixed by
    ``g`` (the samples' and the targets' reading of the cone between two CL points)."""
    return _unit((1 - g)[:, None] * c_H[ca] + g[:, None] * c_H[cb])


def target_cones(plan, X_HT_targets: np.ndarray, refs: dict, cut_windows) -> dict:
    """Margin [rad] of each program target's own tool axis (+Z_T of ``X_HT_targets``, the FK of
    the targets' joints) to the cone of the CL point it cuts (module docstring): ``{"margin":
    (M,) NaN off the cut targets, "per_window": {window: figures}}``. A via target reads the
    cone at its chord point (its two CL points' cone axes interpolated); a plan without cone
    axes is read against the theta box in the CL points' local frames, as the samples are."""
    targets = plan.targets
    margin = np.full(len(targets), np.nan)
    per_window = {}
    for w in cut_windows:
        ref = refs.get(w)
        if ref is None:
            continue
        ks = [k for k, t in enumerate(targets)
              if t.window_index == w and ref.anchor(k) is not None]
        if not ks:
            continue
        an = np.array([ref.anchor(k) for k in ks], float)
        ca, cb, g = an[:, 0].astype(int), an[:, 1].astype(int), an[:, 2]
        z = _unit(np.asarray(X_HT_targets, float)[ks, :3, 2])
        tp = ref.tool_path
        if tp is not None and getattr(tp, "cone_zT_H", None) is not None:
            half = cone_half_angle(plan, w, tp)
            m = half - axis_angle(_chord_axes(np.asarray(tp.cone_zT_H, float), ca, cb, g), z)
            info = {"cone_half_angle": half}
        else:
            tA, tB = angles_from_zT_H(lerp_frames(ref.R_HL[ca], ref.R_HL[cb], g), z)
            lo, hi = ref.bounds.theta_min, ref.bounds.theta_max
            m = np.minimum.reduce([tA - lo, hi - tA, tB - lo, hi - tB])
            info = {"cone": "no cone axes in the plan: the theta box is checked"}
        margin[ks] = m
        j = int(np.argmin(m))
        per_window[w] = {"targets": len(ks), "target_min_margin": float(m[j]),
                         "target_worst": int(ks[j]),
                         "target_worst_cl": int(ca[j]) if ca[j] == cb[j] else -1, **info}
    return {"margin": margin, "per_window": per_window}


def _cone(plan, w: int, ref, a: dict, z_T: np.ndarray, box_margin: np.ndarray):
    """Margin of the executed +Z_T to the IK's cone about the interpolated cone axis [rad] and
    the window's cone figures (the theta box stands in when the plan has no cone axes)."""
    tp = ref.tool_path
    if tp is None or getattr(tp, "cone_zT_H", None) is None:
        return box_margin, {"cone": "no cone axes in the plan: the theta box is checked"}
    half = cone_half_angle(plan, w, tp)
    c_H = np.asarray(tp.cone_zT_H, float)
    c0 = _chord_axes(c_H, a["ca0"], a["cb0"], a["g0"])
    c1 = _chord_axes(c_H, a["ca1"], a["cb1"], a["g1"])
    f = a["f"]
    ang = axis_angle(_unit((1 - f)[:, None] * c0 + f[:, None] * c1), z_T)
    return half - ang, {"cone_half_angle": half, "max_angle_to_cone_axis": float(ang.max())}


def _window(plan, samples, program, ref, edge: np.ndarray, idx: np.ndarray, out: dict,
            tol) -> None:
    """Fill ``out`` for the samples ``idx`` of one window's cut."""
    k1 = program.move[idx]
    k0 = k1 - 1
    w = int(samples.window[idx[0]])
    a = _anchored(ref, k0, k1, program.fraction[idx])
    if a is None:
        return
    X = samples.X_HT[idx]
    C = _contact(plan.targets, k0, k1, a, X)
    out["contact"][idx] = C
    d, E = closed_polyline_distance(C, edge, cKDTree(edge))
    out["edge_dev"][idx] = d
    out["engagement"][idx] = _engagement(X, E)
    dc = point_segment(edge, C[:-1], C[1:])[0] if len(C) > 1 else np.array([np.inf])
    jc = int(np.argmax(dc))
    out["coverage"][w] = (float(dc[jc]), jc)
    # theta box: executed axis in the interpolated local frame (the source's bounds)
    R_loc = lerp_frames(lerp_frames(ref.R_HL[a["ca0"]], ref.R_HL[a["cb0"]], a["g0"]),
                        lerp_frames(ref.R_HL[a["ca1"]], ref.R_HL[a["cb1"]], a["g1"]), a["f"])
    tA, tB = angles_from_zT_H(R_loc, X[:, :3, 2])  # the executed +Z_T
    out["theta_A"][idx], out["theta_B"][idx] = tA, tB
    lo, hi = ref.bounds.theta_min, ref.bounds.theta_max
    box = np.minimum.reduce([tA - lo, hi - tA, tB - lo, hi - tB])
    out["box_margin"][idx] = box
    out["cone_margin"][idx], cone_info = _cone(plan, w, ref, a, X[:, :3, 2], box)
    out["cone_per_window"][w] = {"bounds": [lo, hi], "reference": ref.source, **cone_info}
    out["s_cut"][idx] = np.concatenate([[0.0], np.cumsum(np.linalg.norm(
        np.diff(samples.p_HT[idx], axis=0), axis=1))])


def _window_figures(out: dict, idx: np.ndarray, tol, half: float | None) -> dict:
    """The cone figures of a window's samples ``idx`` read (all its stretches; ``half``: the
    cone's half-angle, None where the theta box stands in)."""
    i = idx[np.isfinite(out["theta_A"][idx])]
    tA, tB, box = out["theta_A"][i], out["theta_B"][i], out["box_margin"][i]
    fig = {"theta_A_min": float(tA.min()), "theta_A_max": float(tA.max()),
           "theta_B_min": float(tB.min()), "theta_B_max": float(tB.max()),
           "in_box_share": float(np.mean(box >= -tol.cone_slack)), "samples": len(i),
           "sample_min_margin": float(np.min(out["cone_margin"][i]))}
    if half is not None:
        fig["max_angle_to_cone_axis"] = float(half - fig["sample_min_margin"])
    return fig


def cut_geometry(plan, samples, program, refs: dict, edge_of: dict, cut_windows, tol):
    """:class:`drakedeburr.verify.types.CutGeometry` of every cut (module docstring)."""
    from drakedeburr.verify.types import KIND_CODE, CutGeometry

    n = len(samples)
    out = {name: np.full(n, np.nan) for name in ("edge_dev", "engagement", "theta_A",
                                                 "theta_B", "cone_margin", "box_margin",
                                                 "s_cut")}
    out.update(contact=np.full((n, 3), np.nan), coverage={}, cone_per_window={})
    from drakedeburr.verify.checks_plan import partial_windows

    partial = set(partial_windows(plan))
    for w in cut_windows:
        ref = refs.get(w)
        if ref is None or w not in edge_of:
            continue
        idx = np.flatnonzero((samples.window == w) & (samples.kind == KIND_CODE["cut"])
                             & (program.move >= 1))
        if not len(idx):
            continue
        edge = np.asarray(edge_of[w].p_HE, float)
        # a partial window (plan.partial) cuts open stretches: each its own samples, the edge
        # it leaves uncut not counted in its coverage
        chunks = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
        for chunk in chunks:
            _window(plan, samples, program, ref, edge, chunk, out, tol)
        if w in out["cone_per_window"]:  # over every stretch of a partial window
            info = out["cone_per_window"][w]
            info.update(_window_figures(out, idx, tol, info.get("cone_half_angle")))
        if w in partial:
            whole = ref.tool_path is not None
            out["coverage"][w] = stretch_coverage(
                plan.targets, program.move, chunks, out["contact"], edge,
                ref.p_HC if whole else None, ref.cl_of if whole else None)
    return CutGeometry(**out)


def stretch_coverage(targets, move: np.ndarray, chunks: list, contact: np.ndarray,
                     edge: np.ndarray, loop_cl: np.ndarray | None = None,
                     cl_of: dict | None = None) -> tuple[float, int]:
    """(farthest gap [m], edge point) of the edge points a window's open stretches cut from
    their executed contact paths: each edge point is given to the CL point nearest to it; it
    is checked against its stretch when that CL point is inside the stretch (not its first or
    last), so the edge left uncut (before, between and after the stretches) is not counted
    here: the plan's partial record says it is uncut (``uncut_edge``).

    With ``loop_cl`` (the whole loop's CL points, the plan's ToolPath) and ``cl_of`` (target
    -> its CL index) the nearest CL point is sought over the whole loop, the uncut ones too:
    on a 3-D loop (down a spoke flank and back) an uncut edge point can lie nearer to a cut
    stretch's CL point than to the rest of the loop's and be read as a 40 mm gap of that
    stretch (audibot rim window 2). Without them, over the stretches' own CL targets."""
    from scipy.spatial import cKDTree

    whole = loop_cl is not None and cl_of is not None
    per_chunk, loop = [], list(loop_cl) if whole else []
    for chunk in chunks:
        ks = sorted(set(int(k) for k in move[chunk]) | {int(move[chunk][0]) - 1})
        if whole:
            per_chunk.append([cl_of[k] for k in ks if k in cl_of])
            continue
        # no ToolPath: the stretches' own CL targets stand for the loop's CL points
        pts = [targets[k].p_HC for k in ks if targets[k].p_HC is not None]
        per_chunk.append(list(range(len(loop), len(loop) + len(pts))))
        loop += pts
    of = np.full(len(loop), -1)  # each CL point: the stretch it is inside of, or -1
    for c, ids in enumerate(per_chunk):
        of[ids[1:-1]] = c
    _, near = cKDTree(np.asarray(loop, float)).query(edge)
    label = of[near]
    inner = label >= 0
    worst = (0.0, -1)
    for c, chunk in enumerate(chunks):
        sel = np.flatnonzero(inner & (label == c))
        C = contact[chunk]
        if not sel.size or len(C) < 2:
            continue
        dc = point_segment(edge[sel], C[:-1], C[1:])[0]
        j = int(np.argmax(dc))
        if dc[j] > worst[0] or worst[1] < 0:
            worst = (float(dc[j]), int(sel[j]))
    return worst
