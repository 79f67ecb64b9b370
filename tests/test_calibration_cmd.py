"""``drakedeburr calibrate`` on a simulated cell with known frame errors (source 002).

The simulated cell: the IRB1600 of the tool-in-hand scenario, its work table (the chuck top,
weld ``fixture::chuck_top``) 2.5 / -1.8 / 1.2 mm and (0.3, -0.2, 0.8) deg off its design pose,
the calibration tip 0.8 / -0.6 / +1.5 mm off the tool set on the controller. Every touch is
simulated by the arm's forward kinematics: the tip (true TCP) put on the true feature point
(plus 0.02 mm touch noise) by the analytic IK, the pose the controller reports = FK(q) times
the tool it has set. The fitted frames are checked against the truth, the written scenario
through Drake's own frame poses, the written program by a parser written here and FK.
"""

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from drakedeburr.cli import main
from drakedeburr.post.calibration import extrapolation_error, fit_pivot_tcp, fit_touch_points
from drakedeburr.robots import fk_opw, get_robot, ik_opw

SIGMA = 0.02e-3  # touch noise [m]
TOOL_SET = np.array([0.0, 0, 200, 0, 0, 0])  # mm, deg: the tool set on the controller
TIP_TRUE = np.array([0.8, -0.6, 201.5]) * 1e-3  # the real tip in the flange [m]
X_TABLE_NOMINAL = np.eye(4)
X_TABLE_NOMINAL[:3, 3] = [0.75, 0.0, -0.46]  # models/scenarios/tool_in_hand.yaml


def _X(xyz, rpy_deg):
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("xyz", rpy_deg, degrees=True).as_matrix()
    X[:3, 3] = xyz
    return X


X_TABLE_TRUE = X_TABLE_NOMINAL @ _X(np.array([2.5, -1.8, 1.2]) * 1e-3, [0.3, -0.2, 0.8])


def _mm_deg(X):
    rz, ry, rx = Rotation.from_matrix(X[:3, :3]).as_euler("ZYX", degrees=True)
    return [float(v) for v in (*(X[:3, 3] * 1e3), rx, ry, rz)]


def _touch(spec, p_B, R_BT, rng):
    """The pose the controller reports when the real tip touches p_B with the tool axis
    orientation R_BT: IK for the flange, FK back, times the tool it has set."""
    X_BF = np.eye(4)
    X_BF[:3, :3] = R_BT
    X_BF[:3, 3] = p_B + rng.normal(0, SIGMA, 3) - R_BT @ TIP_TRUE
    sols = ik_opw(spec.kinematics.opw, X_BF[None])
    ok = np.flatnonzero(sols.valid[0] & spec.kinematics.limits.contains(sols.q[0]))
    assert ok.size, p_B
    q = sols.q[0, ok[0]]
    from drakedeburr.post.cl_post import pose_from_mm_deg

    X_report = np.linalg.inv(spec.X_BR) @ fk_opw(spec.kinematics.opw, q) @ pose_from_mm_deg(
        TOOL_SET)
    return _mm_deg(X_report)


def _down(tilt_deg=0.0, about=0.0):
    """Tool axis pointing down, tilted by tilt_deg in the direction ``about`` [deg]."""
    return (Rotation.from_euler("z", about, degrees=True)
            * Rotation.from_euler("y", tilt_deg, degrees=True)
            * Rotation.from_euler("x", 180, degrees=True)).as_matrix()


FEATURES = np.array([[-100, -140, 0], [100, -140, 0], [100, 140, 0], [-100, 140, 0],
                     [0, 0, 0], [60, -40, 30], [-60, 70, 30], [0, 150, 0]], float)  # mm


def _touch_file(path, spec, part=None, rng_seed=0):
    rng = np.random.default_rng(rng_seed)
    pivot_B = np.array([0.70, 0.20, -0.20])
    tcp = [_touch(spec, pivot_B, _down(t, a), rng)
           for t, a in ((0, 0), (25, 0), (25, 90), (25, 180), (25, 270), (35, 45))]
    points = []
    for i, f in enumerate(FEATURES):
        p = X_TABLE_TRUE[:3, :3] @ (f * 1e-3) + X_TABLE_TRUE[:3, 3]
        points.append({"feature": f.tolist(), "pose": _touch(spec, p, _down(8, 45 * i), rng)})
    doc = {"robot": spec.name, "tool": TOOL_SET.tolist(), "tcp": tcp,
           "table": {"points": points}}
    if part is not None:
        doc["table"]["part"] = part
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.fixture(scope="module", params=["irb1600", "m10ia"])
def calibrated(tmp_path_factory, request):
    """The same cell calibrated with the IRB1600 (RAPID) and the M-10iA (LS; its controller's
    robot frame is 0.45 m above the model's base, so the reported poses are in that frame)."""
    d = tmp_path_factory.mktemp("cal")
    spec = get_robot(request.param)
    touches = _touch_file(d / "touches.yaml", spec, part=[[-90, -130, 0], [90, 130, 0]])
    ext = ".mod" if spec.controller == "abb" else ".ls"
    out = {k: d / n for k, n in (("report", "rep.yaml"), ("scenario", "cell.yaml"),
                                  ("program", "check" + ext))}
    rc = main(["calibrate", str(touches), "--report", str(out["report"]),
               "--scenario", "tool_in_hand", "--scenario-out", str(out["scenario"]),
               "--program", str(out["program"])])
    return rc, out, spec


def test_calibrate_recovers_the_known_frame_errors_within_the_noise(calibrated):
    rc, out, _ = calibrated
    assert rc == 0
    rep = yaml.safe_load(out["report"].read_text())
    assert rep["ok"]
    tool = np.array(rep["tcp"]["tool_mm_deg"])
    assert np.linalg.norm(tool[:3] * 1e-3 - TIP_TRUE) < 3 * SIGMA  # 0.8 / 0.6 / 1.5 mm off
    assert np.allclose(tool[3:], 0, atol=1e-6)  # the pivot cannot see the tool's orientation
    from drakedeburr.post.cl_post import pose_from_mm_deg

    X = pose_from_mm_deg(rep["table"]["frame_mm_deg"])
    f = FEATURES * 1e-3
    err = np.linalg.norm(f @ (X[:3, :3] - X_TABLE_TRUE[:3, :3]).T + X[:3, 3]
                         - X_TABLE_TRUE[:3, 3], axis=1)
    assert err.max() < 3 * SIGMA  # the table placed within the noise at every feature
    assert rep["table"]["rms_mm"] < 2 * SIGMA * 1e3


def test_calibrated_scenario_places_the_table_where_it_is(calibrated):
    """Drake's own frame pose of the written scenario's chuck top (and so the hub mount)."""
    from drakedeburr.cell import load_cell

    _, out, _ = calibrated
    cell = load_cell(out["scenario"])
    ctx = cell.plant.CreateDefaultContext()
    frame = cell.plant.GetFrameByName("chuck_top")
    X = frame.CalcPoseInWorld(ctx).GetAsMatrix4()
    f = FEATURES * 1e-3
    err = np.linalg.norm(f @ (X[:3, :3] - X_TABLE_TRUE[:3, :3]).T + X[:3, 3]
                         - X_TABLE_TRUE[:3, 3], axis=1)
    assert err.max() < 3 * SIGMA


def test_check_program_puts_the_real_tip_on_the_nominal_points(calibrated):
    """Parse the RAPID / LS program (parsers of tests/test_virtual_tcp_program.py, not ours),
    compose wobj * target * tool^-1 = the flange the controller commands, joints by the
    analytic IK, FK with the REAL tip: on the true feature within 0.1 mm."""
    from test_virtual_tcp_program import _parse_ls, _parse_rapid

    _, out, spec = calibrated
    parse = _parse_rapid if spec.controller == "abb" else _parse_ls
    text = out["program"].read_text()
    if spec.controller == "abb":
        from test_programs_formats import rapidcheck  # third-party RAPID grammar checker

        assert rapidcheck(text) == []
    X_FT, X_RU, targets = parse(text)
    assert len(targets) == 3 * len(FEATURES)
    errs = []
    for i, X_UT in enumerate(targets[1::3]):  # the linear move onto each feature
        X_BF = spec.X_BR @ X_RU @ X_UT @ np.linalg.inv(X_FT)
        sols = ik_opw(spec.kinematics.opw, X_BF[None])
        q = sols.q[0, np.flatnonzero(sols.valid[0])[0]]
        X = fk_opw(spec.kinematics.opw, q)
        tip = X[:3, :3] @ TIP_TRUE + X[:3, 3]
        truth = X_TABLE_TRUE[:3, :3] @ (FEATURES[i] * 1e-3) + X_TABLE_TRUE[:3, 3]
        errs.append(np.linalg.norm(tip - truth))
    assert max(errs) < 0.1e-3, max(errs)


def test_part_outside_the_touched_region_is_warned_and_quantified():
    """A robot with a systematic error growing with distance (scale 1.0009: ~0.09 mm per
    100 mm) touched over +-100 mm: a part point 350 mm outside is predicted off by about what
    the fit really leaves there."""
    rng = np.random.default_rng(5)
    X = _X([0.8, -0.1, 0.3], [0.5, -0.4, 20])
    p_T = np.column_stack([rng.uniform(-0.1, 0.1, 8), rng.uniform(-0.1, 0.1, 8),
                           np.zeros(8)])
    s = 1.0009
    reach = lambda p: s * p @ X[:3, :3].T + X[:3, 3]  # noqa: E731 (where the robot goes)
    fit = fit_touch_points(p_T, reach(p_T) + rng.normal(0, SIGMA, p_T.shape))
    far = np.array([[0.45, 0.0, 0.0], [0.0, -0.45, 0.0]])  # ~350 mm outside
    actual = np.linalg.norm(far @ fit.X_WT[:3, :3].T + fit.X_WT[:3, 3] - reach(far), axis=1)
    predicted = extrapolation_error(fit, far)
    assert actual.min() > 0.3e-3  # the 0.30-0.35 mm
    assert np.all(np.abs(predicted - actual) < 0.3 * actual)


def test_calibrate_warns_and_fails_on_a_far_part(tmp_path, caplog):
    """A part point 500 mm beyond the touches: warned with its predicted error (noise-only
    cell: ~0.07 mm); over --max-error the result fails (exit 1): report, no scenario."""
    spec = get_robot("irb1600")
    touches = _touch_file(tmp_path / "t.yaml", spec, part=[[600, 0, 0]])
    rep = tmp_path / "rep.yaml"
    args = ["calibrate", str(touches), "--report", str(rep),
            "--scenario", "tool_in_hand", "--scenario-out", str(tmp_path / "s.yaml")]
    assert main(args) == 0 and "outside the touched region" in caplog.text
    doc = yaml.safe_load(rep.read_text())
    assert doc["table"]["part_outside_mm"] == pytest.approx(500, abs=0.5)
    predicted = doc["table"]["part_predicted_error_mm"]
    assert 0.02 < predicted < 0.1
    (tmp_path / "s.yaml").unlink()
    assert main(args + ["--max-error", f"{predicted / 2}"]) == 1
    assert not (tmp_path / "s.yaml").exists() and not yaml.safe_load(rep.read_text())["ok"]


def test_pivot_refuses_too_little_tilt():
    from drakedeburr.errors import InputError

    X = np.tile(np.eye(4), (5, 1, 1))
    X[:, :3, 3] = np.arange(15).reshape(5, 3) * 1e-3
    with pytest.raises(InputError, match="tilt the tool"):
        fit_pivot_tcp(X)


@pytest.mark.parametrize("text, match", [
    ("target,fx,fy,fz,x,y,z,rx,ry,rz\ntable,0,0,0,1,2,3,4,5\n", r"t\.csv:2: expected 10"),
    ("target,fx,fy,fz,x,y,z,rx,ry,rz\nbench,0,0,0,1,2,3,4,5,6\n", r"t\.csv:2: target 'bench'"),
    ("target,fx,fy,fz,x,y,z,rx,ry,rz\ntable,0,0,x,1,2,3,4,5,6\n", r"t\.csv:2: feature"),
    ("x,y\n", r"t\.csv:1: expected the header"),
])
def test_calibrate_bad_input_is_one_line_exit_2(tmp_path, capsys, text, match):
    import re

    f = tmp_path / "t.csv"
    f.write_text(text)
    assert main(["calibrate", str(f), "--tool", "0,0,200,0,0,0"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(match, err), err


def test_holder_calibration_moves_the_spindle_stand(tmp_path):
    """The tool holder of the workpiece-in-hand cell (weld ``stand::stand``, design pose
    (0.90, 0, -0.80)) 1.5 mm / 0.4 deg off: features touched round the spindle nose (1.2 m up
    the stand); the written scenario's tool_tip, by Drake, is where the real one is."""
    from drakedeburr.cell import load_cell

    X_nom = np.eye(4)
    X_nom[:3, 3] = [0.9, 0.0, -0.8]
    X_true = X_nom @ _X(np.array([1.5, 0.8, -0.6]) * 1e-3, [0.2, -0.3, 0.4])
    feats = np.array([[-60, -60, 1150], [60, -60, 1150], [60, 60, 1150], [-60, 60, 1150],
                      [0, -80, 1100], [0, 0, 1200]], float)
    rng = np.random.default_rng(11)
    spec = get_robot("irb1600")
    points = [{"feature": f.tolist(),
               "pose": _touch(spec, X_true[:3, :3] @ (f * 1e-3) + X_true[:3, 3],
                              _down(10, 60 * i), rng)} for i, f in enumerate(feats)]
    touches = tmp_path / "holder.yaml"
    tcp = [_touch(spec, np.array([0.70, 0.20, -0.20]), _down(t, a), rng)
           for t, a in ((0, 0), (25, 0), (25, 120), (25, 240), (35, 60))]
    touches.write_text(yaml.safe_dump({"tool": TOOL_SET.tolist(), "tcp": tcp,
                                       "holder": {"points": points}}))
    out = tmp_path / "wih.yaml"
    assert main(["calibrate", str(touches), "--scenario", "workpiece_in_hand",
                 "--scenario-out", str(out)]) == 0
    cell = load_cell(out)
    X = cell.plant.GetFrameByName("tool_tip").CalcPoseInWorld(
        cell.plant.CreateDefaultContext()).GetAsMatrix4()
    tip_true = X_true @ np.array([0, 0, 1.2 + 0.048, 1.0])  # spindle_stand.sdf tool_tip
    assert np.linalg.norm(X[:3, 3] - tip_true[:3]) < 3 * SIGMA


def test_csv_touch_file_gives_the_same_frames(tmp_path):
    spec = get_robot("irb1600")
    doc = yaml.safe_load(_touch_file(tmp_path / "t.yaml", spec).read_text())
    rows = ["target,fx,fy,fz,x,y,z,rx,ry,rz", "# the pivot, then the table"]
    rows += ["tcp,,,," + ",".join(map(str, p)) for p in doc["tcp"]]
    rows += ["table," + ",".join(map(str, t["feature"] + t["pose"]))
             for t in doc["table"]["points"]]
    (tmp_path / "t.csv").write_text("\n".join(rows) + "\n")
    reps = []
    for name, extra in (("t.yaml", []), ("t.csv", ["--tool", "0,0,200,0,0,0"])):
        rep = tmp_path / f"{name}.rep"
        assert main(["calibrate", str(tmp_path / name), "--report", str(rep)] + extra) == 0
        reps.append(yaml.safe_load(rep.read_text()))
    assert reps[0]["tcp"] == reps[1]["tcp"] and reps[0]["table"] == reps[1]["table"]


# ----------------------------------------------------------- calibration_io read directly
def test_read_touches_csv_refuses_bad_rows_naming_file_and_line(tmp_path):
    from drakedeburr.errors import InputError
    from drakedeburr.post.calibration_io import read_touches

    header = "target,fx,fy,fz,x,y,z,rx,ry,rz\n"
    bad = {"x.csv": ("target,x\n", ":1: expected the header"),
           "y.csv": (header + "table,0,0,0,1,2,3,0,0\n", ":2: expected 10 columns"),
           "z.csv": (header + "# c\nfloor,0,0,0,1,2,3,0,0,0\n", ":3: target 'floor'"),
           "e.csv": (header, "no touches")}
    for name, (text, why) in bad.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(InputError, match=why) as e:
            read_touches(tmp_path / name)
        assert str(tmp_path / name) in str(e.value)
    with pytest.raises(InputError, match="touch file not found"):
        read_touches(tmp_path / "missing.yaml")


def test_calibrate_command_refuses_a_missing_touch_file_in_one_line(tmp_path, capsys):
    """post.calibrate_cmd (the `calibrate` subcommand): bad input is exit 2, one line."""
    from drakedeburr.post import calibrate_cmd

    assert callable(calibrate_cmd.register)
    assert main(["calibrate", str(tmp_path / "none.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "none.csv" in err[0] and "Traceback" not in err[0]
    assert not any(tmp_path.iterdir())


def test_calibrate_takes_an_arm_file_like_the_other_commands(tmp_path):
    """`calibrate --robot FILE`: a copy of the M-10iA's arm file (whose controller frame is
    0.45 m above the model base) gives the same fit as the registered name, and the fit is
    the true one (it would be 0.45 m off if the file's base frame were ignored)."""
    import shutil

    from drakedeburr.post.cl_post import pose_from_mm_deg

    spec = get_robot("m10ia")
    touches = _touch_file(tmp_path / "touches.yaml", spec)
    root = Path(__file__).resolve().parents[1]
    arm = shutil.copy(root / "models" / "robots" / "m10ia.yaml", tmp_path / "my_arm.yaml")
    reps = []
    for robot in ("m10ia", str(arm)):
        rep = tmp_path / f"rep_{len(reps)}.yaml"
        assert main(["calibrate", str(touches), "--robot", robot, "--report", str(rep)]) == 0
        reps.append(yaml.safe_load(rep.read_text()))
    assert reps[0]["tcp"] == reps[1]["tcp"]
    assert reps[0]["table"]["frame_mm_deg"] == reps[1]["table"]["frame_mm_deg"]
    X = pose_from_mm_deg(reps[1]["table"]["frame_mm_deg"])
    f = FEATURES * 1e-3
    err = np.linalg.norm(f @ (X[:3, :3] - X_TABLE_TRUE[:3, :3]).T + X[:3, 3]
                         - X_TABLE_TRUE[:3, 3], axis=1)
    assert err.max() < 3 * SIGMA
    assert main(["calibrate", str(touches), "--robot", str(tmp_path / "none.yaml")]) == 2
