"""How a cell is built again: the :func:`drakedeburr.cell.station.load_cell` arguments a cell
records (``cell._cache["load_args"]``), from which a worker process builds the same cell, and
those of the cell a saved plan was made in (so a worker can start building it before this
process has)."""

from __future__ import annotations

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["cell_recipe", "plan_cell_args"]


def cell_recipe(scenario, hub=None, *, robot=None, tool=None, time_step: float = 0.0,
                hub_pose=None, q_home=None) -> dict:
    """The arguments as :func:`~drakedeburr.cell.station.load_cell` records them."""
    return dict(scenario=scenario, hub=hub, robot=robot, tool=tool, time_step=time_step,
                hub_pose=None if hub_pose is None else np.array(hub_pose, float),
                q_home=None if q_home is None else np.array(q_home, float))


def plan_cell_args(plan) -> dict:
    """The cell a plan was made in: its scenario and hub, its arm, its hub placement and its
    home (``plan.meta["robot"]``, ``["tool"]``, ``["hub_pose"]``, ``["q_home"]``).

    Raises:
        InputError: ``q_home`` is not 6 finite joint angles.
    """
    meta = plan.meta or {}
    pose, home = meta.get("hub_pose"), meta.get("q_home")
    a = None if home is None else np.asarray(home, dtype=object)
    if a is not None and not (a.shape == (6,) and all(
            isinstance(v, int | float) and np.isfinite(v) for v in a)):
        raise InputError(f"plan of {plan.hub}: meta q_home must be 6 finite joint angles [rad], "
                         f"got {home!r}")
    return cell_recipe(plan.scenario, plan.hub, robot=meta.get("robot"), tool=meta.get("tool"),
                       hub_pose=pose, q_home=None if a is None else a.astype(float))
