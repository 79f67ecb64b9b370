"""Issues 21 and 43: property-based fuzzing of the readers of files a user hands in: the plan folder
(:func:`drakedeburr.plan.io.load_plan`), the verification report the export gate reads
(:func:`drakedeburr.verify.gate.read_report`) and robot programs
(:func:`drakedeburr.programs.read_program`). Whatever the bytes, a reader returns its result or
raises InputError naming the file, never another exception (like the APT fuzz in
test_cl_reader.py). Issue 43: the recipe reader (process.yaml, as YAML of every type and as
raw bytes) and the CLI's arguments, at a budget CI affords (a few seconds each)."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import verify_support as vs
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drakedeburr.errors import InputError


def _write_npz(path: Path, arrays: dict) -> None:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())


_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=6),
    lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=6), c, max_size=3),
    max_leaves=10)


def _paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:2]):
            yield from _paths(v, (*prefix, i))


@pytest.fixture(scope="module")
def seed_plan(tmp_path_factory):
    from drakedeburr.plan.io import save_plan

    folder = save_plan(vs.good_plan(), tmp_path_factory.mktemp("seed") / "plan")
    doc = json.loads((folder / "plan.json").read_text())
    return (doc, [p for p in _paths(doc) if p], dict(np.load(folder / "arrays.npz")),
            (folder / "arrays.npz").read_bytes())


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_fuzz_load_plan(seed_plan, fuzz_dir, data):
    """Any plan.json and arrays.npz: the plan loads, or InputError names the file."""
    from drakedeburr.plan.io import load_plan

    doc, paths, arrays, npz = seed_plan
    doc = json.loads(json.dumps(doc))
    folder = fuzz_dir / "plan"
    folder.mkdir(exist_ok=True)
    if data.draw(st.booleans()):
        for _ in range(data.draw(st.integers(1, 3))):
            path = data.draw(st.sampled_from(paths))
            obj = doc
            try:
                for k in path[:-1]:
                    obj = obj[k]
                if data.draw(st.booleans()):
                    obj[path[-1]] = data.draw(_JSON)
                else:
                    del obj[path[-1]]
            except (KeyError, IndexError, TypeError):
                pass
        text = json.dumps(doc).encode()
    else:
        text = data.draw(st.binary(max_size=200) | st.sampled_from(
            [b"[1,2,3]", b"{}", b"null", b"[" * 5000, b'{"format": "drakedeburr-plan"}']))
    (folder / "plan.json").write_bytes(text)
    how = data.draw(st.sampled_from(["same", "drop", "shape", "dtype", "value", "bytes"]))
    a = dict(arrays)
    key = data.draw(st.sampled_from(sorted(a)))
    if how == "bytes":
        cut = data.draw(st.integers(0, len(npz)))
        (folder / "arrays.npz").write_bytes(npz[:cut] + data.draw(st.binary(max_size=20)))
    else:
        if how == "drop":
            del a[key]
        elif how == "shape":
            a[key] = a[key].reshape(-1)[: data.draw(st.integers(0, 30))]
        elif how == "dtype":
            a[key] = a[key].astype(data.draw(st.sampled_from(["U3", "complex128", "int8",
                                                              "bool", "float32"])))
        elif how == "value":
            a[key] = a[key].copy()
            a[key].reshape(-1)[data.draw(st.integers(0, a[key].size - 1))] = data.draw(
                st.sampled_from([np.nan, np.inf, -1e300, 0.0]))
        _write_npz(folder / "arrays.npz", a)
    try:
        plan = load_plan(folder)
    except InputError as exc:
        assert str(folder) in str(exc)
        return
    assert plan.X_WH.shape == (4, 4) and all(t.q.shape == (6,) for t in plan.targets)


@settings(max_examples=600, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_fuzz_read_report(fuzz_dir, data):
    """Any report.json: it reads, or InputError names the file; the gate never raises."""
    from drakedeburr.verify.gate import read_report

    good = {"passed": True, "plan": {"identity": {"plan_digest": "a", "cell_digest": "b",
                                                  "verifier_version": "c"}},
            "settings": {"tolerances": {"min_clearance": 0.002}}, "summary": {"failed": []}}
    if data.draw(st.booleans()):
        doc = json.loads(json.dumps(good))
        for path in data.draw(st.lists(st.sampled_from([p for p in _paths(good) if p]),
                                       min_size=1, max_size=3)):
            obj = doc
            try:
                for k in path[:-1]:
                    obj = obj[k]
                obj[path[-1]] = data.draw(_JSON | st.integers(min_value=10**308))
            except (KeyError, IndexError, TypeError):
                pass
        text = json.dumps(doc).encode()
    else:
        text = data.draw(st.binary(max_size=300))
    path = fuzz_dir / "report.json"
    path.write_bytes(text)
    try:
        report = read_report(path)
    except InputError as exc:
        assert str(path) in str(exc)
        return
    assert isinstance(report["passed"], bool)


_SEED_PROGRAMS: dict = {}


def _seed_programs(root: Path) -> dict:
    import program_support as ps

    from drakedeburr.programs import write_program

    if not _SEED_PROGRAMS:
        root.mkdir(exist_ok=True)
        for fmt in ("rapid", "krl", "ls"):
            for stationary in (False, True):
                d = root / f"{fmt}_{stationary}"
                d.mkdir()
                paths = write_program(ps.random_program(ps.ARMS[fmt], stationary, n=4,
                                                        name="prog"),
                                      d / f"prog{ps.SUFFIX[fmt]}", fmt)
                _SEED_PROGRAMS[(fmt, stationary)] = {p.name: p.read_bytes() for p in paths}
    return _SEED_PROGRAMS


@settings(max_examples=1000, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_fuzz_read_program(fuzz_dir, data):
    """Any bytes in a RAPID, KRL (.src and .dat) or LS file: read, or InputError
    (ProgramFormatError) naming the file."""
    from drakedeburr.programs import read_program

    seeds = _seed_programs(fuzz_dir / "seeds")
    fmt, stationary = data.draw(st.sampled_from(sorted(seeds)))
    files = dict(seeds[(fmt, stationary)])
    name = data.draw(st.sampled_from(sorted(files)))
    lines = files[name].split(b"\n")
    for _ in range(data.draw(st.integers(1, 4))):
        op = data.draw(st.sampled_from(["del", "dup", "text", "bytes", "char", "cut"]))
        i = data.draw(st.integers(0, max(0, len(lines) - 1)))
        if op == "del" and lines:
            del lines[i]
        elif op == "dup" and lines:
            lines.insert(i, lines[i])
        elif op == "text":
            lines.insert(i, data.draw(st.text(max_size=40)).encode("utf-8", "surrogatepass"))
        elif op == "bytes":
            lines.insert(i, data.draw(st.binary(max_size=20)))
        elif op == "char" and lines and lines[i]:
            line = bytearray(lines[i])
            line[data.draw(st.integers(0, len(line) - 1))] = data.draw(
                st.sampled_from(list(b"0123456789-+.,[]{}():=;'\"/ eE\x00\xffXYZ")))
            lines[i] = bytes(line)
        elif op == "cut":
            lines = lines[:i]
    files[name] = b"\n".join(lines)
    d = fuzz_dir / "prog"
    shutil.rmtree(d, ignore_errors=True)
    d.mkdir()
    for n, b in files.items():
        (d / n).write_bytes(b)
    first = next(n for n in sorted(files) if not n.endswith(".dat"))
    try:
        read_program(d / first)
    except InputError as exc:
        assert str(d) in str(exc)


# --------------------------------------------------------------------------- issue 43: recipes

_RECIPE_KEYS = ("grinding_speed", "approach_speed", "spindle_air_pressure", "w1", "l_max",
                "depth_of_cut_small", "chamfer_width_min", "chamfer_width_max", "bounds_large",
                "bounds_small", "acceptance", "grinding_sped", "theta_min")
_SCALARS = (st.none() | st.booleans() | st.integers(-10**25, 10**25)
            | st.floats(allow_nan=True, allow_infinity=True)
            | st.sampled_from(["1.0e6", "0.15", "high", "yes", "on", "", "~", ".nan", "-.inf",
                               "1e-3", "0x10", "1_000", "150 mm/s"]))
_YAML_VALUES = st.recursive(_SCALARS, lambda c: st.lists(c, max_size=3)
                            | st.dictionaries(st.sampled_from(["theta_min", "theta_max",
                                                               "speed_band_fraction", "x"]),
                                              c, max_size=3), max_leaves=6)


def _check_recipe(recipe) -> None:
    """A recipe that loads holds only values its schema allows (unit ranges, no booleans)."""
    import dataclasses

    from drakedeburr.config import ACCEPTANCE_SCHEMA, RECIPE_SCHEMA

    for f in dataclasses.fields(recipe.process):
        v = getattr(recipe.process, f.name)
        if f.name.startswith("bounds_"):
            assert -np.pi / 2 < v.theta_min < v.theta_max < np.pi / 2
            continue
        key = RECIPE_SCHEMA[f.name]
        assert not isinstance(v, bool) and np.isfinite(v), (f.name, v)
        assert key.lo <= v <= key.hi, (f.name, v)
    for f in dataclasses.fields(recipe.acceptance):
        v = getattr(recipe.acceptance, f.name)
        key = ACCEPTANCE_SCHEMA[f.name]
        assert v is None or (not isinstance(v, bool) and key.lo <= v <= key.hi), (f.name, v)


@settings(max_examples=200, deadline=None, suppress_health_check=list(HealthCheck))
@given(items=st.lists(st.tuples(st.sampled_from(_RECIPE_KEYS), _YAML_VALUES), max_size=5),
       style=st.sampled_from(["block", "flow", "json"]))
def test_fuzz_recipe_reader(fuzz_dir, items, style):
    """Any process.yaml of known and unknown keys, repeated keys and values of every YAML
    type: the recipe loads with every value in its schema's range, or InputError names the
    file in one line."""
    import yaml as pyyaml

    from drakedeburr.config import PROCESS_FILE, load_recipe

    folder = fuzz_dir / "recipe"
    folder.mkdir(exist_ok=True)
    if style == "json":  # JSON is YAML; a repeated key stays in the text
        text = "{" + ", ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in items) + "}"
    else:
        flow = style == "flow"
        text = "".join(pyyaml.safe_dump({k: v}, default_flow_style=flow) for k, v in items)
    (folder / PROCESS_FILE).write_text(text)
    keys = [k for k, _ in items]
    try:
        recipe = load_recipe(folder)
    except InputError as exc:
        assert str(folder / PROCESS_FILE) in str(exc)
        assert len(str(exc)) < 2000, len(str(exc))
        return
    assert len(set(keys)) == len(keys), "a repeated key was accepted"
    _check_recipe(recipe)


@settings(max_examples=200, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.binary(max_size=300) | st.text(max_size=200).map(lambda t: t.encode("utf-8")))
def test_fuzz_recipe_bytes(fuzz_dir, data):
    """Any bytes as process.yaml: a recipe within its schema, or InputError naming the file."""
    from drakedeburr.config import PROCESS_FILE, load_recipe

    folder = fuzz_dir / "recipe_bytes"
    folder.mkdir(exist_ok=True)
    (folder / PROCESS_FILE).write_bytes(data)
    try:
        recipe = load_recipe(folder)
    except InputError as exc:
        assert str(folder / PROCESS_FILE) in str(exc) and len(str(exc)) < 2000
        return
    _check_recipe(recipe)


# --------------------------------------------------------------------------- issue 43: the CLI

_WORDS = ["plan", "plan/plan.json", "plan/arrays.npz", "x.mod", "x.src", "c.ls", "r.json",
          ".", "..", "/dev/zero", "a b", "a\nb", "-", "--", "0", "-1", "1.5", "nan", "inf",
          "1e300", "1e-9", "100000000000000000000", "0,99", "1,1", "x", "tool_in_hand",
          "h5_straight", "tool_in_hand/h5_straight", "small.cl", "*", "tcp://127.0.0.1:1"]
_OPTIONS = ["-o", "--json", "--html", "--program", "--windows", "--grinding-speed", "--name",
            "--robot", "--format", "--force", "--quick", "--hub", "--diameter", "--spacing",
            "--feed", "--lead-in", "--center", "--seed", "--count", "--out", "--spec", "-vv",
            "--no-replay", "--planner", "--scenario"]
_COMMANDS = [["plan"], ["verify", "plan"], ["export", "plan"], ["hub", "random"],
             ["hub", "generate"], ["laser", "shape", "circle"], ["post", "small.cl"],
             ["verify", "tool_in_hand/h5_straight"]]


class _Stub(Exception):
    pass


@pytest.fixture(scope="module")
def cli_ws(tmp_path_factory, seed_plan):
    from drakedeburr.plan.io import save_plan

    root = tmp_path_factory.mktemp("cli_fuzz")
    save_plan(vs.good_plan(), root / "plan")
    (root / "small.cl").write_text("TOOL PATH/P1\nGOTO/800,0,600,0,0,1\nGOTO/810,0,600,0,0,1"
                                   "\nEND-OF-PATH\n")
    return root


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck))
@given(command=st.sampled_from(_COMMANDS),
       rest=st.lists(st.sampled_from(_OPTIONS) | st.sampled_from(_WORDS), max_size=6))
def test_fuzz_cli_arguments(cli_ws, monkeypatch, capsys, command, rest):
    """Random arguments to the commands: exit 0, 1 or 2, never an internal error or a
    traceback without -vv, one line for exit 2, and the plan folder never changed by
    anything but its own report. The long work (planning, verification, hub generation) is
    replaced by a stub raising at its start: arguments that get that far passed every check."""
    import hashlib

    from drakedeburr.cli import main

    def stub(*a, **k):
        raise _Stub("reached the work")

    import drakedeburr.hub.generate as gen
    import drakedeburr.plan.planner as planner
    import drakedeburr.verify.batch as batch
    import drakedeburr.verify.checks as checks

    for mod, name in ((planner, "plan_hub"), (batch, "make_plan"), (checks, "verify_plan"),
                      (gen, "generate_hub"), (batch, "verify_all")):
        monkeypatch.setattr(mod, name, stub)
    monkeypatch.chdir(cli_ws)

    def plan_files():
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                for p in (cli_ws / "plan").iterdir() if p.name in ("plan.json", "arrays.npz")}

    before = plan_files()
    capsys.readouterr()
    argv = [*command, *rest]
    code = main(argv)
    out, err = capsys.readouterr()
    lines = [ln for ln in err.splitlines() if ln.strip() and "%|" not in ln]
    assert plan_files() == before, argv
    if "reached the work" in err:
        assert code == 1, (argv, err)  # the stub: an "internal error" by design
        return
    assert code in (0, 1, 2), (argv, code, err)
    assert "internal error" not in err, (argv, err)
    if "-vv" not in argv:
        assert "Traceback" not in err + out, (argv, err)
        if code == 2:
            assert len([ln for ln in lines if " INFO " not in ln and " WARNING " not in ln
                        ]) == 1, (argv, lines)
    for p in cli_ws.iterdir():  # nothing left half-written
        assert ".tmp" not in p.name, (argv, p.name)
