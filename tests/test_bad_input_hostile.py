"""Issue 43: hostile and careless input beyond the one-line table of test_bad_input.py.

* bombs (a YAML of nested aliases, an ``arrays.npz`` with a member that decompresses to
  gigabytes, ``/dev/zero`` as a program, a deeply nested YAML) are refused in a child process
  whose peak memory (``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss``, getrusage(2)) stays
  under 1 GB, with one line naming the file and the limit;
* a plan refers to its hub by absolute path and content hash: it verifies from another
  folder, and a changed hub is refused naming plan.json and both hashes;
* an output folder that is (or holds) the working folder is refused before the work; a
  symbolically linked output folder leaves no temporary behind;
* ``verify-all`` with a broken hub among others reports it in one line, no traceback.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import verify_support as vs

from drakedeburr.cli import main
from drakedeburr.errors import InputError

REPO = Path(__file__).resolve().parent.parent
GB = 1 << 30


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> Path:
    from drakedeburr.plan.io import save_plan

    return save_plan(vs.good_plan(), tmp_path_factory.mktemp("hostile") / "plan")


def _child(argv: list[str], cwd: Path) -> tuple[int, str, int]:
    """Run ``drakedeburr argv`` in a child: (exit code, stderr, peak RSS in bytes).

    ``ru_maxrss`` of RUSAGE_CHILDREN is the largest of the waited-for children (kilobytes on
    Linux); a fresh ``python -c`` that runs the child keeps other children out of it."""
    code = ("import resource, subprocess, sys\n"
            "p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
            "sys.stderr.write(p.stderr)\n"
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
            "sys.exit(p.returncode)\n")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    p = subprocess.run([sys.executable, "-c", code, sys.executable, "-m", "drakedeburr", *argv],
                       capture_output=True, text=True, cwd=cwd, env=env, timeout=300)
    return p.returncode, p.stderr, int(p.stdout.split()[-1]) * 1024


def _one_line_refusal(code: int, err: str, *says: str) -> None:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert "Traceback" not in err and len(lines) == 1, lines
    for text in says:
        assert text in lines[0], (text, lines[0])


def _npz_with_member(src: Path, dst: Path, name: str, nbytes: int) -> None:
    """``src`` plus a member ``name`` of ``nbytes`` zeros (a valid .npy; deflated to a few
    MB)."""
    shutil.copyfile(src, dst)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (nbytes // 8,)})
    block = bytes(1 << 22)
    with zipfile.ZipFile(dst, "a", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        with z.open(name, "w", force_zip64=True) as f:
            f.write(header.getvalue())
            for _ in range(nbytes // len(block)):
                f.write(block)


@pytest.mark.parametrize("kind", ["extra-member", "known-name-over-limit"])
def test_npz_bomb_is_refused_from_its_headers(saved, tmp_path, kind):
    """An arrays.npz with a member that decompresses to 300 MB (the issue's had 3 GB in a
    4 MB file): refused naming the member before it is decompressed, memory < 1 GB."""
    plan = tmp_path / "plan"
    shutil.copytree(saved, plan)
    name = "junk.npy" if kind == "extra-member" else "qd.npy"
    _npz_with_member(saved / "arrays.npz", plan / "arrays.npz", name, 300 << 20)
    assert (plan / "arrays.npz").stat().st_size < 8 << 20
    code, err, peak = _child(["verify", "plan"], tmp_path)
    says = ("junk.npy", "not one of the plan arrays") if kind == "extra-member" else (
        "'qd'", "plan arrays limit of 256 MiB")
    _one_line_refusal(code, err, "plan/arrays.npz", *says)
    assert peak < GB, peak
    print(f"peak RSS {peak / (1 << 20):.0f} MiB")


def test_npz_member_whose_header_lies_is_refused(saved, tmp_path):
    """A member whose .npy header promises another shape than its bytes hold."""
    plan = tmp_path / "plan"
    shutil.copytree(saved, plan)
    arrays = dict(np.load(saved / "arrays.npz"))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for k, v in arrays.items():
            b = io.BytesIO()
            np.save(b, v)
            data = b.getvalue()
            if k == "X_WH":  # the header says (4, 4) float64, the bytes are 8 floats short
                data = data[:-64]
            z.writestr(f"{k}.npy", data)
    (plan / "arrays.npz").write_bytes(buf.getvalue())
    with pytest.raises(InputError, match=r"'X_WH'.*does not match"):
        from drakedeburr.plan.io import load_plan

        load_plan(plan)


@pytest.mark.parametrize("bomb", ["aliases", "deep", "dev-zero-program", "dev-zero-mesh"])
def test_bombs_stay_under_1_gb(tmp_path, saved, bomb):
    hub = REPO / "models" / "hubs" / vs.HUB
    if bomb in ("aliases", "deep"):
        folder = tmp_path / "hub"
        folder.mkdir()
        for f in hub.iterdir():
            if f.name != "process.yaml":
                (folder / f.name).symlink_to(f)
        if bomb == "aliases":  # the issue's 680-byte document: 9 levels of 9 aliases
            rows = ["a0: &a0 [" + ", ".join(["lol"] * 9) + "]"]
            rows += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]"
                     for i in range(1, 10)]
            text, says = "\n".join(rows) + "\n", ("alias expansion limit",)
        else:
            text, says = "w1: " + "[" * 100_000 + "]" * 100_000 + "\n", ("depth limit",)
        (folder / "process.yaml").write_text(text)
        argv = ["plan", "--hub", "hub", "-o", "p"]
        says = ("hub/process.yaml", *says)
    elif bomb == "dev-zero-program":
        (tmp_path / "z.mod").symlink_to("/dev/zero")
        shutil.copytree(saved, tmp_path / "plan")
        argv, says = ["verify", "plan", "--program", "z.mod"], ("z.mod", "character device")
    else:
        (tmp_path / "z.stl").symlink_to("/dev/zero")
        argv, says = ["hub", "import", "z.stl", "--out", "hubs"], ("z.stl", "character device")
    code, err, peak = _child(argv, tmp_path)
    _one_line_refusal(code, err, *says)
    assert peak < GB, peak
    print(f"peak RSS {peak / (1 << 20):.0f} MiB")
    assert not (tmp_path / "p").exists() and not (tmp_path / "hubs").exists()


def test_oversized_files_are_refused_naming_the_limit(tmp_path):
    """A sparse 2 GiB 'mesh' and a 100 MiB 'program': refused from their size alone."""
    from drakedeburr._io import READ_LIMITS, read_bounded
    from drakedeburr.hub.mesh_io import load_hub_mesh

    big = tmp_path / "big.stl"
    with open(big, "wb") as f:
        f.truncate(2 * GB)  # sparse: no disk used
    with pytest.raises(InputError, match=r"big.stl: hub mesh is 2 GiB, more than the mesh read "
                                         r"limit of 1 GiB"):
        load_hub_mesh(big)
    prog = tmp_path / "p.mod"
    with open(prog, "wb") as f:
        f.truncate(READ_LIMITS["program"] + 1)
    with pytest.raises(InputError, match="program read limit of 64 MiB"):
        read_bounded(prog, "program file", "program")


# --------------------------------------------------------------------------- hub reference

def _hub_copy(where: Path) -> Path:
    hub = where / "myhub"
    shutil.copytree(REPO / "models" / "hubs" / vs.HUB, hub)
    return hub


def test_plan_refers_to_its_hub_by_absolute_path_and_hash(tmp_path, monkeypatch):
    from drakedeburr.cell.fingerprint import hub_digest
    from drakedeburr.plan.io import load_plan, save_plan

    make = tmp_path / "made_here"
    make.mkdir()
    hub = _hub_copy(make)
    monkeypatch.chdir(make)
    plan = dataclasses.replace(vs.good_plan(), hub="./myhub")  # as `plan --hub ./myhub`
    save_plan(plan, make / "plan")
    doc = json.loads((make / "plan" / "plan.json").read_text())
    assert doc["hub"] == str(hub.resolve()) and Path(doc["hub"]).is_absolute()
    # the hash is of the folder's bytes: recomputed here independently of hub_digest
    h = hashlib.sha256()
    for f in sorted(p for p in hub.rglob("*") if p.is_file() and p.name != "summary.json"):
        data = f.read_bytes()
        h.update(f"{f.relative_to(hub)}\0{len(data)}\0".encode())
        h.update(data)
    assert doc["hub_ref"] == {"path": str(hub.resolve()), "sha256": h.hexdigest()}
    assert hub_digest(hub) == h.hexdigest()
    # from another folder holding its own ./myhub (another hub): the plan's hub is found
    other = tmp_path / "elsewhere"
    other.mkdir()
    decoy = _hub_copy(other)
    (decoy / "hub.yaml").write_text((decoy / "hub.yaml").read_text() + "# another hub\n")
    monkeypatch.chdir(other)
    assert load_plan(make / "plan").hub == str(hub.resolve())
    # the plan's hub edited: refused, naming plan.json and both hashes
    (hub / "hub.yaml").write_text((hub / "hub.yaml").read_text() + "# edited\n")
    with pytest.raises(InputError) as info:
        load_plan(make / "plan")
    msg = str(info.value)
    assert str(make / "plan" / "plan.json") in msg and h.hexdigest() in msg
    assert hub_digest(hub) in msg and hub_digest(hub) != h.hexdigest()
    code = main(["export", str(make / "plan"), "-o", str(other / "x.mod")])
    assert code == 2 and not (other / "x.mod").exists()
    shutil.rmtree(hub)
    with pytest.raises(InputError, match="not there any more"):
        load_plan(make / "plan")


def test_old_plans_without_a_hub_reference_still_load(saved, tmp_path):
    from drakedeburr.plan.io import load_plan

    plan = tmp_path / "plan"
    shutil.copytree(saved, plan)
    doc = json.loads((plan / "plan.json").read_text())
    doc.pop("hub_ref")
    (plan / "plan.json").write_text(json.dumps(doc))
    assert load_plan(plan).hub == vs.HUB


# --------------------------------------------------------------------------- output folders

def test_plan_into_the_working_folder_is_refused_at_once(saved, tmp_path, monkeypatch,
                                                         capsys):
    """``plan -o .`` inside a plan folder (was: "Device or resource busy" after 8 s)."""
    import time

    work = tmp_path / "plan"
    shutil.copytree(saved, work)
    monkeypatch.chdir(work)
    before = sorted(p.name for p in work.iterdir())
    started = time.monotonic()
    for out in (".", str(work), ".."):
        code = main(["plan", "--windows", "0", "-o", out])
        err = capsys.readouterr().err
        assert code == 2 and "Traceback" not in err and err.count("\n") == 1, err
        assert ("working folder" in err) or ("did not write" in err), err
    assert time.monotonic() - started < 5
    assert sorted(p.name for p in work.iterdir()) == before


def test_a_linked_output_folder_is_replaced_and_leaves_no_temporary(saved, tmp_path):
    from drakedeburr.plan.io import load_plan, save_plan

    target = tmp_path / "target"
    shutil.copytree(saved, target)
    before = {p.name: p.read_bytes() for p in target.iterdir()}
    link = tmp_path / "planlink"
    link.symlink_to(target)
    save_plan(load_plan(saved), link)
    assert link.is_dir() and not link.is_symlink()  # replaced, not followed
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before
    assert not [p.name for p in tmp_path.iterdir() if ".tmp" in p.name or ".old" in p.name]


# --------------------------------------------------------------------------- verify-all

def test_verify_all_reports_a_broken_hub_in_one_line(tmp_path):
    """A catalogue with a broken hub: its job fails with one line of log, no traceback
    (was: four full tracebacks); the summary names it; exit 1."""
    cat = tmp_path / "cat"
    (cat / "broken").mkdir(parents=True)
    (cat / "broken" / "hub.yaml").write_text("name: broken\n")  # no model files
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    p = subprocess.run([sys.executable, "-m", "drakedeburr", "verify-all", str(cat), "-o",
                        str(tmp_path / "out"), "--scenario", "tool_in_hand", "--planner",
                        "reference", "--quick"], capture_output=True, text=True, env=env,
                       timeout=300, cwd=tmp_path)
    assert p.returncode == 1, p.stderr
    assert "Traceback" not in p.stderr + p.stdout
    errors = [ln for ln in p.stderr.splitlines() if "job" in ln and "failed" in ln]
    assert len(errors) == 1 and "broken" in errors[0], p.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["rows"][0]["error"] and not summary["passed"]
    assert "ERROR" in p.stdout


def test_docs_list_every_recipe_key_with_its_unit_and_range():
    """docs/plan.md's recipe table is the schema (drakedeburr.config.RECIPE_SCHEMA)."""
    import dataclasses

    from drakedeburr.config import ACCEPTANCE_SCHEMA, RECIPE_SCHEMA, Acceptance, ProcessParameters

    text = (REPO / "docs" / "plan.md").read_text()
    for f in dataclasses.fields(ProcessParameters):
        if f.name.startswith("bounds_"):
            assert f"| `{f.name}` | rad |" in text, f.name
            continue
        key = RECIPE_SCHEMA[f.name]
        assert f"| `{f.name}` | {key.unit} | {key.range_text()} |" in text, f.name
    for f in dataclasses.fields(Acceptance):
        key = ACCEPTANCE_SCHEMA[f.name]
        assert f"| `acceptance: {f.name}` | {key.unit} | {key.range_text()} or null |" in text
    # and the defaults lie inside their ranges (a schema that refused the defaults would be
    # wrong, not strict)
    defaults = ProcessParameters()
    for name, key in RECIPE_SCHEMA.items():
        if hasattr(defaults, name):
            key.check(getattr(defaults, name), "defaults", name)


@pytest.mark.parametrize("name", ["bad name", "x\ny", "semi;colon", "-dash"])
def test_verify_all_refuses_a_catalogue_folder_whose_name_is_not_a_file_name(tmp_path, capsys,
                                                                             name):
    """Each catalogue folder becomes OUT/SCENARIO/<folder>: its name is checked first."""
    cat = tmp_path / "cat"
    shutil.copytree(REPO / "models" / "hubs" / vs.HUB, cat / name, symlinks=True)
    code = main(["verify-all", str(cat), "-o", str(tmp_path / "out"), "--quick"])
    err = capsys.readouterr().err
    assert code == 2 and "hub folder" in err and repr(name) in err, err
    assert err.count("\n") == 1 and not (tmp_path / "out").exists()


def test_a_scheduler_address_where_another_service_answers(tmp_path, capsys):
    """``--scheduler`` naming a port where something else answers (garbage bytes: Dask read a
    length of 3 EiB from them, "internal error: MemoryError"): one line naming the option."""
    import socket
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    port = srv.getsockname()[1]

    def serve():
        while True:
            try:
                conn, _ = srv.accept()
                conn.sendall(b"HTTP/1.1 200 OK\r\n\r\n" + bytes(range(256)) * 64)
                conn.close()
            except OSError:
                return

    threading.Thread(target=serve, daemon=True).start()
    cat = tmp_path / "cat"
    shutil.copytree(REPO / "models" / "hubs" / vs.HUB, cat / vs.HUB, symlinks=True)
    try:
        code = main(["verify-all", str(cat), "-o", str(tmp_path / "out"), "--scheduler",
                     f"tcp://127.0.0.1:{port}", "--quick", "--planner", "reference"])
    finally:
        srv.close()
    err = capsys.readouterr().err
    assert code == 2 and "internal error" not in err, err
    assert f"--scheduler tcp://127.0.0.1:{port}" in err and "no Dask scheduler" in err
    assert err.count("\n") == 1


def test_an_error_line_quoting_a_huge_input_is_cut_short(monkeypatch, capsys):
    """The issue's alias document gave a 5.8 MB "one line"; any message is cut at
    cli.MAX_LINE characters."""
    from drakedeburr import cli
    from drakedeburr.laser import commands

    def huge(args):
        raise InputError("f.yaml: " + "lol, " * 1_000_000)

    monkeypatch.setattr(commands, "_run_tool", huge)
    code = main(["laser", "tool"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "f.yaml" in err
    assert len(err) <= cli.MAX_LINE + 100 and "cut short" in err


def test_hub_edges_npz_bomb_is_refused_from_its_headers(tmp_path):
    """A hub folder whose edges.npz carries a window loop that decompresses to 300 MB."""
    from drakedeburr.hub.model import load_hub

    hub = tmp_path / "hub"
    shutil.copytree(REPO / "models" / "hubs" / vs.HUB, hub)
    _npz_with_member(hub / "edges.npz", tmp_path / "e.npz", "w9_p_HE.npy", 300 << 20)
    shutil.move(tmp_path / "e.npz", hub / "edges.npz")
    with pytest.raises(InputError, match=r"edges.npz: member 'w9_p_HE' takes the arrays past "
                                         r"the hub edges limit of 256 MiB"):
        load_hub(hub)
    assert len(load_hub(vs.HUB).windows) == 5  # the bundled hub's own edges pass the check
