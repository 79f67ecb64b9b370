"""Every registered arm stands in both bundled cells at the mount the study chose: the cell
builds with it, home is collision-free, the pedestal is clear of the fixture/stand, the rim of
the hub face is reached as the study says, every solution re-checked by the arm's own OPW FK."""

from pathlib import Path

import numpy as np
import pytest

import drakedeburr.cell.mounts as mut
from drakedeburr.cell.reach import ReachOptions, ReachTarget, survey_reach
from drakedeburr.cell.station import load_cell
from drakedeburr.errors import InputError
from drakedeburr.robots import ROBOTS, fk_opw, get_robot

STAND_IN_HUB = Path(__file__).resolve().parent / "data" / "stand_in_hub" / "hub.sdf"
CELLS = ("tool_in_hand", "workpiece_in_hand")
CASES = [(name, cell) for name, spec in ROBOTS.items() for cell in spec.cells]
#: the arms added to carry a wheel in the gripper (issue 41) and the paper's M-710iC/50 (issue
#: 44) stand in the workpiece-in-hand cell where a study placed them
WHEEL_ARMS = ("irb2600", "kr20_r1810", "m20ia", "m710ic50")


def test_every_arm_has_a_mount_in_both_cells():
    for spec in ROBOTS.values():
        if spec.name in WHEEL_ARMS:
            assert set(spec.cells) <= {"workpiece_in_hand"}, spec.name
        else:
            assert spec.cells == CELLS, spec.name
    assert "workpiece_in_hand" in get_robot("irb2600").cells
    with pytest.raises(InputError, match="no mount in cell 'paint_booth'"):
        get_robot("kr6_r700").mount("paint_booth")


def test_generated_pedestals_are_committed():
    texts = mut.pedestal_texts()
    # the IRB1600 keeps the 0.8 m pedestal
    assert len(texts) == sum(len(s.cells) for s in ROBOTS.values() if s.name != "irb1600")
    for url, text in texts.items():
        assert mut._pedestal_file(url).read_text() == text, url


@pytest.mark.parametrize("name, scenario", CASES)
def test_arm_stands_at_its_mount(name, scenario):
    spec = get_robot(name)
    mount = spec.mount(scenario)
    cell = load_cell(scenario, STAND_IN_HUB, robot=name)
    assert cell.arm is spec
    np.testing.assert_allclose(cell.X_WB().GetAsMatrix4(), mount.X_WB, atol=1e-12)
    np.testing.assert_allclose(cell.q_home, mount.q_home)
    np.testing.assert_allclose(cell.q_lower, spec.q_lower)
    np.testing.assert_allclose(cell.a_upper, spec.a_max)
    # the analytic model in the cell's world frame = Drake's flange pose
    X_WF = mount.X_WB @ fk_opw(spec.opw, cell.q_home)
    np.testing.assert_allclose(cell.X_WF(cell.q_home).GetAsMatrix4(), X_WF, atol=1e-9)
    assert cell.collision_pairs(cell.q_home, ignore_burr_hub=False) == []
    assert cell.min_distance(cell.q_home, ignore_burr_hub=False)[0] >= 0.005 - 1e-4
    assert mut.pedestal_gap(cell) >= mut.PEDESTAL_CLEARANCE - 1e-9


@pytest.mark.parametrize("name, scenario", CASES)
def test_rim_and_centre_are_reached_with_margins(name, scenario):
    """Centre and four rim points of the 0.23 m disc, burr along -Z_H and tilted 0.5 rad
    outward and inward: what every mount was chosen to reach."""
    cell = load_cell(scenario, STAND_IN_HUB, robot=name)
    spec = cell.arm
    targets = [ReachTarget(np.zeros(3), np.array([0.0, 0.0, -1.0]))]
    for phi in np.radians([0.0, 90.0, 180.0, 270.0]):
        p = 0.23 * np.array([np.cos(phi), np.sin(phi), 0.0])
        for tilt in (0.0, 0.5):
            a = np.array([np.sin(tilt) * np.cos(phi), np.sin(tilt) * np.sin(phi), -np.cos(tilt)])
            targets.append(ReachTarget(p, a))
    survey = survey_reach(cell, targets, ReachOptions(seeds=4))
    reached = [r for r in survey.results if r.success]
    assert len(reached) >= len(targets) - 1, [r.target for r in survey.results if not r.success]
    X_WB = cell.X_WB().GetAsMatrix4()
    X_F_carried = (cell.X_WF(cell.q_home).inverse().multiply(
        cell.X_WT(cell.q_home) if cell.mode == "tool" else cell.X_WH(cell.q_home))).GetAsMatrix4()
    for r in reached:
        assert spec.within_limits(r.q) and abs(r.q[4]) >= 0.25 - 1e-9
        X_WF = X_WB @ fk_opw(spec.opw, r.q)  # independent: the arm's OPW model
        if cell.mode == "tool":
            X_WT, X_WH = X_WF @ X_F_carried, cell.X_WH(cell.q_home).GetAsMatrix4()
        else:
            X_WT, X_WH = cell.X_WT(cell.q_home).GetAsMatrix4(), X_WF @ X_F_carried
        p_WQ = X_WH[:3, :3] @ r.target.p_HQ + X_WH[:3, 3]
        assert np.linalg.norm(X_WT[:3, 3] - p_WQ) <= 1e-5


@pytest.mark.parametrize("name, scenario", CASES)
def test_home_is_clear_of_the_default_hub(name, scenario):
    from drakedeburr.hub import DEFAULT_HUB

    cell = load_cell(scenario, DEFAULT_HUB, robot=name)
    assert cell.collision_pairs(cell.q_home, ignore_burr_hub=False) == []
    assert cell.min_distance(cell.q_home, ignore_burr_hub=False)[0] >= 0.005 - 1e-4
