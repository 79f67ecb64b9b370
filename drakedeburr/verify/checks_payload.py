"""The payload check: what the arm carries (tool or gripper + the part in hand) against the
arm's rating (mass; wrist moments and inertias where the vendor publishes them), with the
figures of :mod:`drakedeburr.robots.payload`. An overloaded arm is no program: the item is
required, and its detail names the registered arms that would carry the load in this cell."""

from __future__ import annotations

import numpy as np

from drakedeburr.cell.loads import arms_rated_for, cell_load
from drakedeburr.robots.payload import payload_figures
from drakedeburr.verify.report import CheckItem

__all__ = ["cell_load", "payload", "arms_rated_for"]


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
