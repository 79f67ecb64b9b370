"""Issue 21: property-based fuzzing of the readers of files a user hands in: the plan folder
(:func:`drakedeburr.plan.io.load_plan`), the verification report the export gate reads
(:func:`drakedeburr.verify.gate.read_report`) and robot programs
(:func:`drakedeburr.programs.read_program`). Whatever the bytes, a reader returns its result or
raises InputError naming the file, never another exception (like the APT fuzz in
test_cl_reader.py)."""

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
