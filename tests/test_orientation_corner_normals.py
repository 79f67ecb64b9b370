"""orientation.corner_normals: a CL point beside a tessellated corner that carries the wall normal
of the corner's other side (issue 42). Synthetic 3-D corner (the edge runs along the face, then
turns up a flank) and the audibot rim of ../shared/extdata (windows 1 and 9)."""

from __future__ import annotations

import numpy as np
import pytest

import drakedeburr.orientation.corner_normals as mut
from drakedeburr.frames.local_frames import R_HL_from_normals
from drakedeburr.orientation.orient import slope_limited_tangents

Z = np.array([0.0, 0.0, 1.0])
N_FACE_SIDE = np.array([-1.0, 0.0, 0.0])  # along +Y on the face, opening toward -X
N_FLANK = np.array([0.5, -np.sqrt(0.75), 0.0])  # up the flank (+Z), opening toward -Y/+X


def _corner(k_bad: int | None, n_bad=None):
    """10 points along +Y then 10 up +Z; point ``k_bad`` gets ``n_bad``."""
    t = np.array([[0.0, 1.0, 0.0]] * 10 + [[0.0, 0.0, 1.0]] * 10)
    n = np.array([N_FACE_SIDE] * 10 + [N_FLANK] * 10)
    if k_bad is not None:
        n[k_bad] = n_bad
    return t, n


def _upright_z(t, n):
    """Z_H component of the frames' upright (-Z_L, tip -> spindle at zero angles)."""
    tf = slope_limited_tangents(t, n, np.radians(45.0))
    return -R_HL_from_normals(tf, n)[:, 2, 2]


def test_carried_normal_is_the_rotation_that_turns_the_tangent():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 50, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    v = rng.normal(size=(50, 3))
    out = mut.carried_normal(a, b, v)
    # independent: a proper rotation about a x b by the angle between a and b
    for ai, bi, vi, oi in zip(a, b, v, out, strict=True):
        ax = np.cross(ai, bi)
        ang = np.arctan2(np.linalg.norm(ax), ai @ bi)
        ax /= np.linalg.norm(ax)
        K = np.array([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
        R = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
        np.testing.assert_allclose(R @ ai, bi, atol=1e-12)
        np.testing.assert_allclose(oi, R @ vi, atol=1e-12)


@pytest.mark.parametrize(("k_bad", "n_bad", "want", "flipped"),
                         [(9, N_FLANK, N_FACE_SIDE, True), (10, N_FACE_SIDE, N_FLANK, False)])
def test_a_normal_from_across_the_corner_is_replaced_and_the_frame_faces_the_front(
        k_bad, n_bad, want, flipped):
    t, n = _corner(k_bad, n_bad)
    # before the corner the mispaired frame is upside down (axis into the hub); after it the
    # slope limit keeps it upright, but the wall normal is still the wrong side's
    assert (_upright_z(t, n)[k_bad] <= 0.0) == flipped
    out, fixed = mut.side_consistent_normals(t, n, closed=False)
    assert fixed == [k_bad]
    # the neighbour's normal carried over: the same tangent, so the same normal
    np.testing.assert_allclose(out[k_bad], want, atol=1e-12)
    others = np.arange(len(n)) != k_bad
    assert np.array_equal(out[others], n[others])
    up = _upright_z(t, out)
    assert (up > 0.0).all(), up
    # the repaired frame is that of its side's neighbour (no fold, no flip)
    j = k_bad - 1 if k_bad == 9 else k_bad + 1
    tf = slope_limited_tangents(t, out, np.radians(45.0))
    R = R_HL_from_normals(tf, out)
    np.testing.assert_allclose(R[k_bad], R[j], atol=1e-12)


def test_a_reversal_where_the_edge_turns_most_is_kept_and_smooth_loops_are_untouched():
    t, n = _corner(None)  # the corner itself: 90 deg turn, normal 120 deg on: real, kept
    steps, mismatch, turn = mut.normal_reversals(t, n, closed=False)
    assert steps.tolist() == [9] and np.degrees(mismatch[9]) == pytest.approx(120.0)
    out, fixed = mut.side_consistent_normals(t, n, closed=False)
    assert fixed == [] and np.array_equal(out, n)
    s = np.linspace(0, 2 * np.pi, 60, endpoint=False)  # a round window, vertical wall
    tc = np.c_[-np.sin(s), np.cos(s), np.zeros_like(s)]
    nc = np.cross(Z, tc)  # inner normal of a CCW loop: toward the centre
    out, fixed = mut.side_consistent_normals(tc, nc)
    assert fixed == [] and np.array_equal(out, nc)


@pytest.mark.slow
def test_audibot_windows_face_the_front_where_a_corner_normal_was_repaired(tmp_path, extdata):
    from drakedeburr.frames.local_frames import angles_from_zT_H
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.hub.model import load_hub
    from drakedeburr.plan.tool_paths import tool_path

    res = import_mesh(extdata / "wheel_models/audibot__wheel_rim_only_DERIVED_m.stl", tmp_path)
    hub = load_hub(res.dir)
    for w in (1, 9):
        edge = hub.windows[w]
        tp = tool_path(edge, hub.process)
        b = tp.bounds
        a_, b_ = angles_from_zT_H(tp.R_HL, tp.zT_H)  # independent: the axis back to angles
        assert (a_ >= b.theta_min - 1e-9).all() and (a_ <= b.theta_max + 1e-9).all()
        assert (b_ >= b.theta_min - 1e-9).all() and (b_ <= b.theta_max + 1e-9).all()
        t_frame = tp.R_HL[:, :, 1]
        # no reversal of the carried frame normal is left where the edge runs on straight
        steps, mismatch, turn = mut.normal_reversals(t_frame, tp.R_HL[:, :, 0])
        m = len(tp)
        for i in steps.tolist():
            assert turn[i] >= min(turn[(i - 1) % m], turn[(i + 1) % m]), (w, i)
        up = -tp.zT_H @ Z
        if w == 9:
            assert (up > 0.0).all(), np.flatnonzero(up <= 0.0)
        if (up <= 0.0).any():  # what is left is refused with what the geometry there is
            from drakedeburr.errors import InputError
            from drakedeburr.plan.window_targets import WindowTargets

            with pytest.raises(InputError, match=r"runs at \d+ deg to the face plane|a corner "
                                                 r"of the loop \(the edge turns \d+ deg"):
                WindowTargets.from_tool_path(tp)


def test_an_axis_into_the_hub_at_a_corner_says_the_turn_the_normal_and_by_how_much():
    """plan.window_targets: where the ToolPath's axis points into the hub on a stretch that is
    not steep, the refusal measures the corner (turn, inner normal to the face plane here and
    on either side, how far below the face plane the axis is)."""
    from types import SimpleNamespace

    from drakedeburr.errors import InputError
    from drakedeburr.plan.window_targets import WindowTargets

    s = np.radians([0.0, 0.0, 40.0, 80.0, 80.0])  # the edge turns 80 deg in the face plane
    t = np.c_[np.cos(s), np.sin(s), np.zeros(5)]
    n = np.cross(Z, t)
    tilt = np.radians(-50.0)  # the corner point's normal 50 deg below the face plane
    n[2] = np.cos(tilt) * n[2] + np.sin(tilt) * Z
    p = np.cumsum(np.r_[np.zeros((1, 3)), 0.5e-3 * t[:-1]], axis=0)
    R = R_HL_from_normals(t, n)
    below = np.radians(2.0)
    ax = -R[:, :, 2]  # tip -> spindle: upright (-Z_L = +Z_H) everywhere ...
    h = np.cross(Z, n[2])
    h /= np.linalg.norm(h)
    ax[2] = np.cos(below) * h - np.sin(below) * Z  # ... but 2 deg below the plane at CL 2
    tp = SimpleNamespace(window_index=4, kind="small", p_HC=p, R_HL=R, zT_H=-ax, cone_zT_H=-ax,
                         cone_half_angle=0.1, cone_outer_half_angle=0.12, depth_of_cut=0.3e-3)
    assert (ax @ Z <= 0.0).tolist() == [False, False, True, False, False]
    with pytest.raises(InputError) as exc:
        WindowTargets.from_tool_path(tp)
    msg = str(exc.value)
    assert "CL point 2" in msg and "a corner of the loop (the edge turns 80 deg within 1.0 mm" \
        in msg, msg
    assert "inner normal is -50 deg to the face plane (+0 and +0 deg" in msg, msg
    assert "leaves the axis 2.0 deg below the face plane" in msg, msg


def _staircase(tilt_deg: float, slope_deg: float = 20.0, turn_deg: float = 85.0):
    """An open faceted stretch: 6 points down a slope (``slope_deg``) along +Y, one corner
    point, 6 points level after the edge turns ``turn_deg`` in plan (vertical walls: inner
    normals Z x t). The corner point's tangent rounds the corner (the two sides' bisector, as
    the fitted curve's does) and its normal estimate is the sides' plan bisector swung
    ``tilt_deg`` off the face plane (the probe artefact at a facet corner)."""
    s, tr = np.radians(slope_deg), np.radians(turn_deg)
    t_a, t_b = np.array([0.0, np.cos(s), -np.sin(s)]), np.array([-np.sin(tr), np.cos(tr), 0.0])
    n_a, n_b = np.cross(Z, t_a), np.cross(Z, t_b)
    n_a, n_b = n_a / np.linalg.norm(n_a), n_b / np.linalg.norm(n_b)
    t_c = (t_a + t_b) / np.linalg.norm(t_a + t_b)
    h = (n_a + n_b) / np.linalg.norm(n_a + n_b)
    n_c = np.cos(np.radians(tilt_deg)) * h + np.sin(np.radians(tilt_deg)) * Z
    return np.array([t_a] * 6 + [t_c] + [t_b] * 6), np.array([n_a] * 6 + [n_c] + [n_b] * 6)


def _lowest_box_axis_deg(R, lo=0.26, hi=0.44):
    """(M,) the lowest angle [deg] above the face plane of a tool axis (tip -> spindle) in the
    (theta_A, theta_B) box [lo, hi]^2 about each frame (a 9 x 9 grid of the box, the
    large-window recipe's by default)."""
    from drakedeburr.frames.local_frames import axis_from_angles

    g = np.linspace(lo, hi, 9)
    a, b = np.meshgrid(g, g)
    z_T = np.einsum("mij,kj->mki", R, axis_from_angles(a.ravel(), b.ravel()))  # spindle->tip
    return np.degrees(np.arcsin(np.clip(-z_T[:, :, 2].min(axis=1), -1.0, 1.0)))


@pytest.mark.parametrize("tilt", [-75.0, -50.0, 65.0])
def test_a_corner_normal_outside_its_neighbours_span_is_bounded_by_them(tilt):
    t, n = _staircase(tilt)
    out, fixed = mut.side_consistent_normals(t, n, closed=False)
    assert fixed == [6]
    others = np.arange(len(n)) != 6
    assert np.array_equal(out[others], n[others])
    g = out[6]
    # perpendicular to its tangent, on the arc between the two sides' normals (both level
    # here): no further off the face plane than they are, no excess over their span
    assert abs(g @ t[6]) < 1e-12 and abs(np.linalg.norm(g) - 1.0) < 1e-12
    assert abs(g @ Z) < 1e-9
    ang = lambda u, v: np.arccos(np.clip(u @ v, -1.0, 1.0))  # noqa: E731
    assert ang(g, n[5]) + ang(g, n[7]) - ang(n[5], n[7]) < 1e-9
    # the recipe's box about the bounded frame keeps every tool axis above the face plane,
    # where about the estimate's frame it did not (independent: the box's axes in H)
    low_before = _lowest_box_axis_deg(R_HL_from_normals(t, n))[6]
    low_after = _lowest_box_axis_deg(R_HL_from_normals(t, out))
    if tilt < -60.0:
        assert low_before < 0.0, low_before
    assert (low_after > 0.0).all() and low_after[6] > low_before, (low_before, low_after)


def test_a_corner_normal_between_its_neighbours_and_smooth_corners_are_kept():
    t, n = _staircase(0.0)  # the corner's normal the sides' bisector: within their span
    out, fixed = mut.corner_bounded_normals(t, n, closed=False)
    assert fixed == [] and out is n
    # a round window of 24 points (15 deg a step: a 30 deg turn across the neighbours, no
    # more), its normal 5 deg off Z x t at every other point: within the span's excess
    s = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    tc = np.c_[-np.sin(s), np.cos(s), np.zeros_like(s)]
    nc = np.cross(Z, tc)
    nc[::2] = np.cos(np.radians(5.0)) * nc[::2] + np.sin(np.radians(5.0)) * Z
    out, fixed = mut.side_consistent_normals(tc, nc)
    assert fixed == [] and np.array_equal(out, nc)


@pytest.mark.slow
def test_audibot_corners_keep_the_axis_above_the_face_in_every_box(tmp_path, extdata):
    """The audibot rim's windows 1 (CL 110), 3 (CL 177) and 8 (CL 53): a corner normal -50,
    +53 and +65 deg to the face plane put the axis below it (windows 3 and 8 under the
    narrowest theta box); bounded, every box gives targets."""
    from dataclasses import replace

    from drakedeburr.config import OrientationBounds
    from drakedeburr.hub.import_mesh import import_mesh
    from drakedeburr.hub.model import load_hub
    from drakedeburr.plan.tool_paths import tool_path
    from drakedeburr.plan.window_targets import WindowTargets

    res = import_mesh(extdata / "wheel_models/audibot__wheel_rim_only_DERIVED_m.stl", tmp_path)
    hub = load_hub(res.dir)
    for lo, hi in ((0.0, 0.15), (0.09, 0.26), (0.26, 0.44)):
        box = OrientationBounds(lo, hi)
        params = replace(hub.process, bounds_large=box, bounds_small=box)
        for w in (1, 3, 8):
            tp = tool_path(hub.windows[w], params)
            up = -tp.zT_H @ Z
            assert (up > 0.0).all(), (w, lo, hi, np.flatnonzero(up <= 0.0))
            wt = WindowTargets.from_tool_path(tp)
            # independent: each frame's upright and the axis' tilt from it within the box
            tilt = np.arccos(np.clip(np.sum(-tp.zT_H * -tp.R_HL[:, :, 2], axis=1), -1, 1))
            assert tilt.max() <= np.hypot(hi, hi) + 1e-6
            assert len(wt) == len(tp)
