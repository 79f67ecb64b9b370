import numpy as np
import pytest

import drakedeburr.plan.io as mut
from drakedeburr.errors import InputError
from drakedeburr.plan.types import (
    CartesianTarget,
    FailureRecord,
    JointTrajectory,
    Plan,
    PlanSegment,
)


def _plan(failures=()):
    from drakedeburr.robots import IRB1600_10_120, fk_opw

    rng = np.random.default_rng(0)
    q = np.array([[0, 0.3, -0.2, 0.1, 0.8, 0.2], [0.1, 0.35, -0.25, 0.15, 0.7, 0.3],
                  [0.12, 0.36, -0.26, 0.2, 0.72, 0.35]])
    X_FT = np.eye(4)
    X_FT[:3, 3] = [0.1, 0, 0.25]
    X_WH = np.eye(4)
    X_WH[:3, 3] = [0.75, 0, -0.3]
    targets = []
    for i, qi in enumerate(q):
        X_WF = fk_opw(IRB1600_10_120, qi)
        targets.append(CartesianTarget(
            window_index=-1 if i == 0 else 0, segment="home" if i == 0 else "cut",
            cl_index=i - 1, X_HT=np.linalg.inv(X_WH) @ X_WF @ X_FT, X_WF=X_WF, q=qi,
            speed=0.15, motion="joint" if i == 0 else "linear",
            p_HC=None if i == 0 else rng.normal(size=3),
            n_H=None if i == 0 else np.array([1.0, 0, 0])))
    traj = JointTrajectory.from_hermite(t=np.array([0.0, 1.0, 2.0]), q=q, qd=np.zeros((3, 6)))
    meta = dict(X_FT=X_FT.tolist(), X_FH=np.eye(4).tolist(), X_WT=np.eye(4).tolist(), windows=[],
                note=np.float64(1.5))
    return Plan(scenario="tool_in_hand", hub="h5_split", mode="tool", X_WH=X_WH,
                targets=tuple(targets),
                segments=(PlanSegment(-1, "home", (0, 1), (0.0, 1.0)),
                          PlanSegment(0, "cut", (1, 3), (1.0, 2.0))),
                trajectory=traj, failures=tuple(failures), meta=meta)


def test_save_load_round_trip(tmp_path):
    rec = FailureRecord(window=0, kind="ik", reason="x", point=3, value=1e-3, limit=2e-3,
                        unit="m", where={"pair": ["a", "b"]}, tried=("seed",))
    plan = _plan(failures=(rec,))
    mut.save_plan(plan, tmp_path / "p")
    back = mut.load_plan(tmp_path / "p")
    np.testing.assert_array_equal(back.trajectory.q, plan.trajectory.q)
    assert back.targets[0].p_HC is None and back.targets[0].motion == "joint"
    np.testing.assert_array_equal(back.targets[2].p_HC, plan.targets[2].p_HC)
    assert [s.t_range for s in back.segments] == [(0.0, 1.0), (1.0, 2.0)]
    assert back.failures == (rec,) and back.failures[0].where == rec.where
    assert back.meta["note"] == 1.5


def test_load_rejects_other_versions(tmp_path):
    import json

    mut.save_plan(_plan(), tmp_path)
    doc = json.loads((tmp_path / "plan.json").read_text())
    doc["version"] = 99
    (tmp_path / "plan.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match="version 99"):
        mut.load_plan(tmp_path)
    with pytest.raises(FileNotFoundError, match="plan.json"):
        mut.load_plan(tmp_path / "nothing")


def test_joint_csv_in_degrees(tmp_path):
    path = mut.write_joint_csv(_plan(), tmp_path / "j.csv")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 1:], np.degrees(_plan().trajectory.q), atol=1e-6)
    assert path.read_text().startswith("t_s,q1_deg")


def test_export_cli_refuses_an_unverified_plan_unless_forced(tmp_path):
    from drakedeburr.cli import main

    mut.save_plan(_plan(failures=(FailureRecord(window=0, kind="ik", reason="x", point=1),)),
                  tmp_path / "p")
    out = tmp_path / "d.mod"
    # no verification report: the gate refuses (the result failed: exit 1), nothing written
    assert main(["export", str(tmp_path / "p"), "--format", "rapid", "-o", str(out)]) == 1
    assert not out.exists()
    args = ["export", str(tmp_path / "p"), "--format", "rapid", "-o", str(out), "--force"]
    assert main(args) == 0
    text = out.read_text()
    assert "UNVERIFIED" in text and "--force" in text
    # the tool data carry the cell's spindle model (3.05 kg), not a default
    assert "PERS tooldata tBurr := [TRUE," in text and "[3.050,[" in text
    # KRL is not a program for the plan's ABB arm
    assert main(["export", str(tmp_path / "p"), "--format", "krl", "-o",
                 str(tmp_path / "d.src"), "--force"]) == 2


def test_tool_path_reference_survives_save_load(tmp_path):
    """A saved plan keeps what verification checks it against: the ToolPath's CL points,
    frames, angles, box and cones (not only the hub's edges)."""
    from dataclasses import replace

    from drakedeburr.config import OrientationBounds
    from drakedeburr.plan.types import ToolPathRecord

    rng = np.random.default_rng(1)
    m = 7
    R = np.linalg.qr(rng.normal(size=(m, 3, 3)))[0]
    tp = ToolPathRecord(window_index=0, kind="large", p_HC=rng.normal(size=(m, 3)), R_HL=R,
                        zT_H=rng.normal(size=(m, 3)), theta_A=rng.uniform(size=m),
                        theta_B=rng.uniform(size=m), cone_zT_H=rng.normal(size=(m, 3)),
                        bounds=OrientationBounds(0.26, 0.44), cone_half_angle=0.08,
                        cone_outer_half_angle=0.124, depth_of_cut=1.5e-3)
    plan = replace(_plan(), tool_path=(tp,))
    mut.save_plan(plan, tmp_path / "p")
    back = mut.load_plan(tmp_path / "p").tool_path[0]
    for name in ("p_HC", "R_HL", "zT_H", "theta_A", "theta_B", "cone_zT_H"):
        np.testing.assert_array_equal(getattr(back, name), getattr(tp, name))
    assert back.bounds == tp.bounds and back.kind == "large" and back.window_index == 0
    assert (back.cone_half_angle, back.cone_outer_half_angle, back.depth_of_cut) == (
        0.08, 0.124, 1.5e-3)
    # a damaged file names what is missing
    import io as _io
    with np.load(tmp_path / "p" / "arrays.npz") as a:
        arr = {k: a[k] for k in a.files if k != "tp0_R_HL"}
    buf = _io.BytesIO()
    np.savez(buf, **arr)
    (tmp_path / "p" / "arrays.npz").write_bytes(buf.getvalue())
    with pytest.raises(InputError, match="window 0 lacks R_HL"):
        mut.load_plan(tmp_path / "p")


def test_the_burr_of_a_plan_survives_save_load_and_builds_its_cell(tmp_path):
    import json

    from drakedeburr.cell.station import load_plan_cell

    plan = _plan()
    plan.meta["tool"] = "long_reach"
    mut.save_plan(plan, tmp_path / "p")
    back = mut.load_plan(tmp_path / "p")
    assert back.meta["tool"] == "long_reach"
    cell = load_plan_cell(back)
    assert cell.tool == "long_reach" and load_plan_cell(_plan()).tool == "standard"
    doc = json.loads((tmp_path / "p" / "plan.json").read_text())
    doc["meta"]["tool"] = "diamond"
    (tmp_path / "p" / "plan.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match="'diamond' is not a known burr"):
        mut.load_plan(tmp_path / "p")
