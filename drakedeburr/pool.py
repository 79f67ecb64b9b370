"""The process pool every stage shares (the planner's windows, the verifier's distance sweep,
certificate and figures): ``workers`` plain worker processes (:mod:`drakedeburr.pool_worker`:
started with the interpreter, not forked - Drake is not fork-safe - and not through
``multiprocessing``, which would run the caller's main script again in each) fed pickled
``(function, args)`` tasks, while the calling process works too.

:func:`map_tasks` runs tasks from the front here and from the back on the workers (a task a
worker fails or cannot take runs here: the same result); :func:`map_calls` is the same for
short calls on the workers already running; :func:`warm_pool` gives idle workers a task
ahead of time. The workers stay up for later runs of the process (:func:`shutdown_pool`, at
exit); the log records a worker emits are handed back and emitted here. In a worker,
:func:`worker_cell` keeps the caller's cell (built once from its recipe, checked by its
geometry digest) and what a stage builds on it (the planner's checkers, the verifier's pair
scene).

Why hand-written: a process pool that never imports the caller's main module, where the
calling process works too (a worker's start-up, ~2 s of imports and model building, is hidden
behind the first tasks), with each task's log replayed here.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable

__all__ = ["worker_cell", "map_tasks", "map_calls", "warm_pool", "worker_count", "shutdown_pool",
           "running_workers", "logged_call", "replay_records"]

log = logging.getLogger(__name__)

_POOL: dict = {}  # {"workers": [_Worker]}


def worker_count(requested: int | None, n_windows: int) -> int:
    """Processes to plan ``n_windows`` with: ``requested`` (None: ``$DRAKEDEBURR_WORKERS`` if
    set, else the cores this process may use), at most one per window. The variable is for
    runs that already fill the cores with processes of their own (a batch of hubs, a test
    suite on every core): a worker pool there only adds its own cell build (~4 s CPU a hub)."""
    if requested is None and os.environ.get("DRAKEDEBURR_WORKERS"):
        requested = _env_workers(os.environ["DRAKEDEBURR_WORKERS"])
    if requested is None:
        try:
            requested = len(os.sched_getaffinity(0))
        except AttributeError:  # not on Linux
            requested = os.cpu_count() or 1
    return max(1, min(int(requested), n_windows))


def _env_workers(text: str) -> int:
    from drakedeburr.errors import InputError

    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise InputError(f"DRAKEDEBURR_WORKERS={text!r}: a whole number >= 1 is needed")
    return n


class _Records(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.records: list = []

    def emit(self, record: logging.LogRecord) -> None:
        record.msg, record.args = record.getMessage(), None  # picklable, formatted here
        record.exc_info = None
        self.records.append(record)


def logged_call(level: int, fn: Callable, args: tuple):
    """In a worker: (``fn(*args)``, the log records at ``level`` or above it emitted)."""
    root = logging.getLogger()
    handler = _Records()
    handler.setLevel(level)
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(level)
    try:
        return fn(*args), handler.records
    finally:
        root.removeHandler(handler)
        root.setLevel(old_level)


def map_calls(n: int, call: Callable[[int], tuple], workers: int | None = None,
              name: Callable[[int], str] = lambda k: f"task {k}", *,
              here: Callable[[int], object] | None = None) -> list:
    """``fn(*args)`` for each ``call(k) -> (fn, args)`` (``fn`` a module-level function, so a
    worker can import it), ``k = 0..n-1``, by :func:`map_tasks` on the workers *already
    running* and here (``here(k)`` instead, when given: the same value, e.g. with this
    process's own state); the log records a worker emits are emitted here. For short tasks
    (a second each at most): a worker started for them would arrive after they are done.
    -> values in task order."""
    level = logging.getLogger().getEffectiveLevel()
    size = min(worker_count(workers, n), running_workers() + 1)

    def local(k: int):
        if here is not None:
            return here(k)
        fn, args = call(k)
        return fn(*args)

    def remote(k: int) -> tuple:
        fn, args = call(k)
        return logged_call, (level, fn, args)

    def done(k: int, value):
        replay_records(value[1])
        return value[0]

    return map_tasks(n, local, remote, size, done, name)


class _Worker:
    """One worker process (:mod:`drakedeburr.pool_worker`) and its pipes."""

    def __init__(self) -> None:
        import subprocess
        import sys
        from pathlib import Path

        import drakedeburr

        env = dict(os.environ)
        here = str(Path(drakedeburr.__file__).resolve().parent.parent)  # this drakedeburr
        env["PYTHONPATH"] = os.pathsep.join([here] + [p for p in [env.get("PYTHONPATH")] if p])
        env["DRAKEDEBURR_WORKERS"] = "1"  # a worker never starts a pool of its own
        self.proc = subprocess.Popen([sys.executable, "-m", "drakedeburr.pool_worker"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env)
        self.task: int | None = None

    def send(self, fn, args: tuple, task: int) -> None:
        self.send_bytes(_task_bytes(fn, args), task)

    def send_bytes(self, data: bytes, task: int) -> None:
        """A task pickled by :func:`_task_bytes`."""
        self.proc.stdin.write(data)
        self.proc.stdin.flush()
        self.task = task

    def receive(self):
        """("ok", result) or ("error", message); a reply that cannot be read (the process
        died, or was killed while writing it) is an error, and the worker is stopped: its pipe
        may still hold the rest of that reply."""
        import pickle

        self.task = None
        try:
            return pickle.load(self.proc.stdout)
        except Exception as exc:  # EOFError, a truncated pickle, a closed pipe
            self.close(kill=True)
            return "error", f"the worker's reply could not be read ({type(exc).__name__}: {exc})"

    def close(self, kill: bool = False) -> None:
        try:
            if kill:
                self.proc.kill()
            else:
                self.proc.stdin.close()
            self.proc.wait(timeout=None if not kill else 10)
        except (OSError, ValueError):
            pass


def _task_bytes(fn, args: tuple) -> bytes:
    import pickle

    return pickle.dumps((fn, args), protocol=pickle.HIGHEST_PROTOCOL)


def _pool(size: int) -> list[_Worker]:
    """``size`` worker processes (started once, kept for later runs)."""
    import atexit

    workers = _POOL.setdefault("workers", [])
    workers[:] = [w for w in workers if w.proc.poll() is None]
    while len(workers) < size:
        workers.append(_Worker())
    if not _POOL.get("atexit"):
        atexit.register(shutdown_pool)
        _POOL["atexit"] = True
    return workers[:size]


def running_workers() -> int:
    """Worker processes of the pool running now."""
    return sum(w.proc.poll() is None for w in _POOL.get("workers", []))


def shutdown_pool(kill: bool = False) -> None:
    """Stop the worker processes (started again when needed); one still warming up
    (:func:`warm_pool`) is killed, not waited for: it holds nothing but its cache."""
    for w in _POOL.pop("workers", []):
        w.close(kill=kill or w.task == _WARM)


def replay_records(records: list) -> None:
    for rec in records:
        logger = logging.getLogger(rec.name)
        if logger.isEnabledFor(rec.levelno):
            logger.handle(rec)


_WARM = -1  # the task id of a warm-up (map_tasks drops its reply)


def warm_pool(fn, args: tuple, workers: int | None = None, start: bool = True) -> None:
    """Start the pool now (``workers`` as :func:`worker_count` with two tasks) and give each
    idle worker ``fn(*args)`` (build a cell, say), so that a later :func:`map_tasks` finds
    them ready: a worker's start-up (~2 s) then overlaps this process's own work.
    ``start`` False: only the workers already running, none started."""
    size = worker_count(workers, 2) - 1
    for w in _pool(size) if start else _POOL.get("workers", [])[:size]:
        if w.task is None and w.proc.poll() is None:
            w.send(fn, args, _WARM)


def map_tasks(n: int, run_here: Callable[[int], object],
              remote: Callable[[int], tuple] | None, workers: int | None,
              done: Callable[[int, object], object] | None = None,
              name: Callable[[int], str] = lambda k: f"task {k}") -> list:
    """Tasks ``0..n-1``, this process taking them from the front (``run_here(k)``) while
    ``workers - 1`` pool processes take them from the back (``remote(k)`` -> (picklable
    function, args) run there; its value passed through ``done(k, value)`` here). A task a
    worker fails (or cannot be sent) is run here instead, logged by ``name(k)``: the same
    result, since every task's result may depend only on its inputs. ``remote`` None: all
    here, in order. A worker's warm-up (:func:`warm_pool`) still running when the tasks are
    done is not waited for. -> results in task order.

    The workers are fed by a thread of this process (:func:`_feed`), so a worker that
    finishes gets its next task at once, not when this process ends its own task; ``remote``
    and ``done`` run in the calling thread. ``remote(k)`` None: task k runs only here."""
    size = worker_count(workers, n) - 1 if remote is not None else 0
    if size == 0:
        return [run_here(k) for k in range(n)]
    import collections
    import queue
    import threading

    pool = _pool(size)
    sends = [_sendable(remote, k, name) for k in range(n)]  # pickled here, now
    todo, lock = collections.deque(range(n)), threading.Lock()
    replies: queue.Queue = queue.Queue()
    stop = threading.Event()
    feeder = threading.Thread(target=_feed, args=(pool, todo, lock, sends, replies, stop),
                              name="drakedeburr-feed", daemon=True)
    results: dict[int, object] = {}

    def take(block: bool) -> None:  # the workers' replies so far (one at least if block)
        while True:
            try:
                k, status, value = replies.get(block=block, timeout=0.5 if block else None)
            except queue.Empty:
                if not block:
                    return
                if feeder.is_alive() or not replies.empty():
                    continue
                for k in [k for k in range(n) if k not in results]:  # the feeder ended
                    log.warning("%s: no worker reply; running it here", name(k))
                    results[k] = run_here(k)
                return
            if k in results or not 0 <= k < n:  # cannot come from this call: dropped
                log.warning("a worker's reply to no task of this call was dropped")
            elif status == "ok":
                log.debug("%s: done by a worker", name(k))
                results[k] = value if done is None else done(k, value)
            else:
                log.warning("%s: worker failed (%s); running it here", name(k), value)
                results[k] = run_here(k)
            block = False

    feeder.start()
    try:
        while True:
            with lock:
                k = todo.popleft() if todo else None  # this process from the front
            if k is None:
                break
            results[k] = run_here(k)
            take(block=False)
        while len(results) < n:
            take(block=True)
    except BaseException:
        stop.set()
        feeder.join()
        shutdown_pool(kill=True)  # the workers may be busy with tasks nobody waits for
        raise
    stop.set()
    feeder.join()
    return [results[k] for k in range(n)]


def _sendable(remote: Callable[[int], tuple | None], k: int, name) -> bytes | None:
    """Task ``k`` pickled in the calling thread (its arguments as they are now), or None when
    it runs only here (``remote(k)`` None, or it cannot be pickled: logged)."""
    task = remote(k)
    if task is None:
        return None
    try:
        return _task_bytes(*task)
    except Exception as exc:  # not picklable: the caller runs it
        log.warning("%s cannot be sent to a worker (%s); running it here", name(k), exc)
        return None


def _feed(pool: list, todo, lock, sends: list, replies, stop) -> None:
    """The feeder thread of :func:`map_tasks`: gives each idle worker the last task left that
    a worker may run (``todo``, shared with the calling thread under ``lock``; ``sends`` the
    pickled tasks) and puts every reply to a task it sent on ``replies`` as (task, "ok" |
    "error", value); a warm-up's reply is dropped (its failure shows again on a real task).
    Ends when no worker is busy and none can take a task, or on ``stop``. Should it fail, the
    workers busy with its tasks are stopped (their replies would otherwise reach a later
    call) and those tasks reported as errors, so the caller runs them."""
    try:
        _feed_loop(pool, todo, lock, sends, replies, stop)
    except BaseException as exc:
        log.error("the worker feeder failed (%s: %s); the tasks it had sent run here",
                  type(exc).__name__, exc)
        for w in pool:
            if w.task not in (None, _WARM):
                replies.put((w.task, "error", "the worker feeder failed"))
            if w.task is not None:
                w.close(kill=True)
                w.task = None


def _next_sendable(todo, sends: list) -> int | None:
    for k in reversed(todo):
        if sends[k] is not None:
            todo.remove(k)
            return k
    return None


def _feed_loop(pool: list, todo, lock, sends: list, replies, stop) -> None:
    import select

    while not stop.is_set():
        for w in pool:
            if w.task is None and w.proc.poll() is None:
                with lock:
                    k = _next_sendable(todo, sends)
                if k is None:
                    break
                try:
                    w.send_bytes(sends[k], k)
                except OSError as exc:  # the worker is gone: the caller runs the task
                    w.close(kill=True)
                    w.task = None
                    replies.put((k, "error", f"worker unreachable ({exc})"))
        busy = {w.proc.stdout.fileno(): w for w in pool if w.task is not None}
        if not busy:
            return
        ready, _, _ = select.select(list(busy), [], [], 0.05)
        for fd in ready:
            w = busy[fd]
            k = w.task
            status, value = w.receive()
            if k != _WARM:
                replies.put((k, status, value))


def worker_cell(recipe: dict, fingerprint: str, cache: dict, build: Callable) -> tuple:
    """In a worker: (the caller's cell, ``build(cell)``), kept in ``cache`` (one cell at a
    time) and built again when the kept cell's fingerprint is not the caller's (a model
    rewritten since). Raises RuntimeError when even a fresh build differs (the caller then
    runs the task itself). ``fingerprint`` None (a warm-up before the caller has built its
    cell): the kept or fresh cell, unchecked; every task checks it again."""
    from drakedeburr.cell.fingerprint import geometry_digest
    from drakedeburr.cell.station import load_cell

    key = repr(sorted((k, repr(v)) for k, v in recipe.items()))
    got = cache.get(key)
    if got is None or fingerprint not in (None, geometry_digest(got[0])):
        cache.clear()
        cell = load_cell(**recipe)
        if fingerprint not in (None, geometry_digest(cell)):
            raise RuntimeError("the worker's cell differs from the caller's")
        got = cache[key] = (cell, build(cell))
    return got
