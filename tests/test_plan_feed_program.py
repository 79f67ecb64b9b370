"""The feed program (drakedeburr.plan.feed_program.hold_feed) on its own: a synthetic fillet (a
line, a 90-degree arc of 15 mm radius, a line) whose cone axis leans toward the arc's centre
and turns with it; the tool axis on the cone axis makes the joints bind there (the timed TCP
speed falls to ~half the feed). The program's frames are re-checked independently of it: the
exact IK re-solves the joints, the FK reproduces the poses, finite differences of those joints
at the constant feed stay within the joint limits, the axis stays inside its cone (angles from
dot products), and the timing (its own spline, the timing's limits) holds the feed there."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

import drakedeburr.plan.feed_program as mut
from drakedeburr.plan.fillets import slow_stretches
from drakedeburr.plan.timing import TimingLimits, time_path
from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif(not hub_names(), reason="no bundled hub models")

FEED = 0.15  # [m/s]
BAND = 0.05  # the speed band (+-5 %)
HALF = 0.3  # cone half-angle [rad]
STEP = 0.5e-3  # sample spacing [m]


def _fillet(kin, radius=0.015, lean=0.3, leg=0.04):
    """Samples of line - arc - line in the plane normal to the tool axis of a pose near home;
    the cone axis leans by ``lean`` toward the arc's centre (smoothed over ~3 mm, as the cut's
    axis program would); the frames have their axis on the cone axis and their X as close as
    possible to one direction. Returns (s, X_HT, q, cone, q0)."""
    q0 = np.array([0.2, 0.4, 0.1, 0.0, 0.9, 0.0])
    X0 = kin.X_HT_from_q(q0)
    p0, R0 = X0[:3, 3], X0[:3, :3]
    a0 = -R0[:, 2]  # tool axis, tip -> spindle
    e1 = np.cross(a0, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a0, e1)
    s1 = np.arange(0.0, leg, STEP)
    na = int(np.ceil(0.5 * np.pi * radius / STEP))
    th = np.arange(na) * (0.5 * np.pi / na)
    c = p0 + leg * e1 + radius * e2
    P = np.vstack([p0 + s1[:, None] * e1,
                   c - radius * np.cos(th)[:, None] * e2 + radius * np.sin(th)[:, None] * e1,
                   c + radius * e1 + s1[:, None] * e2])
    T = np.vstack([np.repeat(e1[None], len(s1), 0),
                   np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2,
                   np.repeat(e2[None], len(s1), 0)])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    cone = np.cos(lean) * a0[None] + np.sin(lean) * np.cross(-a0[None], T)
    cone = gaussian_filter1d(cone, 6.0, axis=0, mode="nearest")
    cone /= np.linalg.norm(cone, axis=1, keepdims=True)
    z = -cone
    x = R0[:, 0][None] - (z @ R0[:, 0])[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    X = np.repeat(np.eye(4)[None], len(s), axis=0)
    X[:, :3, :3] = np.stack([x, np.cross(z, x), z], axis=2)
    X[:, :3, 3] = P
    q, ok = kin.track(kin.X_WF_from_X_HT(X), q0)
    assert np.all(ok)
    return s, X, q, cone, q0


def _second_differences(s, q):
    """First and second derivatives of q(s) (N, 6) at the inner samples by finite differences
    on the (non-uniform) samples."""
    h0, h1 = np.diff(s)[:-1, None], np.diff(s)[1:, None]
    d1 = (q[2:] - q[:-2]) / (h0 + h1)
    d2 = 2.0 * ((q[2:] - q[1:-1]) / h1 - (q[1:-1] - q[:-2]) / h0) / (h0 + h1)
    return d1, d2


@pytest.fixture(scope="module")
def case():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(load_cell("tool_in_hand"))
    s, X, q, cone, q0 = _fillet(kin)
    lim = TimingLimits(v_cap=FEED, a_cap=3.0, v_max=tuple(kin.v_max), a_max=tuple(kin.a_max))
    before = time_path(s, q, X[:, :3, 3], lim, fk=kin.p_HT)
    runs = slow_stretches(s, before.v_tcp, (1 - BAND) * FEED)
    assert len(runs) == 1  # the fillet, and only it, is slow
    a, b, _ = runs[0]
    lo = int(np.searchsorted(s, s[a] - 0.02))
    hi = int(np.searchsorted(s, s[b] + 0.02))
    acc = lim.acceleration_fraction * np.asarray(kin.a_max)  # what the fillet repair passes
    vel = lim.velocity_fraction * np.asarray(kin.v_max)
    res = mut.hold_feed(kin, mut.FeedStretch(s, X, q, cone, HALF, lo, hi), 0.96 * FEED, acc,
                        vel)
    return dict(kin=kin, s=s, X=X, q=q, cone=cone, q0=q0, lim=lim, before=before, lo=lo,
                hi=hi, acc=acc, vel=vel, res=res)


def test_the_fillet_is_slow_before_the_program(case):
    before, lo, hi = case["before"], case["lo"], case["hi"]
    assert before.v_tcp[lo:hi].min() < 0.6 * FEED


def test_hold_feed_holds_the_feed_with_frames_inside_the_cone(case):
    res, X, cone, lo, hi = case["res"], case["X"], case["cone"], case["lo"], case["hi"]
    assert res.held and res.R is not None and res.sigma[-1] < 1e-3
    R = res.R
    assert R.shape == (hi - lo + 1, 3, 3)
    assert np.allclose(np.einsum("nji,njk->nik", R, R), np.eye(3), atol=1e-9)
    assert np.allclose(np.linalg.det(R), 1.0, atol=1e-9)
    fixed = mut.FeedProgramOptions().fixed
    assert np.allclose(R[:fixed], X[lo:lo + fixed, :3, :3])  # continuity with the cut
    assert np.allclose(R[-fixed:], X[hi - fixed + 1:hi + 1, :3, :3])
    # the frames did turn, and every axis stays inside its cone (angle from the dot product)
    assert np.max(np.abs(R - X[lo:hi + 1, :3, :3])) > 1e-2
    cosang = np.einsum("ni,ni->n", -R[:, :, 2], cone[lo:hi + 1])
    ang = np.arccos(np.clip(cosang, -1.0, 1.0))
    assert np.all(ang <= HALF + 1e-9), np.degrees(ang.max())


def test_hold_feed_joints_within_the_limits_at_the_feed_rechecked(case):
    """The exact IK at the returned frames, the FK back, finite differences at the feed."""
    kin, s, X, res, lo, hi = (case[k] for k in ("kin", "s", "X", "res", "lo", "hi"))
    Xn = X.copy()
    Xn[lo:hi + 1, :3, :3] = res.R
    qn, ok = kin.track(kin.X_WF_from_X_HT(Xn), case["q0"])
    assert np.all(ok)
    assert np.allclose(kin.X_HT_from_q(qn), Xn, atol=1e-9)  # same poses, points unmoved
    assert kin.within_limits(qn).all()
    v = 0.96 * FEED
    d1, d2 = _second_differences(s, qn)
    inner = slice(lo, hi - 1)  # inner samples lo + 1 .. hi - 1
    acc = np.abs(d2[inner]) * v ** 2
    vel = np.abs(d1[inner]) * v
    assert np.all(acc <= case["acc"]), (acc / case["acc"]).max()
    assert np.all(vel <= case["vel"]), (vel / case["vel"]).max()
    # the original frames broke the acceleration limit there (what the program was for)
    d1_0, d2_0 = _second_differences(s, case["q"])
    assert np.max(np.abs(d2_0[inner]) * v ** 2 / case["acc"]) > 1.5


def test_the_timing_holds_the_feed_through_the_fillet_afterwards(case):
    kin, s, X, res, lo, hi, lim = (case[k] for k in ("kin", "s", "X", "res", "lo", "hi", "lim"))
    Xn = X.copy()
    Xn[lo:hi + 1, :3, :3] = res.R
    qn, _ = kin.track(kin.X_WF_from_X_HT(Xn), case["q0"])
    after = time_path(s, qn, Xn[:, :3, 3], lim, fk=kin.p_HT)
    assert after.v_tcp[lo:hi + 1].min() >= (1 - BAND) * FEED
    assert after.t[-1] < case["before"].t[-1] - 0.05
    assert slow_stretches(s, after.v_tcp, (1 - BAND) * FEED) == []


def test_hold_feed_refuses_a_feed_that_stops(case):
    """A profile with a stop would divide the program's scaling by zero: refused up front."""
    kin, s, X, q, cone, lo, hi = (case[k] for k in ("kin", "s", "X", "q", "cone", "lo", "hi"))
    v = np.full(len(s), FEED)
    v[0] = 0.0
    with pytest.raises(ValueError, match="positive"):
        mut.hold_feed(kin, mut.FeedStretch(s, X, q, cone, HALF, lo, hi), v, case["acc"],
                      case["vel"])
