"""Verify every hub model of a catalogue, in parallel processes or on a Dask cluster.

One job = (scenario, hub): plan the hub (the planner's ``plan_hub``, or the verifier's own
reference plan), verify it, write ``<out>/<scenario>/<hub>/report.json`` and return one summary
row. Jobs run in a ``concurrent.futures.ProcessPoolExecutor`` (spawned processes: Drake is not
fork-safe) or, given a scheduler address, on a ``dask.distributed`` cluster. The summary is
written as ``summary.json`` and ``summary.md``.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from drakedeburr._io import atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.viz.scene import collect_here

__all__ = ["BatchJob", "JobSettings", "hub_folders", "make_plan", "run_job", "verify_all",
           "summary_markdown"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class JobSettings:
    """How each job of a batch plans and verifies its hub.

    Attributes:
        planner: "plan_hub" (the planning stage) or "reference" (verify.synthetic).
        windows: windows to plan and expect (None: all).
        quick: coarse sampling (2 mm / 0.1 s): a smoke test, not a certificate.
        html: also write ``report.html`` (without the Meshcat replay).
        grinding_speed: override of the process speed [m/s] (None: the hub's recipe).
        keep_failed_plans: write the plan folder (``<out_dir>/plan``) of a hub that fails, to
            look into it afterwards.
    """

    planner: str = "plan_hub"
    windows: tuple[int, ...] | None = None
    quick: bool = False
    html: bool = False
    grinding_speed: float | None = None
    keep_failed_plans: bool = False


@dataclass(frozen=True)
class BatchJob:
    """One (scenario, hub) verification.

    Attributes:
        scenario: bundled scenario name or path.
        hub: hub folder (or bundled name).
        out_dir: where ``report.json`` (and optionally ``report.html``) go.
        settings: planner, windows, sampling, outputs (:class:`JobSettings`).
        one_process: plan and verify in the process running the job, no pool of worker
            processes (sets ``$DRAKEDEBURR_WORKERS`` to 1 there: a cluster's worker runs
            several jobs at once, and a pool shared by their threads would mix their tasks).
        robot: the arm (``--robot`` NAME or file); None: the scenario's own, or the first arm
            rated for what it carries in this cell (:func:`drakedeburr.cell.loads.
            arm_or_rated_default`, as ``plan``/``verify`` choose); the row records it.
    """

    scenario: str
    hub: str
    out_dir: str
    settings: JobSettings = JobSettings()
    extra: dict = field(default_factory=dict)
    one_process: bool = False
    robot: str | None = None


def hub_folders(root: str | Path) -> list[Path]:
    """Hub model folders (holding ``hub.yaml``) directly under ``root``, sorted by name."""
    root = Path(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: no such hub catalogue folder")
    hubs = sorted(p for p in root.iterdir() if (p / "hub.yaml").is_file())
    if not hubs:
        raise InputError(f"{root}: no hub model folders (*/hub.yaml)")
    return hubs


def make_plan(config, planner: str, windows, progress=None):
    """Plan a hub with the chosen planner (used by the CLI and the batch jobs)."""
    if planner == "reference":
        from drakedeburr.verify.synthetic import reference_plan

        return reference_plan(config.scenario, config.hub, windows, params=config.process,
                              progress=progress)
    if planner == "plan_hub":
        try:
            from drakedeburr.plan.planner import PlanOptions, plan_hub
        except ImportError as exc:
            raise InputError("the planning stage (drakedeburr.plan.planner.plan_hub) is not "
                             "available; use --planner reference") from exc
        options = PlanOptions(windows=tuple(windows) if windows else None)
        return plan_hub(config, options=options, progress=progress)
    raise InputError(f"unknown planner {planner!r} (plan_hub or reference)")


_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def run_job(job: BatchJob) -> dict:
    """Plan + verify one hub; never raises (errors become a row with ``error``)."""
    from drakedeburr.verify.checks import QUICK_SAMPLING, verify_plan
    from drakedeburr.verify.report import write_report_json

    started = time.perf_counter()
    row = {"scenario": Path(job.scenario).stem, "hub": Path(job.hub).name, "passed": False,
           "failed": [], "advisory_failed": [], "error": None}
    try:
        if job.one_process:
            import os

            os.environ["DRAKEDEBURR_WORKERS"] = "1"  # for every job this process runs
        from drakedeburr.cell.loads import arm_or_rated_default
        from drakedeburr.config import default_tolerances, load_config

        js = job.settings
        tol = default_tolerances(**QUICK_SAMPLING) if js.quick else None
        # no robot named: the scenario's arm, or one rated for what it carries (as verify/plan)
        robot = arm_or_rated_default(job.robot, job.scenario, job.hub)
        row["robot"] = robot
        config = load_config(job.scenario, job.hub, tolerances=tol, robot=robot,
                             grinding_speed=js.grinding_speed)
        t0 = time.perf_counter()
        plan = make_plan(config, js.planner, js.windows)
        row["plan_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        report = verify_plan(plan, config, expected_windows=js.windows)
        row["verify_s"] = time.perf_counter() - t0
        out = Path(job.out_dir)
        write_report_json(report, out / "report.json")
        if js.html:
            from drakedeburr.verify.html import write_report_html

            write_report_html(report, out / "report.html")
        if js.keep_failed_plans and not report.passed:
            from drakedeburr.plan.io import save_plan

            save_plan(plan, out / "plan")
        row.update(failure_kinds=sorted({f.kind for f in plan.failures}),
                   failure_notes=[str(f) for f in plan.failures[:5]])
        row.update(passed=report.passed, failed=report.failed,
                   advisory_failed=report.advisory_failed,
                   cycle_s=plan.trajectory.duration, samples=report.settings["samples"],
                   report=str(out / "report.json"))
    except Exception as exc:  # a batch reports every hub; one failure must not stop the rest
        # one line per failed job; its traceback only at debug level (-vv)
        text = " ".join(str(exc).split())
        name = "" if isinstance(exc, (InputError, OSError)) else f"{type(exc).__name__}: "
        log.error("job %s / %s failed: %s%s", job.scenario, job.hub, name, text)
        log.debug("job %s / %s: traceback", job.scenario, job.hub, exc_info=True)
        row["error"] = f"{type(exc).__name__}: {text}"
    row["elapsed_s"] = time.perf_counter() - started
    return row


def verify_all(
    hubs: Sequence[str | Path] | str | Path,
    out_dir: str | Path,
    *,
    scenarios: Sequence[str] = ("tool_in_hand", "workpiece_in_hand"),
    workers: int = 1,
    scheduler: str | object | None = None,
    settings: JobSettings = JobSettings(),
    progress: Callable[[int, int, str], None] | None = None,
) -> dict:
    """Verify every (scenario, hub) and write ``summary.json`` / ``summary.md`` in ``out_dir``.

    Args:
        hubs: a catalogue folder (every ``*/hub.yaml`` below it) or a list of hub folders/names.
        out_dir: output folder; reports go to ``<out_dir>/<scenario>/<hub>/``.
        scenarios: cells to verify each hub in.
        workers: processes on this machine (1 = in this process, no pool).
        scheduler: a Dask scheduler address (``tcp://host:8786``) or a ``distributed.Client``;
            when given, ``workers`` is ignored and the cluster runs the jobs.
        settings: planner, windows, sampling, outputs of every job (:class:`JobSettings`).
        progress: callback (done, total, label).

    Returns:
        The summary: ``{"passed": bool, "rows": [...], "elapsed_s": float, "executor": str}``.
    """
    if isinstance(hubs, (str, Path)):
        hub_list = [str(p) for p in hub_folders(hubs)]
    else:
        hub_list = [str(h) for h in hubs]
    out_dir = Path(out_dir)
    if settings.windows is not None:
        settings = replace(settings, windows=tuple(settings.windows) or None)
    jobs = [BatchJob(scenario=s, hub=h, out_dir=str(out_dir / Path(s).stem / Path(h).name),
                     settings=settings)
            for s in scenarios for h in hub_list]
    started = time.perf_counter()
    rows: list[dict] = []

    def done(row):
        rows.append(row)
        if progress is not None:
            progress(len(rows), len(jobs), f"{row['scenario']}/{row['hub']}")

    if scheduler is not None:
        from distributed import Client, as_completed

        collect_here()  # no Meshcat may be left for the helper threads to free

        client = scheduler if isinstance(scheduler, Client) else _connect(Client, scheduler)
        try:
            futures = client.map(run_job, [replace(j, one_process=True) for j in jobs],
                                 pure=False)
            for fut in as_completed(futures):
                done(fut.result())
        finally:
            if client is not scheduler:
                client.close()
        executor = "dask"
    elif workers > 1:
        collect_here()  # no Meshcat may be left for the helper threads to free
        import multiprocessing
        import os
        from concurrent.futures import ProcessPoolExecutor, as_completed

        ctx = multiprocessing.get_context("spawn")
        # one BLAS/OpenMP thread and one window planner per worker: the workers are the
        # parallelism (nested threads or window pools oversubscribe the cores); spawned
        # children inherit the environment at start
        saved = {v: os.environ.get(v) for v in (*_THREAD_VARS, "DRAKEDEBURR_WORKERS")}
        os.environ.update({v: "1" for v in saved})
        try:
            with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                for fut in as_completed([pool.submit(run_job, j) for j in jobs]):
                    done(fut.result())
        finally:
            for v, old in saved.items():
                if old is None:
                    os.environ.pop(v, None)
                else:
                    os.environ[v] = old
        executor = f"processes({workers})"
    else:
        for j in jobs:
            done(run_job(j))
        executor = "serial"
    rows.sort(key=lambda r: (r["scenario"], r["hub"]))
    summary = {"passed": all(r["passed"] for r in rows), "rows": rows,
               "elapsed_s": time.perf_counter() - started, "executor": executor,
               "jobs": len(jobs)}
    atomic_write_text(out_dir / "summary.json", json.dumps(summary, indent=2, sort_keys=True))
    atomic_write_text(out_dir / "summary.md", summary_markdown(summary))
    return summary


def _connect(Client, address: str):
    """A Dask client of the scheduler at ``address``; anything that is not one (nothing
    listening, another service answering with bytes Dask cannot read) is an InputError naming
    the address, after at most 10 s."""
    try:
        return Client(address, timeout=10)
    except Exception as exc:  # OSError, TimeoutError, a garbled reply (seen: MemoryError)
        text = " ".join(str(exc).split())[:160]
        raise InputError(f"--scheduler {address}: no Dask scheduler there "
                         f"({type(exc).__name__}: {text})") from None


def summary_markdown(summary: dict) -> str:
    """The summary as a Markdown table."""
    lines = ["| scenario | hub | verdict | failed checks | advisory misses | cycle [s] | "
             "plan [s] | verify [s] |", "|---|---|---|---|---|---|---|---|"]
    for r in summary["rows"]:
        verdict = "ERROR" if r.get("error") else ("PASS" if r["passed"] else "FAIL")
        failed = r.get("error") or ", ".join(r["failed"]) or "-"
        lines.append(
            f"| {r['scenario']} | {r['hub']} | {verdict} | {failed} | "
            f"{', '.join(r.get('advisory_failed', [])) or '-'} | "
            f"{r.get('cycle_s', float('nan')):.2f} | {r.get('plan_s', float('nan')):.1f} | "
            f"{r.get('verify_s', float('nan')):.1f} |")
    lines.append("")
    lines.append(f"{summary['jobs']} job(s), executor {summary['executor']}, "
                 f"{summary['elapsed_s']:.1f} s; overall "
                 f"{'PASS' if summary['passed'] else 'FAIL'}")
    return "\n".join(lines) + "\n"
