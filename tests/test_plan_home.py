"""plan.home: a home the hub leaves without clearance is moved to the nearest clear
configuration; the plan records it and the verifier's cell follows the plan's home."""

from __future__ import annotations

import dataclasses
import functools
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.plan import home as mut


def _clearance(cell, q: np.ndarray) -> float:
    """Smallest signed distance over every unfiltered pair at ``q``, read by the cell's own
    Drake query (not the planner's certified checker)."""
    return cell.min_distance(np.asarray(q, float), ignore_burr_hub=False, max_distance=0.05)[0]


@functools.cache
def _mount_home() -> np.ndarray:
    from drakedeburr.cell.station import load_cell

    return np.array(load_cell("workpiece_in_hand", "h5_straight").q_home)


def _checker(cell):
    from drakedeburr.plan.kinematics import ClearanceChecker

    return ClearanceChecker(cell, filter_burr_contact=False)


@pytest.mark.parametrize("joint, step", [(2, 0.5), (1, 0.4)])
def test_a_home_in_collision_moves_to_the_nearest_clear_configuration(joint, step):
    """The workpiece cell with its home moved into the stand (the hub in the spindle body /
    the burr shank, 19-50 mm deep): the home found is clear by 5 mm on Drake's own query, in
    the joint limits with 10 deg margin, the wrist on the home's side 0.25 rad off J5 = 0, and
    no farther (weighted joint travel) than the first clear pose on the straight line back to
    the mount's clear home (found by bisection: a second, plainer search)."""
    from drakedeburr.cell.station import load_cell

    q_mount = _mount_home()
    q_bad = q_mount.copy()
    q_bad[joint] += step
    cell = load_cell("workpiece_in_hand", "h5_straight", q_home=q_bad)
    np.testing.assert_array_equal(cell.q_home, q_bad)
    assert _clearance(cell, q_bad) < -0.01
    q, dev = mut.clear_home(cell, _checker(cell))
    assert dev is not None and dev.window == -1 and dev.item == "home"
    assert "mm from" in dev.reason and "hub::" in dev.reason
    assert _clearance(cell, q) >= mut.HOME_CLEARANCE - 1e-6
    assert np.all(q >= cell.q_lower + mut.JOINT_MARGIN - 1e-9)
    assert np.all(q <= cell.q_upper - mut.JOINT_MARGIN + 1e-9)
    assert q[4] >= mut.WRIST_MARGIN - 1e-9
    lo, hi = 0.0, 1.0  # fraction of the way from q_bad back to q_mount
    assert _clearance(cell, q_mount) >= mut.HOME_CLEARANCE
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        clear = _clearance(cell, q_bad + mid * (q_mount - q_bad)) >= mut.HOME_CLEARANCE
        lo, hi = (lo, mid) if clear else (mid, hi)
    q_line = q_bad + hi * (q_mount - q_bad)
    w = mut._WEIGHTS
    assert w @ (q - q_bad) ** 2 <= w @ (q_line - q_bad) ** 2 + 1e-6
    # the same answer again (deterministic)
    q2, _ = mut.clear_home(cell, _checker(cell))
    np.testing.assert_array_equal(q, q2)


@pytest.mark.parametrize("scenario", ["tool_in_hand", "workpiece_in_hand"])
def test_a_clear_home_is_kept(scenario):
    from drakedeburr.cell.station import load_cell

    cell = load_cell(scenario, "h5_straight")
    q, dev = mut.clear_home(cell, _checker(cell))
    assert dev is None
    np.testing.assert_array_equal(q, cell.q_home)
    assert _clearance(cell, q) >= mut.HOME_CLEARANCE


def test_the_verifier_cell_and_check_follow_the_plan_home():
    """A plan that records its home: the cell it is verified in has that home, and
    start_end_home measures the trajectory against it (not against the mount's)."""
    import verify_support as vs

    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.errors import InputError
    from drakedeburr.verify.checks_motion import start_end_home
    from drakedeburr.verify.types import JointLimits

    plan = vs.good_plan()
    q0 = np.asarray(plan.trajectory.q[0], float)
    moved = q0 + np.array([0.0, 0.0, 0.0, 0.0, 0.02, 0.0])
    for home, expect in ((q0, 0.0), (moved, 0.02)):
        p = dataclasses.replace(plan, meta={**plan.meta, "q_home": home.tolist()})
        cell = load_plan_cell(p)
        np.testing.assert_allclose(cell.q_home, home, atol=0)
        item = start_end_home(SimpleNamespace(plan=p, limits=JointLimits.of_cell(cell)), None)
        assert item.value == pytest.approx(expect, abs=1e-12)
        assert item.passed == (expect == 0.0)
    bad = dataclasses.replace(plan, meta={**plan.meta, "q_home": [0.0, 1.0]})
    with pytest.raises(InputError, match="q_home"):
        load_plan_cell(bad)


def test_a_hub_planned_from_a_home_in_collision_starts_and_ends_at_the_clear_one():
    """The planner's cell stage (placement off, a 16-point stretch of window 0): the cell's
    home is moved into the stand; the plan records the clear home it used as the first recipe
    deviation and in ``meta["q_home"]``, its trajectory starts and ends there, the home moves
    are clear (no failure record), and the cell the verifier builds from the plan has it."""
    from drakedeburr.cell.station import load_cell, load_plan_cell
    from drakedeburr.config import load_config
    from drakedeburr.hub import load_hub
    from drakedeburr.plan import planner
    from drakedeburr.plan.window_targets import WindowTargets

    q_bad = _mount_home().copy()
    q_bad[2] += 0.5
    cell = load_cell("workpiece_in_hand", "h5_straight", q_home=q_bad)
    hub = load_hub("h5_straight")
    wt = WindowTargets.from_window_edge(hub.windows[0]).stretch(0, 16)
    placed = planner.placed_cell(cell, hub, [wt], load_config("workpiece_in_hand", "h5_straight"),
                                 planner.PlanOptions(placement=False, relax=False))
    plan = planner.plan_in_cell(placed, hub, [wt], None).plan()
    q_home, _ = mut.clear_home(cell, _checker(cell))
    np.testing.assert_allclose(plan.meta["q_home"], q_home, atol=1e-12)
    assert plan.meta["recipe_deviations"][0]["item"] == "home"
    np.testing.assert_allclose(plan.trajectory.q[0], q_home, atol=1e-12)
    np.testing.assert_allclose(plan.trajectory.q[-1], q_home, atol=1e-12)
    assert plan.failures == ()
    verifier_cell = load_plan_cell(plan)
    np.testing.assert_allclose(verifier_cell.q_home, q_home, atol=0)
    assert _clearance(verifier_cell, plan.trajectory.q[0]) >= mut.HOME_CLEARANCE - 1e-6
