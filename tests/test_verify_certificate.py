"""The continuous clearance certificate: it catches a graze between two samples that sampling
misses, and on good plans it is at most every distance read and close to a dense brute-force
reading (both cells)."""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest
import verify_support as vs

import drakedeburr.verify.certificate as mut
from drakedeburr.verify import faults
from drakedeburr.verify.checks_distance import clearance, clearance_certificate
from drakedeburr.verify.distances import DistanceProbe
from drakedeburr.verify.sampling import sample_plan


def _clearance(probe, q) -> float:
    return probe.measure(q).clearance


#: how far below the limit the graze goes [m]
GRAZE = 0.1e-3


@functools.cache
def _grazing_case():
    """The good plan with the tool pushed toward the hub and back between two samples (of the
    coarse smoke-test sampling: one every 2 mm of tool travel) next to its closest approach,
    until the burr shank comes GRAZE closer than the limit (``faults.graze_between_samples``;
    what it did is checked below with a dense reading of its own)."""
    cell, hub = vs.cell_and_hub()
    config = vs.config(**vs.COARSE)
    t_near = vs.good_report().item("clearance").time
    bumped, (ta, tb) = faults.graze_between_samples(vs.good_plan(), cell, config.tolerances,
                                                    t_near, GRAZE)
    sp = sample_plan(bumped, config, cell=cell, hub_model=hub, expected_windows=list(vs.WINDOWS))
    return sp, config, (ta, tb), DistanceProbe(cell, 0.02)


def test_certificate_catches_a_graze_between_two_samples():
    sp, config, (ta, tb), probe = _grazing_case()
    t = sp.samples.t
    # the premise: no sample inside the bumped piece, and it really grazes the hub
    assert not np.any((t > ta + 1e-12) & (t < tb - 1e-12))
    assert np.any(np.isclose(t, ta)) and np.any(np.isclose(t, tb))
    dense = [_clearance(probe, sp.plan.trajectory.value(x)) for x in np.linspace(ta, tb, 41)]
    limit = config.tolerances.min_clearance
    assert min(dense) < limit - 0.5 * GRAZE
    # sampling alone misses it ...
    sampled = clearance(sp, config)
    assert sampled.passed and sampled.value >= config.tolerances.min_clearance
    # ... the certificate catches it, with a reading between the two samples
    item = clearance_certificate(sp, config)
    cert = sp.distances.certificate.clearance
    assert not item.passed and item.value < config.tolerances.min_clearance
    assert ta < cert.observed_time < tb and cert.observed < limit - 0.5 * GRAZE
    assert cert.certified <= min(dense) + 1e-12
    assert "between the samples" in item.detail and "burr_shank" in item.detail


@functools.cache
def _good_case(scenario: str = vs.SCENARIO):
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub.model import load_hub
    from drakedeburr.verify.synthetic import reference_plan

    if scenario == vs.SCENARIO:
        cell, hub = vs.cell_and_hub()
        plan, windows, sampling = vs.good_plan(), list(vs.WINDOWS), {}
    else:
        cell, hub = load_cell(scenario, vs.HUB), load_hub(vs.HUB)
        windows = [0]
        plan = reference_plan(scenario, vs.HUB, windows, params=vs.PARAMS)
        sampling = vs.COARSE
    config = replace(vs.config(**sampling), scenario=scenario)
    sp = sample_plan(plan, config, cell=cell, hub_model=hub, expected_windows=windows)
    return sp, config, cell


@pytest.mark.parametrize("scenario", [vs.SCENARIO, "workpiece_in_hand"])
def test_certificate_is_sound_and_tight_on_a_good_plan(scenario):
    sp, config, cell = _good_case(scenario)
    tol = config.tolerances
    cert = sp.distances.certificate
    probe = DistanceProbe(cell, tol.query_distance, tol)
    traj = sp.plan.trajectory
    for k, series, limit in ((cert.clearance, sp.distances.clearance, tol.min_clearance),
                             (cert.self_distance, sp.distances.self_distance, 0.0)):
        # at most every distance read
        assert k.certified <= np.min(series) and k.certified <= k.observed <= k.sampled
        assert k.certified > limit, "the good plan is certified"
        assert k.unresolved == 0
    # dense brute force around the smallest clearance read and around the interval holding
    # the certified bound: never below the certificate; the certificate within its
    # resolution of the smallest
    c = cert.clearance
    res = max(tol.certificate_gap, tol.certificate_share * (c.observed - tol.min_clearance))
    brute = {}
    for name, t_mid in (("observed", c.observed_time), ("certified", 0.5 * sum(c.interval))):
        times = np.linspace(max(t_mid - 0.01, 0.0), min(t_mid + 0.01, traj.duration), 801)
        brute[name] = min(_clearance(probe, traj.value(x)) for x in times)
        assert c.certified <= brute[name] + 1e-12, name
    assert brute["observed"] - c.certified <= res + 2e-6, (brute, c.certified, res)
    # and never below it anywhere on the trajectory (random times)
    rng = np.random.default_rng(3)
    for x in rng.uniform(0.0, traj.duration, 300):
        d = probe.measure(traj.value(x))
        assert d.clearance >= c.certified - 1e-12 and d.self_distance >= \
            cert.self_distance.certified - 1e-12
    item = clearance_certificate(sp, config)
    assert item.passed and item.value == c.certified and item.pair == c.pair


def test_method_is_reported():
    assert "h^2/8" in mut.METHOD and "bisection" in mut.METHOD


def test_registered_right_after_clearance_as_required():
    from drakedeburr.verify.registry import CHECKS

    names = [c.name for c in CHECKS]
    k = names.index("clearance_certificate")
    assert names[k - 1] == "clearance" and CHECKS[k].purpose == "required"


def test_a_plan_just_above_the_limit_is_refined_until_the_limit_is_proven():
    """The good plan with the clearance limit put 2 um under its smallest distance (the dense
    brute-force minimum there): inside the certificate's 10 um resolution. The certificate
    must still prove the limit (refined until every bound reaches it), not stop 10 um short
    and fail a plan that meets it; and stay a lower bound of the brute force."""
    from drakedeburr.verify.sweep import resolution_target

    sp, config, cell = _good_case()
    tol = config.tolerances
    c = sp.distances.certificate.clearance
    probe = DistanceProbe(cell, tol.query_distance, tol)
    traj = sp.plan.trajectory
    times = np.linspace(max(c.observed_time - 0.01, 0.0),
                        min(c.observed_time + 0.01, traj.duration), 801)
    brute = min(_clearance(probe, traj.value(x)) for x in times)
    limit = brute - 2e-6
    config2 = replace(config, tolerances=replace(tol, min_clearance=limit))
    cell, hub = vs.cell_and_hub()
    sp2 = sample_plan(sp.plan, config2, cell=cell, hub_model=hub,
                      expected_windows=list(vs.WINDOWS))
    cert = sp2.distances.certificate.clearance
    assert limit <= cert.certified <= brute + 1e-12
    item = clearance_certificate(sp2, config2)
    assert item.passed and item.value == cert.certified
    # the target: the limit while the smallest reading is within the gap above it
    assert resolution_target(c.observed, limit, config2.tolerances) == limit
    assert resolution_target(limit - 1e-6, limit, config2.tolerances) < limit - 1e-5


def test_the_certificate_made_on_a_worker_is_the_one_made_here(caplog):
    """verify makes the certificate on a pool worker (the sweep's, holding the same pair
    scene) while this process reads the program and the cut geometry: on the grazing case
    (refined intervals, a witness between two samples) every field is the one made here, and
    the scene's reading tally (the method's counts) is the same."""
    import logging
    import time

    from drakedeburr import pool as parallel
    from drakedeburr.verify.distances import pair_scene_of
    from drakedeburr.verify.sweep import sweep

    sp, config, _, _ = _grazing_case()
    tol, traj = config.tolerances, sp.plan.trajectory
    scene = pair_scene_of(sp.cell)
    here = mut.certify(scene, traj, sweep(scene, traj, sp.samples.t, sp.samples.q, tol,
                                          workers=1), tol)
    counts = dict(scene.tally.counts)
    assert here.refined > 0 and here.clearance.observed < tol.min_clearance
    sw = sweep(scene, traj, sp.samples.t, sp.samples.q, tol, workers=1)  # a fresh tally
    ran = []
    parallel.shutdown_pool(kill=True)
    try:
        parallel._pool(1)
        with caplog.at_level(logging.DEBUG, logger="drakedeburr.pool"):
            there = mut.certify_alongside(  # alongside lasts: the worker takes its task
                scene, traj, sw, tol, lambda: (ran.append("here"), time.sleep(1.0)), workers=2)
    finally:
        parallel.shutdown_pool(kill=True)
    assert "the clearance certificate: done by a worker" in caplog.text
    assert ran == ["here"]
    assert there == here
    assert scene.tally.counts == counts
