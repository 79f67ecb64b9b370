"""The arm registry: every arm's Drake model against its OPW reference, analytic IK round trips,
the rs-opw-kinematics KR6 cases, vendor conventions, generated model files."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

import drakedeburr.robots.arms as mut
from drakedeburr.errors import InputError
from drakedeburr.resources import add_package_to, resolve_package_url
from drakedeburr.robots import fk_opw, ik_opw, joint_candidates
from drakedeburr.robots.arm_models import ENVELOPES, arm_sdf

NAMES = ("irb1600", "kr6_r700", "lrmate200ic", "m10ia", "irb2600", "kr20_r1810", "m20ia",
         "m710ic50")
NEW = ("irb2600", "kr20_r1810", "m20ia", "m710ic50")
CHAINS = json.loads((Path(__file__).parent / "data" / "arm_urdf_chains.json").read_text())
_RANGES = Path(__file__).parent / "data" / "vendor_working_ranges.json"
VENDOR = {k: v for k, v in json.loads(_RANGES.read_text()).items() if not k.startswith("_")}
MIRRORED_IN_URDF = {"irb2600": (1,)}  # axis index: see models/robots/irb2600.yaml sources


def _plant(spec):
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (robot,) = parser.AddModels(str(resolve_package_url(spec.model_url)))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base", robot))
    plant.Finalize()
    return plant, robot


def test_registry_lists_the_arms():
    assert mut.robot_names() == NAMES
    assert {mut.get_robot(n).controller for n in NAMES} == {"abb", "kuka", "fanuc"}
    assert mut.get_robot(None) is mut.IRB1600
    assert mut.get_robot(" KR6_R700 ") is mut.KR6_R700
    with pytest.raises(InputError, match="unknown robot 'ur5'.*irb1600, kr6_r700"):
        mut.get_robot("ur5")
    for n in NAMES:
        spec = mut.get_robot(n)
        assert mut.robot_for_model_url(spec.model_url) is spec
        assert spec.program_format == {"abb": "rapid", "kuka": "krl", "fanuc": "ls"}[
            spec.controller]
        assert "ASSUMED" in spec.a_max_note and spec.sources


@pytest.mark.parametrize("name", NAMES)
def test_drake_model_fk_equals_opw_reference(name):
    """Flange pose of our Drake model (base -> flange) = fk_opw, at seeded random joints."""
    spec = mut.get_robot(name)
    plant, robot = _plant(spec)
    ctx = plant.CreateDefaultContext()
    base = plant.GetFrameByName("base", robot)
    flange = plant.GetFrameByName("flange", robot)
    rng = np.random.default_rng(0)
    qs = rng.uniform(spec.q_lower, spec.q_upper, size=(200, 6))
    X_ref = fk_opw(spec.opw, qs)
    worst = 0.0
    for q, X_opw in zip(qs, X_ref, strict=True):
        plant.SetPositions(ctx, q)
        X = plant.CalcRelativeTransform(ctx, base, flange).GetAsMatrix4()
        worst = max(worst, np.abs(X - X_opw).max())
    assert worst <= 1e-9, worst  # the gate is 1e-6 m; the models agree to round-off


@pytest.mark.parametrize("name", NAMES)
def test_analytic_ik_round_trips(name):
    spec = mut.get_robot(name)
    rng = np.random.default_rng(1)
    qs = rng.uniform(spec.q_lower, spec.q_upper, size=(300, 6))
    sols = ik_opw(spec.opw, fk_opw(spec.opw, qs))
    found = 0
    for i, q in enumerate(qs):
        valid = sols.q[i][sols.valid[i]]
        # every branch maps back to the pose
        assert np.abs(fk_opw(spec.opw, valid) - fk_opw(spec.opw, q)[None]).max() < 1e-9
        if abs(np.sin(spec.opw.q_opw_from_robot(q)[4])) < 1e-3:
            continue  # wrist singular: J4/J6 only defined as a sum
        cand = joint_candidates(valid, spec.kinematics.limits)
        assert np.abs(cand - q[None]).max(axis=1).min() < 1e-9, (name, q)
        found += 1
    assert found > 290


def test_kr6_rs_opw_kinematics_cases(extdata):
    """The 1024 KR6 R700 sixx cases of rs-opw-kinematics with the registry's KR6 parameters:
    FK of the listed joints = listed pose; every listed IK solution is one of ours."""
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    with open(extdata / "kinematics" / "opw_cases_rs-opw-kinematics.yaml") as f:
        cases = [c for c in yaml.load(f, Loader=loader)["cases"]
                 if c["parameters"] == "KukaKR6_R700_sixx"]
    assert len(cases) == 1024
    p = mut.KR6_R700.opw
    checked = 0
    for case in cases:
        j5 = abs(case["joints"][4])
        if j5 < 1.0 or abs(j5 - 180.0) < 1.0:
            continue  # singular, print-rounded (extdata README)
        X = np.eye(4)
        X[:3, :3] = Rotation.from_quat(case["pose"]["quaternion"]).as_matrix()
        X[:3, 3] = case["pose"]["translation"]
        assert np.abs(fk_opw(p, np.deg2rad(case["joints"])) - X).max() < 1e-9, case["id"]
        sols = ik_opw(p, X)
        mine = sols.q[0][sols.valid[0]]
        for sol in np.deg2rad(np.array(case["solutions"])):
            d = np.abs((mine - sol + np.pi) % (2 * np.pi) - np.pi).max(axis=1).min()
            assert d < 1e-6, case["id"]
        checked += 1
    assert checked > 950


def test_kr6_fk_matches_the_moveit_plugin_vectors(extdata):
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    vec = ref["opw_test_vectors"][0]
    assert vec["robot"] == "KUKA_KR6_R700_sixx"
    X = fk_opw(mut.KR6_R700.opw, vec["joints_rad"])
    np.testing.assert_allclose(X[:3, :3], vec["expected_rotation_rowmajor"], atol=vec["tolerance"])
    np.testing.assert_allclose(X[:3, 3], vec["expected_translation_m"], atol=vec["tolerance"])
    # "Translation(0.785,0,0.435) * AngleAxis(pi/2, UnitY)" at zero
    X0 = fk_opw(mut.KR6_R700.opw, np.zeros(6))
    np.testing.assert_allclose(X0[:3, 3], [0.785, 0.0, 0.435], atol=1e-12)
    np.testing.assert_allclose(X0[:3, :3], Rotation.from_rotvec([0, np.pi / 2, 0]).as_matrix(),
                               atol=1e-12)


@pytest.mark.parametrize("name, source_file, joints_key", [
    ("kr6_r700", None, "KUKA_KR6_R700_sixx"),
])
def test_limits_equal_the_reference_urdf(extdata, name, source_file, joints_key):
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    joints = ref["urdf_joints"][joints_key]["joints"]
    spec = mut.get_robot(name)
    np.testing.assert_allclose(spec.q_lower, [j["lower_rad"] for j in joints], atol=1e-5)
    np.testing.assert_allclose(spec.q_upper, [j["upper_rad"] for j in joints], atol=1e-5)
    np.testing.assert_allclose(spec.v_max, [j["velocity_rad_s"] for j in joints], atol=1e-5)
    # the URDF's axis directions are the OPW sign corrections of our model
    plant, robot = _plant(spec)
    for i, j in enumerate(joints):
        axis = plant.GetJointByName(f"joint_{i + 1}", robot).revolute_axis()
        np.testing.assert_allclose(axis, j["axis"], atol=1e-12)


@pytest.mark.parametrize("name", ["irb1600", "kr6_r700"])
def test_opw_parameters_equal_the_reference_json(extdata, name):
    ref = json.loads((extdata / "kinematics" / "robot_kinematics_reference.json").read_text())
    key = {"irb1600": "ABB_IRB1600_6_120", "kr6_r700": "KUKA_KR6_R700_sixx"}[name]
    data = ref["opw_parameters"][key]
    p = mut.get_robot(name).opw
    for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4"):
        assert getattr(p, k) == pytest.approx(data[k], abs=1e-12)
    np.testing.assert_allclose(p.offsets, data["offsets"], atol=1e-12)
    np.testing.assert_array_equal(p.sign_corrections, data["sign_corrections"])


@pytest.mark.parametrize("name, fname", [("lrmate200ic", "opw_parameters_fanuc_lrmate200ic.yaml"),
                                          ("m10ia", "opw_parameters_fanuc_m10ia.yaml")])
def test_fanuc_opw_parameters_equal_the_ros_industrial_files(extdata, name, fname):
    data = yaml.safe_load((extdata / "kinematics" / fname).read_text())
    geo = data.get("opw_kinematics_geometric_parameters") or data[
        "kinematics_solver_geometric_parameters"]
    offsets = data.get("opw_kinematics_joint_offsets") or data["kinematics_solver_joint_offsets"]
    signs = (data.get("opw_kinematics_joint_sign_corrections")
             or data["kinematics_solver_joint_sign_corrections"])
    p = mut.get_robot(name).opw
    for k, v in geo.items():
        assert getattr(p, k) == pytest.approx(v, abs=1e-12)
    np.testing.assert_allclose(p.offsets, offsets, atol=1e-10)
    np.testing.assert_array_equal(p.sign_corrections, signs)


def test_fanuc_j2_j3_linkage_and_world_frame():
    spec = mut.LRMATE200IC
    q = np.array([0.1, 0.5, 0.2, 0.0, -0.3, 1.0])
    q_c = spec.controller_joints(q)
    # FANUC J3 is measured from the horizontal: the forearm's pitch is q2 - q3 in the model,
    # the controller reads it as -J3 (J3 positive = forearm up)
    assert q_c[2] == pytest.approx(q[2] - q[1])
    np.testing.assert_allclose(spec.model_joints(q_c), q)
    # raising J2 with the controller's J3 held keeps the forearm's direction
    a = spec.model_joints(np.array([0, 0.0, 0.3, 0, 0.5, 0]))
    b = spec.model_joints(np.array([0, 0.4, 0.3, 0, 0.5, 0]))
    R_a, R_b = fk_opw(spec.opw, a)[:3, :3], fk_opw(spec.opw, b)[:3, :3]
    np.testing.assert_allclose(R_a, R_b, atol=1e-12)
    # FANUC world frame at the J2 axis height; ABB/KUKA at the foot
    assert spec.X_BR[2, 3] == pytest.approx(spec.opw.c1)
    assert np.array_equal(mut.KR6_R700.X_BR, np.eye(4))
    np.testing.assert_allclose(mut.KR6_R700.controller_joints(q), q)


def test_configuration_data_per_controller():
    q = np.array([0.2, 0.3, 0.4, -0.5, 0.6, 2.0])
    assert len(mut.IRB1600.configuration(q)) == 4
    s, t = mut.KR6_R700.configuration(q)
    assert t == 1 << 3  # only A4 negative
    assert mut.M10IA.configuration(q).endswith(", 0, 0, 0")


_NUMBER = re.compile(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def test_generated_arm_models_are_committed():
    """The committed models are what the generator writes, on any machine: the text around the
    numbers is identical and every number agrees within 1e-9 (the generator rounds its
    geometry to 1e-10, far above the last-bit differences of libm between machines)."""
    assert set(ENVELOPES) == set(NAMES) - {"irb1600"}  # the IRB1600 model is hand-written
    for name, env in ENVELOPES.items():
        spec = mut.get_robot(name)
        committed = resolve_package_url(spec.model_url).read_text()
        fresh = arm_sdf(spec, env)
        assert _NUMBER.sub("#", committed) == _NUMBER.sub("#", fresh), name
        a = np.array([float(x) for x in _NUMBER.findall(committed)])
        b = np.array([float(x) for x in _NUMBER.findall(fresh)])
        assert a.shape == b.shape and np.abs(a - b).max() <= 1e-9, name


@pytest.mark.parametrize("name", NAMES)
def test_models_have_collision_geometry_on_every_link(name):
    from pydrake.geometry import SceneGraph
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    spec = mut.get_robot(name)
    plant = MultibodyPlant(0.0)
    scene_graph = SceneGraph()  # keep alive while the plant uses it
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    (robot,) = parser.AddModels(str(resolve_package_url(spec.model_url)))
    plant.Finalize()
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(robot)]
    assert len(bodies) == 7
    for body in bodies:
        assert plant.GetCollisionGeometriesForBody(body), (name, body.name())
        assert body.default_mass() > 0


@pytest.mark.parametrize("name", NAMES)
def test_models_do_not_collide_with_themselves_at_zero_and_ready(name):
    """No permanent self-contact (non-adjacent links) at q = 0 and a working posture."""
    from pydrake.planning import RobotDiagramBuilder

    spec = mut.get_robot(name)
    builder = RobotDiagramBuilder(0.0)
    add_package_to(builder.parser().package_map())
    (robot,) = builder.parser().AddModels(str(resolve_package_url(spec.model_url)))
    builder.plant().WeldFrames(builder.plant().world_frame(),
                               builder.plant().GetFrameByName("base", robot))
    builder.plant().Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    ready = spec.opw.q_robot_from_opw(np.array([0.0, 0.2, 1.9, 0.0, 1.04, 0.0]))
    for q in (np.zeros(6), np.pi - np.mod(np.pi - ready, 2 * np.pi)):
        diagram.plant().SetPositions(diagram.plant().GetMyMutableContextFromRoot(context), q)
        query = diagram.scene_graph().get_query_output_port().Eval(
            diagram.scene_graph().GetMyContextFromRoot(context))
        pairs = query.ComputeSignedDistancePairwiseClosestPoints(0.1)
        assert min((p.distance for p in pairs), default=1.0) > 0.01, (name, q)


def _urdf_chain(chain: dict, q: np.ndarray) -> np.ndarray:
    """base_link -> tool0 of a URDF joint chain (tests/data/arm_urdf_chains.json)."""
    def origin(o):
        X = np.eye(4)
        X[:3, :3] = Rotation.from_euler("xyz", o["rpy"]).as_matrix()  # URDF rpy: Rz Ry Rx
        X[:3, 3] = o["xyz"]
        return X

    X = np.eye(4)
    for j, qi in zip(chain["joints"], q, strict=True):
        R = np.eye(4)
        R[:3, :3] = Rotation.from_rotvec(np.asarray(j["axis"], float) * qi).as_matrix()
        X = X @ origin(j) @ R
    return X @ origin(chain["tool0"])


@pytest.mark.parametrize("name", NEW)
def test_new_arms_fk_equals_the_ros_industrial_urdf_chain(name):
    """fk_opw of the arm file = the URDF joint chain of the cited support package (base_link
    -> tool0), at zero and at 300 seeded joint sets inside the limits: the OPW parameters,
    offsets and signs are those of the source the limits come from."""
    spec = mut.get_robot(name)
    rng = np.random.default_rng(7)
    qs = np.vstack([np.zeros(6), rng.uniform(spec.q_lower, spec.q_upper, size=(300, 6))])
    worst = max(np.abs(fk_opw(spec.opw, q) - _urdf_chain(CHAINS[name], q)).max() for q in qs)
    assert worst < 1e-12, (name, worst)


@pytest.mark.parametrize("name", NEW)
def test_new_arms_limits_equal_the_urdf(name):
    lim = CHAINS["limits"][name]
    spec = mut.get_robot(name)
    lower = np.deg2rad(lim["lower_deg"]) if "lower_deg" in lim else lim["lower"]
    upper = np.deg2rad(lim["upper_deg"]) if "upper_deg" in lim else lim["upper"]
    vel = np.deg2rad(lim["velocity_deg"]) if "velocity_deg" in lim else lim["velocity"]
    lower, upper = np.array(lower, float), np.array(upper, float)
    for j in MIRRORED_IN_URDF.get(name, ()):
        # the URDF writes this axis's range mirrored against the vendor's (same axis
        # direction): the arm file takes the vendor's, which is the URDF's negated
        lower[j], upper[j] = -upper[j], -lower[j]
    np.testing.assert_allclose(spec.q_lower, lower, atol=1e-12)
    np.testing.assert_allclose(spec.q_upper, upper, atol=1e-12)
    np.testing.assert_allclose(spec.v_max, vel, atol=1e-12)
    assert np.all(spec.a_max > 0) and "ASSUMED" in spec.a_max_note


@pytest.mark.parametrize("name", sorted(VENDOR))
def test_limits_lie_inside_the_controllers_working_range(name):
    """A plan inside our limits is one the controller runs: every axis's range lies inside the
    vendor's working range (tests/data/vendor_working_ranges.json, not from our files). The
    IRB 2600's axis 2 was once copied mirrored (-155..+95 deg against ABB's -95..+155 deg):
    plans leaning the arm back past -95 deg would have passed here and stopped on the robot."""
    ref, spec = VENDOR[name], mut.get_robot(name)
    lo, hi = np.deg2rad(ref["lower_deg"]), np.deg2rad(ref["upper_deg"])
    tol = 1e-5  # [rad] the URDFs' 3-4 decimals (1.309 = 75.0002 deg), below a joint's resolution
    assert np.all(spec.q_lower >= lo - tol), (name, np.rad2deg(spec.q_lower), ref["lower_deg"])
    assert np.all(spec.q_upper <= hi + tol), (name, np.rad2deg(spec.q_upper), ref["upper_deg"])
    # and our ranges are not needlessly narrow where the source gives the full range: the
    # IRB 2600's axis 2 forward range is ABB's +155 deg
    if name == "irb2600":
        assert np.rad2deg(spec.q_upper[1]) == pytest.approx(155.0, abs=0.02)  # 2.705 rad
        assert np.rad2deg(spec.q_lower[1]) == pytest.approx(-95.0, abs=0.02)


@pytest.mark.parametrize("name", ["kr20_r1810", "m20ia"])
def test_new_arms_opw_equal_the_published_opw_files(name):
    ref = CHAINS["opw_files"][name]
    p = mut.get_robot(name).opw
    for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4"):
        assert getattr(p, k) == pytest.approx(ref[k], abs=1e-12), k
    np.testing.assert_allclose(p.offsets, ref["offsets"], atol=1e-10)  # the files' 12 digits
    np.testing.assert_array_equal(p.sign_corrections, ref["sign_corrections"])


@pytest.mark.parametrize("name", NEW)
def test_new_arms_reach_equals_the_data_sheet(name):
    """Axis 1 to the wrist centre, arm stretched = the designation's / data sheet's reach."""
    p = mut.get_robot(name).opw
    reach = p.a1 + p.c2 + float(np.hypot(p.a2, p.c3))
    assert reach == pytest.approx(CHAINS["reach_m"][name], abs=0.005), (name, reach)


def test_arms_that_carry_a_wheel_are_rated_for_it():
    """A bundled hub (<= 12.1 kg) on the 4 kg gripper is 16.1 kg: the three arms named in
    issue 41 carry 20 kg, the paper's M-710iC/50 50 kg; the four older arms 5-10 kg."""
    assert {n: mut.get_robot(n).payload_kg for n in NEW} == {
        "irb2600": 20.0, "kr20_r1810": 20.0, "m20ia": 20.0, "m710ic50": 50.0}
    assert max(mut.get_robot(n).payload_kg for n in NAMES[:4]) == 10.0
    assert mut.M710IC50.wrist_moment_Nm == (206.0, 206.0, 127.0)
    assert mut.IRB2600.wrist_inertia_kgm2 == (2.0, 2.0, 1.0)
