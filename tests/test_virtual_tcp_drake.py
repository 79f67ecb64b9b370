"""Virtual-TCP mapping (source 000) cross-checked against the Drake workpiece-in-hand plan.

The planner (``drakedeburr.plan``) plans the workpiece-in-hand cell directly: for each cut
target it solves X_WF(i) such that the hub H, riding on the flange (fixed X_FH), carries the
planned process pose X_HT(i) onto the fixed spindle frame T (fixed X_WT), i.e.
X_WH(i) = X_WF(i) X_FH = X_WT X_HT(i)^-1. The paper's virtual-TCP mapping
(``drakedeburr.post.virtual_tcp.virtual_tcp_poses``) reaches the same goal by a different
route: the contour frames A_i are taught in the robot base R = W at a reference part pose
X_WH_ref, the robot's TCP frame P (rigid with the part) coincides with the tool frame O = T at
that reference, and the TCP is sent to virtual points V_i; the part follows as
X_WH_virtual(i) = X_WV(i) X_WT^-1 X_WH_ref.

Here A_i = the plan's tool pose in the hub (X_HA_i = X_HT(i): the CL point, already offset
by the burr's contact geometry, with the tool frame's orientation) and X_WH_ref is the hub
pose at the first cut target. Comparisons (all exact kinematics, so tight bounds):

* both modes: the contour point A_i lands on the fixed tool point (its position in T is zero,
  <= 1e-9 m) and the tool point traces the same path on the part as the plan
  (X_WH_virtual(i)^-1 p_WT == p_HT(i), <= 1e-9 m): the same part-relative motion;
* rotation mode (X_OV = X_OA^-1) reproduces the plan's full poses: hub, flange (<= 1e-9 m,
  <= 1e-9 rad) and, through the analytic OPW IK (``solve_path`` on X_WF = X_WH X_HF,
  configuration continuity from the joints before the cut), the plan's joints (<= 1e-6 rad);
* translation mode keeps the part's orientation at the reference one by construction, so it
  can equal the plan in orientation (and joints) only where the plan's hub orientation equals
  the reference one: at the reference target itself (checked, joints included). Elsewhere only
  the positional part-relative motion is compared; the tool-axis difference relative to the
  part is exactly the plan's own orientation change since the reference (checked), i.e. the
  mode's documented loss of the 5-axis orientation. Its IK is checked by FK round trip and
  branch continuity (no plan joints exist for those poses).
"""

import numpy as np
import pytest

import drakedeburr.post.virtual_tcp as mut
from drakedeburr.config import load_config
from drakedeburr.resources import hub_names
from drakedeburr.robots.opw import fk_opw
from drakedeburr.robots.opw_ik import arm_branches, solve_path

pytestmark = pytest.mark.skipif(not hub_names(), reason="no bundled hub models")

POS_TOL = 1e-9  # m
ROT_TOL = 1e-9  # rad
Q_TOL = 1e-6  # rad


def _angle(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """(N, 3, 3) x2 -> (N,) rotation angle of R_a^T R_b [rad].

    From the chord ||R_a - R_b||_F = 2 sqrt(2) sin(angle / 2): exact to round-off near zero,
    where arccos of the trace resolves only ~2e-8 rad.
    """
    d = np.linalg.norm(np.asarray(R_a) - np.asarray(R_b), axis=(-2, -1))
    return 2 * np.arcsin(np.clip(d / np.sqrt(8), 0, 1))


@pytest.fixture(scope="module")
def wih():
    """A 16-CL-point workpiece-in-hand plan of one window and the fixed cell transforms."""
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub import DEFAULT_HUB, load_hub
    from drakedeburr.plan import WindowTargets, plan_windows
    from drakedeburr.plan.kinematics import cell_kinematics

    cell = load_cell("workpiece_in_hand", DEFAULT_HUB)
    wt = WindowTargets.from_window_edge(load_hub(DEFAULT_HUB).windows[0]).stretch(0, 16)
    plan = plan_windows(cell, [wt], load_config("workpiece_in_hand", DEFAULT_HUB))
    assert plan.failures == () and plan.mode == "workpiece"
    seg = next(s for s in plan.segments if s.kind == "cut")
    a, b = seg.target_range
    cut = plan.targets[a:b]
    assert len(cut) >= 10
    X_FH = np.array(plan.meta["X_FH"])
    X_WT = np.array(plan.meta["X_WT"])
    return dict(kin=cell_kinematics(cell), X_FH=X_FH, X_WT=X_WT,
                X_HT=np.array([t.X_HT for t in cut]), X_WF=np.array([t.X_WF for t in cut]),
                q=np.array([t.q for t in cut]), q_before=plan.targets[a - 1].q)


def _virtual(wih, mode):
    """Hub and flange poses the virtual-TCP mapping prescribes for the plan's contour."""
    X_WT, X_FH, X_HT = wih["X_WT"], wih["X_FH"], wih["X_HT"]
    X_WH_ref = X_WT @ np.linalg.inv(X_HT[0])  # part pose at the first cut target
    X_RA = X_WH_ref[None] @ X_HT  # contour frames taught in R = W at the reference
    X_RV = mut.virtual_tcp_poses(X_WT, X_RA, mode)
    X_WH = X_RV @ np.linalg.inv(X_WT)[None] @ X_WH_ref[None]  # part rigid with the TCP
    return X_RA, X_RV, X_WH, X_WH @ np.linalg.inv(X_FH)[None]


def test_plan_is_consistent_with_its_fixed_transforms(wih):
    # X_HT(i) = (X_WF X_FH)^-1 X_WT: the plan's own closure, the basis of every comparison
    X_WH = wih["X_WF"] @ wih["X_FH"][None]
    np.testing.assert_allclose(np.linalg.inv(X_WH) @ wih["X_WT"][None], wih["X_HT"], atol=1e-9)
    np.testing.assert_allclose(fk_opw(wih["kin"].robot.opw, wih["q"]), wih["X_WF"], atol=1e-9)


@pytest.mark.parametrize("mode", ["translation", "rotation"])
def test_same_part_relative_motion(wih, mode):
    X_WT, X_HT = wih["X_WT"], wih["X_HT"]
    X_RA, X_RV, X_WH_v, _ = _virtual(wih, mode)
    # the contour point sits on the fixed tool point (library check and by hand)
    X_OA_after = mut.part_contour_at_virtual(X_WT, X_RV, X_RA)
    assert np.abs(X_OA_after[:, :3, 3]).max() <= POS_TOL
    p_T = (np.linalg.inv(X_WT)[None] @ X_WH_v @ X_HT)[:, :3, 3]
    assert np.abs(p_T).max() <= POS_TOL
    # the tool point traces the plan's path on the part
    p_H_tool = (np.linalg.inv(X_WH_v) @ X_WT[None])[:, :3, 3]
    assert np.abs(p_H_tool - X_HT[:, :3, 3]).max() <= POS_TOL
    # hence the same relative displacement between consecutive points (the cut's chords)
    np.testing.assert_allclose(np.diff(p_H_tool, axis=0), np.diff(X_HT[:, :3, 3], axis=0),
                               atol=POS_TOL)


def test_rotation_mode_reproduces_the_plan_poses_and_joints(wih):
    _, _, X_WH_v, X_WF_v = _virtual(wih, "rotation")
    X_WH_plan = wih["X_WF"] @ wih["X_FH"][None]
    assert np.abs(X_WH_v[:, :3, 3] - X_WH_plan[:, :3, 3]).max() <= POS_TOL
    assert _angle(X_WH_v[:, :3, :3], X_WH_plan[:, :3, :3]).max() <= ROT_TOL
    assert np.abs(X_WF_v[:, :3, 3] - wih["X_WF"][:, :3, 3]).max() <= POS_TOL
    assert _angle(X_WF_v[:, :3, :3], wih["X_WF"][:, :3, :3]).max() <= ROT_TOL
    # analytic OPW IK of the virtual flange poses, continuing from the joints before the cut
    robot = wih["kin"].robot
    res = solve_path(robot, X_WF_v, q_start=wih["q_before"])
    assert res.ok and res.configuration_changes == ()
    np.testing.assert_array_equal(res.branch, arm_branches(robot.opw, wih["q"]))
    assert np.abs(res.q - wih["q"]).max() <= Q_TOL


def test_translation_mode_keeps_the_part_orientation(wih):
    X_HT = wih["X_HT"]
    _, _, X_WH_v, X_WF_v = _virtual(wih, "translation")
    X_WH_plan = wih["X_WF"] @ wih["X_FH"][None]
    # the part only translates (no cable wind-up) ...
    assert _angle(X_WH_v[:, :3, :3], X_WH_v[:1, :3, :3]).max() <= ROT_TOL
    # ... so it equals the plan where the plan's orientation is the reference one: target 0
    assert np.abs(X_WH_v[0] - X_WH_plan[0]).max() <= POS_TOL
    assert np.abs(X_WF_v[0] - wih["X_WF"][0]).max() <= POS_TOL
    # elsewhere the tool's orientation relative to the part is frozen at the reference: it
    # differs from the plan's by exactly the plan's own orientation change since then
    R_HT_v = np.swapaxes(X_WH_v[:, :3, :3], -1, -2) @ wih["X_WT"][None, :3, :3]
    np.testing.assert_allclose(_angle(R_HT_v, X_HT[:, :3, :3]),
                               _angle(X_HT[:1, :3, :3], X_HT[:, :3, :3]), atol=1e-9)
    assert _angle(X_HT[:1, :3, :3], X_HT[:, :3, :3]).max() > 1e-3  # a non-trivial comparison
    # IK of the translation-mode flange poses: FK round trip, one configuration, and the
    # plan's joints at the reference target
    robot = wih["kin"].robot
    res = solve_path(robot, X_WF_v, q_start=wih["q_before"])
    assert res.ok and res.configuration_changes == ()
    assert np.abs(fk_opw(robot.opw, res.q) - X_WF_v).max() <= POS_TOL
    assert np.abs(res.q[0] - wih["q"][0]).max() <= Q_TOL
    assert np.abs(np.diff(res.q, axis=0)).max() < 0.2  # no flips or 2*pi turns
