"""The strict readers on programs nobody on the team wrote (extdata/robot_programs): the FANUC
motion programs parse completely; the ABB and KUKA samples are control programs (loops,
interrupts, user routines), refused at the first such line with the reason."""

import numpy as np
import pytest

import drakedeburr.programs as mut


@pytest.fixture(scope="module")
def samples(extdata):
    return extdata / "robot_programs"


@pytest.mark.parametrize("name, n_moves, config", [
    ("crs_application_sizen__surface.ls", None, "F U T, 0, 0, 0"),
    ("crs_application_sizen__surface_cartesian.ls", None, "N U T, 0, 0, 0"),
])
def test_fanuc_samples_parse_completely(samples, name, n_moves, config):
    path = samples / "fanuc" / name
    prog = mut.read_ls(path, check_name=False)
    text = path.read_text()
    assert len(prog.moves) == text.count("P[") - text.count("\nP[")  # one move per /MN P[n]
    assert len(prog.moves) > 10
    first = prog.moves[0]
    assert first.move_type == "joint" and first.joint_percent == 100
    lin = [m for m in prog.moves if m.move_type == "linear"]
    assert {m.speed for m in lin} == {0.2}  # 200mm/sec
    assert {round(m.zone, 6) for m in prog.moves} == {0.006}  # CNT60, nominal 6 mm
    options = {"crs_application_sizen__surface.ls": ("Tool_Offset,PR[15]",)}.get(name, ())
    assert all(m.options == options for m in prog.moves)
    assert first.configuration == config
    assert prog.X_FT is None and prog.X_RO is None  # UTOOL 1 / UFRAME 0 values not in the file
    # positions in mm -> m; the first /POS entry of the file
    assert np.all(np.abs(first.X_OT[:3, 3]) < 2.0) and np.abs(first.X_OT[:3, 3]).max() > 0.4
    # the program's name is not the file's (the file was renamed when collected)
    with pytest.raises(mut.ProgramFormatError, match="/PROG name 'surface"):
        mut.read_ls(path)


def test_abb_sample_is_refused_at_its_first_control_statement(samples):
    path = samples / "abb" / "ros-industrial_abb__ROS_motion.mod"
    with pytest.raises(mut.ProgramFormatError) as err:
        mut.read_program(path)
    msg = str(err.value)
    # LOCAL VAR ROS_joint_trajectory_pt trajectory{MAX_TRAJ_LENGTH}: a user record type
    assert f"{path}:32:" in msg and "'ROS_joint_trajectory_pt' is outside the motion subset" in msg


def test_kuka_dat_parses_and_src_is_refused_at_its_first_user_assignment(samples):
    dat = samples / "kuka" / "kuka_experimental__ros_krlptp.dat"
    name, decls = mut.read_krl_dat(dat)
    assert name == "ROS_KRLPTP"
    assert decls["MOVETIME"] == ("REAL", 0.2, 6)
    dtype, axis, _ = decls["NEXTMOVE"]
    assert dtype == "E6AXIS" and axis["A1"] == pytest.approx(-156.919830)
    assert decls["ROS_PDAT"][0] == "PDAT" and decls["ROS_PDAT"][1]["APO_DIST"] == 20.0
    src = dat.with_suffix(".src")
    with pytest.raises(mut.ProgramFormatError, match=rf"{src}:48: assignment to "
                                                     r"'ROS_joint_pos_tgt' is outside"):
        mut.read_program(src)


def test_kuka_rsi_sample_is_refused_with_its_line(samples):
    src = samples / "kuka" / "kuka_experimental__KR_C4_ros_rsi.src"
    with pytest.raises(mut.ProgramFormatError) as err:
        mut.read_program(src)
    assert f"{src}:" in str(err.value) and "outside the motion subset" in str(err.value)
