"""load_cell: both scenarios, frames, limits, collision sets and filters, home collision-free."""

import itertools
from pathlib import Path

import numpy as np
import pytest

import drakedeburr.cell.station as mut
from drakedeburr.errors import InputError
from drakedeburr.resources import hub_names, models_dir

DATA = Path(__file__).resolve().parent / "data"
STAND_IN_HUB = DATA / "stand_in_hub" / "hub.sdf"


@pytest.fixture(scope="module", params=["tool_in_hand", "workpiece_in_hand"])
def cell(request):
    return mut.load_cell(request.param)  # the default bundled hub


def test_default_hub_is_the_hub_stage_default():
    from drakedeburr.hub import DEFAULT_HUB

    assert mut.resolve_hub_sdf(None) == models_dir() / "hubs" / DEFAULT_HUB / "hub.sdf"
    assert mut.resolve_hub_sdf("h5_split").parent.name == "h5_split"
    assert mut.resolve_hub_sdf(models_dir() / "hubs" / "h5_split").name == "hub.sdf"


@pytest.mark.parametrize("hub", [h for h in hub_names()])
def test_every_bundled_hub_fits_both_cells_at_home(hub):
    for scenario in ("tool_in_hand", "workpiece_in_hand"):
        cell = mut.load_cell(scenario, hub=hub)
        assert len(cell.hub_ids) > 10  # convex pieces, not one hull
        assert cell.collision_pairs(cell.q_home, ignore_burr_hub=False) == []
        distance, pair = cell.min_distance(cell.q_home, ignore_burr_hub=False)
        assert distance > 0.002, (hub, scenario, pair)


def test_modes_and_degrees_of_freedom(cell):
    expected = {"tool_in_hand": "tool", "workpiece_in_hand": "workpiece"}[cell.scenario.stem]
    assert cell.mode == expected
    assert cell.plant.num_positions() == 6 and cell.num_joints == 6
    assert cell.tool_frame.name() == "tool_tip"
    assert cell.hub_frame.body().name() == "hub"
    assert cell.flange_frame.name() == "flange"


def test_limits_come_from_the_robot_model(cell):
    arm = cell.arm
    assert arm.name == "irb1600"  # the bundled scenarios' own arm
    np.testing.assert_allclose(cell.q_lower, arm.q_lower)
    np.testing.assert_allclose(cell.q_upper, arm.q_upper)
    np.testing.assert_allclose(cell.v_upper, arm.v_max)
    np.testing.assert_allclose(cell.v_lower, -arm.v_max)
    np.testing.assert_allclose(cell.a_upper, arm.a_max)
    np.testing.assert_allclose(cell.a_lower, -arm.a_max)
    assert not cell.q_home.flags.writeable


def test_home_is_collision_free_and_sensible(cell):
    q = cell.q_home
    assert np.all(q > cell.q_lower + 0.1) and np.all(q < cell.q_upper - 0.1)
    assert abs(q[4]) > 0.25  # away from the wrist singularity
    assert cell.collision_pairs(q, ignore_burr_hub=False) == []
    distance, pair = cell.min_distance(q, ignore_burr_hub=False)
    assert distance > 0.002, pair
    # burr vertical and clear above the hub face at home
    X_HT = cell.X_HT(q)
    assert X_HT.rotation().matrix()[:, 2] @ [0, 0, -1] == pytest.approx(1.0, abs=1e-5)
    assert 0.2 < X_HT.translation()[2] < 0.5


def test_pose_helpers_are_consistent(cell):
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = rng.uniform(cell.q_lower, cell.q_upper)
        X_HT = cell.X_WH(q).inverse().multiply(cell.X_WT(q))
        assert np.allclose(X_HT.GetAsMatrix4(), cell.X_HT(q).GetAsMatrix4(), atol=1e-12)
    # what is fixed stays fixed
    q1, q2 = rng.uniform(cell.q_lower, cell.q_upper, (2, 6))
    fixed = cell.X_WH if cell.mode == "tool" else cell.X_WT
    assert np.allclose(fixed(q1).GetAsMatrix4(), fixed(q2).GetAsMatrix4(), atol=1e-15)
    with pytest.raises(InputError, match=r"shape \(6,\)"):
        cell.X_WT(np.zeros(5))


def test_documented_placements(cell):
    q = cell.q_home
    if cell.mode == "tool":
        X_WH = cell.X_WH(q)
        np.testing.assert_allclose(X_WH.translation(), [0.75, 0.0, -0.30], atol=1e-12)
        np.testing.assert_allclose(X_WH.rotation().matrix(), np.eye(3), atol=1e-12)
        # the spindle's burr axis is 45 deg off the flange axis
        z_F = cell.X_WF(q).rotation().matrix()[:, 2]
        z_T = cell.X_WT(q).rotation().matrix()[:, 2]
        assert np.degrees(np.arccos(z_F @ z_T)) == pytest.approx(45.0, abs=1e-9)
    else:
        X_WT = cell.X_WT(q)
        np.testing.assert_allclose(X_WT.translation(), [0.90, 0.0, 0.448], atol=1e-12)
        np.testing.assert_allclose(X_WT.rotation().matrix()[:, 2], [0, 0, 1], atol=1e-12)
        X_FH = cell.X_WF(q).inverse().multiply(cell.X_WH(q))
        np.testing.assert_allclose(X_FH.translation(), [0, 0, 0.30], atol=1e-12)
        np.testing.assert_allclose(X_FH.rotation().matrix(), np.eye(3), atol=1e-12)


def test_geometry_sets_partition_proximity_geometry(cell):
    from pydrake.geometry import Role

    inspector = cell.scene_graph.model_inspector()
    everything = set(inspector.GetAllGeometryIds(Role.kProximity))
    sets = [cell.burr_head_ids, cell.hub_ids, cell.robot_ids, cell.environment_ids]
    assert all(sets)
    assert set().union(*sets) == everything
    assert sum(len(s) for s in sets) == len(everything)
    assert all(inspector.GetName(g).endswith("burr_head") for g in cell.burr_head_ids)
    # robot link geometries are in robot_ids; the pedestal is environment
    names = {inspector.GetName(g) for g in cell.environment_ids}
    assert any("pedestal" in n for n in names)
    moving = cell.robot_ids | (cell.burr_head_ids if cell.mode == "tool" else cell.hub_ids)
    world = {b.index() for b in cell.plant.GetBodiesWeldedTo(cell.plant.world_body())}
    for g in moving:
        body = cell.plant.GetBodyFromFrameId(inspector.GetFrameId(g))
        assert body.index() not in world
        assert body.model_instance() in cell.moving_model_instances


def test_collision_filters(cell):
    inspector = cell.scene_graph.model_inspector()
    plant = cell.plant

    def ids(body_name, model=cell.robot):
        return plant.GetCollisionGeometriesForBody(plant.GetBodyByName(body_name, model))

    links = ["base_link"] + [f"link_{i}" for i in range(1, 7)]
    for a, b in zip(links[:-1], links[1:], strict=True):  # adjacent links filtered
        assert all(inspector.CollisionFiltered(x, y) for x in ids(a) for y in ids(b))
    for a, b in [("link_1", "link_3"), ("link_2", "link_4"), ("base_link", "link_3")]:
        assert not any(inspector.CollisionFiltered(x, y) for x in ids(a) for y in ids(b))
    # burr head vs hub is NOT filtered (the planner decides); hub vs its holder is
    assert not any(inspector.CollisionFiltered(x, y)
                   for x, y in itertools.product(cell.burr_head_ids, cell.hub_ids))
    holder = "fixture" if cell.mode == "tool" else "gripper"
    holder_ids = [g for g in cell.environment_ids | cell.robot_ids
                  if inspector.GetName(g).startswith(holder + "::")]
    assert holder_ids
    assert all(inspector.CollisionFiltered(x, y)
               for x, y in itertools.product(holder_ids, cell.hub_ids))
    # the hub still collides with the robot arm
    assert not any(inspector.CollisionFiltered(x, y)
                   for x, y in itertools.product(ids("link_3"), cell.hub_ids))


def test_collision_queries_agree_and_detect_contact(cell):
    """Penetration pairs and signed distance agree; random postures do hit something."""
    rng = np.random.default_rng(0)
    hits = 0
    for q in rng.uniform(cell.q_lower, cell.q_upper, (16, 6)):
        pairs = cell.collision_pairs(q)
        distance, pair = cell.min_distance(q, max_distance=0.05)
        assert bool(pairs) == (distance < 0), (pairs, distance, pair)
        if pairs:
            hits += 1
    assert 0 < hits < 16


def test_bad_inputs_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="no scenario 'nope'"):
        mut.load_cell("nope", hub=STAND_IN_HUB)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        mut.load_cell("tool_in_hand", hub=tmp_path / "missing.sdf")
    bad_hub = tmp_path / "hub.sdf"
    bad_hub.write_text(STAND_IN_HUB.read_text().replace('model name="hub"', 'model name="disc"'))
    with pytest.raises(InputError, match="must be named 'hub'"):
        mut.load_cell("tool_in_hand", hub=bad_hub)
    scenario = tmp_path / "no_tool.yaml"
    text = (models_dir() / "scenarios" / "tool_in_hand.yaml").read_text()
    scenario.write_text(text.replace("floating_spindle.sdf", "hub_gripper.sdf")
                        .replace("spindle::spindle", "spindle::gripper"))
    with pytest.raises(InputError, match="exactly one frame named 'hub_mount', found 2"):
        mut.load_cell(scenario, hub=STAND_IN_HUB)
    lines = text.splitlines()
    start = lines.index("    name: spindle") - 1
    scenario.write_text("\n".join(lines[:start] + lines[start + 6:]) + "\n")
    assert "floating_spindle" not in scenario.read_text()
    with pytest.raises(InputError, match="exactly one frame named 'tool_tip', found 0"):
        mut.load_cell(scenario, hub=STAND_IN_HUB)
