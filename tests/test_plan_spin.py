import numpy as np
import pytest

import drakedeburr.plan.spin as mut
from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif(not hub_names(), reason="no bundled hub models")


def _cost(kin, q):
    return float(np.sum((np.diff(q, axis=0) / np.asarray(kin.v_max)) ** 2))


def test_spin_frames_turn_about_z_only():
    rng = np.random.default_rng(0)
    R = np.linalg.qr(rng.normal(size=(5, 3, 3)))[0]
    R[np.linalg.det(R) < 0, :, 0] *= -1
    psi = rng.uniform(-3, 3, 5)
    out = mut.spin_frames(R, psi)
    assert np.allclose(out[:, :, 2], R[:, :, 2])
    assert np.allclose(np.einsum("nij,nik->njk", R, out)[:, 2, 2], 1.0)
    ang = np.arctan2(np.einsum("ni,ni->n", np.cross(R[:, :, 0], out[:, :, 0]), R[:, :, 2]),
                     np.einsum("ni,ni->n", R[:, :, 0], out[:, :, 0]))
    assert np.allclose(ang, np.mod(psi + np.pi, 2 * np.pi) - np.pi)


def test_spin_search_keeps_axes_and_points_and_removes_a_wobble():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(load_cell("tool_in_hand"))
    # a smooth arm motion near home, its tool poses, then a +-1 rad spin wobble added
    n = 240
    s = np.linspace(0.0, 0.06, n)
    q0 = np.array([0.2, 0.4, 0.1, 0.0, 0.9, 0.0])  # wrist centred, well off J5 = 0
    q = q0 + np.outer(np.sin(np.pi * s / s[-1]), [0.1, 0.05, -0.05, 0.2, 0.1, 0.3])
    X = kin.X_HT_from_q(q)
    X_wob = X.copy()
    X_wob[:, :3, :3] = mut.spin_frames(X[:, :3, :3], 1.0 * np.sin(2 * np.pi * s / 0.02))
    q_wob, ok = kin.track(kin.X_WF_from_X_HT(X_wob), q0)
    assert np.all(ok)
    out, stats = mut.optimize_spin(kin, X_wob, s, q0, mut.SpinSearch(wrist_margin=0.15))
    assert stats["ok"]
    assert np.allclose(out[:, :3, 3], X_wob[:, :3, 3], atol=1e-12)
    assert np.allclose(out[:, :3, 2], X_wob[:, :3, 2], atol=1e-12)
    q_out, ok = kin.track(kin.X_WF_from_X_HT(out), q0)
    assert np.all(ok) and np.all(np.abs(q_out[:, 4]) >= 0.15)
    # FK of the result reproduces its poses (independent re-check of the tracking)
    assert np.allclose(kin.X_HT_from_q(q_out), out, atol=1e-9)
    assert _cost(kin, q_out) < 0.5 * _cost(kin, q_wob)


def test_spin_search_result_stays_inside_the_limits_near_a_j4_limit():
    # a cut whose wrist winds J4 up to within a few degrees of its limit: the smoothing of the
    # searched spin must not carry J4 past it (it did, 200.6 deg against 200)
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(load_cell("tool_in_hand"))
    n = 300
    s = np.linspace(0.0, 0.08, n)
    top = kin.q_upper[3] - 0.03
    q0 = np.array([0.2, 0.4, 0.1, top - 1.2, 0.9, 0.0])
    ramp = np.clip(s / (0.6 * s[-1]), 0.0, 1.0)
    q = q0 + np.outer(ramp, [0.1, 0.05, -0.05, 1.2, 0.2, 0.8])
    X = kin.X_HT_from_q(q)
    X[:, :3, :3] = mut.spin_frames(X[:, :3, :3], 0.6 * np.sin(2 * np.pi * s / 0.03))
    for sigma in (4e-3, 12e-3, 30e-3):
        search = mut.SpinSearch(wrist_margin=0.15, sigma=sigma)
        out, stats = mut.optimize_spin(kin, X, s, q0, search)
        if not stats["ok"]:
            continue
        q_out, ok = kin.track(kin.X_WF_from_X_HT(out), q0)
        assert np.all(ok), (sigma, np.degrees(q_out[:, 3].max()))
        assert np.all(q_out[:, 3] <= kin.q_upper[3] + 1e-9)
        assert np.all(np.abs(q_out[:, 4]) >= 0.8 * 0.15)
        assert np.allclose(out[:, :3, 2], X[:, :3, 2], atol=1e-12)
        assert stats["sigma_m"] <= sigma
