"""Fillet repair (drakedeburr.plan.fillets, on by default): where the cut slows below the feed
band, the feed program's tool orientation holds the feed where it can; re-checked by the
independent verifier, against the same window planned without it."""

import numpy as np
import pytest

import drakedeburr.plan.fillets as mut
from drakedeburr.config import load_config
from drakedeburr.plan.planner import PlanOptions, plan_hub
from drakedeburr.resources import hub_names

pytestmark = pytest.mark.skipif(not hub_names(), reason="no bundled hub models")


def test_slow_stretches_keep_off_the_ends_and_merge_close_runs():
    s = np.linspace(0.0, 0.2, 2001)  # 0.1 mm samples
    v = np.full_like(s, 0.15)
    v[s < 0.004] = 0.05  # the ramp from rest: not a fillet
    v[(s > 0.050) & (s < 0.060)] = 0.08
    v[(s > 0.065) & (s < 0.070)] = 0.03  # 5 mm after the first run: the same fillet
    v[(s > 0.120) & (s < 0.125)] = 0.10
    runs = mut.slow_stretches(s, v, 0.1425)
    assert len(runs) == 2
    (a0, b0, c0), (a1, b1, c1) = runs
    assert s[a0] > 0.050 and s[b0] < 0.070 and 0.065 < s[c0] < 0.070
    assert 0.120 < s[a1] and s[b1] < 0.125


def test_fillet_repair_holds_the_feed_where_it_says_and_still_passes_the_verifier():
    """h5_straight window 0, tool in hand, real chain: with the repair (the default) more of the
    cut is in the band and it is no slower, the planner leaves no failure record, every slow
    stretch it reports as held and kept is in the band by the verifier's own reading (its
    dense samples of the timed trajectory), one kept under the feed (FilletOptions.slower)
    reports a speed held above the cut's slowest there, the planner's bound is at least the
    measured share, and the verifier passes every required item, the tcp_speed_band item
    showing the bound."""
    from drakedeburr.verify.checks import config_for_plan, verify_plan

    plans = [plan_hub(load_config("tool_in_hand", "h5_straight"), source="toolpath",
                      options=PlanOptions(windows=(0,), fillets=f, workers=1))
             for f in (None, mut.FilletOptions())]
    assert all(p.failures == () for p in plans)
    before, after = (p.meta["windows"][0] for p in plans)
    assert before["speed_in_band_bound"] is None
    assert after["speed_in_band_fraction"] > before["speed_in_band_fraction"] + 0.03
    assert after["cut_seconds"] <= before["cut_seconds"] + 1e-3
    kept = [f for f in after["fillets"] if f["kept"]]
    held = [f for f in kept if f["held"]]
    assert held
    v_g = load_config("tool_in_hand", "h5_straight").process.grinding_speed
    for f in kept:  # held at the feed, or (FilletOptions.slower) faster than before, under it
        if f["held"]:
            assert f["held_mps"] == pytest.approx(mut.FilletOptions().speed_share * v_g)
        else:
            assert f["slowest_mps"] < f["held_mps"] < v_g
    assert after["speed_in_band_bound"] >= after["speed_in_band_fraction"]
    report = verify_plan(plans[1], config_for_plan(plans[1]), expected_windows=[0])
    assert report.passed, report.failed
    assert report.item("cone").passed and report.item("clearance").value >= 2e-3
    band = report.item("tcp_speed_band")
    assert band.value > before["speed_in_band_fraction"]
    assert "planner's own figure" in band.detail
    w0 = band.per_window[0]
    assert w0["planner_bound_in_band"] == pytest.approx(after["speed_in_band_bound"])
    for f in held:  # the verifier finds no slow stretch inside a held one
        for st in w0["slow_stretches"]:
            assert st["to_m"] <= f["from_m"] + 1e-3 or st["from_m"] >= f["to_m"] - 1e-3, (f, st)
