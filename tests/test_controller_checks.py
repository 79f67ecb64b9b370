"""The controller's motion checked like a plan (issue 41, item 2): ``verify --program``
re-simulates the written program (joints from the written poses and configuration) and runs the
registry's clearance certificate, cone, edge deviation, burr contact and joint limits on that
motion (``controller_*``). The written program passes them; a RAPID file edited by hand (a
target moved off the edge, tilted out of its cone, past a joint limit, into the hub) fails the
item concerned, its value re-checked here from the written pose by forward kinematics and
distances of our own."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import verify_support as vs
from scipy.spatial.transform import Rotation

from drakedeburr.post.program_check import CONTROLLER_CHECKS, plan_program, program_items
from drakedeburr.programs import read_program, write_program
from drakedeburr.robots import abb_confdata, fk_opw
from drakedeburr.verify.distances import DistanceProbe
from drakedeburr.verify.geometry import point_segment
from drakedeburr.verify.refs import cone_half_angle, tool_paths_of

NAMES = [f"controller_{n}" for n in CONTROLLER_CHECKS]
DOCS = Path(__file__).resolve().parents[1] / "docs" / "verify.md"


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    plan = vs.good_plan()
    cell, hub = vs.cell_and_hub()
    expected = plan_program(plan, "deburr", cell=cell)
    path = write_program(expected, tmp_path_factory.mktemp("ctrl") / "deburr.mod", "rapid")[0]
    # program move of each plan target (the program adds via points on bent joint moves)
    move_of, j = {}, 0
    for k, t in enumerate(plan.targets):
        while not np.array_equal(expected.moves[j].q, t.q):
            j += 1
        move_of[k] = j
        j += 1
    return plan, cell, hub, expected, path, move_of


def _items(setup, path, coarse=True):
    plan, cell, hub = setup[:3]
    cfg = vs.config(**(vs.COARSE if coarse else {}))
    return {i.name: i for i in program_items(plan, read_program(path), cell, cfg.tolerances,
                                             config=cfg, hub_model=hub)}


def _X_OH(setup):
    plan, expected = setup[0], setup[3]
    return np.linalg.solve(expected.X_WO, plan.X_WH)


def _write_target(setup, tmp_path, k, X_OT, conf=None):
    """The RAPID file with plan target ``k``'s robtarget rewritten by hand: position [mm],
    quaternion and (optionally) confdata."""
    path, move_of = setup[4], setup[5]
    name = read_program(path).moves[move_of[k]].name
    text = path.read_text()
    line = re.search(rf"CONST robtarget {name} := \[.*\];", text)
    old = re.match(r"CONST robtarget \w+ := \[\[.*?\],\[.*?\],(\[.*?\]),(\[.*\])\];",
                   line.group(0))
    w = Rotation.from_matrix(X_OT[:3, :3]).as_quat(scalar_first=True)
    pos = ",".join(f"{v * 1e3:.6f}" for v in X_OT[:3, 3])
    cf = old.group(1) if conf is None else "[" + ",".join(str(int(c)) for c in conf) + "]"
    new = (f"CONST robtarget {name} := [[{pos}],[{','.join(f'{v:.10f}' for v in w)}],{cf},"
           f"{old.group(2)}];")
    out = tmp_path / "deburr.mod"
    out.write_text(text.replace(line.group(0), new))
    return out


def _confdata(setup, q):
    return abb_confdata(setup[3].spec.kinematics, q)


def _cut_target(plan, window=0):
    """A CL target in the middle of a window's cut, its neighbours on the same cut."""
    seg = next(s for s in plan.segments if s.kind == "cut" and s.window_index == window)
    return (seg.target_range[0] + seg.target_range[1]) // 2


def _cl(plan, k):
    """The CL point (window's tool path) target ``k`` cuts, in H [m]."""
    t = plan.targets[k]
    return np.asarray(tool_paths_of(plan)[t.window_index].p_HC, float)[t.cl_index]


def _tangent(plan, k):
    """Unit tangent of the cut at CL target ``k`` (its neighbours' CL points)."""
    d = _cl(plan, k + 1) - _cl(plan, k - 1)
    return d / np.linalg.norm(d)


def _edge_distance(hub, window, p):
    e = np.asarray(next(w for w in hub.windows if w.index == window).p_HE, float)
    e = np.vstack([e, e[:1]])
    d = point_segment(np.atleast_2d(p), e[:-1], e[1:])
    return float(np.min(d[0] if isinstance(d, tuple) else d))


def _controller_joints_at(setup, X_OT, q_near):
    """The IK solution of a written TCP pose nearest ``q_near`` (FK re-checked)."""
    from drakedeburr.robots import ik_opw

    expected = setup[3]
    X_BF = expected.X_WO @ X_OT @ np.linalg.inv(expected.X_FT)
    sols = ik_opw(expected.spec.opw, X_BF).q[0]
    sols = sols[~np.isnan(sols).any(axis=1)]
    turns = np.round((q_near - sols) / (2 * np.pi)) * 2 * np.pi
    sols = sols + turns
    q = sols[np.argmin(np.abs(sols - q_near).max(axis=1))]
    np.testing.assert_allclose(fk_opw(expected.spec.opw, q), X_BF, atol=1e-9)
    return q


@pytest.fixture(scope="module")
def good_items(setup):
    return _items(setup, setup[4], coarse=False)


def test_the_docs_table_lists_every_program_item(good_items):
    text = DOCS.read_text()
    table = text[text.index("| item | required | what | limit |"):]
    rows = []
    for line in table.splitlines()[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows.append((cells[0], cells[1]))
    assert rows == [(n, "yes" if i.required else "info") for n, i in good_items.items()]


def test_the_written_program_passes_every_controller_check(setup, good_items):
    plan, cell = setup[:2]
    items = good_items
    for n in NAMES:
        assert items[n].passed and items[n].required, (n, items[n].detail)
    assert "controller_clearance" not in items  # the certificate, not samples
    # independently: the clearance at the written targets (our own probe at the joints the
    # written poses give) is at least the certified bound; the cone margin at a CL target from
    # the written orientation is at least the reported smallest
    probe = DistanceProbe(cell, 0.05)
    X_OH = _X_OH(setup)
    k = _cut_target(plan)
    X_OT = np.array(read_program(setup[4]).moves[setup[5][k]].X_OT)
    q = _controller_joints_at(setup, X_OT, plan.targets[k].q)
    cert = items["controller_clearance_certificate"].value
    for kk in (1, 2, k, len(plan.targets) - 2):
        X = np.array(read_program(setup[4]).moves[setup[5][kk]].X_OT)
        assert probe.measure(_controller_joints_at(setup, X, plan.targets[kk].q)).clearance \
            >= cert - 1e-9
    z_H = (np.linalg.inv(X_OH) @ X_OT)[:3, 2]
    tp = tool_paths_of(plan)[0]
    axis = np.asarray(tp.cone_zT_H)[plan.targets[k].cl_index]
    margin = cone_half_angle(plan, 0, tp) - np.arccos(np.clip(z_H @ axis / np.linalg.norm(axis),
                                                             -1, 1))
    assert items["controller_cone"].value <= margin + 1e-6
    assert probe.measure(q).clearance >= cert - 1e-9


def test_a_target_moved_off_the_edge_fails_the_edge_deviation(setup, tmp_path):
    plan, hub = setup[0], setup[2]
    k = _cut_target(plan)
    t = plan.targets[k]
    n = np.cross(_tangent(plan, k), np.asarray(t.X_HT)[:3, 2])  # across the edge
    n /= np.linalg.norm(n)
    M = np.eye(4)
    M[:3, 3] = 1e-3 * n  # 1 mm across the edge
    X_OH = _X_OH(setup)
    X_OT = X_OH @ M @ np.asarray(t.X_HT)
    items = _items(setup, _write_target(setup, tmp_path, k, X_OT))
    dev = items["controller_edge_deviation"]
    assert not dev.passed
    # the contact point at the target is the CL point carried by the moved tool pose
    assert dev.value == pytest.approx(_edge_distance(hub, 0, _cl(plan, k) + 1e-3 * n),
                                      abs=2e-5)
    assert dev.value > 0.9e-3
    for name in ("controller_cone", "controller_joint_position",
                 "controller_clearance_certificate"):
        assert items[name].passed, (name, items[name].detail)


def test_a_target_tilted_out_of_its_cone_fails_the_cone(setup, tmp_path):
    plan = setup[0]
    k = _cut_target(plan, window=1)
    t = plan.targets[k]
    X_HT = np.asarray(t.X_HT)
    axis = _tangent(plan, k)  # tilted about the edge
    tilt = np.radians(9.0)
    R = Rotation.from_rotvec(tilt * axis).as_matrix()
    c = _cl(plan, k)  # about the CL point: the contact stays on the edge
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, c - R @ c
    X_OT = _X_OH(setup) @ M @ X_HT
    conf = _confdata(setup, _controller_joints_at(setup, X_OT, t.q))
    items = _items(setup, _write_target(setup, tmp_path, k, X_OT, conf))
    cone = items["controller_cone"]
    assert not cone.passed
    tp = tool_paths_of(plan)[1]
    a = np.asarray(tp.cone_zT_H)[t.cl_index]
    z_new = (M @ X_HT)[:3, 2]
    ang = np.arccos(np.clip(z_new @ a / np.linalg.norm(a), -1, 1))
    assert cone.value == pytest.approx(cone_half_angle(plan, 1, tp) - ang, abs=1e-4)
    assert items["controller_edge_deviation"].passed, items["controller_edge_deviation"].detail


def test_a_target_past_a_joint_limit_fails_the_joint_limits(setup, tmp_path):
    plan, cell = setup[0], setup[1]
    lo, hi = np.asarray(cell.q_lower), np.asarray(cell.q_upper)
    # the cut target and joint nearest a limit, pushed 2 deg past it
    cut = [k for s in plan.segments if s.kind == "cut"
           for k in range(s.target_range[0] + 1, s.target_range[1])]
    q = np.array([plan.targets[k].q for k in cut])
    margin = np.minimum(q - lo, hi - q)
    i, j = np.unravel_index(np.argmin(margin), margin.shape)
    k = cut[i]
    q_new = np.array(plan.targets[k].q, float)
    past = np.radians(2.0)
    q_new[j] = lo[j] - past if q_new[j] - lo[j] < hi[j] - q_new[j] else hi[j] + past
    expected = setup[3]
    X_OT = np.linalg.solve(expected.X_WO, fk_opw(expected.spec.opw, q_new)) @ expected.X_FT
    items = _items(setup, _write_target(setup, tmp_path, k, X_OT, _confdata(setup, q_new)))
    jp = items["controller_joint_position"]
    assert not jp.passed
    assert jp.value == pytest.approx(-past, abs=1e-4)
    assert f"J{j + 1} at {np.degrees(q_new[j]):.2f} deg" in jp.detail


def test_a_target_moved_into_the_hub_fails_the_clearance_certificate(setup, tmp_path):
    """The approach of window 0 pushed 40 mm along the tool axis: the tool runs into the hub;
    the certificate is at most the clearance our own probe reads there."""
    plan, cell = setup[0], setup[1]
    seg = next(s for s in plan.segments if s.kind == "approach" and s.window_index == 0)
    k = seg.target_range[1] - 1
    t = plan.targets[k]
    X_HT = np.asarray(t.X_HT)
    M = np.eye(4)
    M[:3, 3] = 0.04 * X_HT[:3, 2]
    X_OT = _X_OH(setup) @ M @ X_HT
    q = _controller_joints_at(setup, X_OT, t.q)
    items = _items(setup, _write_target(setup, tmp_path, k, X_OT, _confdata(setup, q)))
    cert = items["controller_clearance_certificate"]
    assert not cert.passed
    probe = DistanceProbe(cell, 0.05)
    read = probe.measure(q)
    assert read.clearance < vs.config().tolerances.min_clearance
    assert cert.value <= read.clearance + 1e-9
    assert items["controller_joint_position"].passed


def test_a_motion_that_stops_is_not_measured(setup, tmp_path):
    """A target the controller cannot reach: the controller's motion stops there and every
    check of it fails as not measurable (no item passes by having nothing to read)."""
    plan = setup[0]
    k = _cut_target(plan)
    X_OT = _X_OH(setup) @ np.asarray(plan.targets[k].X_HT)
    X_OT = X_OT.copy()
    X_OT[:3, 3] += [5.0, 0.0, 0.0]  # 5 m away
    items = _items(setup, _write_target(setup, tmp_path, k, X_OT))
    assert not items["controller_motion"].passed
    for n in NAMES:
        assert not items[n].passed and "not measurable" in items[n].detail, n

