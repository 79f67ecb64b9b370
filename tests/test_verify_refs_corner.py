"""verify.refs: the fallback reference frames (a plan without a ToolPath, frames from the hub's
edge) get the corner repair of orientation.corner_normals (issue 42). Synthetic tessellated
corner: a triangular window (the edge turns 120 deg at each corner) whose edge sample beside a
corner carries the wall normal of the corner's other side, as a mesh probe next to a facet
corner does."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.config import ProcessParameters
from drakedeburr.frames.local_frames import R_HL_from_normals
from drakedeburr.hub.types import WindowEdge
from drakedeburr.verify.refs import edge_wall_normals, window_ref

Z = np.array([0.0, 0.0, 1.0])
SIDE = 30e-3  # [m] triangle side
STEP = 0.5e-3  # [m] edge sample spacing


def _triangle():
    """CCW equilateral triangle loop (z = 0): points, tangents, analytic inner wall normals
    (vertical walls, into the opening = Z x t) and the side of each sample."""
    corners = SIDE * np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0],
                               [0.5, np.sqrt(0.75), 0.0]])
    p, t, side = [], [], []
    per = int(round(SIDE / STEP))
    for k in range(3):
        a, b = corners[k], corners[(k + 1) % 3]
        u = (b - a) / np.linalg.norm(b - a)
        for i in range(per):
            p.append(a + i * STEP * u)
            t.append(u)
            side.append(k)
    t = np.array(t)
    return np.array(p), t, np.cross(Z, t), np.array(side)


def _targets(p):
    """One approach target on the first edge point, then one cut target on every sample."""
    def tgt(q, seg):
        X = np.eye(4)
        X[:3, 3] = q
        return SimpleNamespace(window_index=0, segment=seg, cl_index=-1, X_HT=X)
    return [tgt(p[0], "approach")] + [tgt(q, "cut") for q in p[1:]] + [tgt(p[0], "cut")]


def _angle_deg(a, b):
    c = np.sum(a * b, axis=1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


@pytest.mark.parametrize("where", ["before", "after"])
def test_fallback_frame_beside_a_tessellated_corner_faces_the_opening(where):
    p, t, n_true, side = _triangle()
    per = int(round(SIDE / STEP))
    k = per - 1 if where == "before" else per  # last sample of side 0 / first of side 1
    other = 1 if where == "before" else 0
    n = n_true.copy()
    n[k] = np.cross(Z, t[side == other][0])  # the wall normal of the corner's other side
    edge = WindowEdge(index=0, kind="large", p_HE=p, t_H=t, n_wall_H=n)
    # without the repair that frame is upside down: its X_L > 90 deg from the true wall normal
    raw = R_HL_from_normals(t, n)[:, :, 0]
    assert _angle_deg(raw[k:k + 1], n_true[k:k + 1])[0] > 90.0
    ref = window_ref(0, _targets(p), None, edge, ProcessParameters())
    assert ref is not None and ref.source.startswith("hub edge")
    # every CL point is an edge sample (the targets sit on them): compare with the analytic
    # wall normal of the side it lies on - independent of the repair's own reading
    np.testing.assert_allclose(ref.p_HC, p, atol=1e-12)
    err = _angle_deg(ref.R_HL[:, :, 0], n_true)
    assert err.max() < 1e-6, (err.argmax(), err.max())
    # right-handed frames, Z_L into the material (-Z_H on this flat face)
    np.testing.assert_allclose(np.linalg.det(ref.R_HL), 1.0, atol=1e-12)
    np.testing.assert_allclose(ref.R_HL[:, :, 2] @ Z, -1.0, atol=1e-12)


def test_edge_normals_without_a_corner_mismatch_come_back_bit_for_bit():
    p, t, n_true, _ = _triangle()
    edge = WindowEdge(index=0, kind="small", p_HE=p, t_H=t, n_wall_H=n_true)
    out = edge_wall_normals(edge, 0)
    assert np.array_equal(out, n_true)


def test_bundled_hub_edges_have_no_corner_repair():
    """The bundled hubs' edge normals have no reversal: the fallback frames are unchanged."""
    from drakedeburr.hub.model import load_hub
    from drakedeburr.resources import hub_dir, hub_names

    for name in hub_names():
        for e in load_hub(hub_dir(name)).windows:
            assert np.array_equal(edge_wall_normals(e, e.index),
                                  np.asarray(e.n_wall_H, float)), (name, e.index)
