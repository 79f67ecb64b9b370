"""Distance checks: clearance to the hub and the cell, self-collision, the burr's contact, and
the continuous clearance certificate between the samples."""

from __future__ import annotations

import numpy as np

from drakedeburr.verify.refs import LINEAR_KINDS
from drakedeburr.verify.report import CheckItem
from drakedeburr.verify.types import KIND_CODE

__all__ = ["clearance", "clearance_certificate", "self_collision", "burr_contact"]


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
    # against the collision pieces: convex hulls that may stand proud of the true surface
    # (a generated hub's by at most collision_model_excess); the true edge's engagement is
    # checked by burr_engagement
    true_lim = np.where(contact_kinds, -(depth + tol.edge_deviation), tol.min_clearance)
    lim = np.where(contact_kinds, true_lim - tol.collision_model_excess, tol.min_clearance)
    value, limit = np.array(d.burr, float), lim.copy()
    # where the pieces' reading fails, the samples are read against the hub's triangle mesh
    # (cell.true_surface), the excess allowance dropped: the pieces may reach further than
    # it on an imported mesh
    bad = np.flatnonzero(value < lim)
    note = ""
    if len(bad):
        reach = np.where(contact_kinds[bad], 0.0, tol.min_clearance)
        reading = sp.memo("burr_true_surface", lambda: _true_surface(
            sp, bad, reach))
        ok = ~reading.engulfed
        idx = reading.index[ok]
        value[idx], limit[idx] = reading.value[ok], true_lim[idx]
        note = (f"; {len(bad)} sample(s) where the pieces' reading failed re-read against the "
                f"true surface ({int(ok.sum())} read, {int((~ok).sum())} with the burr's "
                f"in-centre inside a piece kept; bounds within {reading.resolution * 1e3:.3f} mm, "
                f"{reading.points} triangle reads)")
    i = int(np.argmin(value - limit))
    v = value[i]
    return CheckItem(
        "burr_contact", bool(v >= limit[i]), float(v), float(limit[i]), "m", ">=",
        pair=d.burr_pair[i] if np.isfinite(v) else None, **sp.where(i),
        detail=f"burr head vs hub collision pieces: penetration at most the depth of cut + "
               f"edge tolerance + {tol.collision_model_excess * 1e3:.2f} mm collision-model "
               f"excess on approach/cut/retract (burr_engagement checks the true edge), full "
               f"clearance elsewhere" + note)


def _true_surface(sp, index, reach):
    from drakedeburr.cell.true_surface import true_surface_distances

    return true_surface_distances(sp.hub_model, sp.samples.X_HT, index, reach=reach)


def clearance_certificate(sp, cfg) -> CheckItem:
    tol, cert = cfg.tolerances, sp.distances.certificate
    if cert is None:
        return CheckItem("clearance_certificate", False, None, tol.min_clearance, "m", ">=",
                         detail="no certificate: the distances were measured by the dense "
                                "reference method")
    c, s = cert.clearance, cert.self_distance
    mm = 1e3
    t_mid = 0.5 * (c.interval[0] + c.interval[1])
    where = sp.where_time(t_mid) if np.isfinite(t_mid) else {}
    problems = []
    for name, k in (("clearance", c), ("self", s)):
        if not k.passed:
            problems.append(f"{name} certified {k.certified * mm:.4f} mm below its limit "
                            f"{k.limit * mm:.4f} mm")
        if k.observed < k.limit and k.observed < k.sampled:
            problems.append(f"{name} {k.observed * mm:.4f} mm read at t={k.observed_time:.4f} s "
                            f"between the samples ({k.observed_pair[0]} <-> "
                            f"{k.observed_pair[1]}): the samples miss it")
        if k.unresolved_below_limit:
            problems.append(f"{name}: {k.unresolved_below_limit} pair bound(s) below the limit "
                            f"at the {cert.floor:.0e} s floor")
    res = f"{cert.gap * mm:.3f} mm or {cert.share:.0%} of the margin above the limit"
    detail = (f"certified over the whole trajectory: clearance >= {c.certified * mm:.4f} mm "
              f"(sampled {c.sampled * mm:.4f} mm, smallest read {c.observed * mm:.4f} mm), "
              f"self >= {s.certified * mm:.4f} mm (sampled {s.sampled * mm:.4f} mm); "
              f"method: {cert.method}; {cert.refined} intervals refined ({cert.refine_readings} "
              f"readings, {cert.depth} levels), resolution {res}")
    return CheckItem(
        "clearance_certificate", c.passed and s.passed and not problems,
        float(c.certified), float(c.limit), "m", ">=", pair=c.pair, **where,
        detail="; ".join(problems + [detail]))
