"""plan.window.tool_refusal and plan.clearance (ToolScene, tool_axis_clearance) on a real wheel:
the audibot rim of ../shared/extdata (issue 42).

On that rim the large windows' loops run 47-55 mm down the spoke flanks; at many CL points of
a large window no tool axis of the recipe's cone keeps the round tool parts (shank, collet, spindle
body) off the part, whatever the arm does. The window must be refused before the IK with that
reason, and the reason must hold up: the penetration is re-checked here on the RAW mesh (the
file's triangles, not the collision pieces) with an independent measure (surface points of the
mesh inside the tool's cylinders), at axes sampled independently of the planner's (random axes
in the cone, seeded).
"""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pytest

import drakedeburr.plan.window as mut

AUDIBOT = "wheel_models/audibot__wheel_rim_only_DERIVED_m.stl"
# a large window whose loop runs down the spoke flanks (window 1, the same shape, keeps one
# corner point whose axis the orientation stage leaves under the face plane: no targets)
WINDOW = 2

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def audibot(tmp_path_factory, extdata):
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import default_tolerances
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.hub.model import load_hub
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.planner import window_targets_for_hub

    res = import_mesh(extdata / AUDIBOT, tmp_path_factory.mktemp("audibot"))
    hub = load_hub(res.dir)
    cell = load_cell("tool_in_hand", res.dir)
    checker = ClearanceChecker(cell)
    ctx = PlanContext(cell=cell, kin=cell_kinematics(cell), checker=checker, free_checker=None,
                      config=SimpleNamespace(tolerances=default_tolerances()),
                      options=PlanOptions())
    wt = window_targets_for_hub(hub, windows=[WINDOW], skipped=[])[0]
    return SimpleNamespace(hub=hub, cell=cell, ctx=ctx, wt=wt)


def _surface_points(hub, spacing: float = 1.5e-3) -> np.ndarray:
    """Points on the raw mesh's triangles, about ``spacing`` apart (deterministic)."""
    V, F = np.asarray(hub.vertices_H, float), np.asarray(hub.faces, int)
    out = [V]
    for a, b, c in V[F]:
        n = int(np.ceil(max(np.linalg.norm(b - a), np.linalg.norm(c - a)) / spacing))
        if n < 2:
            continue
        u, v = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
        keep = u + v <= 1.0
        out.append(a + np.outer(u[keep], b - a) + np.outer(v[keep], c - a))
    return np.vstack(out)


def _cylinders():
    """The round tool parts as (radius, z_from, z_to) along the axis from T toward the
    spindle [m], from the tool's own numbers (cell.tools), not from the collision model."""
    from drakedeburr.cell.tools import BURR, FLOATING_SPINDLE

    base = (BURR.head_radius - BURR.contact_radius) / np.tan(BURR.cone_half_angle)
    shank = (0.5 * BURR.shank_diameter, base, base + BURR.stick_out)
    top = base + BURR.stick_out
    collet = (0.5 * BURR.collet_diameter, top, top + BURR.collet_length)
    top += BURR.collet_length
    body = (0.5 * FLOATING_SPINDLE.body_diameter, top, top + FLOATING_SPINDLE.body_length)
    return {"burr_shank": shank, "collet": collet, "spindle_body": body}


def _depth_inside(P: np.ndarray, p_T: np.ndarray, a: np.ndarray, cyl) -> float:
    """Deepest point of ``P`` inside the cylinder (radius, z0, z1) on the axis ``a`` (unit,
    tip -> spindle) from ``p_T``: its distance to the cylinder's boundary [m] (<= 0: none
    inside)."""
    r, z0, z1 = cyl
    d = P - p_T
    z = d @ a
    rho = np.linalg.norm(d - np.outer(z, a), axis=1)
    depth = np.minimum.reduce([r - rho, z - z0, z1 - z])
    return float(depth.max())


def _axes_in_cone(c: np.ndarray, half: float, n: int, rng) -> np.ndarray:
    """``n`` random unit axes uniformly in the cone of ``half`` about ``c`` (and ``c``)."""
    from drakedeburr.frames.vectors import perpendicular_basis

    e1, e2, _ = perpendicular_basis(c).T
    cos_t = rng.uniform(np.cos(half), 1.0, n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    s = np.sqrt(1 - cos_t ** 2)
    A = cos_t[:, None] * c + s[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
    return np.vstack([c, A])


def test_a_large_window_refused_before_its_ik_with_the_physical_reason(audibot):
    from drakedeburr.plan.results import WindowStatus

    ctx, wt = audibot.ctx, audibot.wt
    rec = mut.tool_refusal(ctx, wt)
    assert rec is not None and rec.window == WINDOW and rec.kind == "window"
    m = re.search(r"at (\d+) of (\d+) CL points every tool axis within the ([\d.]+) deg cone "
                  r"puts the ([a-z_/]+) up to ([\d.]+) mm \(median ([\d.]+) mm\) inside the part "
                  r"at (\d+) of them .* the worst at CL (\d+), .* runs at (\d+) deg to the face",
                  rec.reason)
    assert m, rec.reason
    blocked, total = int(m[1]), int(m[2])
    assert total == len(wt) and blocked == len(rec.where["blocked_points"]) >= 20
    assert float(m[3]) == pytest.approx(np.degrees(wt.cone_half_angle), abs=0.05)
    assert "spindle_body" in m[4]
    assert float(m[5]) >= 20.0  # the spindle body meets the spoke, not a near miss
    worst = int(m[8])
    assert rec.point == worst and rec.value == pytest.approx(-1e-3 * float(m[5]), rel=1e-3)
    # the IK is not run: plan_window returns the refusal alone (partial windows off: with
    # them the clear runs are planned, tests/test_plan_partial.py)
    from dataclasses import replace

    whole = replace(ctx, options=replace(ctx.options, partial_windows=False))
    plan = mut.plan_window(whole, wt)
    assert plan.status is WindowStatus.IK_FAILED and plan.failures == [rec]
    audibot.record = rec


def test_the_refusal_rechecked_on_the_raw_mesh(audibot):
    """At the refused CL points, at random axes of the cone (not the planner's samples), the
    file's own surface enters the tool's round parts: the collision is the part's, not the
    collision model's; and at the worst point the depth agrees with the record (the pieces lie
    0-1 mm behind the open shell's surface: the raw depth is at most that much smaller)."""
    from drakedeburr.plan.targets import contact_geometry, tool_point_H

    ctx, wt, hub = audibot.ctx, audibot.wt, audibot.hub
    rec = getattr(audibot, "record", None) or mut.tool_refusal(ctx, wt)
    P = _surface_points(hub, 3e-3)
    cyl = _cylinders()
    r_c, lift = contact_geometry(ctx.options.contact_radius)
    p_HQ = tool_point_H(wt.p_HC, wt.n_H, wt.retract_H, wt.depth_of_cut, r_c, 0.0)
    rng = np.random.default_rng(0)
    blocked = np.asarray(rec.where["blocked_points"], int)
    chosen = sorted({int(rec.point), *blocked[np.linspace(0, len(blocked) - 1, 8).astype(int)]})
    best = {}
    for i in chosen:
        axes = _axes_in_cone(wt.cone_retract_H[i], wt.cone_half_angle, 16, rng)
        depth = []
        for a in axes:
            p_T = p_HQ[i] + lift * a
            d = P - p_T
            near = P[np.linalg.norm(d - np.outer(d @ a, a), axis=1) < 0.045]  # body radius +
            depth.append(max(_depth_inside(near, p_T, a, c) for c in cyl.values()))
        best[i] = min(depth)  # the least bad of the random axes
    # every refused point: at each random axis the raw surface is inside a round part or
    # within the 2 mm clearance of it (depth > -2 mm)
    assert min(best.values()) > -ctx.min_clearance, best
    # where the record reads the tool over 1 mm deep in the pieces, the raw surface is inside
    drake = np.asarray(rec.where["best_clearance_mm"]) * 1e-3
    deep = [i for i in best if drake[i] < -1e-3]
    assert len(deep) >= 3 and all(best[i] > 0.0 for i in deep), (best, drake[list(best)])
    worst = rec.point
    assert best[worst] > 0.0
    assert best[worst] <= -rec.value + 1.5e-3  # raw depth <= the pieces' (+ shell offset)
    assert best[worst] >= 0.5 * -rec.value  # and of the same size


def test_tool_scene_agrees_with_the_cell_checker(audibot):
    """A ToolScene reading at a tool pose equals the cell's own reading of the round tool parts
    against the hub at an arm pose with that tool pose (the same shapes, the same narrow
    phase)."""
    from drakedeburr.plan.clearance import spin_invariant_parts, tool_scene

    ctx = audibot.ctx
    scene = tool_scene(ctx.checker)
    names = {scene.names[g] for g in scene.reach}
    assert {"burr_shank", "collet", "spindle_body"} <= names
    assert len(spin_invariant_parts(ctx.checker)) == len(scene.reach)
    kin = ctx.kin
    q = kin.q_home
    X = kin.X_HT_from_q(q)
    d_scene, _ = scene.clearance(X, 0.5)
    query = ctx.checker.query_at(q)
    parts = set(scene.tool_parts)
    hub = ctx.cell.hub_ids
    d_cell = min((r.distance for r in query.ComputeSignedDistancePairwiseClosestPoints(0.5)
                  if (r.id_A in parts and r.id_B in hub) or (r.id_B in parts and r.id_A in hub)),
                 default=0.5)
    # the poses are composed otherwise (X_HT from the arm's FK, then the parts' offsets in T):
    # the same reading to well under a micrometre (0.5 um measured at home)
    assert d_scene == pytest.approx(d_cell, abs=2e-6)
