"""Hub-pose registration on a synthetic 5-window hub-like disc."""

import numpy as np
import pytest
from orient_geometry import disc_with_windows, scan_of
from pydrake.math import RigidTransform, RotationMatrix

import drakedeburr.hub.registration as mut
from drakedeburr.hub.types import ScanCloud

N_WINDOWS = 5


@pytest.fixture(scope="module")
def scene():
    mesh = disc_with_windows(N_WINDOWS)
    rng = np.random.default_rng(0)
    phi = rng.uniform(-np.pi / N_WINDOWS, np.pi / N_WINDOWS)
    shift = rng.uniform(-5e-3, 5e-3, 3)
    X_true = RigidTransform(RotationMatrix.MakeZRotation(phi), shift)
    scan = scan_of(mesh, spacing=0.6e-3, sigma=0.05e-3, seed=1)
    p = scan.p_S
    keep = (p[:, 2] > -0.0115) & (p[:, 0] > -0.045)  # partial: no back face, one side cut off
    p_W = mut.points_in_world(X_true, p[keep])
    return mesh, X_true, ScanCloud(p_W, source="scan.ply")


def test_recovers_turn_and_shift(scene):
    mesh, X_true, scan = scene
    res = mut.register_hub(scan, mesh, options=mut.RegistrationOptions(symmetry_order=N_WINDOWS))
    assert res.accepted, res.message
    err = res.X_WH.inverse().multiply(X_true)
    assert np.linalg.norm(err.translation()) <= 0.1e-3
    assert np.degrees(err.rotation().ToAngleAxis().angle()) <= 0.05
    assert res.fitness >= 0.95 and res.rmse <= 0.1e-3
    # CL points follow the registered pose
    p_H = np.array([[0.035, 0.0, 0.0], [0.0, 0.035, 0.0]])
    np.testing.assert_allclose(mut.points_in_world(res.X_WH, p_H),
                               mut.points_in_world(X_true, p_H), atol=0.1e-3)


def test_refuses_a_wrong_hub_model(scene):
    _, _, scan = scene
    wrong = disc_with_windows(N_WINDOWS, window=(0.013, 0.008, 0.004))  # 1 mm longer windows
    res = mut.register_hub(scan, wrong, options=mut.RegistrationOptions(symmetry_order=N_WINDOWS))
    assert not res.accepted
    assert "REFUSED" in res.message and "fitness" in res.message
    with pytest.raises(mut.RegistrationRefused, match="REFUSED"):
        res.require()


def test_turn_about_hub_axis():
    X = RigidTransform(RotationMatrix.MakeXRotation(0.3), [1.0, 2.0, 3.0])
    Y = mut.turn_about_hub_axis(X, 0.5)
    np.testing.assert_allclose(Y.rotation().matrix()[:, 2], X.rotation().matrix()[:, 2])
    np.testing.assert_allclose(Y.translation(), X.translation())
