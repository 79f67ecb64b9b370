"""Distance checks: clearance to the hub and the cell, self-collision, the burr's contact."""

from __future__ import annotations

import numpy as np

from drakedeburr.verify.refs import LINEAR_KINDS
from drakedeburr.verify.report import CheckItem
from drakedeburr.verify.sampling import KIND_CODE

__all__ = ["clearance", "self_collision", "burr_contact"]


def clearance(sp, cfg) -> CheckItem:
    tol, d = cfg.tolerances, sp.distances
    i = int(np.argmin(d.clearance))
    v = d.clearance[i]
    return CheckItem(
        "clearance", bool(v >= tol.min_clearance), float(v), tol.min_clearance, "m", ">=",
        pair=d.clearance_pair[i] if np.isfinite(v) else None, **sp.where(i),
        detail=("smallest distance robot/tool to hub and cell, burr head-hub excepted"
                + ("" if np.isfinite(v) else
                   f" (nothing within {tol.query_distance * 1e3:.0f} mm)")))


def self_collision(sp, cfg) -> CheckItem:
    d = sp.distances
    i = int(np.argmin(d.self_distance))
    v = d.self_distance[i]
    return CheckItem(
        "self_collision", bool(v > 0.0), float(v), 0.0, "m", ">=",
        pair=d.self_pair[i] if np.isfinite(v) else None, **sp.where(i),
        detail="smallest distance between unfiltered robot/tool geometries")


def burr_contact(sp, cfg) -> CheckItem:
    tol, d, s = cfg.tolerances, sp.distances, sp.samples
    contact_kinds = np.isin(s.kind, [KIND_CODE[k] for k in LINEAR_KINDS])
    depth = np.array([sp.depth_of_cut(w) for w in s.window])
    # the collision pieces are convex hulls that may reach past the true surface (the hub
    # generator splits a piece that reaches > 0.5 mm into an opening); the burr's true
    # engagement is checked against the true edge (burr_engagement)
    lim = np.where(contact_kinds, -(depth + tol.edge_deviation + tol.collision_model_excess),
                   tol.min_clearance)
    i = int(np.argmin(d.burr - lim))
    v = d.burr[i]
    return CheckItem(
        "burr_contact", bool(v >= lim[i]), float(v), float(lim[i]), "m", ">=",
        pair=d.burr_pair[i] if np.isfinite(v) else None, **sp.where(i),
        detail=f"burr head vs hub collision pieces: penetration at most the depth of cut + "
               f"edge tolerance + {tol.collision_model_excess * 1e3:.2f} mm collision-model "
               f"excess on approach/cut/retract (burr_engagement checks the true edge), full "
               f"clearance elsewhere")
