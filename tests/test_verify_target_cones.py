"""verify ``cone`` on the program's own targets (drakedeburr.verify.cut_geometry.target_cones,
read by drakedeburr.verify.checks_path.cone): a target whose axis, by the forward kinematics of
the joints written, leaves the cone of the CL point it cuts fails the check, whatever the dense
samples of the trajectory read; its margin is the constructed angle."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import verify_support as vs

from drakedeburr.robots.opw_ik import ik_opw
from drakedeburr.verify.cut_geometry import axis_angle, target_cones
from drakedeburr.verify.kinematics import VerifyKinematics
from drakedeburr.verify.refs import cone_half_angle, tool_paths_of, window_ref

WINDOW = 0


def _rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit ``a`` onto unit ``b`` (Rodrigues)."""
    v, c = np.cross(a, b), float(a @ b)
    s = np.linalg.norm(v)
    if s < 1e-15:
        return np.eye(3)
    k = v / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def _tilted(plan, past: float):
    """The plan with one mid-loop CL target of WINDOW re-solved (analytic IK) so that its tool
    axis lies ``past`` [rad] beyond its CL point's cone (negative: inside), turned about the
    tool point; the trajectory is left as it is. -> (plan, target index, CL index)."""
    cell, _ = vs.cell_and_hub()
    kin = VerifyKinematics(cell)
    tp = tool_paths_of(plan)[WINDOW]
    ks = [k for k, t in enumerate(plan.targets)
          if t.window_index == WINDOW and t.segment == "cut" and t.cl_index >= 0]
    k = ks[len(ks) // 2]
    t = plan.targets[k]
    c = np.asarray(tp.cone_zT_H[t.cl_index], float)
    c /= np.linalg.norm(c)
    half = cone_half_angle(plan, WINDOW, tp)
    X = np.asarray(t.X_HT, float)
    e = X[:3, 0] - (X[:3, 0] @ c) * c
    e /= np.linalg.norm(e)
    ang = half + past
    z_new = np.cos(ang) * c + np.sin(ang) * e
    X_new = X.copy()
    X_new[:3, :3] = _rotation(X[:3, 2], z_new) @ X[:3, :3]
    X_WF = kin.X_WH @ X_new @ np.linalg.inv(kin.X_FT)
    sol = ik_opw(kin.opw, np.linalg.solve(kin.X_WB, X_WF))
    q_all = sol.q[0][sol.valid[0]]
    step = np.mod(q_all - t.q + np.pi, 2 * np.pi) - np.pi
    q = t.q + step[int(np.argmin(np.abs(step).sum(axis=1)))]
    assert np.allclose(kin.X_HT(q)[0], X_new, atol=1e-10)
    targets = list(plan.targets)
    targets[k] = replace(t, q=q, X_HT=X_new, X_WF=X_WF)
    return replace(plan, targets=tuple(targets)), k, int(t.cl_index)


@pytest.mark.parametrize("past", [1e-5, -1e-5])
def test_target_outside_its_cone_fails_inside_passes(past):
    plan, k, cl = _tilted(vs.good_plan(), past)
    report = vs.verify(plan)
    item = report.item("cone")
    tol = report.settings["tolerances"]["cone_slack"]
    assert tol < abs(past)
    # the dense samples of the (unchanged) trajectory stay well inside the 0.1 rad cone
    assert report.item("cone").per_window[WINDOW]["max_angle_to_cone_axis"] < 1e-6
    assert item.passed is (past < 0)
    assert ("cone" in report.failed) is (past > 0)
    assert item.window == WINDOW and item.target_index == k
    assert item.value == pytest.approx(-past, abs=1e-9)
    fig = item.per_window[WINDOW]
    assert fig["target_worst"] == k and fig["target_worst_cl"] == cl
    assert fig["target_min_margin"] == pytest.approx(-past, abs=1e-9)
    assert f"program target {k}" in item.detail


def test_target_cones_read_each_target_independently():
    """On the good plan every cut target of both windows is read, each at its own cone: the
    margin equals half-angle minus the angle between the target's FK axis and the CL point's
    cone axis, recomputed here by hand."""
    plan = vs.good_plan()
    cell, _ = vs.cell_and_hub()
    kin = VerifyKinematics(cell)
    X = kin.X_HT(np.array([t.q for t in plan.targets]))
    tps = tool_paths_of(plan)
    refs = {w: window_ref(w, plan.targets, tps[w], None, vs.PARAMS) for w in vs.WINDOWS}
    tc = target_cones(plan, X, refs, list(vs.WINDOWS))
    for w in vs.WINDOWS:
        tp = tps[w]
        ks = [k for k, t in enumerate(plan.targets) if t.window_index == w and t.cl_index >= 0]
        c = np.asarray(tp.cone_zT_H)[[plan.targets[k].cl_index for k in ks]]
        c /= np.linalg.norm(c, axis=1, keepdims=True)
        want = cone_half_angle(plan, w, tp) - axis_angle(c, X[ks, :3, 2])
        assert np.allclose(tc["margin"][ks], want, atol=1e-12)
        assert tc["per_window"][w]["targets"] >= len(ks)
    off = [k for k, t in enumerate(plan.targets) if t.window_index not in vs.WINDOWS]
    assert np.isnan(tc["margin"][off]).all()
