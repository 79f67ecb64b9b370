"""plan.clearance: the tool pre-check's poses built many axes at a time (cone_poses, the cells
of tool_axis_clearance's branch and bound) give the same search as one axis at a time (issue 42:
``X_HT_from_axis`` called per axis was half the pre-check's time on the audibot rim).

The batched builder is compared bit for bit with ``plan.targets.X_HT_from_axis`` called on each
axis alone (seeded axes); the search on one audibot window is compared with an independent
re-implementation of the scalar search (one pose, one reading per axis, in the order the branch
and bound asks them), which must give the same best clearances, axes, parts, reads and the same
proven-blocked set.
"""

from __future__ import annotations

import heapq
from types import SimpleNamespace

import numpy as np
import pytest

import drakedeburr.plan.clearance as mut
from drakedeburr.plan.targets import X_HT_from_axis

AUDIBOT = "wheel_models/audibot__wheel_rim_only_DERIVED_m.stl"


def test_cone_poses_equal_the_scalar_builder_bit_for_bit():
    rng = np.random.default_rng(42)
    for _ in range(20):
        p_Q, t_H = rng.normal(size=3) * 0.1, rng.normal(size=3)
        lift = float(rng.uniform(0.0, 0.03))
        A = rng.normal(size=(int(rng.integers(1, 60)), 3)) * rng.uniform(0.1, 10.0)
        U, X = mut.cone_poses(p_Q, lift, A, t_H)
        for k, a in enumerate(A):
            u = a / np.linalg.norm(a)
            ref = X_HT_from_axis((p_Q + lift * u)[None], u[None], t_H[None])[0]
            assert np.array_equal(U[k], u)
            assert np.array_equal(X[k], ref)
        # and the poses are what they claim: +Z_T = -axis, T lift above p_Q on the axis,
        # a right-handed orthonormal frame
        R = X[:, :3, :3]
        assert np.allclose(np.einsum("kji,kjl->kil", R, R), np.eye(3), atol=1e-12)
        assert np.allclose(np.linalg.det(R), 1.0, atol=1e-12)
        assert np.allclose(X[:, :3, 2], -U, atol=1e-15)
        assert np.allclose(X[:, :3, 3], p_Q + lift * U, atol=1e-15)


def _scalar_search(scene, wt, p_HQ, lift, bound, margin):
    """The pre-check one axis at a time (the path before the batching): the same cone cells,
    best-first order and limits (mut.CONE_CELLS, CONE_HALVINGS, CONE_READS)."""
    from drakedeburr.frames.vectors import perpendicular_basis

    half = float(wt.cone_half_angle)
    rad = float(np.tan(half))
    m = len(wt)
    out = SimpleNamespace(best=np.full(m, -np.inf), axis=np.zeros((m, 3)), part=[""] * m,
                          proven=np.zeros(m, bool), reads=np.zeros(m, int))
    s0 = rad / mut.CONE_CELLS
    g = -rad + s0 * (2 * np.arange(2 * mut.CONE_CELLS) + 1)
    start = [(x, y, s0) for x in g for y in g if np.hypot(x, y) - np.sqrt(2) * s0 <= rad]
    for i in range(m):
        c = wt.cone_retract_H[i] / np.linalg.norm(wt.cone_retract_H[i])
        e1, e2, _ = perpendicular_basis(c).T

        def read(a, i=i):
            a = a / np.linalg.norm(a)
            X = X_HT_from_axis((p_HQ[i] + lift * a)[None], a[None], wt.t_H[i][None])[0]
            d, gid = scene.clearance(X, bound + 1e-3)
            out.reads[i] += 1
            if d > out.best[i]:
                out.best[i], out.axis[i] = d, a
                out.part[i] = scene.names[gid] if gid is not None else ""
            return d, scene.reach[gid] + lift if gid is not None else np.inf

        if read(wt.retract_H[i])[0] >= bound:
            continue
        heap = [(-np.inf, k, cell) for k, cell in enumerate(start)]
        heapq.heapify(heap)
        clear, n, stopped = False, len(heap), False
        while heap and not clear and out.reads[i] < mut.CONE_READS:
            _, _, (x, y, s) = heapq.heappop(heap)
            r = np.hypot(x, y)
            px, py = (x, y) if r <= rad else (x * rad / r, y * rad / r)
            d, reach = read(c + px * e1 + py * e2)
            clear = d >= bound
            upper = d + reach * (np.hypot(px - x, py - y) + np.sqrt(2) * s)
            if clear or upper < bound - margin:
                continue
            if s <= s0 / 2 ** mut.CONE_HALVINGS:
                stopped = True
                break
            for dx in (-s / 2, s / 2):
                for dy in (-s / 2, s / 2):
                    if np.hypot(x + dx, y + dy) - np.sqrt(2) * s / 2 <= rad:
                        n += 1
                        heapq.heappush(heap, (-upper, n, (x + dx, y + dy, s / 2)))
        out.proven[i] = not clear and not heap and not stopped
    return out


@pytest.mark.slow
def test_the_batched_search_equals_the_scalar_one_on_an_audibot_window(tmp_path, extdata):
    from drakedeburr.cell.station import load_cell
    from drakedeburr.config import default_tolerances
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.hub.model import load_hub
    from drakedeburr.plan.kinematics import ClearanceChecker, cell_kinematics
    from drakedeburr.plan.options import PlanContext, PlanOptions
    from drakedeburr.plan.planner import window_targets_for_hub
    from drakedeburr.plan.window import REFUSAL_MARGIN, cut_targets

    res = import_mesh(extdata / AUDIBOT, tmp_path)
    hub, cell = load_hub(res.dir), load_cell("tool_in_hand", res.dir)
    checker = ClearanceChecker(cell)
    ctx = PlanContext(cell=cell, kin=cell_kinematics(cell), checker=checker, free_checker=None,
                      config=SimpleNamespace(tolerances=default_tolerances()),
                      options=PlanOptions())
    wt = window_targets_for_hub(hub, windows=[2], skipped=[])[0]
    m = len(wt)
    targets = cut_targets(ctx, wt, np.zeros((m, 3)))
    scene = mut.tool_scene(checker)
    args = (targets.p_HQ[:m], targets.lift)
    got = mut.tool_axis_clearance(scene, wt, *args, bound=ctx.min_clearance,
                                  margin=REFUSAL_MARGIN)
    ref = _scalar_search(scene, wt, *args, ctx.min_clearance, REFUSAL_MARGIN)
    assert np.array_equal(got.proven, ref.proven)
    assert got.proven.sum() >= 20  # the window's flank points: blocked on every axis
    assert np.array_equal(got.best, ref.best)
    assert np.array_equal(got.best_axis_H, ref.axis)
    assert np.array_equal(got.reads, ref.reads) and list(got.part) == ref.part
    # independent of both: the best axis lies in the cone, and its reading is the scene's
    cos_half = np.cos(got.half_angle)
    c = wt.cone_retract_H / np.linalg.norm(wt.cone_retract_H, axis=1, keepdims=True)
    for i in range(0, m, 17):
        a = got.best_axis_H[i]
        assert abs(np.linalg.norm(a) - 1.0) < 1e-12
        in_cone = a @ c[i] >= cos_half - 1e-12
        assert in_cone or np.allclose(a, wt.retract_H[i] / np.linalg.norm(wt.retract_H[i]))
        X = X_HT_from_axis((targets.p_HQ[i] + targets.lift * a)[None], a[None],
                           wt.t_H[i][None])[0]
        assert scene.clearance(X, ctx.min_clearance + 1e-3)[0] == got.best[i]
