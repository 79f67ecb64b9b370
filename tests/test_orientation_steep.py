"""Issue 42: the local frames on steep stretches of a window edge (frames.contact_frames, used by
orientation.orient and verify.refs), asserted by geometry on an analytic edge.

The edge: a straight line descending (or climbing) at a slope d to the face plane X_H Y_H between
two planes, the flank face (normal B = T x N, d off +Z_H) and the opening's wall (inner
normal N = +Y_H, horizontal). The material is the quadrant {p . N < 0, p . B < 0}; its edge
bisector b = (N + B)/sqrt2 points out of it.

Closed forms used below (box centre c = (theta_min + theta_max)/2, its spindle direction u):
u makes beta with b, cos beta = (sin c cos c + cos^2 c)/sqrt2, and +Z_H makes gamma with b,
cos gamma = cos d/sqrt2. In the source's frame u . Z_H = -/+ sin c sin d + cos^2 c cos d
(descent/climb), which fixes the dihedral angle phi0 about b between u and +Z_H:
cos phi0 = (cos theta_src - cos beta cos gamma)/(sin beta sin gamma). A turn about b by
w phi0 leaves cos theta = cos beta cos gamma + sin beta sin gamma cos((1 - w) phi0): the full
turn (w = 1, from the full-turn slope 55 deg up) gamma - beta, the ramp's half turn at 50 deg
(w = 1/2) cos((phi0)/2).
"""

import math

import numpy as np
import pytest

from drakedeburr.config import ProcessParameters
from drakedeburr.frames.contact_frames import (
    B_L,
    BURR_HALF_ANGLE,
    FULL_TURN_SLOPE,
    edge_slopes,
    flank_contact_frames,
    rotation_about,
    steep_contact_frames,
    turn_share,
)
from drakedeburr.frames.local_frames import R_HL_from_normals, axis_from_angles
from drakedeburr.orientation.corner_normals import side_consistent_normals
from drakedeburr.orientation.orient import OrientOptions, orient_window, slope_limited_tangents
from drakedeburr.path.types import ClPath

Z_H = np.array([0.0, 0.0, 1.0])
MAX_SLOPE = OrientOptions().max_frame_slope
BOXES = {"large": ProcessParameters().bounds_large, "small": ProcessParameters().bounds_small}


def _edge(slope_deg: float, climb: bool):
    d = math.radians(slope_deg)
    T = np.array([math.cos(d), 0.0, (1.0 if climb else -1.0) * math.sin(d)])
    N = np.array([0.0, 1.0, 0.0])
    B = np.cross(T, N)
    return T, N, B, (N + B) / math.sqrt(2.0)


def _box_axes(lo: float, hi: float, n: int = 41) -> np.ndarray:
    """(n*n, 3) +Z_T in L over the whole (theta_A, theta_B) box (interior and boundary)."""
    a, b = np.meshgrid(np.linspace(lo, hi, n), np.linspace(lo, hi, n))
    return axis_from_angles(a.ravel(), b.ravel())


def _deg(c):
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _turned(T, N, lo, hi):
    R_src = R_HL_from_normals(T[None], N[None])
    R = steep_contact_frames(R_src, T[None], N[None], lo, hi, MAX_SLOPE)
    return R_src[0], R[0]


def _centre_angle(c: float, slope: np.ndarray, climb: bool, share: np.ndarray) -> np.ndarray:
    """The closed form of the module docstring: the box centre's angle [rad] to +Z_H after the
    turn by ``share`` of the full one, at edge slopes ``slope`` [rad]."""
    cb = (math.sin(c) * math.cos(c) + math.cos(c) ** 2) / math.sqrt(2.0)
    beta = math.acos(cb)
    gamma = np.arccos(np.cos(slope) / math.sqrt(2.0))
    z_src = (1.0 if climb else -1.0) * math.sin(c) * np.sin(slope) \
        + math.cos(c) ** 2 * np.cos(slope)
    phi0 = np.arccos((z_src - cb * np.cos(gamma)) / (math.sin(beta) * np.sin(gamma)))
    return np.arccos(cb * np.cos(gamma)
                     + math.sin(beta) * np.sin(gamma) * np.cos((1.0 - share) * phi0))


def test_turn_share_ramp():
    """0 up to the limit, 1/2 halfway, 1 from the full-turn slope, smooth at both ends."""
    lo, hi = MAX_SLOPE, FULL_TURN_SLOPE
    assert hi > lo
    sl = np.linspace(lo - 0.1, hi + 0.1, 2001)
    w = turn_share(sl, lo, hi)
    assert (w[sl <= lo] == 0.0).all() and (w[sl >= hi] == 1.0).all()
    assert turn_share(np.array([0.5 * (lo + hi)]), lo, hi)[0] == pytest.approx(0.5, abs=1e-15)
    assert (np.diff(w) >= 0.0).all()
    # the largest rate is the smoothstep's 3/2 per band width, at its middle; ~0 at its ends
    rate = np.diff(w) / np.diff(sl)
    assert rate.max() == pytest.approx(1.5 / (hi - lo), rel=1e-3)
    eps = 1e-4
    assert turn_share(np.array([lo + eps]), lo, hi)[0] < 3.0 * (eps / (hi - lo)) ** 2 + 1e-15
    # without a band (full slope <= limit) the turn applies at once
    np.testing.assert_array_equal(turn_share(sl, lo, lo), (sl > lo).astype(float))


@pytest.mark.parametrize("climb", [False, True])
@pytest.mark.parametrize("kind", ["large", "small"])
@pytest.mark.parametrize("slope_deg", [50.0, 60.0])
def test_steep_edge_flank_contact_outer_side_and_angle_to_hub_axis(kind, climb, slope_deg):
    """At 60 deg (past the full-turn slope) the full turn; at 50 deg, halfway up the ramp,
    half of it (closed forms of the module docstring)."""
    box = BOXES[kind]
    lo, hi = box.theta_min, box.theta_max
    T, N, B, b = _edge(slope_deg, climb)
    R_src, R = _turned(T, N, lo, hi)
    # a proper rotation, turned about the edge bisector (b is fixed: the chamfer plane is kept)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(R @ B_L, b, atol=1e-12)
    np.testing.assert_allclose(R_src @ B_L, b, atol=1e-12)
    # the turned upright cuts the symmetric chamfer: its spindle is alpha from b
    up = -R[:, 2]
    assert _deg(up @ b) == pytest.approx(math.degrees(BURR_HALF_ANGLE), abs=1e-9)
    spindles = -(R @ _box_axes(lo, hi).T).T  # -Z_T in H for every axis of the box
    # every axis of the box meets the edge line with the flank: >= 45 deg from the tangent
    assert _deg(np.abs(spindles @ T)).min() >= 45.0
    # on the material's outer side: out along the bisector, never into the material quadrant
    assert (spindles @ b > 0.0).all()
    assert not ((spindles @ N < 0.0) & (spindles @ B < 0.0)).any()
    # each box axis keeps its angle to b (its tilt off the symmetric-chamfer family)
    src = -(R_src @ _box_axes(lo, hi).T).T
    np.testing.assert_allclose(spindles @ b, src @ b, atol=1e-12)
    # the box centre: the derivation's angle to +Z_H. Rotating about b keeps the centre's angle
    # beta to b; +Z_H is gamma from b; the nearest the full turn can bring it is gamma - beta
    c = 0.5 * (lo + hi)
    d = math.radians(slope_deg)
    share = 0.5 if slope_deg == 50.0 else 1.0
    centre = -(R @ axis_from_angles(c, c))
    want = float(_centre_angle(c, np.array(d), climb, np.array(share)))
    assert _deg(centre @ Z_H) == pytest.approx(math.degrees(want), abs=1e-6)
    old = _deg(-(R_src @ axis_from_angles(c, c)) @ Z_H)
    assert old == pytest.approx(math.degrees(float(_centre_angle(c, np.array(d), climb,
                                                                  np.array(0.0)))), abs=1e-6)
    if share == 1.0:
        beta = math.acos((math.sin(c) * math.cos(c) + math.cos(c) ** 2) / math.sqrt(2.0))
        gamma = math.acos(math.cos(d) / math.sqrt(2.0))
        assert _deg(centre @ Z_H) == pytest.approx(math.degrees(gamma - beta), abs=1e-6)
    else:  # the frame is the source's turned by half the rule's psi
        psi = flank_contact_frames(R_src[None], lo, hi)[1][0]
        np.testing.assert_allclose(R, R_src @ rotation_about(B_L, 0.5 * psi), atol=1e-12)
    # nearer upright than the source's frame (the issue: 60-72 deg on the 50 deg descent;
    # large box 72.3 -> 46.6 deg halfway up the ramp, -> 31.4 deg with the full turn)
    assert _deg(centre @ Z_H) < old
    if not climb and slope_deg == 50.0:
        assert old > 60.0 and _deg(centre @ Z_H) < 47.0


@pytest.mark.parametrize("slope_deg", [55.0, 70.0, 85.0])
def test_turn_is_the_best_feasible_one_by_brute_force(slope_deg):
    """Independently: every turn psi about b (0.05 deg steps), kept where every box axis is
    >= 45 deg from the tangent (dense box), the best box centre angle to +Z_H; the rule's
    frame (the full turn from 55 deg up) reaches it within the search step."""
    box = BOXES["large"]
    lo, hi = box.theta_min, box.theta_max
    T, N, B, b = _edge(slope_deg, False)
    R_src, R = _turned(T, N, lo, hi)
    A = _box_axes(lo, hi, 25)
    c = 0.5 * (lo + hi)
    u = -axis_from_angles(c, c)
    K = np.array([[0, -b[2], b[1]], [b[2], 0, -b[0]], [-b[1], b[0], 0]])
    best = np.inf
    for psi in np.radians(np.arange(-180.0, 180.0, 0.05)):
        Q = np.eye(3) + math.sin(psi) * K + (1 - math.cos(psi)) * K @ K  # about b, in H
        F = Q @ R_src
        if _deg(np.abs((F @ A.T).T @ T)).min() >= 45.0:
            best = min(best, float(_deg((F @ u) @ Z_H)))
    got = float(_deg((R @ u) @ Z_H))
    assert _deg(np.abs((R @ A.T).T @ T)).min() >= 45.0
    assert got == pytest.approx(best, abs=0.3)


def _descent_cl(m: int = 15) -> tuple[ClPath, np.ndarray]:
    """A descent whose slope runs 47 -> 53 deg while it turns 20 deg in plan (a bent flank)."""
    d, f = np.radians(np.linspace(47.0, 53.0, m)), np.radians(np.linspace(0.0, 20.0, m))
    T = np.stack([np.cos(d) * np.cos(f), np.cos(d) * np.sin(f), -np.sin(d)], axis=1)
    n = np.stack([-np.sin(f), np.cos(f), np.zeros(m)], axis=1)
    p = np.concatenate([[np.zeros(3)], np.cumsum(0.002 * 0.5 * (T[1:] + T[:-1]), axis=0)])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    cl = ClPath(0, "large", "test", np.linspace(0, 1, m, endpoint=False), p, T,
                np.zeros(m), s, float(s[-1]))
    return cl, n


def test_orient_window_on_the_steep_edge_solves_in_the_turned_box():
    cl, n = _descent_cl()
    # the source's PSO: on this smooth analytic stretch the optimum is ~0 and the exact solver's
    # model cross-check compares rounding noise (1e-13 vs 1e-14) with no absolute floor
    tp = orient_window(cl, n, solver="pso")
    assert tp.success, tp.message
    T = cl.t_H
    box = BOXES["large"]
    R_src = R_HL_from_normals(cl.t_H, n)
    psi = flank_contact_frames(R_src, box.theta_min, box.theta_max)[1]
    share = turn_share(edge_slopes(T), MAX_SLOPE, FULL_TURN_SLOPE)
    assert 0.0 < share.min() < share.max() < 1.0  # the stretch lies inside the ramp
    np.testing.assert_allclose(tp.R_HL, np.einsum("mij,mjk->mik", R_src,
                                                  rotation_about(B_L, share * psi)), atol=1e-12)
    # the solved axes (re-derived from the frames and angles) touch with the flank, outer side
    z = np.einsum("mij,mj->mi", tp.R_HL, axis_from_angles(tp.theta_A, tp.theta_B))
    np.testing.assert_allclose(z, tp.zT_H, atol=1e-9)
    assert _deg(np.abs(np.sum(z * T, axis=1))).min() >= 45.0
    b = (n + np.cross(T, n)) / math.sqrt(2.0)
    assert (np.sum(-z * b, axis=1) > 0).all()
    lo, hi = box.theta_min, box.theta_max
    assert ((tp.theta_A >= lo - 1e-9) & (tp.theta_A <= hi + 1e-9)).all()
    assert ((tp.theta_B >= lo - 1e-9) & (tp.theta_B <= hi + 1e-9)).all()
    # the cone axis: the closed form at every point's slope and ramp share (module docstring)
    c = 0.5 * (lo + hi)
    want = _centre_angle(c, edge_slopes(T), False, share)
    np.testing.assert_allclose(_deg(-(tp.cone_zT_H @ Z_H)), np.degrees(want), atol=1e-6)


def _slope_sweep(lo_deg: float, hi_deg: float, m: int):
    """Tangents of a descent whose slope runs ``lo_deg`` -> ``hi_deg`` over ``m`` points (a
    straight plan direction, the wall normal +Y_H)."""
    d = np.radians(np.linspace(lo_deg, hi_deg, m))
    T = np.stack([np.cos(d), np.zeros(m), -np.sin(d)], axis=1)
    return T, np.tile([0.0, 1.0, 0.0], (m, 1)), d


@pytest.mark.parametrize("kind", ["large", "small"])
def test_turn_in_the_ramp_keeps_the_flank_contact(kind):
    """In the ramp (45-55 deg) the source's frame (psi = 0) and every partial turn keep every
    box axis >= 45 deg from the edge line (dense box, independent of the rule's grid): in the
    source's frame a box axis' component along the edge line is sin theta_B, so its axes are
    >= 90 deg - |theta_B|max (0.44 rad: 64.8 deg) from it."""
    box = BOXES[kind]
    lo, hi = box.theta_min, box.theta_max
    T, N, d = _slope_sweep(45.05, 55.0, 41)
    A = _box_axes(lo, hi, 31)
    R_src = R_HL_from_normals(T, N)
    R = steep_contact_frames(R_src, T, N, lo, hi, MAX_SLOPE)
    for i in range(len(T)):
        src_min = _deg(np.abs((R_src[i] @ A.T).T @ T[i])).min()
        assert src_min >= 90.0 - math.degrees(max(abs(lo), abs(hi))) - 1e-9
        assert _deg(np.abs((R[i] @ A.T).T @ T[i])).min() >= 45.0


def _frame_steps(R: np.ndarray) -> np.ndarray:
    rel = np.einsum("mji,mjk->mik", R[:-1], R[1:])
    return np.degrees(np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1, 1)))


def test_frame_is_continuous_where_the_slope_passes_the_limit():
    """A descent whose slope runs 40 -> 60 deg in 0.1 deg steps: the largest frame change
    between neighbouring CL points is bounded by the tangent's turn (0.1 deg) plus the ramp's
    largest rate (3/2 per 10 deg) times the full turn's psi times the slope step, plus psi's
    own change; applied at once (no ramp) the frame jumped by the full psi at 45 deg."""
    box = BOXES["large"]
    lo, hi = box.theta_min, box.theta_max
    T, N, d = _slope_sweep(40.0, 60.0, 201)
    R_src = R_HL_from_normals(T, N)
    R = steep_contact_frames(R_src, T, N, lo, hi, MAX_SLOPE)
    steep = edge_slopes(T) > MAX_SLOPE
    psi = np.zeros(len(T))
    psi[steep] = flank_contact_frames(R_src[steep], lo, hi)[1]
    step = math.radians(0.1)
    rate = 1.5 / (FULL_TURN_SLOPE - MAX_SLOPE)
    bound = (0.1 + math.degrees(rate * step * np.abs(psi).max())
             + math.degrees(np.abs(np.diff(psi)).max()) + 1e-6)
    got = _frame_steps(R)
    assert got.max() <= bound
    assert got.max() < 2.0  # degrees per 0.1 deg of slope
    # the same edge with the turn applied at once: the frame jumps at the limit
    R_step = steep_contact_frames(R_src, T, N, lo, hi, MAX_SLOPE, MAX_SLOPE)
    jump = _frame_steps(R_step)
    i = int(np.argmax(jump))
    assert steep[i + 1] and not steep[i]
    assert jump[i] > 40.0 and jump[i] == pytest.approx(math.degrees(abs(psi[i + 1])), abs=0.2)


def _flat_loop(amplitude: float, m: int = 48):
    """A CCW circle of radius 30 mm, height z = amplitude * sin(2 phi) (slope <= 43 deg)."""
    phi = np.linspace(0, 2 * np.pi, m, endpoint=False)
    r = 0.03
    p = np.stack([r * np.cos(phi), r * np.sin(phi), amplitude * np.sin(2 * phi)], axis=1)
    t = np.stack([-r * np.sin(phi), r * np.cos(phi), 2 * amplitude * np.cos(2 * phi)], axis=1)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = np.stack([-np.cos(phi), -np.sin(phi), np.zeros(m)], axis=1)  # into the opening
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    cl = ClPath(0, "large", "test", phi / (2 * np.pi), p, t, np.full(m, 1 / r), arc,
                float(arc[-1] + np.linalg.norm(p[0] - p[-1])))
    return cl, n


@pytest.mark.parametrize("amplitude", [0.0, 0.0139])
def test_flat_loop_frames_bit_for_bit(amplitude):
    cl, n = _flat_loop(amplitude)
    assert math.degrees(edge_slopes(cl.t_H).max()) <= 43.0
    box = BOXES["large"]
    R_src = R_HL_from_normals(cl.t_H, n)
    assert steep_contact_frames(R_src, cl.t_H, n, box.theta_min, box.theta_max,
                                MAX_SLOPE) is R_src
    # the frames the stage used before the rule existed, computed here the old way
    t = slope_limited_tangents(cl.t_H, n, MAX_SLOPE)
    assert t is not None and np.array_equal(t, cl.t_H)
    n_fixed, _ = side_consistent_normals(t, n)
    old = R_HL_from_normals(t, n_fixed, name="window 0")
    tp = orient_window(cl, n)
    assert np.array_equal(tp.R_HL, old)


def _tilted_circle(tilt_deg: float, m: int = 180):
    """A CCW circle of radius 30 mm in a plate tilted ``tilt_deg`` about X_H: the edge's slope
    runs 0 -> tilt; wall normals in the plate, toward the centre (into the opening)."""
    phi = np.linspace(0, 2 * np.pi, m, endpoint=False)
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    r = 0.03
    u = np.stack([np.cos(phi), np.sin(phi) * c, np.sin(phi) * s], axis=1)
    t = np.stack([-np.sin(phi), np.cos(phi) * c, np.cos(phi) * s], axis=1)
    return r * u, t, -u


@pytest.mark.parametrize("tilt_deg", [30.0, 60.0])
def test_verifier_fallback_frames_follow_the_rule(tilt_deg):
    """verify.refs (a plan without a ToolPath): the frames from the hub's own edge samples are
    the source's where the edge is within 45 deg of the face plane (bit for bit) and touch with
    the flank, on the outer side, nearer +Z_H than the source's where it is steeper."""
    from types import SimpleNamespace

    from drakedeburr.verify.refs import window_ref

    p, t, n = _tilted_circle(tilt_deg)
    edge = SimpleNamespace(index=0, kind="large", p_HE=p, t_H=t, n_wall_H=n)

    def tgt(q, seg):
        X = np.eye(4)
        X[:3, 3] = q
        return SimpleNamespace(window_index=0, segment=seg, cl_index=-1, X_HT=X)

    targets = [tgt(p[0], "approach")] + [tgt(q, "cut") for q in p[1:]] + [tgt(p[0], "cut")]
    ref = window_ref(0, targets, None, edge, ProcessParameters())
    assert ref is not None and ref.source.startswith("hub edge")
    np.testing.assert_allclose(ref.p_HC, p, atol=1e-12)
    src = R_HL_from_normals(t, n)
    steep = edge_slopes(t) > MAX_SLOPE
    assert steep.any() == (tilt_deg > 45.0)
    assert np.array_equal(ref.R_HL[~steep], src[~steep])
    if not steep.any():
        return
    box = BOXES["large"]
    A = _box_axes(box.theta_min, box.theta_max, 21)
    c = 0.5 * (box.theta_min + box.theta_max)
    for i in np.flatnonzero(steep):
        b = (n[i] + np.cross(t[i], n[i])) / math.sqrt(2.0)
        sp = -(ref.R_HL[i] @ A.T).T
        assert _deg(np.abs(sp @ t[i])).min() >= 45.0
        assert (sp @ b > 0.0).all()
        new = _deg(-(ref.R_HL[i] @ axis_from_angles(c, c)) @ Z_H)
        old = _deg(-(src[i] @ axis_from_angles(c, c)) @ Z_H)
        assert new <= old + 1e-9
