"""What the arm of a cell carries, from the cell's models, and which registered arms are rated
for it (:mod:`drakedeburr.robots.payload`): the verifier's required ``payload`` item and the
workpiece-in-hand default arm (:func:`rated_default_arm`)."""

from __future__ import annotations

import logging

from drakedeburr.robots.payload import CarriedLoad, carried_load, payload_figures

__all__ = ["cell_load", "arms_rated_for", "rated_default_arm", "arm_or_rated_default"]

log = logging.getLogger(__name__)


def cell_load(cell) -> CarriedLoad:
    """The load on the flange of ``cell``'s arm: every body that moves with the arm and is not
    one of its links (the tool or gripper models, and the hub when it is held), from the cell's
    models (mass, centre of mass, rotational inertia), in the flange frame."""
    plant = cell.plant
    context = cell.create_context()
    ctx = plant.GetMyContextFromRoot(context)
    X_FW = cell.flange_frame.CalcPoseInWorld(ctx).inverse()
    parts = []
    for instance in cell.moving_model_instances:
        if instance == cell.robot:
            continue
        for index in plant.GetBodyIndices(instance):
            body = plant.get_body(index)
            M_BBo_B = body.CalcSpatialInertiaInBodyFrame(ctx)
            m = M_BBo_B.get_mass()
            if m <= 0:
                continue
            p_BoBcm = M_BBo_B.get_com()
            I_Bcm_B = M_BBo_B.Shift(p_BoBcm).CalcRotationalInertia().CopyToFullMatrix3()
            X_FB = X_FW.multiply(body.EvalPoseInWorld(ctx))
            R = X_FB.rotation().matrix()
            parts.append((f"{plant.GetModelInstanceName(instance)}::{body.name()}", m,
                          X_FB.multiply(p_BoBcm), R @ I_Bcm_B @ R.T))
    return carried_load(parts)


def arms_rated_for(load: CarriedLoad, cell_name: str | None) -> list[str]:
    """Registered arms rated for ``load`` (every figure) with a mount in the bundled cell
    ``cell_name`` (every rated arm when None)."""
    from drakedeburr.robots import ROBOTS

    return [s.name for s in ROBOTS.values()
            if (cell_name is None or cell_name in s.cells)
            and all(f.ok for f in payload_figures(s, load))]


def rated_default_arm(scenario, hub=None) -> str | None:
    """The arm to use when none is named: None (the scenario's own) when that arm is rated for
    what it carries in this cell with this hub, else the registered arm rated for it that has a
    mount in this bundled cell, one with a wrist rating (moments or inertias published) before
    one rated by mass only, then in listing order (logged), else None (the scenario's own: the
    verifier's payload item then fails and names the arms that would carry it)."""
    from drakedeburr.cell.station import bundled_cell_name, load_cell
    from drakedeburr.resources import scenario_path

    cell = load_cell(scenario, hub, warn_payload=False)  # the cell run uses warns, not this
    load = cell_load(cell)
    if all(f.ok for f in payload_figures(cell.arm, load)):
        return None
    cell_name = bundled_cell_name(scenario_path(scenario))
    rated = arms_rated_for(load, cell_name) if cell_name else []
    if not rated:
        return None
    from drakedeburr.robots import ROBOTS

    # an arm whose wrist is rated too (moments or inertias published) before one rated by mass
    # only, then the registry's order
    rated.sort(key=lambda n: ROBOTS[n].wrist_moment_Nm is None
               and ROBOTS[n].wrist_inertia_kgm2 is None)
    log.warning("%s: the scenario's arm %s is not rated for the %.1f kg it carries here; "
                "using %s (rated, mounted in this cell; --robot NAME to choose)",
                cell.scenario.name, cell.arm.name, load.mass, rated[0])
    return rated[0]


def arm_or_rated_default(robot, scenario, hub=None):
    """``robot`` when one is named (``--robot``), else :func:`rated_default_arm`."""
    return robot if robot is not None else rated_default_arm(scenario, hub)
