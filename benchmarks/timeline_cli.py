"""Where a CLI run spends its wall time: ``PYTHONPATH=. python benchmarks/timeline_cli.py
verify PLAN_FOLDER`` (any ``drakedeburr`` arguments).

Runs the command in this process with wall-clock marks around its stage functions (start
and duration of each call, seconds since this script started) and prints them in start
order; the command's own output is hidden. Work done by the pool's worker processes shows
only as the time this process waits for it. Not a ``bench_*`` script (``run_all.py`` does not
run it): it needs the arguments of the run to look at.
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import io
import sys
import time

T0 = time.perf_counter()

#: (module, function) timed; nested ones show inside their callers' spans. A module that
#: binds a timed function at its import is listed after that function's own module.
STAGES = [
    ("drakedeburr.verify.registry", "run_checks"),
    ("drakedeburr.plan.io", "load_plan"),
    ("drakedeburr.cell.station", "load_plan_cell"),
    ("drakedeburr.verify.checks", "verify_plan"),
    ("drakedeburr.verify.distances", "measure_samples"),
    ("drakedeburr.verify.distances", "pair_scene_of"),
    ("drakedeburr.verify.sweep", "sweep"),
    ("drakedeburr.verify.certificate", "certify_alongside"),
    ("drakedeburr.verify.html", "write_report_files"),
    ("drakedeburr.verify.html", "meshcat_replay_html"),
    ("drakedeburr.verify.html", "report_figures"),
    ("drakedeburr.plan.planner", "window_targets_for_hub"),
    ("drakedeburr.plan.placement", "place_hub"),
    ("drakedeburr.plan.parallel", "plan_all_windows"),
    ("drakedeburr.plan.window", "plan_window"),
]


def _timed(marks: list, module: str, name: str) -> None:
    mod = importlib.import_module(module)
    fn = getattr(mod, name)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            marks.append((start - T0, time.perf_counter() - start, f"{module}.{name}"))

    setattr(mod, name, wrapper)


def main(argv: list[str]) -> int:
    from drakedeburr import cli

    marks: list = []
    imported = time.perf_counter() - T0
    for module, name in STAGES:
        _timed(marks, module, name)
    setup = time.perf_counter() - T0
    code = 0
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code
    total = time.perf_counter() - T0
    print(f"imports of the cli {imported:.2f} s; of the timed stages' modules "
          f"{setup - imported:.2f} s (a CLI run imports them too)")
    print("start s   took s   stage")
    for start, took, what in sorted(marks):
        print(f"{start:7.2f}  {took:7.2f}   {what}")
    print(f"total {total:.2f} s, exit {code}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
