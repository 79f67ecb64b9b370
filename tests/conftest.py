import logging
import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("DRAKEDEBURR_TEST_MODE", "1")

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
