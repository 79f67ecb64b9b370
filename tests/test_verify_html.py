"""report.html: self-contained, renders in headless Chromium without console errors, plots
present. Needs the Debian packages chromium + chromium-driver and selenium (PyPI); without
them the browser test fails (set DRAKEDEBURR_SKIP_BROWSER_TEST=1 to skip it locally)."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest
import verify_support as vs

import drakedeburr.verify.html as mut

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")


@pytest.fixture(scope="module")
def report_file(tmp_path_factory):
    plan = vs.good_plan()
    report = vs.good_report()
    cell, hub = vs.cell_and_hub()
    replay = mut.meshcat_replay_html(plan, cell, hub, max_frames=120)
    path = tmp_path_factory.mktemp("html") / "report.html"
    mut.write_report_html(report, path, replay_html=replay)
    return path, report


def test_html_is_self_contained(report_file):
    path, report = report_file
    text = path.read_text()
    assert text.startswith("<!DOCTYPE html>")
    for key in ("theta", "joints", "speed", "clearance", "deviation"):
        assert f'id="plot-{key}"><svg' in text
    assert text.count('class="item"') == len(report.items)
    assert 'iframe id="replay"' in text and "srcdoc=" in text
    # one row per slow stretch of the speed band (the good plan: each cut's start and end)
    stretches = sum(len(i["slow_stretches"])
                    for i in report.item("tcp_speed_band").per_window.values())
    table = text.split('id="slow-stretches"')[1].split("</table>")[0]
    assert stretches >= 2 and table.count("<tr><td>") == stretches
    # nothing fetched from outside the file: no http(s) src/href attributes
    for attr in ('src="http', "src='http", 'href="http', "href='http"):
        assert attr not in text.split('srcdoc="')[0]


def test_html_renders_in_headless_chromium(report_file):
    # CI must run this test: missing tools are a failure, unless explicitly allowed
    if CHROMIUM is None or DRIVER is None:
        if os.environ.get("DRAKEDEBURR_SKIP_BROWSER_TEST"):
            pytest.skip("DRAKEDEBURR_SKIP_BROWSER_TEST set and no chromium/chromedriver")
        pytest.fail("needs the Debian packages chromium and chromium-driver "
                    "(apt-get install -y chromium chromium-driver)")
    try:
        from selenium import webdriver
    except ImportError:
        pytest.fail("needs selenium from PyPI (pip install 'drakedeburr[dev]')")
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    path, report = report_file
    profile = tempfile.mkdtemp(prefix="drakedeburr-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                 f"--user-data-dir={profile}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    try:
        driver.set_page_load_timeout(120)
        driver.get(Path(path).resolve().as_uri())
        assert "verification" in driver.title
        rows = driver.find_elements(By.CSS_SELECTOR, "#checks tr.item")
        assert len(rows) == len(report.items)
        for key in ("theta", "joints", "speed", "clearance", "deviation"):
            svg = driver.find_element(By.CSS_SELECTOR, f"#plot-{key} svg")
            size = svg.size
            assert size["width"] > 100 and size["height"] > 50, (key, size)
        frame = driver.find_element(By.ID, "replay")
        assert frame.size["height"] > 100
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
        # control: the same probe does see a console error
        bad = Path(profile) / "bad.html"
        bad.write_text("<!DOCTYPE html><html><body><script>throw new Error('probe')"
                       "</script></body></html>")
        driver.get(bad.as_uri())
        assert any("probe" in e["message"] for e in driver.get_log("browser"))
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def test_envelope_keeps_extremes():
    import numpy as np

    rng = np.random.default_rng(0)
    x = np.arange(50000.0)
    y = rng.normal(size=50000)
    y[12345] = 40.0
    y[40000:40010] = np.nan
    xe, ye = mut._envelope(x, y, n=500)
    assert len(xe) <= 1000
    assert np.nanmax(ye) == 40.0 and np.nanmin(ye) == np.nanmin(y)
    assert np.all(np.diff(xe) > 0)


def _envelope_by_bins(x, y, n):
    """A second implementation: bin by bin, the first minimum and maximum (NaN-aware)."""
    import numpy as np

    if len(x) <= 2 * n:
        return x, y
    edges = np.linspace(0, len(x), n + 1).astype(int)
    xs, ys = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        seg = y[a:b]
        if not np.isfinite(seg).any():
            xs.append(x[a])
            ys.append(np.nan)
            continue
        for k in sorted({int(np.nanargmin(seg)), int(np.nanargmax(seg))}):
            xs.append(x[a + k])
            ys.append(seg[k])
    return np.asarray(xs), np.asarray(ys)


def test_envelope_equals_a_bin_by_bin_reading():
    """Ties (rounded values), NaN runs longer than a bin, +-inf values, bins of 2 samples
    (the fewest the binning makes): the same points as the bin-by-bin reading."""
    import numpy as np

    rng = np.random.default_rng(1)
    for trial in range(24):
        n = int(rng.choice([3, 50, 2000]))
        n_pts = int(rng.integers(2 * n + 1, max(4 * n, 30000)))
        x = np.sort(rng.uniform(0.0, 100.0, n_pts))
        y = rng.normal(size=n_pts)
        if trial % 3 == 0:
            y = np.round(y, 1)
        if trial % 2 == 0:
            y[rng.uniform(size=n_pts) < 0.3] = np.nan
            a = int(rng.integers(0, n_pts))
            y[a:a + 300] = np.nan
        if trial % 4 == 1:
            y[rng.uniform(size=n_pts) < 0.05] = np.inf
            y[rng.uniform(size=n_pts) < 0.05] = -np.inf
        xe, ye = mut._envelope(x, y, n=n)
        assert len(xe) < n_pts  # the binned path, not the short series' pass-through
        xr, yr = _envelope_by_bins(x, y, n)
        np.testing.assert_array_equal(xe, xr)
        np.testing.assert_array_equal(ye, yr)


def test_figures_drawn_on_a_worker_are_the_figures_drawn_here(report_file, caplog,
                                                            monkeypatch):
    """With a pool worker running, the report's figures are drawn there while this process
    records the replay: the same SVG text as drawn here (deterministic, no date). Without a
    running worker they are drawn here and no worker is started for them."""
    import logging
    import time

    from drakedeburr import pool as parallel

    replay_here = mut.meshcat_replay_html

    def replay_once_sent(*args, **kwargs):
        # the replay (this process's task) starts only once the feeder thread has handed the
        # figures to the worker, so that this process never takes them first: the test does
        # not depend on how the interpreter slices the two threads
        deadline = time.monotonic() + 20.0
        while (parallel.running_workers() and time.monotonic() < deadline
               and all(w.task is None for w in parallel._POOL.get("workers", []))):
            time.sleep(0.005)
        return replay_here(*args, **kwargs)

    monkeypatch.setattr(mut, "meshcat_replay_html", replay_once_sent)
    _, report = report_file
    here = mut.report_figures(report)
    assert list(here) == ["theta", "joints", "speed", "clearance", "deviation"]
    assert all("<dc:date>" not in svg for svg in here.values())
    plan = vs.good_plan()
    cell, _ = vs.cell_and_hub()
    parallel.shutdown_pool(kill=True)
    try:
        parallel._pool(1)
        with caplog.at_level(logging.DEBUG, logger="drakedeburr.pool"):
            figs, replay = mut.figures_and_replay(report, plan, cell, workers=2)
    finally:
        parallel.shutdown_pool(kill=True)
    assert "the report's figures: done by a worker" in caplog.text
    assert figs == here
    assert replay is not None and "<html" in replay[:500].lower()
    figs, replay = mut.figures_and_replay(report, plan, cell, workers=2)
    assert figs == here and parallel.running_workers() == 0
