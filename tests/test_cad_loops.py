"""hub.cad_loops.continuous_frames on an analytic loop: a circle of radius R in the plane z = 0
(face normal +z, wall normal radial outward), with the B-rep's kind of fault injected: at a
few points the wall normal is the next side's wall (along the tangent) and the face normal
jumps 27 deg. The frames must come back square, radial within the averaging's reach and
continuous, and the tangent must run with the loop's travel."""

import numpy as np
import pytest

pytest.importorskip("OCP")  # hub.cad (imported by cad_loops) needs OpenCASCADE

from drakedeburr.hub.cad_loops import continuous_frames  # noqa: E402


def test_frames_square_continuous_and_radial_on_a_circle():
    R, spacing = 0.05, 0.5e-3
    n = int(round(2 * np.pi * R / spacing))
    a = 2 * np.pi * np.arange(n) / n
    p = np.c_[R * np.cos(a), R * np.sin(a), np.zeros(n)]
    t = np.c_[-np.sin(a), np.cos(a), np.zeros(n)]
    radial = np.c_[np.cos(a), np.sin(a), np.zeros(n)]
    n_wall, n_face = radial.copy(), np.tile([0.0, 0.0, 1.0], (n, 1))
    bad = np.arange(100, 106)
    n_wall[bad] = t[bad]  # the next side's wall, along the tangent (a 90 deg jump)
    tilt = np.radians(27)
    n_face[300:340] = [np.sin(tilt), 0.0, np.cos(tilt)]  # a crease of the front surface
    w, f, tt = continuous_frames(p, t, n_wall, n_face, spacing)
    for v in (w, f, tt):
        assert np.allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-12)
    assert np.abs(np.einsum("ij,ij->i", w, tt)).max() < 1e-9  # square
    assert np.abs(np.einsum("ij,ij->i", f, tt)).max() < 1e-9
    assert np.einsum("ij,ij->i", tt, t).min() > 0.9  # runs with the travel
    # radial where the faults are out of the 1.5 mm averaging reach
    far = np.ones(n, bool)
    far[80:126] = far[280:360] = False
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", w[far], radial[far]), -1, 1))
                      ).max() < 0.5
    # continuous: no jump between points 0.5 mm apart (the input jumped 90 and 27 deg)
    for v in (w, f, tt):
        turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", v, np.roll(v, -1, 0)),
                                            -1, 1)))
        assert turn.max() < 6.0
