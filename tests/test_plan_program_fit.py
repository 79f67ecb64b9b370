"""plan.program_fit: via targets where the program's linear moves leave the executed tool
point (a path that winds between its targets: seen on a relaxed window of catalogue hub
271128_046, 0.059 mm against the 0.05 mm path_deviation between two via targets)."""

from __future__ import annotations

import numpy as np
import pytest

from drakedeburr.plan import program_fit as mut
from drakedeburr.plan.cut_path import CutPath
from drakedeburr.plan.program_reading import moves_in_order
from drakedeburr.verify.geometry import point_segment

TOL_POS = 0.04e-3  # [m] the planner's default: 0.8 x the 0.05 mm path_deviation


def _winding_cut(amplitude: float, wavelength: float = 0.5e-3, length: float = 3e-3,
                 step: float = 0.01e-3) -> CutPath:
    """A tool point winding about the x axis (y = A sin(2 pi x / wavelength)), constant
    orientation; targets where it crosses the axis (the program's moves run along it)."""
    s = np.arange(0.0, length + step / 2, step)
    X = np.tile(np.eye(4), (len(s), 1, 1))
    X[:, 0, 3] = s
    X[:, 1, 3] = amplitude * np.sin(2 * np.pi * s / wavelength)
    ti = np.flatnonzero(np.isclose(np.mod(s + step / 2, wavelength / 2), step / 2, atol=step / 4))
    return CutPath(X_HT=X, s=s, target_index=ti, X_target=X[ti].copy(),
                   zone=np.full(len(ti), 0.1e-3))


def _deviation(cp: CutPath) -> tuple[float, float]:
    """(the verifier's reading: monotone moves, the nearest of any move) [m]."""
    P = cp.X_target[:, :3, 3]
    d = moves_in_order(cp.X_HT[:, :3, 3], P[:-1], P[1:])[0]
    nearest = point_segment(cp.X_HT[:, :3, 3], P[:-1], P[1:])[0]
    return float(d.max()), float(nearest.max())


def test_vias_split_moves_the_winding_path_leaves():
    cp = _winding_cut(0.06e-3)
    before = _deviation(cp)
    assert before[0] > 0.059e-3 and before[1] > 0.059e-3
    out, via = mut.add_vias(cp, np.inf, 8, 0, tol_position=TOL_POS)
    after = _deviation(out)
    assert after[0] <= TOL_POS and after[1] <= TOL_POS, after
    # analytic: a via at each crest; a quarter wave's sine leaves its chord by at most
    # A max(sin x - 2x/pi) = 0.2105 A (0.22 A: the crest sample is up to half a step off)
    assert after[0] <= 0.22 * 0.06e-3
    assert via.sum() == len(cp.target_index) - 1
    np.testing.assert_array_equal(out.X_target[via], out.X_HT[out.target_index[via]])
    np.testing.assert_array_equal(out.target_index[~via], cp.target_index)
    assert not np.intersect1d(out.target_index[via], cp.target_index).size
    assert np.all(np.diff(out.target_index) > 0) and np.all(out.zone > 0)


def test_a_path_within_the_bound_gets_no_via():
    cp = _winding_cut(0.035e-3)
    assert _deviation(cp)[0] <= TOL_POS
    out, via = mut.add_vias(cp, np.inf, 8, 0, tol_position=TOL_POS)
    assert not via.any() and out is cp
    # and without the position bound the orientation reading alone adds none (constant R)
    out, via = mut.add_vias(_winding_cut(0.06e-3), 0.01, 8, 0)
    assert not via.any()


def _spinning_cut(spin_step: float):
    """Samples 0.25 mm apart on a straight 2.5 mm line at a reachable pose of the tool cell,
    the tool turned about its own axis by +-``spin_step`` from sample to sample (the tool
    point stays on the line; the joints between samples do not)."""
    from types import SimpleNamespace

    from scipy.spatial.transform import Rotation

    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    kin = cell_kinematics(load_cell("tool_in_hand", "h5_straight"))
    q0 = np.array([0.1, 0.5, 0.3, 0.2, -0.9, 0.1])
    X0 = kin.X_HT_from_q(q0)
    s = np.arange(11) * 0.25e-3
    X = np.tile(X0, (len(s), 1, 1))
    X[:, :3, 3] += s[:, None] * X0[:3, 0]
    psi = spin_step * (np.arange(len(s)) % 2)
    X[:, :3, :3] = X0[:3, :3] @ Rotation.from_euler("z", psi[:, None]).as_matrix()
    q, ok = kin.track(kin.X_WF_from_X_HT(X), q0)
    assert ok.all()
    ends = np.array([0, len(s) - 1])
    return kin, SimpleNamespace(s=s, q=q), SimpleNamespace(X_target=X[ends]), X


def test_between_samples_the_tool_point_is_read_against_the_program():
    """The spline's tool point between two samples whose wrist turns 0.3 rad leaves the
    program's line (the near stop of catalogue hub 271128_046); read as the verifier reads
    it and equal to the distance of the quarter points from the line (point_segment);
    without the turn it stays on the line to interpolation accuracy."""
    from drakedeburr.plan.cut import between_samples_error
    from drakedeburr.plan.timing import joint_spline

    kin, cut, cp, _ = _spinning_cut(0.3)
    dev = between_samples_error(kin, cut, cp)[2]
    ds = np.diff(cut.s)
    s_q = np.concatenate([cut.s[:-1] + f * ds for f in (0.25, 0.5, 0.75)])
    p = kin.X_HT_from_q(joint_spline(cut.s, cut.q)(s_q))[:, :3, 3]
    P = cp.X_target[:, :3, 3]
    ref = point_segment(p, P[:1], P[1:])[0].max()
    assert dev == pytest.approx(ref, rel=1e-9, abs=1e-12)
    assert dev > TOL_POS
    kin, cut, cp, _ = _spinning_cut(0.0)
    assert between_samples_error(kin, cut, cp)[2] < 1e-6
