"""Payload as a required check (issue 41 item 4): the load the arm carries, summed from the
cell's models, against the arm file's rating; the figures against closed forms and against the
vendors' own formulas (ABB product spec IRB 2600: Ja5 = m((Z + d)^2 + L^2) + max(J0x, J0y),
Ja6 = m L^2 + J0z)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.resources import hub_dir, models_dir
from drakedeburr.robots import get_robot
from drakedeburr.robots.payload import G, carried_load, payload_figures
from drakedeburr.verify.checks_payload import cell_load, payload


def _inertial(sdf_path, link: str):
    """(mass, pose xyz, 3x3 inertia) of a link's <inertial> read from the SDF text."""
    root = ET.parse(sdf_path).getroot()
    el = next(li for li in root.iter("link") if li.get("name") == link).find("inertial")
    xyz = [float(v) for v in el.findtext("pose").split()[:3]]
    i = {k: float(el.find("inertia").findtext(k)) for k in
         ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    inertia = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
                        [i["ixz"], i["iyz"], i["izz"]]])
    return float(el.findtext("mass")), np.array(xyz), inertia


def test_point_mass_figures_are_the_closed_forms():
    """A point mass m at (x, 0, z) in the flange frame: J4/J5 moment m g sqrt(x^2 + (z+c4)^2),
    J6 m g |x|; inertias m r^2 about J4/J5, m x^2 about J6."""
    spec = replace(get_robot("m710ic50"))
    m, x, z = 12.0, 0.05, 0.2
    load = carried_load([("p", m, (x, 0.0, z), np.zeros((3, 3)))])
    f = {it.name: it.value for it in payload_figures(spec, load)}
    r = np.hypot(x, z + spec.opw.c4)
    assert f["mass"] == m
    assert f["J4 moment"] == pytest.approx(m * G * r) and f["J5 moment"] == f["J4 moment"]
    assert f["J6 moment"] == pytest.approx(m * G * x)
    assert f["J4 inertia"] == pytest.approx(m * r * r)
    assert f["J5 inertia"] == pytest.approx(m * r * r)  # the J5 axis normal to x and z
    assert f["J6 inertia"] == pytest.approx(m * x * x)


def test_inertia_figures_equal_abbs_formula():
    """ABB's Ja5/Ja6 for a body with its principal axes along the flange axes, centre of
    gravity on the flange axis at Z (L = 0) and off it (L along x): Ja5 = m((Z + d)^2 + L^2) +
    max(J0x, J0y) bounds ours (ours keeps the cross term), equal for L = 0; Ja6 equal."""
    spec = get_robot("irb2600")
    d = spec.opw.c4
    J0 = np.diag([0.20, 0.25, 0.40])
    for L in (0.0, 0.04):
        m, Z = 15.0, 0.23
        load = carried_load([("hub", m, (L, 0.0, Z), J0)])
        f = {it.name: it.value for it in payload_figures(spec, load)}
        ja5 = m * ((Z + d) ** 2 + L ** 2) + max(J0[0, 0], J0[1, 1])
        ja6 = m * L ** 2 + J0[2, 2]
        assert f["J6 inertia"] == pytest.approx(ja6, rel=1e-12)
        assert f["J5 inertia"] <= ja5 + 1e-12
        if L == 0.0:
            assert f["J5 inertia"] == pytest.approx(ja5, rel=1e-12)


def test_the_cell_load_is_the_models_sum():
    """Workpiece in hand: gripper (4 kg at z_F 0.12) + hub (its hub.sdf mass, centre at
    0.30 m + its own z_H), read here from the SDF files, not from Drake."""
    from drakedeburr.cell.station import load_cell

    cell = load_cell("workpiece_in_hand", "h5_straight")
    load = cell_load(cell)
    mg, pg, Ig = _inertial(models_dir() / "tools" / "hub_gripper.sdf", "gripper")
    mh, ph, Ih = _inertial(hub_dir("h5_straight") / "hub.sdf", "hub")
    ph = ph + np.array([0.0, 0.0, 0.30])  # hub_mount: 0.30 m ahead, +Z_H = +Z_F
    assert load.mass == pytest.approx(mg + mh, abs=1e-9)
    assert mg + mh == pytest.approx(16.111227)  # the 16.1 kg of issue 41
    np.testing.assert_allclose(load.cog_F, (mg * pg + mh * ph) / (mg + mh), atol=1e-9)
    c = load.cog_F
    ref = sum(I + m * ((p - c) @ (p - c) * np.eye(3) - np.outer(p - c, p - c))
              for m, p, I in ((mg, pg, Ig), (mh, ph, Ih)))
    np.testing.assert_allclose(load.inertia_cog_F, ref, atol=1e-9)


@pytest.mark.parametrize("robot, passed", [(None, False), ("kr6_r700", False),
                                           ("m10ia", False)])
def test_workpiece_in_hand_on_a_small_arm_fails_naming_mass_and_rating(robot, passed):
    from drakedeburr.cell.station import load_cell

    cell = load_cell("workpiece_in_hand", "h5_straight", robot=robot)
    item = payload(SimpleNamespace(cell=cell), None)
    assert item.passed is passed
    assert item.value == pytest.approx(16.111227) and item.unit == "kg"
    assert item.limit == cell.arm.payload_kg
    assert f"mass 16.111 kg (rated {cell.arm.payload_kg:g})" in item.detail
    assert "irb2600" in item.detail and "m710ic50" in item.detail  # who would carry it


def test_tool_in_hand_spindle_is_within_every_rating():
    from drakedeburr.cell.station import load_cell

    cell = load_cell("tool_in_hand", "h5_straight")
    item = payload(SimpleNamespace(cell=cell), None)
    assert item.passed and item.value == pytest.approx(3.05) and item.limit == 10.0
    assert "not published for this arm" in item.detail


@pytest.mark.parametrize("hub, ok", [("h5_straight", True), ("h5_deepdish", False)])
def test_irb2600_wrist_inertia_decides_the_deep_dish(hub, ok):
    """The IRB 2600 carries 16 kg by mass; ABB's J5 inertia limit (2.0 kg m^2) holds for
    h5_straight (1.95) and not for h5_deepdish (2.11: its centre of gravity 14 mm further
    out)."""
    from drakedeburr.cell.station import load_cell

    load = cell_load(load_cell("workpiece_in_hand", hub))
    f = {it.name: it for it in payload_figures(get_robot("irb2600"), load)}
    assert f["mass"].ok and f["J6 inertia"].ok
    assert f["J5 inertia"].ok is ok
    assert f["J5 inertia"].value == pytest.approx(1.951 if ok else 2.109, abs=1e-3)


def test_the_workpiece_in_hand_default_is_an_arm_rated_for_the_hub():
    """No --robot: the scenario's arm where it is rated (tool in hand: the 3 kg spindle on the
    IRB 1600-10), else the first registered arm rated for the load with a mount in the cell
    (h5_straight on the gripper: the IRB 2600-20/1.65; h5_deepdish, over the IRB 2600's J5
    inertia: the M-710iC/50), else the scenario's own, whose payload item then fails naming the
    arms that would carry it."""
    from drakedeburr.cell.loads import rated_default_arm
    from drakedeburr.robots import ROBOTS

    assert rated_default_arm("tool_in_hand", "h5_straight") is None
    assert rated_default_arm("workpiece_in_hand", "h5_straight") == "irb2600"
    # the deep dish: rated by mass on the KR 20 R1810-2 (its wrist ratings unpublished) and by
    # mass, moments and inertias on the M-710iC/50: a wrist-rated arm is taken first
    assert {"kr20_r1810", "m710ic50"} <= {n for n, s in ROBOTS.items()
                                          if "workpiece_in_hand" in s.cells}
    assert rated_default_arm("workpiece_in_hand", "h5_deepdish") == "m710ic50"


@pytest.mark.slow
def test_workpiece_in_hand_overload_fails_and_a_rated_arm_passes(tmp_path):
    """Issue 41 "checked by": window 0 of h5_straight held on the gripper (16.1 kg).
    IRB 1600-10 (--robot irb1600): verify exit 1 with the payload item failing (mass and
    rating named), export exit 1 and no program. No --robot: the default is the rated
    IRB 2600-20/1.65; verify exit 0 (every required item) and export writes its RAPID program
    with the 16.1 kg load."""
    import json

    from drakedeburr.cli import main

    runs = {"small": ["--robot", "irb1600"], "default": []}
    for key, extra in runs.items():
        folder = tmp_path / key
        assert main(["-q", "plan", "workpiece_in_hand", "--hub", "h5_straight", "--windows",
                     "0", "-o", str(folder), *extra]) == 0
        code = main(["-q", "verify", str(folder), "--windows", "0", "--no-replay"])
        report = json.loads((folder / "report.json").read_text())
        item = next(i for i in report["items"] if i["name"] == "payload")
        out = tmp_path / f"{key}.mod"
        if key == "small":
            assert code == 1 and report["summary"]["failed"] == ["payload"]
            assert not item["passed"] and item["limit"] == 10.0
            assert "mass 16.111 kg (rated 10)" in item["detail"] and "irb2600" in item["detail"]
            assert main(["-q", "export", str(folder), "-o", str(out)]) == 1
            assert not out.exists()
        else:
            assert json.loads((folder / "plan.json").read_text())["meta"]["robot"] == "irb2600"
            assert code == 0 and report["passed"] and item["passed"]
            assert main(["-q", "export", str(folder), "-o", str(out)]) == 0
            text = out.read_text()
            assert "ABB IRB 2600-20/1.65" in text and "loaddata" in text


def _payload_warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno >= 30 and "kg" in r.getMessage()]


def test_the_default_arm_is_the_one_warning_names(caplog, monkeypatch):
    """No --robot, workpiece in hand (h5_deepdish, 15.9 kg): the scenario's IRB 1600-10 (rated
    10 kg) only stands in while the default is chosen: one warning, naming the arm used (the
    M-710iC/50), and no "payload check fails" for an arm that is not used; loading the cell
    with the arm chosen (the run's cells) warns nothing more."""
    import logging

    import drakedeburr.cell.station as station
    from drakedeburr.cell.loads import arm_or_rated_default

    monkeypatch.setattr(station, "_PAYLOAD_WARNED", set())  # as in a fresh process
    caplog.set_level(logging.WARNING)
    robot = arm_or_rated_default(None, "workpiece_in_hand", "h5_deepdish")
    cell = station.load_cell("workpiece_in_hand", "h5_deepdish", robot=robot)
    assert robot == cell.arm.name == "m710ic50"
    msgs = _payload_warnings(caplog)
    assert len(msgs) == 1, msgs
    assert "irb1600 is not rated for the 15.9 kg" in msgs[0] and "using m710ic50" in msgs[0]
    assert "fail" not in msgs[0]
    assert payload(SimpleNamespace(cell=cell), None).passed


def test_a_forced_small_arm_warns_once_that_payload_fails(caplog, monkeypatch):
    """--robot irb1600 (forced): no default chosen; the cell warns once that the payload check
    fails (the arm, the mass, the rating), however often the run loads the cell; the payload
    item fails."""
    import logging

    import drakedeburr.cell.station as station
    from drakedeburr.cell.loads import arm_or_rated_default

    monkeypatch.setattr(station, "_PAYLOAD_WARNED", set())
    caplog.set_level(logging.WARNING)
    robot = arm_or_rated_default("irb1600", "workpiece_in_hand", "h5_deepdish")
    assert robot == "irb1600"
    for _ in range(2):
        cell = station.load_cell("workpiece_in_hand", "h5_deepdish", robot=robot)
    msgs = _payload_warnings(caplog)
    assert len(msgs) == 1, msgs
    assert "the arm irb1600 carries 15.9 kg" in msgs[0] and "rated for 10.0 kg" in msgs[0]
    assert "payload check fails and no program is written" in msgs[0]
    assert not payload(SimpleNamespace(cell=cell), None).passed
    # a worker process builds the cell again from its recipe: no second warning from there
    monkeypatch.setattr(station, "_PAYLOAD_WARNED", set())  # the worker's own process
    again = station.load_cell(**cell.recipe)
    assert again.arm.name == "irb1600" and len(_payload_warnings(caplog)) == 1
    # verify in a new process: the plan's cell, built there the first time, warns
    monkeypatch.setattr(station, "_PAYLOAD_WARNED", set())
    plan = SimpleNamespace(scenario="workpiece_in_hand", hub="h5_deepdish",
                           meta={"robot": "irb1600"})
    assert station.load_plan_cell(plan).arm.name == "irb1600"
    assert len(_payload_warnings(caplog)) == 2
