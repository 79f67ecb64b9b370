"""Shared by the worker-pool tests: wait for what a worker does, with a deadline."""

from __future__ import annotations

import time
from collections.abc import Callable


def wait_until(done: Callable[[], bool], what: str, timeout: float = 60.0,
               poll: float = 0.02) -> None:
    """Return once ``done()`` is true; fail the test with ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while not done():
        assert time.monotonic() < deadline, what
        time.sleep(poll)
