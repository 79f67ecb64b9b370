"""benchmarks/RESULTS.md is a reference written by benchmarks/run_all.py, not a journal: no dated
or numbered sections, one section per benchmark file with the command and commit that made it,
and run_all finds exactly the benchmark files there are."""

import importlib.util
import re
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
BENCH = REPO / "benchmarks"
RESULTS = BENCH / "RESULTS.md"

DATED = re.compile(
    r"\b[Ss]ession \d+|\b20\d\d-\d\d-\d\d\b|\b(January|February|March|April|May|June|July|"
    r"August|September|October|November|December) 20\d\d\b|\bfirst round\b", re.IGNORECASE)


def _run_all():
    spec = importlib.util.spec_from_file_location("run_all_under_test", BENCH / "run_all.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def run_all():
    return _run_all()


@pytest.fixture(scope="module")
def sections(run_all):
    return run_all.split_sections(RESULTS.read_text())


def test_run_all_lists_exactly_the_benchmark_files(run_all):
    files = sorted(p.name for p in BENCH.iterdir()
                   if re.fullmatch(r"(bench|study)_\w+\.py", p.name))
    assert sorted(b.name for b in run_all.discover()) == files
    # a benchmark declares both runs as tuples of strings (or gets the documented defaults)
    for b in run_all.discover():
        assert all(isinstance(a, str) for a in b.full_args + b.quick_args), b.name
        assert b.purpose and b.purpose != "(no docstring)", b.name


def test_results_has_no_dated_or_numbered_journal_sections():
    text = RESULTS.read_text()
    hits = [line for line in text.splitlines() if DATED.search(line)]
    assert not hits, hits[:5]
    headings, fenced = [], False  # a benchmark's own output (fenced) may print headings
    for line in text.splitlines():
        fenced ^= line.startswith("```")
        if not fenced and line.startswith("#"):
            headings.append(line)
    assert headings[0] == "# Benchmark results", headings[:1]
    bad = [h for h in headings[1:] if not re.fullmatch(r"## (bench|study)_\w+\.py", h)]
    assert not bad, bad


def test_every_section_is_a_benchmark_with_its_command_and_commit(run_all, sections):
    benches = {b.name: b for b in run_all.discover()}
    assert list(sections) == list(benches)  # one section each, in run_all's order
    for name, text in sections.items():
        assert (BENCH / name).is_file(), name
        b = benches[name]
        commands = {b.command(True), b.command(False)}
        cited = re.findall(r"^- command: `(.+)`$", text, re.MULTILINE)
        assert len(cited) == 1 and cited[0] in commands, (name, cited)
        if "- not run yet" in text:
            continue
        assert re.search(r"^- commit: [0-9a-f]{40}\b", text, re.MULTILINE), name
        mode = re.search(r"^- mode: (quick|full)\b", text, re.MULTILINE)
        assert mode, name
        assert (cited[0] == b.command(True)) or mode.group(1) == "full", name
        assert re.search(r"^- took: \d+ s wall, ", text, re.MULTILINE), name


def test_declarations_are_read_from_the_source_and_defaults_follow_the_docstring(tmp_path,
                                                                                  run_all):
    declared = tmp_path / "bench_declared.py"
    declared.write_text('"""Times a thing.\n\nMore."""\nFULL_ARGS = ("--n", "9")\n'
                        'QUICK_ARGS = ("--n", "1")\nraise SystemExit("never imported")\n')
    b = run_all.read_benchmark(declared)
    assert (b.purpose, b.full_args, b.quick_args) == ("Times a thing.", ("--n", "9"),
                                                      ("--n", "1"))
    assert b.command(True) == "python benchmarks/bench_declared.py --n 1"
    bare = tmp_path / "bench_bare.py"
    bare.write_text('"""A new benchmark\nover two lines."""\nimport argparse\n'
                    'argparse.ArgumentParser().add_argument("--quick")\n')
    b = run_all.read_benchmark(bare)
    assert (b.purpose, b.full_args, b.quick_args) == ("A new benchmark over two lines.", (),
                                                      ("--quick",))
    bad = tmp_path / "bench_bad.py"
    bad.write_text('"""x"""\nFULL_ARGS = "--quick"\n')
    with pytest.raises(ValueError, match="bench_bad.py: FULL_ARGS"):
        run_all.read_benchmark(bad)


def test_sections_round_trip_and_fenced_output_is_not_a_heading(run_all, tmp_path):
    (tmp_path / "bench_a.py").write_text('"""A."""\n')
    (tmp_path / "study_b.py").write_text('"""B."""\n')
    benches = run_all.discover(tmp_path)
    assert [b.name for b in benches] == ["bench_a.py", "study_b.py"]  # bench_ before study_
    body = "## bench_a.py\n\nA.\n\n```text\n## bench_gone.py\nfigure 1.00x\n```\n"
    text = run_all.render(benches, {"bench_a.py": body, "bench_gone.py": "## bench_gone.py\n"})
    back = run_all.split_sections(text)
    assert list(back) == ["bench_a.py", "study_b.py"]  # the vanished benchmark is dropped
    assert back["bench_a.py"] == body and "figure 1.00x" in back["bench_a.py"]
    assert "- not run yet: `python benchmarks/run_all.py --only study_b.py`" in back["study_b.py"]


def test_unknown_name_is_bad_usage_and_nothing_is_written(run_all, tmp_path, capsys):
    out = tmp_path / "RESULTS.md"
    assert run_all.main(["--only", "bench_nonexistent", "--output", str(out)]) == 2
    assert "bench_nonexistent" in capsys.readouterr().err and not out.exists()
    assert run_all.main(["--list"]) == 0
    listed = capsys.readouterr().out
    assert all(f"{b.name}\n" in listed for b in run_all.discover())
