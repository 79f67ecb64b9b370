"""The payload check: what the arm carries (tool or gripper + the part in hand) against the
arm's rating (mass; wrist moments and inertias where the vendor publishes them), with the
figures of :mod:`drakedeburr.robots.payload`. An overloaded arm is no program: the item is
required, and its detail names the registered arms that would carry the load in this cell."""

from __future__ import annotations

import numpy as np

from drakedeburr.robots.payload import CarriedLoad, carried_load, payload_figures
from drakedeburr.verify.report import CheckItem

__all__ = ["cell_load", "payload", "arms_rated_for"]


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


def payload(sp, cfg) -> CheckItem:
    cell = sp.cell
    spec = cell.arm
    load = cell_load(cell)
    figures = payload_figures(spec, load)
    worst = max(figures, key=lambda f: f.ratio)
    over = [f for f in figures if not f.ok]
    unrated = [k for k, v in (("wrist moments", spec.wrist_moment_Nm),
                              ("wrist inertias", spec.wrist_inertia_kgm2)) if v is None]
    head = (f"{spec.title} carries {load.mass:.3f} kg ({', '.join(load.parts)}), centre of "
            f"gravity {np.round(np.asarray(load.cog_F) * 1000.0, 1).tolist()} mm in the flange "
            f"frame")
    if over:
        from drakedeburr.cell.station import bundled_cell_name

        cell_name = bundled_cell_name(cell.scenario)
        mounted = arms_rated_for(load, cell_name) if cell_name else []
        others = [n for n in arms_rated_for(load, None) if n not in mounted]
        detail = f"{head}: over its rating: {'; '.join(map(str, over))}. "
        if mounted:
            detail += f"Arms rated for this load with a mount in this cell: " \
                      f"{', '.join(mounted)} (--robot NAME)"
        else:
            detail += "No registered arm rated for this load has a mount in this cell"
        if others:
            detail += (f"; rated{' too' if mounted else ''}, placed by a scenario of yours: "
                       f"{', '.join(others)}")
    else:
        detail = f"{head}: within its rating: {'; '.join(map(str, figures))}"
    if unrated:
        detail += f" ({' and '.join(unrated)} not published for this arm: not checked)"
    return CheckItem("payload", not over, worst.value, worst.limit, worst.unit, "<=",
                     detail=detail,
                     per_window={"load": {f.name: {"value": f.value, "limit": f.limit,
                                                   "unit": f.unit} for f in figures}})
