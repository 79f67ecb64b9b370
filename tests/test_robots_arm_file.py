"""Arms as data (issue 44 item 4): every registry arm is an arm file; a copy loaded by path is
the same arm; a bad field is one clear error naming the file and the field (CLI exit 2)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

import drakedeburr.robots.arms as arms
from drakedeburr.errors import InputError
from drakedeburr.resources import arm_file_path, models_dir
from drakedeburr.robots import arm_file_text, fk_opw, get_robot, load_arm


def _copy(name: str, tmp_path: Path, edit=None) -> Path:
    data = yaml.safe_load(arm_file_path(name).read_text())
    if edit is not None:
        edit(data)
    path = tmp_path / f"my_{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize("name", arms.BUILTIN_ARMS)
def test_every_registry_arm_is_a_shipped_arm_file(name):
    path = arm_file_path(name)
    assert path.parent == models_dir() / "robots"
    spec = arms.ROBOTS[name]
    assert spec.name == name and spec.source_file == "" and spec.ref == name
    keys = {s.split(": ", 1)[0] for s in spec.sources}
    assert {"opw", "joints", "payload"} <= keys  # a citation per group of values
    if spec.wrist_moment_Nm is not None:
        assert "wrist_moment_Nm" in keys
    if spec.wrist_inertia_kgm2 is not None:
        assert "wrist_inertia_kgm2" in keys


@pytest.mark.parametrize("name", arms.BUILTIN_ARMS)
def test_a_copy_loaded_by_path_is_the_same_arm(tmp_path, name):
    ref = arms.ROBOTS[name]
    spec = get_robot(str(_copy(name, tmp_path)))
    assert spec is get_robot(str(tmp_path / f"my_{name}.yaml"))  # one object per file
    assert spec.source_file == str((tmp_path / f"my_{name}.yaml").resolve())
    assert spec.ref == spec.source_file and spec.name == name
    assert spec.opw == ref.opw and spec.model_url == ref.model_url
    for key in ("q_lower", "q_upper", "v_max", "a_max", "X_BR"):
        assert np.array_equal(getattr(spec, key), getattr(ref, key)), key
    assert spec.payload_kg == ref.payload_kg and spec.mounts[0][0] == ref.mounts[0][0] \
        if ref.mounts else True
    q = np.random.default_rng(0).uniform(ref.q_lower, ref.q_upper, (20, 6))
    assert np.array_equal(fk_opw(spec.opw, q), fk_opw(ref.opw, q))


@pytest.mark.parametrize("name", ["irb1600", "m710ic50"])
def test_arm_file_text_round_trips(tmp_path, name):
    """A spec written as an arm file (radians exact) reads back as the same arm."""
    ref = arms.ROBOTS[name]
    path = tmp_path / "dumped.yaml"
    path.write_text(arm_file_text(ref))
    spec = load_arm(path)
    assert spec.opw == ref.opw and spec.sources == ref.sources
    for key in ("q_lower", "q_upper", "v_max", "a_max", "X_BR"):
        assert np.array_equal(getattr(spec, key), getattr(ref, key)), key
    assert spec.wrist_moment_Nm == ref.wrist_moment_Nm
    for (k, m), (k2, m2) in zip(spec.mounts, ref.mounts, strict=True):
        assert k == k2 and np.array_equal(m.q_home, m2.q_home)


def _set(path: str, value):
    def edit(data):
        node = data
        keys = path.split(".")
        for k in keys[:-1]:
            node = node[k]
        if value is _DELETE:
            del node[keys[-1]]
        else:
            node[keys[-1]] = value
    return edit


_DELETE = object()


@pytest.mark.parametrize("field, value, message", [
    ("schema", "drakedeburr.arm/0", r"field schema: expected 'drakedeburr.arm/1'"),
    ("name", "my arm", r"field name: 'my arm' is not an identifier"),
    ("controller", "staubli", r"field controller: 'staubli' is not one of abb, kuka, fanuc"),
    ("vendor", "ABB", r"field vendor: 'ABB' does not make a kuka controller"),
    ("program_language", "rapid", r"field program_language: a kuka controller runs krl"),
    ("opw.c2", -0.78, r"field opw.c2: a link length must be > 0"),
    ("opw.c3", "0.86", r"field opw.c3: expected a finite number, got '0.86'"),
    ("opw.sign_corrections", [-1, 1, 1, -1, 1, 2], r"field opw.sign_corrections: each must be"),
    ("opw.offsets_deg", [0, -90, 0], r"field opw.offsets_deg: expected a list of 6 finite"),
    ("joints.lower_deg", _DELETE, r"field joints.lower: give exactly one of lower_deg or"),
    ("joints.upper_deg", [185, -200, 175, 350, 130, 350],
     r"field joints: joint 2: lower limit .* is not below the upper"),
    ("joints.speed_deg_s", [200, 175, 0, 430, 430, 630],
     r"field joints.speed_deg_s: every value must be > 0"),
    ("payload.mass_kg", 0, r"field payload.mass_kg: must be > 0"),
    ("payload.wrist_moment_Nm", [1, 2], r"field payload.wrist_moment_Nm: expected a list of 3"),
    ("payload.wrist_inertia_kgm2", [1.0, 1.0, 0.5], r"field sources.wrist_inertia_kgm2: missing"),
    ("sources.payload", _DELETE, r"field sources.payload: missing"),
    ("model", "missing.sdf", r"field model: no model file .*missing.sdf"),
    ("j23_coupling", 0.5, r"field j23_coupling: expected 0 \(ABB, KUKA\) or 1 \(FANUC\)"),
    ("robot_frame_m", [0, 0], r"field robot_frame_m: expected a list of 3"),
    ("colour", "orange", r"field colour: unknown key"),
])
def test_a_bad_field_is_one_error_naming_file_and_field(tmp_path, field, value, message):
    path = _copy("kr20_r1810", tmp_path, _set(field, value))
    with pytest.raises(InputError, match=message) as err:
        load_arm(path)
    assert str(err.value).startswith(f"{path.resolve()}: field ")
    assert "\n" not in str(err.value)


def test_unreadable_and_missing_arm_files(tmp_path):
    with pytest.raises(InputError, match=r"nope.yaml: no such arm file"):
        get_robot(str(tmp_path / "nope.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("schema: [\n")
    with pytest.raises(InputError, match=r"bad.yaml: not a YAML arm file \(line"):
        load_arm(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(InputError, match=r"an arm file is a YAML mapping"):
        load_arm(bad)


def test_a_model_path_relative_to_the_arm_file(tmp_path):
    """A user's arm brings its own model next to its file."""
    shutil.copy(models_dir() / "robots" / "m20ia.sdf", tmp_path / "cell_m20ia.sdf")
    path = _copy("m20ia", tmp_path, _set("model", "cell_m20ia.sdf"))
    spec = load_arm(path)
    assert spec.model_url == (tmp_path / "cell_m20ia.sdf").resolve().as_uri()


def test_cli_robot_file_bad_field_exits_2_with_one_line(tmp_path, capsys):
    from drakedeburr.cli import main

    path = _copy("kr20_r1810", tmp_path, _set("payload.mass_kg", -3))
    out = tmp_path / "p"
    code = main(["plan", "workpiece_in_hand", "--robot", str(path), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert f"{path.resolve()}: field payload.mass_kg: must be > 0" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_an_arm_file_plans_verifies_and_exports_like_the_builtin_arm(tmp_path):
    """A copy of kr6_r700.yaml loaded by path: window 0 of h5_straight, tool in hand. The plan
    is the built-in arm's (every array, every meta value but the arm's name: the file's path);
    it verifies (exit 0, the plan names its arm file) and exports the same program."""
    from drakedeburr.cli import main
    from drakedeburr.programs import read_program

    arm = tmp_path / "cell_kr6.yaml"
    shutil.copy(arm_file_path("kr6_r700"), arm)
    folders = {}
    for key, robot in (("file", str(arm)), ("name", "kr6_r700")):
        folders[key] = tmp_path / f"plan_{key}"
        assert main(["-q", "plan", "tool_in_hand", "--hub", "h5_straight", "--windows", "0",
                     "--robot", robot, "-o", str(folders[key])]) == 0
    a, b = (np.load(folders[k] / "arrays.npz") for k in ("file", "name"))
    assert a.files == b.files
    for k in a.files:
        assert np.array_equal(a[k], b[k], equal_nan=True), k
    import json

    ja, jb = (json.loads((folders[k] / "plan.json").read_text()) for k in ("file", "name"))
    assert ja["meta"].pop("robot") == str(arm.resolve()) and jb["meta"].pop("robot") == "kr6_r700"
    ja["meta"]["config"].pop("robot")
    jb["meta"]["config"].pop("robot")
    assert ja == jb
    assert main(["-q", "verify", str(folders["file"]), "--windows", "0", "--no-replay"]) == 0
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    out_file, out_name = tmp_path / "a" / "deburr.src", tmp_path / "b" / "deburr.src"
    assert main(["-q", "export", str(folders["file"]), "-o", str(out_file)]) == 0
    assert main(["-q", "export", str(folders["name"]), "-o", str(out_name), "--force"]) == 0
    # the same program: every statement (KRL comments after ';' carry the flag and the plan's
    # path: the forced export of the built-in plan says FORCED)
    for suffix in (".src", ".dat"):
        texts = [[st for ln in p.with_suffix(suffix).read_text().splitlines()
                  if (st := ln.split(";")[0].rstrip())] for p in (out_name, out_file)]
        assert texts[0] == texts[1], suffix
    assert read_program(out_file).moves and "FORCED" not in out_file.read_text()


def test_post_with_a_renamed_fanuc_arm_file_writes_the_builtins_program(tmp_path, extdata):
    """post --robot FILE: a renamed copy of m20ia.yaml writes the LS program of --robot m20ia
    (positions in the FANUC world frame 0.525 m above the foot, CONFIG, speeds): the program
    finds the file's robot frame, not an identity."""
    from drakedeburr.cli import main

    cl = str(extdata / "cl_files" / "CreoPost__profilfraesen_2.ncl.2")
    arm = _copy("m20ia", tmp_path, _set("name", "cell3_m20ia"))
    common = ["--wobj", "900,0,200,0,0,0", "--spin", "greedy"]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    a, b = tmp_path / "a" / "prog.ls", tmp_path / "b" / "prog.ls"
    assert main(["-q", "post", cl, "--robot", "m20ia", "-o", str(a), *common]) == 0
    assert main(["-q", "post", cl, "--robot", str(arm), "-o", str(b), *common]) == 0
    body = [ln for ln in a.read_text().splitlines() if "m20ia" not in ln.lower()]
    assert body == [ln for ln in b.read_text().splitlines() if "m20ia" not in ln.lower()]
    assert "P[1]" in a.read_text()
