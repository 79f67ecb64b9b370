"""Issue 21: every bad input gets one clear line and its exit code, and nothing is lost.

One table of bad inputs across the commands (:data:`CASES`): each runs ``drakedeburr`` in a
copy of a small workspace (a reference plan, broken copies of it, a hub with a bad recipe, a
mesh with a NaN vertex, files and folders in the way) and asserts the exit code, that stderr
is one line naming the file or argument and what is wrong, that there is no traceback, and
that the workspace is byte for byte what it was. Then interruptions (Ctrl-C, SIGTERM, a full
disk) and leftovers of killed runs, and the umask. The readers are fuzzed in test_bad_input_fuzz.py.

The contract (drakedeburr/cli.py): 0 done/passed, 1 the result failed (a report says why), 2 bad
input or usage, 130 interrupted; no traceback without -vv.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import verify_support as vs

from drakedeburr.cli import main

REPO = Path(__file__).resolve().parent.parent


# --------------------------------------------------------------------------- the workspace

def _write_npz(path: Path, arrays: dict) -> None:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())


def _broken_plans(root: Path, good: Path) -> None:
    """Copies of the good plan folder, each broken in one item."""
    arrays = dict(np.load(good / "arrays.npz"))
    doc = json.loads((good / "plan.json").read_text())

    def copy(name: str) -> Path:
        shutil.copytree(good, root / name)
        return root / name

    (copy("plan_list") / "plan.json").write_text("[1, 2, 3]\n")
    (copy("plan_badjson") / "plan.json").write_text(json.dumps(doc)[:500])
    npz = (good / "arrays.npz").read_bytes()
    (copy("plan_trunc") / "arrays.npz").write_bytes(npz[: len(npz) // 3])
    (copy("plan_nonpz") / "arrays.npz").unlink()
    for name, change in (
            ("plan_shape", lambda a: a.update(q_targets=a["q_targets"][:, :5])),
            ("plan_nan", lambda a: a["q_targets"].__setitem__((3, 2), np.nan)),
            ("plan_missing", lambda a: a.pop("X_WF"))):
        a = {k: v.copy() for k, v in arrays.items()}
        change(a)
        _write_npz(copy(name) / "arrays.npz", a)
    bad = json.loads(json.dumps(doc))
    bad["targets"][3]["speed"] = "fast"
    (copy("plan_badtarget") / "plan.json").write_text(json.dumps(bad))
    for name, change in (  # issue 43: numbers that overflowed or asked for petabytes
            ("plan_bigindex", lambda d: d["targets"][3].__setitem__("cl_index", 10**20)),
            ("plan_longtime", lambda d: d["segments"][1].__setitem__("t_range", [0.0, 1e12]))):
        bad = json.loads(json.dumps(doc))
        change(bad)
        (copy(name) / "plan.json").write_text(json.dumps(bad))
    a = {k: v.copy() for k, v in arrays.items()}
    a["t"] = a["t"] * 1e10  # a trajectory of 1e11 s
    _write_npz(copy("plan_longtraj") / "arrays.npz", a)
    bad = json.loads(json.dumps(doc))
    bad["segments"][1]["target_range"] = [0, 10**6]
    (copy("plan_badsegment") / "plan.json").write_text(json.dumps(bad))
    report = {"passed": True, "plan": {"identity": [1]}, "settings": {"tolerances": {}},
              "summary": {"failed": []}}
    (copy("plan_badreport") / "report.json").write_text(json.dumps(report))
    (copy("plan_cutreport") / "report.json").write_text('{"passed": tr')


def _files(root: Path) -> None:
    import trimesh

    (root / "afile").write_text("a file where a folder is needed\n")
    (root / "adir").mkdir()
    (root / "userdir").mkdir()
    (root / "userdir" / "keep.txt").write_text("the user's own folder\n")
    m = trimesh.creation.annulus(r_min=0.1, r_max=0.2, height=0.05)
    v = np.array(m.vertices)
    v[3] = np.nan
    (root / "nan.stl").write_bytes(trimesh.Trimesh(v, m.faces, process=False)
                                   .export(file_type="stl"))
    (root / "garbage.stl").write_bytes(bytes(range(256)) * 2)
    (root / "nan.obj").write_text("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n")
    (root / "badidx.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    (root / "adir.stl").mkdir()
    (root / "bin.mod").write_bytes(b"MODULE x\n\x00\xff\xfe\nENDMODULE\n")
    (root / "bad.mod").write_text("MODULE x\nENDMODULE garbage\n")
    (root / "c.ls").write_text("a program written before\n")
    (root / "x.mod").write_text("a program written before\n")
    (root / "garbage.yaml").write_text(": : [\n")
    (root / "small.cl").write_text("TOOL PATH/P1\nGOTO/800,0,600,0,0,1\nGOTO/810,0,600,0,0,1"
                                   "\nEND-OF-PATH\n")
    hub = REPO / "models" / "hubs" / vs.HUB
    for name, recipe in (("hub_negspeed", "grinding_speed: -1\n"),
                         ("hub_listrecipe", "[1, 2]\n"),
                         ("hub_badkey", "grinding_sped: 0.1\n"), *HOSTILE_RECIPES.items()):
        (root / name).mkdir()
        for f in hub.iterdir():  # the bundled hub's files, its own recipe
            if f.name != "process.yaml":
                (root / name / f.name).symlink_to(f)
        data = recipe if isinstance(recipe, bytes) else recipe.encode()
        (root / name / "process.yaml").write_bytes(data)
    _hostile_files(root)


def _yaml_bomb(levels: int = 9, width: int = 9) -> str:
    """Nested aliases: ``width ** levels`` nodes once expanded (a "billion laughs")."""
    rows = [f"a0: &a0 [{', '.join(['lol'] * width)}]"]
    for i in range(1, levels):
        rows.append(f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]")
    return "\n".join(rows) + "\n"


#: process.yaml files a careless or hostile user may hand in (issue 43)
HOSTILE_RECIPES = {
    "hub_boolspeed": "grinding_speed: true\n",
    "hub_mmspeed": "grinding_speed: 150\n",  # mm/s where the recipe is SI (m/s)
    "hub_negair": "spindle_air_pressure: -0.2e6\n",
    "hub_nanaccept": "acceptance: {theta_box_share: .nan}\n",
    "hub_highband": "acceptance: {speed_band_fraction: high}\n",
    "hub_dupkey": "grinding_speed: 0.1\napproach_speed: 0.05\ngrinding_speed: 0.2\n",
    "hub_latin1": "# r\xe9glage de l'atelier\ngrinding_speed: 0.1\n".encode("latin-1"),
    "hub_utf16": "grinding_speed: 0.1\n".encode("utf-16"),
    "hub_bomb": "acceptance: {}\n" + _yaml_bomb(),
    "hub_deep": "w1: " + "[" * 5000 + "]" * 5000 + "\n",
    "hub_huge": "# " + "x" * (2 << 20) + "\n",  # over the 1 MiB recipe limit
    "hub_strbounds": "bounds_small: {theta_min: '0.1', theta_max: 0.2}\n",
    "hub_chamfer": "chamfer_width_min: 1.5e-3\nchamfer_width_max: 0.5e-3\n",
    "hub_python": "grinding_speed: !!python/object/apply:os.system ['touch pwned']\n",
}


def _hostile_files(root: Path) -> None:
    """Devices, pipes and names with path characters where files are expected."""
    for name in ("zero.stl", "zero.cl", "zero.mod", "zero.obj"):
        (root / name).symlink_to("/dev/zero")
    os.mkfifo(root / "fifo.stl")
    spec = (REPO / "models" / "hubs" / vs.HUB / "hub.yaml").read_text()
    for name, hub_name in (("spec_dotdot.yaml", '".."'), ("spec_newline.yaml", '"a\\nb"'),
                           ("spec_shell.yaml", '"x;rm -rf ~"'), ("spec_slash.yaml", "a/b"),
                           ("spec_dot.yaml", '"."'), ("spec_hidden.yaml", ".hub")):
        (root / name).write_text(spec.replace(f"name: {vs.HUB}", f"name: {hub_name}"))
    (root / "spec_dup.yaml").write_text(spec + "spoke_count: 7\n")
    # every triangle collinear (was LinAlgError in cl, hub import and verify)
    (root / "collinear.obj").write_text("".join(f"v {0.1 * i} 0 0\n" for i in range(5))
                                        + "f 1 2 3\nf 2 3 4\nf 3 4 5\nf 1 3 5\n")
    (root / "up" / vs.HUB).mkdir(parents=True)  # a user's folder where a hub would go
    (root / "up" / vs.HUB / "hub.yaml").write_text("the user's own file\n")
    (root / "huge.csv").write_text("0,0\n1e308,0\n0,1\n")  # was OverflowError
    (root / "bomb_cell.yaml").write_text(_yaml_bomb())  # a scenario of nested aliases
    (root / "o").mkdir()
    (root / "o" / "hub.yaml").write_text("the user's own file\n")


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """The workspace every case starts from (built once)."""
    from drakedeburr.plan.io import save_plan

    root = tmp_path_factory.mktemp("bad_input_base")
    save_plan(vs.good_plan(), root / "plan")
    _broken_plans(root, root / "plan")
    _files(root)
    return root


@pytest.fixture
def ws(base, tmp_path, monkeypatch) -> Path:
    """A fresh copy of the workspace, the working directory of the case."""
    root = tmp_path / "ws"
    # hard links: every output is written to a new file and renamed (the tree hash catches
    # any write in place)
    shutil.copytree(base, root, symlinks=True, copy_function=os.link)
    monkeypatch.chdir(root)
    return root


def tree(root: Path) -> dict[str, str]:
    """Every file, folder and link under ``root`` (hidden ones too) -> its content hash."""
    out = {}
    for dirpath, dirs, files in os.walk(root):
        for name in dirs + files:
            p = Path(dirpath) / name
            rel = str(p.relative_to(root))
            if p.is_symlink():
                out[rel] = f"link {os.readlink(p)}"
            elif p.is_dir():
                out[rel] = "dir"
            elif not p.is_file():  # a pipe: never read (it would block)
                out[rel] = "special"
            else:
                out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


# --------------------------------------------------------------------------- the table

@dataclass(frozen=True)
class Case:
    argv: str
    code: int
    says: tuple[str, ...]

    def __str__(self) -> str:
        return self.argv


C = Case
CASES = [
    # usage
    C("plan --bogus", 2, ("unrecognized arguments: --bogus", "--help")),
    C("", 2, ("COMMAND",)),
    C("verify plan --grinding-speed x", 2, ("--grinding-speed", "expected a number > 0 mm/s")),
    # plan: arguments, the hub's windows, outputs, the recipe and the scenario
    C("plan --windows 0,99 -o p", 2, ("--windows", "no window 99", "its windows: 0, 1, 2, 3, 4")),
    C("plan --windows x -o p", 2, ("--windows", "'x'", "window numbers")),
    C("plan --windows 1,1 -o p", 2, ("--windows", "twice")),
    C("plan --windows -2 -o p", 2, ("--windows", ">= 0")),
    C("plan -o afile", 2, ("afile", "is a file", "folder is needed")),
    C("plan -o userdir", 2, ("userdir", "did not write")),
    C("plan -o plan --html adir", 2, ("adir", "--html", "folder")),
    C("plan --hub missing -o p", 2, ("missing",)),
    C("plan nosuchcell -o p", 2, ("nosuchcell", "tool_in_hand")),
    C("plan garbage.yaml --windows 0 -o p", 2, ("garbage.yaml",)),
    C("plan --robot bogus -o p", 2, ("bogus", "irb1600")),
    C("plan --hub hub_negspeed -o p", 2, ("process.yaml", "grinding_speed", "-1",
                                         "0 < value <= 1 m/s")),
    C("plan --hub hub_listrecipe -o p", 2, ("process.yaml", "mapping")),
    C("plan --hub hub_badkey -o p", 2, ("process.yaml", "grinding_sped", "known")),
    # verify: numbers, the plan folder's files, outputs
    C("verify plan --windows 0,99", 2, ("--windows", "no window 99", "its windows: 0, 1")),
    C("verify plan --grinding-speed 0", 2, ("--grinding-speed", "> 0 mm/s", "'0'")),
    C("verify plan --grinding-speed -5", 2, ("--grinding-speed", "> 0 mm/s")),
    C("verify plan --grinding-speed nan", 2, ("--grinding-speed", "> 0 mm/s")),
    C("verify plan_list", 2, ("plan_list/plan.json", "not an object")),
    C("verify plan_badjson", 2, ("plan_badjson/plan.json", "not valid JSON")),
    C("verify plan_trunc", 2, ("plan_trunc/arrays.npz", "BadZipFile")),
    C("verify plan_nonpz", 2, ("plan_nonpz", "missing arrays.npz")),
    C("verify plan_shape", 2, ("arrays.npz", "'q_targets'", "shape (357, 5)", "(357, 6)")),
    C("verify plan_nan", 2, ("arrays.npz", "'q_targets'", "not finite")),
    C("verify plan_missing", 2, ("arrays.npz", "'X_WF'", "missing")),
    C("verify plan_badtarget", 2, ("plan.json", "targets[3].speed", "finite number")),
    C("verify plan_badsegment", 2, ("plan.json", "segments[1].target_range", "357 targets")),
    C("verify plan_bigindex", 2, ("plan.json", "targets[3].cl_index", "out of range")),
    C("verify plan_longtime", 2, ("plan.json", "segments[1].t_range", "not within")),
    C("verify plan_longtraj", 2, ("arrays.npz", "'t'", "duration limit of 3600 s")),
    C("export plan_longtime -o x.mod", 2, ("segments[1].t_range",)),
    C("verify nothere", 2, ("nothere", "SCENARIO/HUB")),
    C("verify plan --json adir", 2, ("adir", "--json", "folder")),
    C("verify plan --html adir", 2, ("adir", "--html", "folder")),
    C("verify plan --program missing.mod", 2, ("missing.mod", "not found")),
    C("verify plan --program bin.mod", 2, ("bin.mod:2", "UTF-8")),
    C("verify plan --program bad.mod", 2, ("bad.mod",)),
    C("verify plan --program afile", 2, ("afile", "program file type")),
    C("verify plan -o p2", 2, ("-o/--out", "only for a hub")),
    C("verify tool_in_hand/h5_straight --planner reference --windows 0,99", 2,
      ("--windows", "no window 99")),
    C("verify tool_in_hand/h5_straight --windows 0 -o afile", 2, ("afile", "folder is needed")),
    C("verify tool_in_hand/h5_straight --windows 0 -o userdir", 2, ("userdir", "did not write")),
    C("verify missing.stl", 2, ("missing.stl", "no such hub mesh file")),
    C("verify nan.stl", 2, ("nan.stl", "not finite")),
    C("verify-all nothere", 2, ("nothere", "catalogue")),
    C("verify-all . -j 0", 2, ("--workers", ">= 1")),
    # export: output, the plan, the format for its arm, then the gate (exit 1)
    C("export plan -o adir", 2, ("adir", "-o/--output is a folder")),
    C("export plan -o x.src", 2, ("x.src", "RAPID", ".mod")),
    C("export plan -o x.txt", 2, ("x.txt", ".mod")),
    C("export plan -o x.mod --name 9bad", 2, ("--name", "'9bad'", "a letter")),
    C("export plan -o x.mod --robot kr6_r700", 2, ("--robot kr6_r700", "irb1600")),
    C("export plan -o x.mod --format krl", 2, ("--format krl", "RAPID")),
    C("export nothere -o x.mod", 2, ("nothere", "no such plan folder")),
    C("export plan_list -o x.mod", 2, ("plan_list/plan.json",)),
    C("export plan_trunc -o x.mod", 2, ("plan_trunc/arrays.npz",)),
    C("export plan -o x.mod", 1, ("refusing to export", "no verification report")),
    C("export plan_badreport -o x.mod", 1, ("refusing", "report.json", "'plan.identity'")),
    C("export plan_cutreport -o x.mod", 1, ("refusing", "report.json", "not valid JSON")),
    # cl, orient
    C("cl missing.stl", 2, ("missing.stl", "not found")),
    C("cl nan.stl", 2, ("nan.stl", "facet", "not finite")),
    C("cl nothere", 2, ("nothere",)),
    C("cl garbage.stl", 2, ("garbage.stl", "no triangles")),
    C("cl nan.obj", 2, ("nan.obj", "vertex 1", "not finite")),
    C("cl badidx.obj", 2, ("badidx.obj", "cannot read mesh")),
    C("cl adir.stl", 2, ("adir.stl", "folder")),
    C("cl h5_straight --l-max-mm 0", 2, ("--l-max-mm", "> 0 mm")),
    C("cl h5_straight --delta-max-mm -1", 2, ("--delta-max-mm", "> 0 mm")),
    C("cl h5_straight --json adir", 2, ("adir", "--json")),
    C("cl h5_straight --burr-mm 0", 2, ("--burr-mm", "> 0 mm")),
    C("orient missing", 2, ("missing",)),
    C("orient h5_straight --spacing-mm 0 --cl loop", 2, ("--spacing-mm", "> 0 mm")),
    C("orient h5_straight --sigma-mm -1", 2, ("--sigma-mm", ">= 0 mm")),
    C("orient h5_straight --seed -3", 2, ("--seed", ">= 0")),
    C("orient h5_straight --json adir", 2, ("adir", "--json")),
    # hub
    C("hub import missing.stl --out hubs", 2, ("missing.stl", "not found")),
    C("hub import afile --out hubs", 2, ("afile", ".stl, .obj, .ply")),
    C("hub import nan.stl --out hubs", 2, ("nan.stl", "not finite")),
    C("hub import nan.stl --out afile", 2, ("afile", "--out", "folder is needed")),
    C("hub import nan.stl --out hubs --axis 0 0 0", 2, ("--axis", "non-zero")),
    C("hub import nan.stl --out hubs --windows 0", 2, ("--windows", ">= 1")),
    C("hub random --seed 1 --count 0 -o r", 2, ("--count", ">= 1")),
    C("hub random --seed -1 -o r", 2, ("--seed", ">= 0")),
    C("hub random --seed 1 -o afile --no-collision", 2, ("afile", "folder is needed")),
    C("hub generate --spec missing.yaml --out g", 2, ("missing.yaml", "not found")),
    C("hub generate h5_straight --out afile", 2, ("afile", "folder is needed")),
    C("hub info missing", 2, ("missing",)),
    C("hub scan h5_straight adir", 2, ("adir", "folder")),
    C("hub list --dir nothere", 2, ("nothere", "--dir")),
    # post (checked by the post command itself)
    C("post missing.cl -o p.mod", 2, ("missing.cl", "not found")),
    C("post small.cl -o adir", 2, ("adir", "folder")),
    C("post small.cl -o p.mod --feed 0", 2, ("--feed", "> 0")),
    # laser
    C("laser shape circle --diameter 0 -o c.ls", 2, ("--diameter", "0.01 <= value <= 5000 mm")),
    C("laser shape circle --diameter 10 --spacing 0 -o c.ls", 2,
      ("--spacing", "0.001 <= value <= 1000 mm")),
    C("laser shape circle --diameter 10 --feed 0 -o c.ls", 2, ("--feed", "0 < value <= 600")),
    # issue 43: sizes that overflowed, spacings that asked for billions of points
    C("laser shape circle --diameter 1e300 -o c.ls", 2, ("--diameter", "<= 5000 mm")),
    C("laser shape circle --diameter 10 --spacing 1e-9 -o c.ls", 2, ("--spacing", "0.001")),
    C("laser shape circle --diameter 4000 --spacing 0.001 -o c.ls", 2,
      ("--spacing", "points", "limit of 200000")),
    C("laser shape circle --diameter 10 --lead-in 1e300 -o c.ls", 2, ("--lead-in",)),
    C("laser shape circle --diameter 10 --center inf 0 -o c.ls", 2, ("--center",)),
    C("laser shape circle --diameter 10 --feed 1e308 -o c.ls", 2, ("--feed",)),
    C("laser shape hexagon --across-flats 1e-300 -o c.ls", 2, ("--across-flats", "0.01")),
    C("laser shape polyline --points huge.csv -o c.ls", 2, ("1e+308 mm", "finite")),
    C("cl collinear.obj", 2, ("collinear.obj", "degenerate")),
    C("hub import collinear.obj --out hubs", 2, ("collinear.obj", "degenerate")),
    C("verify collinear.obj", 2, ("collinear.obj", "degenerate")),
    C("laser shape circle --diameter 10 -o adir", 2, ("adir", "folder")),
    C("laser shape circle --diameter 10 -o c.txt", 2, ("c.txt", ".ls")),
    C("laser shape circle --diameter 10 --name 9x -o c.ls", 2, ("'9x'", "letter")),
    C("laser shape circle --diameter 10 --min-command 5 --max-command 2 -o c.ls", 2,
      ("--max-command", "--min-command")),
    C("laser shape polyline --points missing.csv -o c.ls", 2, ("missing.csv", "not found")),
    C("laser tool --sdf adir", 2, ("adir", "--sdf")),
    # issue 43: recipes, each key typed with its unit and range; bounded, strict YAML
    C("plan --hub hub_boolspeed -o p", 2, ("hub_boolspeed/process.yaml", "grinding_speed",
                                           "True", "boolean", "0 < value <= 1 m/s")),
    C("plan --hub hub_mmspeed -o p", 2, ("process.yaml", "grinding_speed", "150",
                                         "out of range", "m/s", "0.15")),
    C("plan --hub hub_negair -o p", 2, ("process.yaml", "spindle_air_pressure", "-200000",
                                        "0 < value <= 1e+06 Pa")),
    C("plan --hub hub_nanaccept -o p", 2, ("process.yaml", "theta_box_share", "nan",
                                           "0 <= value <= 1")),
    C("plan --hub hub_highband -o p", 2, ("process.yaml", "speed_band_fraction", "'high'",
                                          "not a number")),
    C("plan --hub hub_dupkey -o p", 2, ("process.yaml:3", "'grinding_speed'", "twice",
                                        "line 1")),
    C("plan --hub hub_latin1 -o p", 2, ("hub_latin1/process.yaml:1", "not UTF-8", "0xe9")),
    C("plan --hub hub_utf16 -o p", 2, ("hub_utf16/process.yaml", "not UTF-8", "UTF-16")),
    C("plan --hub hub_bomb -o p", 2, ("process.yaml", "alias expansion limit of 10000")),
    C("plan --hub hub_deep -o p", 2, ("process.yaml", "depth limit of 64")),
    C("plan --hub hub_huge -o p", 2, ("process.yaml", "recipe read limit of 1 MiB")),
    C("plan --hub hub_strbounds -o p", 2, ("process.yaml", "bounds_small.theta_min", "'0.1'",
                                           "rad")),
    C("plan --hub hub_chamfer -o p", 2, ("process.yaml", "chamfer_width_min", "more than")),
    C("plan --hub hub_python -o p", 2, ("process.yaml", "python/object")),
    C("plan bomb_cell.yaml -o p", 2, ("bomb_cell.yaml", "alias expansion limit")),
    # issue 43: devices, pipes and oversized files are never read
    C("cl zero.stl", 2, ("zero.stl", "character device", "regular files")),
    C("cl fifo.stl", 2, ("fifo.stl", "a pipe")),
    C("hub import zero.stl --out hubs", 2, ("zero.stl", "character device")),
    C("verify zero.obj", 2, ("zero.obj", "character device")),
    C("verify plan --program zero.mod", 2, ("zero.mod", "character device")),
    C("post zero.cl -o p.mod", 2, ("zero.cl", "CL file", "character device")),
    # issue 43: names that become paths
    C("hub generate --spec spec_dotdot.yaml --out o/hubs", 2, ("spec_dotdot.yaml", "'..'",
                                                             "cannot be a file name")),
    C("hub generate --spec spec_newline.yaml --out o", 2, ("'a\\nb'", "file name")),
    C("hub generate --spec spec_shell.yaml --out o", 2, ("'x;rm -rf ~'", "file name")),
    C("hub generate --spec spec_slash.yaml --out o", 2, ("'a/b'", "file name")),
    C("hub generate --spec spec_dot.yaml --out o", 2, ("'.'", "file name")),
    C("hub generate --spec spec_hidden.yaml --out o", 2, ("'.hub'", "file name")),
    C("hub generate --spec spec_dup.yaml --out o", 2, ("spec_dup.yaml", "spoke_count", "twice")),
    C("hub generate .. --out o/hubs", 2, ("hub name", "'..'")),
    C("hub generate h5_straight --out up", 2, ("up/h5_straight", "did not generate")),
    # issue 43: outputs never replace inputs or each other
    C("verify plan --json plan/plan.json", 2, ("plan/plan.json", "--json", "plan folder")),
    C("verify plan --html plan/arrays.npz", 2, ("plan/arrays.npz", "--html", "plan folder")),
    C("verify plan --json plan/report.json", 2, ("plan/report.json", "plan folder")),
    C("verify plan --json r.out --html r.out", 2, ("r.out", "--html", "--json", "same file")),
    C("verify plan --program x.mod --json x.mod", 2, ("x.mod", "--json", "--program",
                                                      "input")),
    C("verify plan --json ./plan/../plan/plan.json", 2, ("--json", "plan folder")),
    C("export plan -o plan/plan.json", 2, ("plan/plan.json", "plan.json", "input")),
    C("plan -o p --html p/replay.html", 2, ("p/replay.html", "inside the output folder")),
    C("post small.cl -o small.cl", 2, ("small.cl", "input")),
    C("laser shape circle --diameter 10 -o c.ls --summary c.ls", 2, ("--summary", "same file")),
    C("cl nan.stl --json nan.stl", 2, ("nan.stl", "--json", "input")),
    # issue 43: verify-all's scheduler, checked before any work, naming the option
    C("verify-all . --scheduler notaurl", 2, ("--scheduler", "'notaurl'", "SCHEME://HOST:PORT")),
    C("verify-all . --scheduler tcp://127.0.0.1:1", 2, ("--scheduler", "127.0.0.1:1",
                                                        "no scheduler answers")),
    # show, demo
    C("show missing --html s.html", 2, ("missing",)),
    C("show tool_in_hand --hub missing --html s.html", 2, ("missing",)),
    C("show tool_in_hand --html adir", 2, ("adir", "--html")),
    C("demo --out afile --test-mode", 2, ("afile", "folder is needed")),
    C("demo -o afile --test-mode", 2, ("afile", "-o/--out", "folder is needed")),
    C("demo --out d --hub missing --test-mode", 2, ("missing",)),
    C("demo --out d --robot bogus --test-mode", 2, ("bogus", "irb1600")),
]


@pytest.mark.parametrize("case", CASES, ids=str)
def test_bad_input(case, ws, capsys):
    before = tree(ws)
    code, out, err = run(case.argv.split(), capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == case.code, err
    assert "Traceback" not in err + out
    for text in case.says:
        assert text in err, f"{text!r} not in {err!r}"
    if code == 2:
        assert len(lines) == 1, f"one line expected, got {lines}"
        assert ": error: " in lines[0]
    assert tree(ws) == before  # nothing written, nothing changed, no leftovers


def test_every_help_states_the_exit_codes(capsys):
    import argparse

    from drakedeburr.cli import _build_parser

    def parsers(p):
        yield p
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub in a.choices.values():
                    yield from parsers(sub)

    for p in parsers(_build_parser()):
        text = p.format_help()
        assert "exit codes:" in text and "130" in text and "-vv" in text, p.prog


def test_unwritable_folder(ws, capsys):
    if os.geteuid() == 0:  # root writes anywhere a mode allows nothing; /proc/1 refuses even root
        folder = Path("/proc/1")
    else:
        folder = ws / "ro"
        folder.mkdir()
        folder.chmod(0o555)
    before = tree(ws)
    for argv in (f"export plan -o {folder}/x.mod", f"plan -o {folder}/p",
                 f"laser shape circle --diameter 10 -o {folder}/c.ls"):
        code, _, err = run(argv.split(), capsys)
        assert code == 2 and "not writable" in err and str(folder) in err, err
    assert tree(ws) == before


def test_free_space_is_checked_before_the_work(ws, capsys, monkeypatch):
    import collections

    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 10**9 - 1000, 1000))
    before = tree(ws)
    code, _, err = run("plan --windows 0 -o p".split(), capsys)
    assert code == 2 and "1000 bytes free" in err and "needs about" in err, err
    assert "0.0 MB" not in err and "KiB" in err  # issue 43: never "0.0 MB free"
    code, _, err = run("export plan -o x.mod --force".split(), capsys)
    assert code == 2 and "1000 bytes free" in err
    assert tree(ws) == before


def _fail_on_write(monkeypatch, exc: BaseException) -> None:
    """Every file written through drakedeburr._io fails at its fsync with ``exc``."""
    from drakedeburr import _io

    def fsync(fd):
        raise type(exc)(*exc.args)  # a new one each time, as the system gives

    monkeypatch.setattr(_io.os, "fsync", fsync)


@pytest.mark.parametrize("exc, code, says", [
    (OSError(28, "No space left on device"), 2, "no space left"),
    (KeyboardInterrupt(), 130, "interrupted"),
], ids=["disk-full", "ctrl-c"])
def test_a_write_that_fails_leaves_the_old_output(ws, capsys, monkeypatch, exc, code, says):
    """ENOSPC or Ctrl-C while writing: the earlier program stays whole, no temporary file."""
    before = tree(ws)
    _fail_on_write(monkeypatch, exc)
    for argv, output in (("export plan -o x.mod --force", "x.mod"),
                         ("laser shape circle --diameter 10 -o c.ls", "c.ls")):
        got, _, err = run(argv.split(), capsys)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert got == code and says in lines[-1] and "Traceback" not in err, err
        if code == 2:  # the file is named, not its temporary
            assert lines[-1].split(": ")[2] == output and ".tmp" not in err, err
    from drakedeburr._io import atomic_write_files

    pair = {ws / "k.src": "new src", ws / "k.dat": "new dat"}  # a KRL pair: both or neither
    with pytest.raises(type(exc)):
        atomic_write_files(pair)
    assert tree(ws) == before


def test_a_plan_folder_write_that_fails_leaves_the_old_plan(ws, capsys, monkeypatch):
    from drakedeburr.plan import io as plan_io
    from drakedeburr.plan.io import save_plan

    before = tree(ws)
    for exc in (OSError(28, "No space left on device"), KeyboardInterrupt()):
        def broken(*args, exc=exc, **kwargs):
            raise exc

        monkeypatch.setattr(plan_io, "write_joint_csv", broken)
        with pytest.raises(type(exc)) as info:
            save_plan(vs.good_plan(), ws / "plan")
        if isinstance(exc, OSError):  # names the plan folder, not its temporary
            assert info.value.filename == str(ws / "plan")
    assert tree(ws) == before


def test_internal_errors_are_one_line_and_vv_shows_the_traceback(ws, capsys, monkeypatch):
    from drakedeburr.laser import commands

    def bug(args):
        return 1 / 0

    monkeypatch.setattr(commands, "_run_tool", bug)  # main() builds its parser afresh
    code, _, err = run(["laser", "tool"], capsys)
    assert code == 1 and "Traceback" not in err
    assert err.count("\n") == 1 and "internal error: ZeroDivisionError" in err
    assert "-vv" in err
    code, _, err = run(["-vv", "laser", "tool"], capsys)
    assert code == 1 and "Traceback" in err and "ZeroDivisionError" in err
    code, _, err = run(["verify", "plan_trunc", "-vv"], capsys)  # -vv after the command too
    assert code == 2 and "Traceback" in err and "BadZipFile" in err.splitlines()[-1]


def _nothing_planned():
    """The plan the planner returns when no window could be planned: home only, one knot."""
    from dataclasses import replace

    from drakedeburr.plan.types import FailureRecord, JointTrajectory, PlanSegment

    good = vs.good_plan()
    return replace(good, targets=good.targets[:1],
                   segments=(PlanSegment(-1, "home", (0, 1), (0.0, 0.0)),),
                   trajectory=JointTrajectory(t=np.zeros(1), c=np.zeros((7, 0, 6))),
                   tool_path=None, meta={**good.meta, "windows": []},
                   failures=(FailureRecord(window=0, kind="window", reason="IK reached only "
                                           "28 of 93 targets; window skipped"),))


def test_nothing_planned_is_a_failed_result_with_a_report(ws, capsys, monkeypatch):
    """A hub whose windows cannot be cut is not bad input: exit 1 and a report saying why,
    and no program even with --force (the planner's part is faked: planning a hub that
    cannot be cut takes minutes; test_plan_* cover the planner)."""
    from drakedeburr.verify import batch

    monkeypatch.setattr(batch, "make_plan", lambda *a, **k: _nothing_planned())
    code, out, err = run("verify tool_in_hand/h5_straight --windows 0 -o np".split(), capsys)
    assert code == 1 and "Traceback" not in err and "error" not in err, err
    assert "FAIL  windows" in out and "FAILED" in out
    report = json.loads((ws / "np" / "report.json").read_text())
    assert not report["passed"] and "windows" in report["summary"]["failed"]
    assert "could be planned" in json.dumps(report["items"])
    assert (ws / "np" / "report.html").stat().st_size > 0
    assert (ws / "np" / "joints.csv").read_text().count("\n") == 2  # header + home
    before = tree(ws)
    for force in ([], ["--force"]):
        code, _, err = run(["export", "np", "-o", "n.mod", *force], capsys)
        assert code == 1 and ("refusing" in err or "no program to write" in err), err
    code, out, _ = run("verify np".split(), capsys)  # the saved plan verifies the same way
    assert code == 1 and "FAILED" in out
    assert {k: v for k, v in tree(ws).items() if "report" not in k} == {
        k: v for k, v in before.items() if "report" not in k}


def test_a_window_without_a_tool_path_is_a_failure_not_bad_input(ws, capsys, monkeypatch):
    """The real planner (plan_hub) on a hub where the orientation stage gives an axis into
    the hub (seen on a real mesh: was exit 2, no report): the window is a failure record,
    verify exits 1 with the report naming it."""
    from drakedeburr.errors import InputError
    from drakedeburr.plan.window_targets import WindowTargets

    def into_the_hub(cls, tool_path, **kwargs):
        raise InputError(f"ToolPath of window {tool_path.window_index}: tool axis (tip -> "
                         "spindle) points into the hub at CL point 7")

    monkeypatch.setattr(WindowTargets, "from_tool_path", classmethod(into_the_hub))
    code, out, err = run("verify tool_in_hand/h5_straight --windows 1 -o np".split(), capsys)
    assert code == 1 and "Traceback" not in err and "error" not in err, err
    report = json.loads((ws / "np" / "report.json").read_text())
    assert not report["passed"] and "planner_failures" in report["summary"]["failed"]
    assert "window 1 (window): no tool path" in json.dumps(report["items"])


# --------------------------------------------------------------------------- signals, leftovers

def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "drakedeburr", *args]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_interrupted_plan_exits_130_and_keeps_the_old_plan(ws, sig):
    """A signal during planning: exit 130, one line, the previous plan folder untouched."""
    before = tree(ws)
    # the child with Ctrl-C at its default: a shell's background job (``cmd &`` without job
    # control) runs with SIGINT ignored, which its children inherit, and Python then leaves
    # it ignored
    proc = subprocess.Popen(_cli("plan", "--windows", "0", "--source", "edges", "-o", "plan"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ws,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # the first log line comes once the command runs (its handlers are installed)
    first = proc.stderr.readline()
    assert first, proc.communicate()
    time.sleep(0.5)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    lines = [ln for ln in err.splitlines() if ln.strip() and "%|" not in ln]
    assert proc.returncode == 130, err
    assert "interrupted" in lines[-1] and "Traceback" not in err
    assert tree(ws) == before


def test_the_next_run_removes_what_a_killed_run_left(ws, capsys):
    """Temporaries of a run that was killed (its process has ended) go; a live run's stay."""
    dead = subprocess.Popen(["true"])
    dead.wait()
    live = os.getppid()
    left = [ws / f".plan.tmp-{dead.pid}-abcdefgh", ws / f".x.mod.{dead.pid}-abcdefgh.tmp",
            ws / f".c.ls.{dead.pid}-abcdefgh.tmp"]
    kept = [ws / f".plan.tmp-{live}-abcdefgh", ws / f".x.mod.{live}-abcdefgh.tmp"]
    for p in left + kept:
        p.mkdir() if ".tmp-" in p.name else p.write_text("partial")
    code, _, err = run("laser shape circle --diameter 10 -o c.ls".split(), capsys)
    assert code == 0, err
    code, _, err = run("export plan -o x.mod --force".split(), capsys)
    assert code == 0, err
    from drakedeburr.plan.io import save_plan

    save_plan(vs.good_plan(), ws / "plan")
    assert not any(p.exists() for p in left)
    assert all(p.exists() for p in kept)


def test_outputs_get_the_users_umask(ws, capsys):
    from drakedeburr._io import temp_folder_beside
    from drakedeburr.hub.import_output import ImportRecord, write_folder

    old = os.umask(0o027)
    try:
        code, _, _ = run("laser shape circle --diameter 10 -o c2.ls".split(), capsys)
        assert code == 0 and (ws / "c2.ls").stat().st_mode & 0o777 == 0o640
        from drakedeburr.plan.io import save_plan

        save_plan(vs.good_plan(), ws / "p2")
        assert (ws / "p2").stat().st_mode & 0o777 == 0o750
        assert (ws / "p2" / "plan.json").stat().st_mode & 0o777 == 0o640
        assert temp_folder_beside(ws / "t").stat().st_mode & 0o777 == 0o750
        # the imported hub folder (was 0700: made by mkdtemp)
        V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 0.1
        F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        rec = ImportRecord("h", ws / "nan.stl", "0" * 64, "k", "m", True, np.eye(4), None, {},
                           V, F, [], 1.0, np.zeros(3), np.eye(3) * 1e-3, 1e-3, "test", 0.1, [])
        write_folder(ws / "hubs" / "h_1", ws / "hubs", rec, {"name": "h"})
        assert (ws / "hubs" / "h_1").stat().st_mode & 0o777 == 0o750
    finally:
        os.umask(old)


def test_no_user_output_is_made_by_mkdtemp_or_mkstemp():
    """Temporary files and folders that become outputs come from drakedeburr._io, which gives
    them the user's umask and names the next run can clean up."""
    import ast

    root = REPO / "drakedeburr"
    found = []
    for f in root.rglob("*.py"):
        if f.name == "_io.py":
            continue
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in ("mkdtemp", "mkstemp"):
                found.append(f"{f.relative_to(root)}:{node.lineno}")
    assert not found, found
