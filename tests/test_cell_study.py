"""The cell-design study (drakedeburr.cell.study, drakedeburr.cell.commands): candidate scenario
files checked by building their cells (FK of the tool and hub frames against the bundled cell's,
turned and lifted by an independently built wedge), read back from the file, ranked, and a
quick real study through the CLI whose recommended file is loaded and checked."""

import json
import math

import numpy as np
import pytest

import drakedeburr.cell.study as mut
from drakedeburr.cell.station import load_cell
from drakedeburr.cell.tools import FLOATING_SPINDLE
from drakedeburr.errors import InputError
from drakedeburr.hub import DEFAULT_HUB

CANDIDATES = [mut.MountCandidate(math.radians(30), 0.0, -0.05),
              mut.MountCandidate(math.radians(60), 0.05, 0.05)]


def _rot_y(a: float) -> np.ndarray:
    """A turn about +Y by ``a`` (right hand), built from its axis-angle form (Rodrigues)."""
    k = np.array([0.0, 1.0, 0.0])
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K


def _X_FT(cell, q) -> np.ndarray:
    return (cell.X_WF(q).inverse() @ cell.X_WT(q)).GetAsMatrix4()


@pytest.fixture(scope="module")
def bundled():
    return load_cell("tool_in_hand", DEFAULT_HUB)


@pytest.mark.parametrize("c", CANDIDATES, ids=lambda c: c.name)
def test_candidate_scenario_round_trips(tmp_path, c):
    f = mut.write_candidate_scenario(c, tmp_path / "a.yaml")
    back = mut.candidate_from_scenario(f)
    assert back.name == c.name
    assert abs(back.mount_angle - c.mount_angle) < 1e-9
    assert abs(back.offset - c.offset) < 1e-9
    assert abs(back.fixture_shift - c.fixture_shift) < 1e-9
    # written again from what was read: the same file
    g = mut.write_candidate_scenario(back, tmp_path / "b.yaml")
    assert g.read_text() == f.read_text()


@pytest.mark.parametrize("c", CANDIDATES, ids=lambda c: c.name)
def test_candidate_cell_tool_and_hub_frames(tmp_path, bundled, c):
    cell = load_cell(mut.write_candidate_scenario(c, tmp_path / "c.yaml"), DEFAULT_HUB)
    q = np.array(bundled.q_home)
    X_FT, X_FT_ref = _X_FT(cell, q), _X_FT(bundled, q)
    z_F = X_FT[:3, 2]  # the burr axis in the flange frame
    assert math.degrees(math.acos(z_F[2])) == pytest.approx(math.degrees(c.mount_angle),
                                                            abs=1e-6)
    assert abs(z_F[1]) < 1e-9 and z_F[0] > 0  # tilted about +Y_F, tip towards +X_F
    # the bundled tool frame turned by the wedge about +Y_F and lifted off the flange face
    wedge = c.mount_angle - math.radians(45)
    lift = c.offset + FLOATING_SPINDLE.plate_radius * abs(math.sin(wedge))
    R = _rot_y(wedge)
    np.testing.assert_allclose(X_FT[:3, :3], R @ X_FT_ref[:3, :3], atol=1e-9)
    np.testing.assert_allclose(X_FT[:3, 3], R @ X_FT_ref[:3, 3] + [0, 0, lift], atol=1e-9)
    # the hub face moved with the fixture along +Z_W only
    dp = cell.X_WH(q).translation() - bundled.X_WH(q).translation()
    np.testing.assert_allclose(dp, [0, 0, c.fixture_shift], atol=1e-9)


def test_bundled_candidate_is_the_bundled_cell(tmp_path, bundled):
    c = mut.MountCandidate()
    assert c.is_bundled() and c.name == "m45_o000_f+000"
    cell = load_cell(mut.write_candidate_scenario(c, tmp_path / "c.yaml"), DEFAULT_HUB)
    q = np.array(bundled.q_home)
    np.testing.assert_allclose(_X_FT(cell, q), _X_FT(bundled, q), atol=1e-12)


def test_candidates_out_of_range_are_refused():
    with pytest.raises(InputError, match="mount angle"):
        mut.MountCandidate(math.radians(100))
    with pytest.raises(InputError, match="offset"):
        mut.MountCandidate(offset=-0.01)
    with pytest.raises(InputError, match="fixture"):
        mut.MountCandidate(fixture_shift=0.5)


def test_ranking_and_recommendation(tmp_path):
    """A failing candidate is listed with its failing check and never recommended, however fast;
    equal cycles (within 10 ms) are ranked by the wrist travel, then by name."""
    cands = mut.candidate_grid((30, 45, 60), (0,), (0,))
    figures = {  # name -> (passed, cycle s, travel deg)
        "m30_o000_f+000": (False, 10.0, 50.0),
        "m45_o000_f+000": (True, 20.004, 120.0),
        "m60_o000_f+000": (True, 20.001, 110.0)}

    def evaluate(c, f):
        assert mut.candidate_from_scenario(f).name == c.name
        ok, cycle, travel = figures[c.name]
        return {"passed": ok, "failing": [] if ok else ["clearance"], "cycle_s": cycle,
                "worst_wrist_travel_deg": travel}

    res = mut.run_study(cands, evaluate, tmp_path)
    names = [r["name"] for r in res["ranking"]]
    assert names == ["m60_o000_f+000", "m45_o000_f+000", "m30_o000_f+000"]
    assert res["ranking"][-1]["failing"] == ["clearance"]
    assert res["recommended"] == "m60_o000_f+000"
    rec = mut.candidate_from_scenario(res["recommended_scenario"])
    assert rec.mount_angle == pytest.approx(math.radians(60), abs=1e-9)
    # nothing passes: nothing recommended, no file
    figures.update({k: (False, *v[1:]) for k, v in figures.items()})
    res = mut.run_study(cands, evaluate, tmp_path / "none")
    assert res["recommended"] is None and not (tmp_path / "none" / "recommended.yaml").exists()


@pytest.mark.slow
def test_cell_study_quick_cli(tmp_path):
    """Two real candidates on window 0: the recommended file is the first-ranked passing
    candidate's cell, its tool frame at the recommended angle."""
    from drakedeburr.cli import main

    out = tmp_path / "study"
    assert main(["cell", "study", "--quick", "-o", str(out)]) == 0
    doc = json.loads((out / "study.json").read_text())
    ranking = doc["ranking"]
    assert len(ranking) == 2 and doc["windows"] == [0]
    best = ranking[0]
    assert best["passed"] and doc["recommended"] == best["name"]
    passing = [r for r in ranking if r["passed"]]
    assert all(best["cycle_s"] <= r["cycle_s"] + mut.CYCLE_QUANTUM_S for r in passing)
    for r in ranking:  # the figures are the verifier's, in range
        assert 0.0 < r["feed_held_worst"] <= 1.0 and r["cycle_ratio"] >= 1.0
        j = r["j4_j6_deg_per_window"]["0"]
        assert r["worst_wrist_travel_deg"] == pytest.approx(sum(j))
    rec = mut.candidate_from_scenario(out / "recommended.yaml")
    assert rec.name == best["name"]
    cell = load_cell(out / "recommended.yaml", DEFAULT_HUB)
    z_F = _X_FT(cell, np.array(cell.q_home))[:3, 2]
    assert math.acos(z_F[2]) == pytest.approx(best["mount_angle"], abs=1e-9)


@pytest.mark.parametrize("argv, says", [
    (["--angles", "30,x"], "--angles '30,x': expected comma-separated numbers"),
    (["--angles", "30,30"], "expected distinct finite numbers"),
    (["--angles", "120"], "mount angle must be within [0, 90] deg"),
    (["--offsets", "-10"], "mount offset must be within [0, 200] mm"),
    (["--windows", "99"], "has no window 99")])
def test_cell_study_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, says):
    from drakedeburr.cli import main

    out = tmp_path / "study"
    assert main(["cell", "study", *argv, "-o", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and says in err[0], err
    assert not out.exists()


@pytest.mark.parametrize("deg", [0, 15])
def test_straight_and_shallow_mount_frames(tmp_path, bundled, deg):
    """Mount 0 deg (straight: the burr axis is the J6 axis) and 15 deg: FK of the built cell puts
    the burr axis at the mount angle from the flange axis (parallel to it at 0 deg), the tip where
    the bundled tool model turned by the wedge and lifted by the plate says, and the spindle body
    clear of the wrist at the home pose (the collision model finds no penetration)."""
    c = mut.MountCandidate(math.radians(deg))
    cell = load_cell(mut.write_candidate_scenario(c, tmp_path / "s.yaml"), DEFAULT_HUB)
    q = np.array(bundled.q_home)
    X_FT, X_FT_ref = _X_FT(cell, q), _X_FT(bundled, q)
    z_F = X_FT[:3, 2]
    tilt = math.atan2(math.hypot(z_F[0], z_F[1]), z_F[2])  # well conditioned near 0
    assert math.degrees(tilt) == pytest.approx(deg, abs=1e-6)
    if deg == 0:
        np.testing.assert_allclose(z_F, [0, 0, 1], atol=1e-9)  # parallel to the flange axis
    wedge = math.radians(deg - 45)
    lift = FLOATING_SPINDLE.plate_radius * abs(math.sin(wedge))
    R = _rot_y(wedge)
    np.testing.assert_allclose(X_FT[:3, 3], R @ X_FT_ref[:3, 3] + [0, 0, lift], atol=1e-9)
    # the tip's distance from the flange's origin is a rigid property of the spindle model
    assert np.linalg.norm(X_FT[:3, 3] - [0, 0, lift]) == pytest.approx(
        np.linalg.norm(X_FT_ref[:3, 3]), abs=1e-9)
    assert cell.collision_pairs(q) == []


@pytest.fixture(scope="module")
def coaxial_cell(tmp_path_factory):
    c = mut.MountCandidate(0.0, coaxial=True)
    f = mut.write_candidate_scenario(c, tmp_path_factory.mktemp("coax") / "coax.yaml")
    return c, f, load_cell(f, DEFAULT_HUB)


def test_coaxial_bracket_puts_the_burr_on_the_flange_axis(bundled, coaxial_cell):
    """The coaxial straight bracket (issue 46): FK of the built cell puts the burr axis on +Z_F
    and the tip on the flange axis, standing off by the bracket plate, the spindle body and the
    burr's tip height; turning J6 alone then spins the tool about its own axis (the tip and the
    axis stay put in W), which no wedge does (the 0 deg wedge leaves the axis 102.5 mm off)."""
    c, _, cell = coaxial_cell
    assert c.name == "coax_f+000" and not c.is_bundled()
    q = np.array(bundled.q_home)
    X_FT = _X_FT(cell, q)
    np.testing.assert_allclose(X_FT[:3, 2], [0, 0, 1], atol=1e-12)  # burr axis = +Z_F
    np.testing.assert_allclose(X_FT[:2, 3], [0, 0], atol=1e-12)  # tip on the flange axis
    sp = FLOATING_SPINDLE
    assert X_FT[2, 3] == pytest.approx(sp.plate_thickness + sp.body_length + sp.burr.z_tool_tip,
                                       abs=1e-12)
    for dq in (0.3, -1.2, 2.5):
        q2 = q.copy()
        q2[5] += dq
        X0, X1 = cell.X_WT(q).GetAsMatrix4(), cell.X_WT(q2).GetAsMatrix4()
        np.testing.assert_allclose(X1[:3, 3], X0[:3, 3], atol=1e-12)
        np.testing.assert_allclose(X1[:3, 2], X0[:3, 2], atol=1e-12)
        # the spin about the burr axis is dq
        assert math.atan2(np.cross(X0[:3, 0], X1[:3, 0]) @ X0[:3, 2],
                          X0[:3, 0] @ X1[:3, 0]) == pytest.approx(dq, abs=1e-12)
    # the 0 deg wedge: the axis parallel to +Z_F, 102.5 mm off it; J6 moves the tip
    wedge0 = mut.MountCandidate(0.0)
    p_F = wedge0.X_FM()[:3, :3] @ sp.p_FT + wedge0.X_FM()[:3, 3]
    assert math.hypot(p_F[0], p_F[1]) == pytest.approx(
        abs(np.array([math.cos(sp.mount_angle), 0, -math.sin(sp.mount_angle)]) @ sp.p_FC),
        abs=1e-12)
    assert math.hypot(p_F[0], p_F[1]) > 0.1


def test_coaxial_bracket_is_a_part_that_collides(bundled, coaxial_cell):
    """The bracket's flange plate and clamp ring are collision geometry moving with the robot,
    the spindle's own 45 deg adapter plate and bracket block are gone, nothing penetrates at
    home, and the bracket is where its model says (the plate on the flange face, the ring round
    the body's rear)."""
    from pydrake.geometry import Role

    _, _, cell = coaxial_cell
    inspector = cell.scene_graph.model_inspector()
    names = {inspector.GetName(g): g for g in cell.robot_ids}
    assert {"coaxial_bracket::flange_plate", "coaxial_bracket::clamp_ring"} <= set(names)
    assert not any(n.startswith("spindle::") and n.split("::")[1] in ("adapter_plate", "bracket")
                   for n in names)
    assert all(inspector.GetProximityProperties(names[n]) is not None
               for n in ("coaxial_bracket::flange_plate", "coaxial_bracket::clamp_ring"))
    assert len(inspector.GetAllGeometryIds(Role.kProximity)) > 0
    q = np.array(bundled.q_home)
    assert cell.collision_pairs(q) == []
    X_WF = cell.X_WF(q).GetAsMatrix4()
    plant = cell.plant
    ctx = plant.GetMyContextFromRoot(cell.create_context())
    body = plant.GetBodyByName("bracket", plant.GetModelInstanceByName(mut.BRACKET_MODEL))
    np.testing.assert_allclose(body.EvalPoseInWorld(ctx).GetAsMatrix4(), X_WF, atol=1e-12)
    # the body's rear face is on the plate: the spindle body cylinder's axis is +Z_F, its rear
    # end at the plate's top
    g = names["spindle::spindle_body"]
    X_WG = plant.GetBodyFromFrameId(inspector.GetFrameId(g)).EvalPoseInWorld(ctx).multiply(
        inspector.GetPoseInFrame(g)).GetAsMatrix4()
    X_FG = np.linalg.inv(X_WF) @ X_WG
    np.testing.assert_allclose(X_FG[:3, 2], [0, 0, 1], atol=1e-12)
    length = inspector.GetShape(g).length()
    assert X_FG[2, 3] - length / 2 == pytest.approx(FLOATING_SPINDLE.plate_thickness, abs=1e-12)


def test_coaxial_candidate_round_trips_and_refuses_a_tampered_file(tmp_path, coaxial_cell):
    c, f, _ = coaxial_cell
    back = mut.candidate_from_scenario(f)
    assert back == c
    c2 = mut.MountCandidate(0.0, 0.0, -0.05, coaxial=True)
    g = mut.write_candidate_scenario(c2, tmp_path / "c2.yaml")
    assert mut.candidate_from_scenario(g) == c2 and c2.name == "coax_f-050"
    # the bracket kept but the spindle moved off the axis: not the coaxial bracket
    text = g.read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("package://drakedeburr/tools/floating_spindle_coaxial.sdf",
                                "package://drakedeburr/tools/floating_spindle.sdf"))
    with pytest.raises(InputError, match="coaxial bracket"):
        mut.candidate_from_scenario(bad)
    with pytest.raises(InputError, match="coaxial bracket has mount angle 0"):
        mut.MountCandidate(math.radians(45), coaxial=True)
    with pytest.raises(InputError, match="coaxial bracket has mount angle 0"):
        mut.MountCandidate(0.0, 0.05, coaxial=True)


def test_coaxial_candidates_from_the_options():
    import argparse

    from drakedeburr.cell.commands import study_setup

    args = argparse.Namespace(hub=None, windows=None, quick=False, angles="none", offsets="0",
                              fixture_heights="0,-50", coaxial=True)
    _, _, cands = study_setup(args)
    assert [c.name for c in cands] == ["coax_f+000", "coax_f-050"]
    args.coaxial = False
    with pytest.raises(InputError, match="no candidates"):
        study_setup(args)


def _ik_over_spins(cell, tilt: float, spins: np.ndarray) -> np.ndarray:
    """(spins, 8, 6) every analytic IK branch [rad] for the tool tip 0.14 m out on the hub face,
    its axis tilted ``tilt`` from the face normal, at each spin about the axis."""
    from drakedeburr.plan.kinematics import cell_kinematics
    from drakedeburr.plan.spin import spin_frames

    kin = cell_kinematics(cell)
    c, s = math.cos(tilt), math.sin(tilt)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.diag([1.0, -1.0, -1.0])  # Z_T down
    X = np.repeat(np.eye(4)[None], len(spins), 0)
    X[:, :3, :3] = spin_frames(np.repeat(R[None], len(spins), 0), spins)
    X[:, :3, 3] = (0.12, 0.08, 0.0)
    return kin.ik_all(kin.X_WF_from_X_HT(X))[0]


def test_coaxial_spin_moves_j6_alone(bundled, coaxial_cell):
    """With the coaxial bracket the analytic IK gives the same J1-J5 at every spin about the
    tool axis and J6 turned by the spin: J4's and J5's motion along a cut is fixed by the tool
    axis and the arm's posture, no spin choice changes it. With the bundled 45 deg mount the
    spin moves J4 and J5 too."""
    spins = np.linspace(-math.pi, math.pi, 13)[:-1]
    q = _ik_over_spins(coaxial_cell[2], 0.3, spins)
    ok = np.all(np.isfinite(q), axis=(0, 2))
    assert ok.any()
    for b in np.flatnonzero(ok):
        d = np.angle(np.exp(1j * (q[:, b, :5] - q[:1, b, :5])))  # (revolute: mod 2 pi)
        np.testing.assert_allclose(d, 0.0, atol=1e-9)
        # J6 turned by the spin (mod 2 pi)
        off = np.angle(np.exp(1j * (q[:, b, 5] - q[0, b, 5] - (spins - spins[0]))))
        np.testing.assert_allclose(off, 0.0, atol=1e-9)
    q45 = _ik_over_spins(bundled, 0.3, spins)
    reached = np.all(np.isfinite(q45), axis=2)  # (spins, branches)
    b = int(np.argmax(reached.sum(axis=0)))
    assert reached[:, b].sum() >= 3
    # J5 swings by more than 0.5 rad over the spins this branch reaches
    assert np.ptp(q45[reached[:, b], b, 4]) > 0.5


def test_coaxial_spin_search_holds_j6(coaxial_cell):
    """drakedeburr.plan.spin on the coaxial cell: a cut along a third of a 0.14 m circle on the
    hub face with the tool axis tilted 0.3 rad towards the centre (the axis turns, J4 winds):
    the chosen spin holds J6 at the start (under 1 mrad) and leaves J1-J5 those of any
    other spin (the spin moves J6 alone); the tip and axis stay the cut's."""
    from drakedeburr.plan.kinematics import cell_kinematics
    from drakedeburr.plan.spin import optimize_spin

    kin = cell_kinematics(coaxial_cell[2])
    phi = np.linspace(0.0, 2 * math.pi / 3, 121)
    X = np.repeat(np.eye(4)[None], len(phi), 0)
    for k, f in enumerate(phi):
        r = np.array([math.cos(f), math.sin(f), 0.0])  # radial, in H
        t = np.array([-math.sin(f), math.cos(f), 0.0])
        z = -(math.cos(0.3) * np.array([0, 0, 1.0]) + math.sin(0.3) * r)  # Z_T into the face
        x = np.cross(t, z)
        X[k, :3, :3] = np.column_stack([x / np.linalg.norm(x), np.cross(z, x / np.linalg.norm(x)),
                                        z])
        X[k, :3, 3] = 0.14 * r
    s = 0.14 * phi
    q_all = kin.ik_all(kin.X_WF_from_X_HT(X[:1]))[0][0]
    b = [i for i in range(8) if np.all(np.isfinite(q_all[i])) and abs(q_all[i, 4]) > 0.3
         and kin.within_limits(q_all[i])]
    assert b
    q0 = q_all[b[0]]
    X_out, stats = optimize_spin(kin, X, s, q0)
    assert stats["ok"] and stats["rule"] == "hold J6", stats
    q_out, ok = kin.track(kin.X_WF_from_X_HT(X_out), q0)
    q_in, ok_in = kin.track(kin.X_WF_from_X_HT(X), q0)
    assert ok.all() and ok_in.all()
    # held exactly at the program's samples (every 2nd), the spin interpolated between them
    assert np.ptp(q_out[::2, 5]) < 1e-9 and abs(q_out[0, 5] - q0[5]) < 1e-9
    assert np.ptp(q_out[:, 5]) < 1e-3
    assert np.ptp(q_in[:, 5]) > 0.5  # the cut's own spin winds J6
    np.testing.assert_allclose(q_out[:, :5], q_in[:, :5], atol=1e-9)
    np.testing.assert_allclose(X_out[:, :3, 3], X[:, :3, 3], atol=1e-12)
    np.testing.assert_allclose(X_out[:, :3, 2], X[:, :3, 2], atol=1e-12)
