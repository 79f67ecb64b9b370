"""Five-bar Cutting Tool kinematics: eqs. 1-9 FK, IK, Jacobian, singularities, Drake model."""

import numpy as np
import pytest

import drakedeburr.laser.kinematics as mut
from drakedeburr.errors import InputError

G = mut.FiveBarGeometry()


def _disc_points(g, n_grid=41, n_random=2000, seed=0):
    rng = np.random.default_rng(seed)
    xs = np.linspace(-g.work_radius, g.work_radius, n_grid)
    grid = np.array([(x, y) for x in xs for y in xs if np.hypot(x, y) <= g.work_radius])
    r = g.work_radius * np.sqrt(rng.uniform(0, 1, n_random))
    a = rng.uniform(0, 2 * np.pi, n_random)
    rand = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
    return g.p_CHome + np.concatenate([grid, rand])


@pytest.mark.parametrize("g", [G, mut.FiveBarGeometry(l0=0.02, l1=0.05, l2=0.05, l3=0.075,
                                                      l4=0.075, home_x=0.07)])
def test_fk_ik_round_trip_over_workspace(g):
    p = _disc_points(g)
    q, ok = mut.inverse_kinematics(g, p)
    assert ok.all()
    st = mut.forward_kinematics(g, q)
    assert st.valid.all()
    assert np.max(np.linalg.norm(st.p_CJ5 - p, axis=1)) <= 1e-9
    # links have their lengths and the crank tips sit where eqs. 1-6 say
    assert np.allclose(np.linalg.norm(st.p_CJ5 - st.p_CJ3, axis=1), g.l3, atol=1e-12)
    assert np.allclose(np.linalg.norm(st.p_CJ5 - st.p_CJ4, axis=1), g.l4, atol=1e-12)
    assert np.allclose(np.linalg.norm(st.p_CJ4 - g.p_CJ2, axis=1), g.l2, atol=1e-12)
    # working mode as documented
    s1 = np.sign(mut._cross(st.p_CJ3 - g.p_CJ1, p - g.p_CJ1))
    s2 = np.sign(mut._cross(st.p_CJ4 - g.p_CJ2, p - g.p_CJ2))
    assert (s1 == g.working_mode[0]).all() and (s2 == g.working_mode[1]).all()


def test_eq9_matches_circle_intersection_and_satisfies_eq8():
    rng = np.random.default_rng(0)
    q, _ = mut.inverse_kinematics(G, _disc_points(G, 5, 200))
    q = q + rng.normal(0, 0.05, q.shape)  # also off the disc
    st = mut.forward_kinematics(G, q)
    p2 = mut.forward_kinematics_circles(G, q)
    ok = st.valid
    assert ok.sum() > 100
    assert np.max(np.abs(st.p_CJ5[ok] - p2[ok])) < 1e-12
    th1, th2, th3 = q[ok, 0], q[ok, 1], st.theta3[ok]
    L0, L1, L2, L3, L4 = G.l0, G.l1, G.l2, G.l3, G.l4
    A = 2 * L1 * L3 * np.cos(th1) - 2 * L2 * L3 * np.cos(th2) + 2 * L0 * L3
    B = -2 * L1 * L3 * np.sin(th1) + 2 * L2 * L3 * np.sin(th2)
    C = (L0**2 + L1**2 + L2**2 + L3**2 - L4**2 + 2 * L0 * L1 * np.cos(th1)
         - 2 * L0 * L2 * np.cos(th2) - 2 * L1 * L2 * np.cos(th1 - th2))
    assert np.allclose(A * np.cos(th3) + B * np.sin(th3), C, atol=1e-15)
    # eqs. 3, 4 loop closure with theta4
    th4 = st.theta4[ok]
    assert np.allclose(L0 + L1 * np.cos(th1) - L2 * np.cos(th2) - L3 * np.cos(th3)
                       - L4 * np.cos(th4), 0, atol=1e-12)
    assert np.allclose(L1 * np.sin(th1) - L2 * np.sin(th2) + L3 * np.sin(th3)
                       - L4 * np.sin(th4), 0, atol=1e-12)


def test_other_assembly_mode_is_the_mirror_branch():
    q, _ = mut.inverse_kinematics(G, G.p_CHome)
    other = mut.FiveBarGeometry(assembly_mode=+1)
    p_a = mut.forward_kinematics(G, q).p_CJ5[0]
    p_b = mut.forward_kinematics(other, q).p_CJ5[0]
    assert np.linalg.norm(p_a - G.p_CHome) < 1e-12
    assert np.linalg.norm(p_b - p_a) > 1e-3
    st = mut.forward_kinematics(G, q)
    # mirror of J5 about the line J3-J4
    j3, j4 = st.p_CJ3[0], st.p_CJ4[0]
    e = (j4 - j3) / np.linalg.norm(j4 - j3)
    d = p_a - j3
    mirror = j3 + 2 * np.dot(d, e) * e - d
    assert np.allclose(mirror, p_b, atol=1e-12)


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(0)
    q, _ = mut.inverse_kinematics(G, _disc_points(G, 3, 50))
    J = mut.jacobian(G, q)
    h = 1e-7
    for k in range(2):
        dq = np.zeros(2)
        dq[k] = h
        fd = (mut.forward_kinematics(G, q + dq).p_CJ5
              - mut.forward_kinematics(G, q - dq).p_CJ5) / (2 * h)
        assert np.allclose(J[:, :, k], fd, atol=1e-7)
    _ = rng


def test_singularities_detected():
    g = G
    # serial (type I): leg 1 stretched out, J5 at distance L1 + L3 from J1
    a = np.deg2rad(10.0)
    p_serial = g.p_CJ1 + (g.l1 + g.l3) * np.array([np.cos(a), np.sin(a)])
    q, ok = mut.inverse_kinematics(g, p_serial)
    assert ok.all()
    m = mut.singularity_measures(g, q)
    assert m["serial_1"][0] < 1e-6
    assert m["condition"][0] > 1e6
    rep = mut.check_reach(g, p_serial, use_disc=False)
    assert not rep.reachable[0] and rep.reason[0] == "serial singularity"
    # parallel (type II): J3, J5, J4 collinear with the links stretched, |J3 - J4| = L3 + L4;
    # the default tool cannot get there (its cranks cannot spread that far), so use a wide one
    g = mut.FiveBarGeometry(l0=0.10, l1=0.05, l2=0.05, l3=0.06, l4=0.06, home_x=0.05)
    th1 = 0.3
    j3 = np.array([g.l1 * np.sin(th1), -g.l1 * np.cos(th1)])
    # find th2 with |J4 - J3| = L3 + L4
    ths = np.linspace(0, 2 * np.pi, 200001)
    j4 = np.stack([g.l2 * np.sin(ths), g.l0 - g.l2 * np.cos(ths)], axis=1)
    k = np.argmin(np.abs(np.linalg.norm(j4 - j3, axis=1) - (g.l3 + g.l4)))
    q2 = np.array([[th1, ths[k]]])
    m2 = mut.singularity_measures(g, q2)
    assert m2["parallel"][0] < 1e-2
    # eq. 8 discriminant: A^2 + B^2 ~ C^2 there (double root)
    plus, minus, valid = mut.solve_theta3(g, q2)
    assert valid[0] and abs(plus[0] - minus[0]) < 0.05
    # every point of the default tool's working disc is far from both
    g = G
    q_disc, _ = mut.inverse_kinematics(g, _disc_points(g, 21, 0))
    md = mut.singularity_measures(g, q_disc)
    assert md["serial_1"].min() > g.min_sin_serial and md["serial_2"].min() > g.min_sin_serial
    assert md["parallel"].min() > g.min_sin_parallel
    assert md["condition"].max() < 2.0


def test_unreachable_points_named():
    far = np.array([[0.5, 0.0], [G.home_x, G.l0 / 2]])
    rep = mut.check_reach(G, far, use_disc=False)
    assert rep.reason[0] == "out of reach" and rep.reachable[1]
    assert rep.first_failure == 0
    q, ok = mut.inverse_kinematics(G, far)
    assert not ok[0] and np.isnan(q[0]).all()


def test_bad_geometry_rejected():
    with pytest.raises(InputError, match="l3 must be > 0"):
        mut.FiveBarGeometry(l3=-1.0)
    with pytest.raises(InputError, match="assembly_mode"):
        mut.FiveBarGeometry(assembly_mode=0)


def test_drake_model_matches_closed_form():
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    import drakedeburr.laser.model as model
    from drakedeburr.resources import model_path

    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.001)
    tool = model.add_cutting_tool(plant, G)
    plant.Finalize()
    assert plant.num_constraints() == 1  # the loop closure at J5
    assert plant.num_actuated_dofs() == 2 and plant.num_positions(tool) == 4
    actuated = {plant.get_joint_actuator(i).joint().name()
                for i in plant.GetJointActuatorIndices(tool)}
    assert actuated == {"servo_1", "servo_2"}
    ctx = plant.CreateDefaultContext()
    p = _disc_points(G, 5, 20)
    q, _ = mut.inverse_kinematics(G, p)
    tcp = plant.GetFrameByName("laser_tcp", tool)
    l1 = plant.GetBodyByName("link_1", tool)
    l2 = plant.GetBodyByName("link_2", tool)
    for qi, pi in zip(q, p, strict=True):
        model.set_tool_positions(plant, ctx, tool, G, qi)
        X = tcp.CalcPoseInWorld(ctx)
        assert np.allclose(X.translation(), [*pi, model.NOZZLE_LENGTH], atol=1e-12)
        # loop closed: both distal links end at J5
        a = l1.EvalPoseInWorld(ctx).multiply(np.array([0, G.l3, 0]))
        b = l2.EvalPoseInWorld(ctx).multiply(np.array([0, -G.l4, 0]))
        assert np.allclose(a, b, atol=1e-12)
    # the shipped SDF is the generated default
    assert model_path(model.DEFAULT_SDF).read_text() == model.five_bar_sdf()
