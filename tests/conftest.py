import logging
import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("DRAKEDEBURR_TEST_MODE", "1")
# one process per test: the suite already fills the cores (pytest -n auto), and a window or
# sweep worker pool there only adds its own model building; the pools are tested with
# explicit worker counts (test_plan_parallel, test_verify_distances)
os.environ.setdefault("DRAKEDEBURR_WORKERS", "1")

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def extdata() -> Path:
    """../shared/extdata (third-party reference files). Required: CI clones with shared/ beside."""
    from drakedeburr.resources import extdata_dir

    path = extdata_dir()
    if path is None:
        pytest.fail("../shared/extdata not found next to the checkout")
    return path


@pytest.fixture(autouse=True)
def _quiet_logs(caplog):
    caplog.set_level(logging.INFO, logger="drakedeburr")


@pytest.fixture(autouse=True, scope="module")
def _collect_cycles_on_main_thread():
    """Free each module's leftover Drake objects on the main thread.

    A Drake Meshcat left in a reference cycle (any diagram with a MeshcatVisualizer) aborts the
    whole test process if the cycle collector happens to run on another thread (a later test's
    process-pool manager thread): ``meshcat.cc: IsThread(main_thread_id_) failed``.
    """
    yield
    from drakedeburr.viz.scene import collect_here

    collect_here()


def pytest_collection_modifyitems(config, items):
    """Tests marked slow run first (a stable sort: the rest keep their order). On several
    workers (``pytest -n auto``) the longest tests then start together at the beginning instead
    of one of them ending the run alone (measured: the last whole-hub plan, 185 s, ran by itself
    for the last ~10 min of a 16 min run)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
