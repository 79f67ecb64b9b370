"""plan.window.execute_cut samples the executed cut finer, more than once, while the trajectory
would stray from the program between its samples (issue 42, audibot rim window 6: an open
stretch starting on a flank-to-face corner where the tool turns 33 deg/mm near the wrist
singularity; at the one halving allowed before, 0.125 mm, the verifier read 15 mrad between the
executed orientation and the program's slerp, against 10 mrad).

The synthetic cut: a 1 mm straight line at a reachable pose of the tool cell near the wrist
singularity (J5 = -0.45 rad), the tool turning steadily about its own X_T by 0.7 rad/mm. A
steady turn about a fixed axis is exactly the slerp of its end poses, so the program (targets
every 0.25 mm) agrees with every sample: all that can stray is the joint spline between the
samples, which swings the tool point off the line and turns the tool unevenly.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from drakedeburr.config import load_config
from drakedeburr.plan import cut as cut_mod
from drakedeburr.plan import window as mut
from drakedeburr.plan.cut_path import CutPath
from drakedeburr.plan.interpolate import DensePath
from drakedeburr.plan.options import PlanContext, PlanOptions, RunMode
from drakedeburr.plan.program_reading import program_orientation_error
from drakedeburr.plan.results import IkStep, WindowStatus
from drakedeburr.plan.timing import joint_spline

RATE = 0.7  # rad per mm of travel
LENGTH = 1.0e-3
Q0 = np.array([0.1, 0.5, 0.3, 0.2, -0.45, 0.1])


@pytest.fixture(scope="module")
def kin():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.plan.kinematics import cell_kinematics

    return cell_kinematics(load_cell("tool_in_hand", "h5_straight"))


def _track(kin):
    """A stand-in for plan.cut.track_cut: the synthetic cut sampled every ``step``."""
    X0 = kin.X_HT_from_q(Q0)
    tracked = []

    def track(ctx, wt, ik, step):
        s = np.linspace(0.0, LENGTH, int(round(LENGTH / step)) + 1)
        X = np.tile(X0, (len(s), 1, 1))
        X[:, :3, 3] += s[:, None] * X0[:3, 0]
        X[:, :3, :3] = X0[:3, :3] @ Rotation.from_euler("x", RATE * s[:, None] / 1e-3).as_matrix()
        q, ok = kin.track(kin.X_WF_from_X_HT(X), Q0)
        ti = np.flatnonzero(np.isclose(np.mod(s + 1e-12, 0.25e-3), 0.0, atol=1e-9))
        cp = CutPath(X_HT=X, s=s, target_index=ti, X_target=X[ti].copy(),
                     zone=np.zeros(len(ti)))
        tracked.append(step)
        return cut_mod._Try(cp=cp, cut=DensePath(X_HT=X, s=s, target_index=ti, q=q, ok=ok),
                            dist=np.full(len(s), 0.01), spin_mode="ik")

    return track, tracked


def _executed_stray(kin, ex, per_interval: int = 16) -> float:
    """Independently, as the verifier reads it: the joint spline through the executed samples
    read densely between them, FK, against the program's slerp (plan.program_reading)."""
    s = ex.cut.s
    f = np.arange(per_interval) / per_interval
    s_all = np.concatenate([(s[:-1, None] + f[None] * np.diff(s)[:, None]).ravel(), s[-1:]])
    X = kin.X_HT_from_q(joint_spline(s, ex.cut.q)(s_all))
    return float(program_orientation_error(X, ex.cp.X_target)[0].max())


def _execute(kin, monkeypatch):
    track, tracked = _track(kin)
    monkeypatch.setattr(mut, "track_cut", track)
    ctx = PlanContext(cell=None, kin=kin, checker=None, free_checker=None,
                      config=load_config("tool_in_hand", "h5_straight"),
                      options=PlanOptions(fillets=None, conform_program=False))
    X_t = track(ctx, None, None, ctx.options.dense_step).cp.X_target
    tracked.clear()
    k = len(X_t)
    retract = -X_t[:, :3, 2]  # the cone axes (tip -> spindle) at the targets: the tool's own
    wt = SimpleNamespace(window_index=0, cone_retract_H=retract, cone_half_angle=0.5)
    ik = IkStep(status=WindowStatus.OK, wik=None, good=np.arange(k), order=np.arange(k),
                failures=(), seconds=0.0, starts=1)
    return ctx, mut.execute_cut(ctx, wt, ik, RunMode.FULL), tracked


def test_the_cut_is_sampled_finer_until_it_keeps_to_the_program(kin, monkeypatch):
    ctx, out, tracked = _execute(kin, monkeypatch)
    tol = ctx.config.tolerances.orientation_match
    assert out.status is WindowStatus.OK and not out.failures
    # 0.25 -> 0.125 -> 0.0625 mm: the second halving is the one that brings it within the bound
    assert tracked == pytest.approx([0.25e-3, 0.125e-3, 0.0625e-3])
    ex = out.executed
    assert np.diff(ex.cut.s).max() == pytest.approx(0.0625e-3)
    assert not ex.via.any()  # the program agrees with every sample (a steady turn is a slerp)
    stray = _executed_stray(kin, ex)
    assert stray <= 0.8 * tol
    # the wrist turns fast here: 0.7 rad/mm near J5 = -0.45 rad (not a trivial case)
    assert np.abs(ex.cut.q[:, 4]).min() < 0.5


def test_one_halving_leaves_the_trajectory_straying_from_the_program(kin, monkeypatch):
    """What the one halving allowed before left: the cut kept at 0.125 mm, its trajectory
    reading more than the tolerance off the program's slerp between the samples."""
    monkeypatch.setattr(mut, "FINER_HALVINGS", 1)
    ctx, out, tracked = _execute(kin, monkeypatch)
    assert tracked == pytest.approx([0.25e-3, 0.125e-3])
    assert _executed_stray(kin, out.executed) > ctx.config.tolerances.orientation_match


def test_the_halvings_are_bounded(kin, monkeypatch):
    """A cut that strays at every step stops after FINER_HALVINGS halvings (no endless
    refinement): 1/8 of the dense step."""
    from drakedeburr.plan.results import ProgramFit

    calls = []

    def fit(ctx, wt, tr, order, refine):
        calls.append(refine)
        return ProgramFit(status=WindowStatus.OK, finer=True) if refine else \
            ProgramFit(status=WindowStatus.OK, executed=SimpleNamespace(cut=tr.cut))

    monkeypatch.setattr(mut, "fit_program", fit)
    _, out, tracked = _execute(kin, monkeypatch)
    assert tracked == pytest.approx([0.25e-3 / 2 ** k for k in range(mut.FINER_HALVINGS + 1)])
    assert calls == [True] * mut.FINER_HALVINGS + [False]
