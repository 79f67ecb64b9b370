"""The reachability claims behind the fixture and stand poses, re-checked by independent FK."""

from pathlib import Path

import numpy as np
import pytest

import drakedeburr.cell.reach as mut
from drakedeburr.cell.station import load_cell
from drakedeburr.robots import IRB1600_10_120, fk_opw

STAND_IN_HUB = Path(__file__).resolve().parent / "data" / "stand_in_hub" / "hub.sdf"


def test_face_targets():
    targets = mut.face_targets(0.23, rings=2, per_ring=8, tilt=0.5, tilts=4)
    assert len(targets) == 17 * 5
    radii = {round(float(np.hypot(*t.p_HQ[:2])), 9) for t in targets}
    assert radii == {0.0, 0.115, 0.23}
    angles = {round(float(np.arccos(-t.a_H[2])), 9) for t in targets}
    assert angles == {0.0, 0.5}


@pytest.mark.parametrize("scenario", ["tool_in_hand", "workpiece_in_hand"])
def test_whole_face_is_reachable_with_margins(scenario):
    cell = load_cell(scenario, hub=STAND_IN_HUB)
    # rim (0.23 m) and centre, vertical and 0.5 rad tilts: the hardest targets of the study
    targets = [t for t in mut.face_targets(0.23, rings=1, per_ring=6, tilt=0.5, tilts=4)]
    survey = mut.survey_reach(cell, targets, mut.ReachOptions(
        joint_margin=np.radians(10), wrist_margin=0.25, min_distance=0.005))
    assert survey.all_reached, [targets[i] for i in survey.failed]
    assert survey.min_wrist >= 0.25 - 1e-9
    X_FT = cell.X_WF(cell.q_home).inverse().multiply(cell.X_WT(cell.q_home))
    X_WH = cell.X_WH(cell.q_home)
    for r in survey.results:
        q = r.q
        assert np.all(q >= cell.q_lower + np.radians(10) - 1e-9)
        assert np.all(q <= cell.q_upper - np.radians(10) + 1e-9)
        # independent FK: OPW flange pose composed with the fixed tool / hub offsets
        X_WF = fk_opw(IRB1600_10_120, q)
        if cell.mode == "tool":
            X_WT = X_WF @ X_FT.GetAsMatrix4()
            X_WH_q = X_WH.GetAsMatrix4()
        else:
            X_WT = cell.X_WT(cell.q_home).GetAsMatrix4()
            X_FH = cell.X_WF(cell.q_home).inverse().multiply(X_WH).GetAsMatrix4()
            X_WH_q = X_WF @ X_FH
        p_WQ = X_WH_q[:3, :3] @ r.target.p_HQ + X_WH_q[:3, 3]
        assert np.linalg.norm(X_WT[:3, 3] - p_WQ) <= 1e-5
        a_W = X_WH_q[:3, :3] @ r.target.a_H
        assert np.arccos(np.clip(X_WT[:3, 2] @ a_W, -1, 1)) <= 0.0101
        distance, pair = cell.min_distance(q, ignore_burr_hub=True)
        # only the burr body may come close to the (solid stand-in) hub face
        assert distance >= 0.005 - 1e-4 or "burr" in pair[0] + pair[1], pair


def test_unreachable_target_is_reported_not_raised():
    cell = load_cell("tool_in_hand", hub=STAND_IN_HUB)
    far = mut.ReachTarget(np.array([3.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]))
    survey = mut.survey_reach(cell, [far], mut.ReachOptions(seeds=2, min_distance=None))
    assert survey.failed == [0] and not survey.all_reached
    assert np.all(np.isnan(survey.results[0].q))
