"""How a cell is built again: the :func:`drakedeburr.cell.station.load_cell` arguments a cell
records (``Cell.recipe``), from which a worker process builds the same cell, and those of the
cell a saved plan was made in (so a worker can start building it before this process has);
and :class:`CellMemo`, what later stages derive from a cell once and keep with it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["CellMemo", "cell_recipe", "plan_cell_args"]


@dataclass(eq=False)
class CellMemo:
    """What is derived from a loaded cell once and kept with it (``Cell.memo``), each field
    written by one owner only, the first time it is asked for.

    Attributes:
        context: the diagram context of the cell's pose queries (``Cell``; not thread-safe).
        geometry_digest: digest of the cell's geometry
            (:func:`drakedeburr.cell.fingerprint.geometry_digest`).
        motion_bound: the planner's ``MotionBound`` (:func:`drakedeburr.plan.clearance.
            motion_bound`).
        pair_scene: the verifier's ``PairScene`` (:func:`drakedeburr.verify.pair_scene.
            pair_scene_of`).
    """

    context: object = None
    geometry_digest: str | None = None
    motion_bound: object = None
    pair_scene: object = None


def cell_recipe(scenario, hub=None, *, robot=None, tool=None, time_step: float = 0.0,
                hub_pose=None, q_home=None) -> dict:
    """The arguments as :func:`~drakedeburr.cell.station.load_cell` records them. A cell built
    again from them (a worker's, a placement candidate's) does not warn about its payload
    again (``warn_payload`` False): the run's first build of it did."""
    return dict(scenario=scenario, hub=hub, robot=robot, tool=tool, time_step=time_step,
                hub_pose=None if hub_pose is None else np.array(hub_pose, float),
                q_home=None if q_home is None else np.array(q_home, float), warn_payload=False)


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
