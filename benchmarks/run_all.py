"""Regenerate ``benchmarks/RESULTS.md``: the current figure of every benchmark.

    python benchmarks/run_all.py [--quick] [--only NAME[,NAME...]] [--list] [--timeout S]

A benchmark is any ``bench_*.py`` or ``study_*.py`` file in this folder (found by name, so a new
file is picked up without editing this script). Each declares, as module constants read from
its source (not imported):

* ``FULL_ARGS``: the arguments of its reference run (a tuple of strings; default ``()``);
* ``QUICK_ARGS``: the arguments of a fast run (default ``("--quick",)`` when the script
  mentions ``--quick``, else ``FULL_ARGS``);
* ``PURPOSE``: one paragraph (default: the first paragraph of its docstring).

``{tmp}`` in an argument is replaced by a fresh temporary folder (for outputs that must not land
in the repository). Each benchmark runs in its own process from the repository root with this
tree first on ``PYTHONPATH``; its standard output (its tables, ratios against the baseline it
measures in the same run) becomes its section of RESULTS.md, with its purpose, the exact
command, the mode, the commit (``git rev-parse HEAD``) and its exit status. ``--only`` runs the
named benchmarks and keeps every other section as it stands in the file. The file is written
atomically (a temporary file renamed over it) after each benchmark, so an interrupted run keeps
what it finished. There are no dated sections: the history of every figure is in git
(``git log -p benchmarks/RESULTS.md``).

Exit status: 0 every benchmark run exited 0; 1 one of them failed; 2 bad usage (an unknown
name); 130 interrupted.
"""

from __future__ import annotations

import argparse
import ast
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "RESULTS.md"
PATTERNS = ("bench_*.py", "study_*.py")
HEADING = re.compile(r"^## (\S+\.py)$")
FENCE = "```"

HEADER = """# Benchmark results

The current figure of every benchmark in `benchmarks/`, written by `python benchmarks/run_all.py`
(do not edit by hand; `benchmarks/README.md` says how to run one and how to add one). Each
section gives the benchmark's purpose, the exact command, the mode, the commit it ran on and its
output: its tables, with each ratio taken against a baseline measured in the same run. The
machine is shared (2 cores): compare ratios, not absolute seconds, between sections. The
history of a figure is in git: `git log -p benchmarks/RESULTS.md`.
"""


@dataclass(frozen=True)
class Benchmark:
    """One benchmark script and what run_all needs of it."""

    name: str  # file name, e.g. "bench_plan.py"
    purpose: str
    full_args: tuple[str, ...]
    quick_args: tuple[str, ...]

    def args(self, quick: bool) -> tuple[str, ...]:
        return self.quick_args if quick else self.full_args

    def command(self, quick: bool) -> str:
        return shlex.join(["python", f"benchmarks/{self.name}", *self.args(quick)])


def _constant(tree: ast.Module, name: str):
    for node in tree.body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == name for t in targets) and node.value:
                return ast.literal_eval(node.value)
    return None


def _args(value, path: Path, name: str) -> tuple[str, ...] | None:
    if value is None:
        return None
    if not isinstance(value, (tuple, list)) or not all(isinstance(a, str) for a in value):
        raise ValueError(f"{path}: {name} must be a tuple of strings, got {value!r}")
    return tuple(value)


def read_benchmark(path: Path) -> Benchmark:
    """The declarations of the benchmark at ``path`` (its source parsed, not run)."""
    source = path.read_text()
    tree = ast.parse(source, filename=str(path))
    doc = ast.get_docstring(tree) or ""
    purpose = _constant(tree, "PURPOSE") or " ".join(doc.split("\n\n")[0].split())
    full = _args(_constant(tree, "FULL_ARGS"), path, "FULL_ARGS") or ()
    quick = _args(_constant(tree, "QUICK_ARGS"), path, "QUICK_ARGS")
    if quick is None:
        quick = ("--quick",) if "--quick" in source else full
    return Benchmark(path.name, purpose or "(no docstring)", full, quick)


def discover(folder: Path = HERE) -> list[Benchmark]:
    """Every benchmark in ``folder``, in name order (``bench_*`` before ``study_*``: a study may
    read what a benchmark left, e.g. the plans of bench_verify.py)."""
    paths = [p for pattern in PATTERNS for p in sorted(folder.glob(pattern))]
    return [read_benchmark(p) for p in paths]


def split_sections(text: str) -> dict[str, str]:
    """The sections of an existing RESULTS.md by benchmark file name (fenced output skipped)."""
    sections: dict[str, list[str]] = {}
    current = None
    fenced = False
    for line in text.splitlines():
        if line.startswith(FENCE):
            fenced = not fenced
        match = None if fenced else HEADING.match(line)
        if match:
            current = match.group(1)
            sections[current] = []
        if current is not None:
            sections[current].append(line)
    return {k: "\n".join(v).rstrip() + "\n" for k, v in sections.items()}


def git_commit(bench: str) -> str:
    """HEAD, with a note when the code benchmark ``bench`` runs (the package, the benchmark's
    own file and the helpers of this folder) differs from it."""
    others = [f":!benchmarks/{p.name}" for pattern in PATTERNS for p in HERE.glob(pattern)
              if p.name != bench]
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "drakedeburr", "benchmarks",
             ":!benchmarks/RESULTS.md", ":!benchmarks/README.md", ":!benchmarks/run_all.py",
             *others],
            cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (git not available)"
    return f"{head} (with uncommitted changes to the code)" if dirty else head


def run_one(bench: Benchmark, quick: bool, timeout: float | None) -> tuple[str, bool]:
    """Run ``bench``: its section of RESULTS.md, and whether it exited 0."""
    with tempfile.TemporaryDirectory(prefix=f"run_all_{bench.name[:-3]}_",
                                     ignore_cleanup_errors=True) as tmp:
        return _run_in(bench, quick, timeout, [a.replace("{tmp}", tmp)
                                               for a in bench.args(quick)])


def _run_in(bench: Benchmark, quick: bool, timeout: float | None,
            args: list[str]) -> tuple[str, bool]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env["PYTHONUNBUFFERED"] = "1"
    commit = git_commit(bench.name)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, str(HERE / bench.name), *args], cwd=ROOT,
                              env=env, capture_output=True, text=True, timeout=timeout)
        rc, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired as exc:
        rc = None
        out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        err = f"stopped after the {timeout:.0f} s timeout"
    took = time.perf_counter() - t0
    mode = (f"quick (a fast regeneration; the reference run is `{bench.command(False)}`)"
            if quick and bench.quick_args != bench.full_args else "full")
    status = "exit 0" if rc == 0 else ("timed out" if rc is None else f"exit {rc} (FAILED)")
    lines = [f"## {bench.name}", "", bench.purpose, "",
             f"- command: `{bench.command(quick)}`", f"- mode: {mode}",
             f"- commit: {commit}", f"- took: {took:.0f} s wall, {status}",
             f"- machine: {os.cpu_count()} cores, load average {load:.1f} at the start", "",
             FENCE + "text", out.rstrip(), FENCE]
    if rc != 0:
        tail = "\n".join(err.rstrip().splitlines()[-15:])
        lines += ["", "Last lines of its error output:", "", FENCE + "text", tail, FENCE]
    return "\n".join(lines) + "\n", rc == 0


def placeholder(bench: Benchmark) -> str:
    return (f"## {bench.name}\n\n{bench.purpose}\n\n- command: `{bench.command(False)}`\n"
            f"- not run yet: `python benchmarks/run_all.py --only {bench.name}`\n")


def render(benches: list[Benchmark], sections: dict[str, str]) -> str:
    """The whole file: the header, an index, one section per benchmark (in discovery order;
    sections of benchmarks that no longer exist are dropped)."""
    index = ["| benchmark | purpose |", "|---|---|"]
    for b in benches:
        first = re.split(r"(?<=[.?])\s", b.purpose, maxsplit=1)[0]
        first = first if len(first) <= 110 else first[:107].rsplit(" ", 1)[0] + " ..."
        index.append(f"| [{b.name}](#{b.name.replace('.', '')}) | {first} |")
    body = [sections.get(b.name) or placeholder(b) for b in benches]
    return HEADER + "\n" + "\n".join(index) + "\n\n" + "\n".join(body)


def write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="each benchmark's QUICK_ARGS")
    ap.add_argument("--only", default="", help="comma-separated benchmarks (file name or stem); "
                                               "the other sections are kept")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and their commands")
    ap.add_argument("--timeout", type=float, default=None, help="seconds per benchmark")
    ap.add_argument("--output", default=str(RESULTS), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    benches = discover()
    if args.list:
        for b in benches:
            print(f"{b.name}\n  full:  {b.command(False)}\n  quick: {b.command(True)}")
        return 0
    by_name = {b.name: b for b in benches} | {b.name[:-3]: b for b in benches}
    wanted = [n.strip() for n in args.only.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in by_name]
    if unknown:
        print(f"run_all: unknown benchmark {', '.join(unknown)} (see --list)", file=sys.stderr)
        return 2
    todo = [by_name[n] for n in wanted] if wanted else benches
    out = Path(args.output)
    rc = 0
    try:
        for bench in todo:
            print(f"run_all: {bench.command(args.quick)}", flush=True)
            section, ok = run_one(bench, args.quick, args.timeout)
            rc |= int(not ok)
            # the file as it is now (another run may have written its sections meanwhile)
            sections = split_sections(out.read_text()) if out.exists() else {}
            sections[bench.name] = section
            write_atomic(out, render(benches, sections))
    except KeyboardInterrupt:
        return 130
    return rc


if __name__ == "__main__":
    sys.exit(main())
