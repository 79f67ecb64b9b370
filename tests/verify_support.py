"""Shared, cached fixtures of the verify tests: one reference plan, one cell, one hub.

The reference plan (drakedeburr.verify.synthetic) is consistent by construction. It runs at
75 mm/s: at the process speed of 150 mm/s the 10 mm fillets of the bundled hubs need J3
accelerations of ~21 rad/s^2 in this cell, above the model's assumed 10 rad/s^2 (see
docs/verify.md), so a *good* plan at 150 mm/s cannot be built this simply.
"""

from __future__ import annotations

import functools

from drakedeburr.config import Config, ProcessParameters, Recipe, default_tolerances

HUB = "h5_straight"
SCENARIO = "tool_in_hand"
WINDOWS = (0, 1)
PARAMS = ProcessParameters(grinding_speed=0.075)
#: cheaper sampling for the fault tests (knots are always sampled)
COARSE = {"dense_step": 2e-3, "time_step": 0.1, "joint_move_step": 10e-3}


def config(params=PARAMS, **sampling) -> Config:
    """The verify tests' configuration: ``params`` (None: the process defaults) and the
    default tolerances with ``sampling`` overrides."""
    return Config(SCENARIO, HUB, Recipe(process=params or ProcessParameters()),
                  default_tolerances(**sampling))


@functools.cache
def cell_and_hub():
    from drakedeburr.cell.station import load_cell
    from drakedeburr.hub.model import load_hub

    return load_cell(SCENARIO, HUB), load_hub(HUB)


@functools.cache
def good_plan():
    from drakedeburr.verify.synthetic import reference_plan

    return reference_plan(SCENARIO, HUB, list(WINDOWS), params=PARAMS)


def verify(plan, coarse: bool = True, **kwargs):
    from drakedeburr.verify.checks import verify_plan

    cell, hub = cell_and_hub()
    cell = kwargs.pop("cell", cell)
    params = kwargs.pop("params", PARAMS)
    sampling = dict(COARSE) if coarse else {}
    sampling.update(kwargs.pop("sampling", {}))
    kwargs.setdefault("expected_windows", list(WINDOWS))
    return verify_plan(plan, config(params, **sampling), cell=cell, hub_model=hub, **kwargs)


@functools.cache
def good_report():
    """The dense (default sampling) verification of the good plan."""
    return verify(good_plan(), coarse=False)
