"""Which side of a hub mesh is the front (the visible face the tool works on)?

The hub axis is known up to its sign. Four cues vote, each stated with its evidence:

* **lug seats** (weight 3): lug nuts and bolts seat from the front, in 60 deg cones or balls:
  around each bolt hole, facets facing one side and leaning 15-75 deg toward the hole's
  axis on at least half of the ring seen from that side (and clearly fewer from the other);
* **barrel** (weight 2 x how far off-centre): the spoke disc sits toward the barrel's front
  end (positive wheel offset; counted only when the outer ring is >= 60 mm long and >= 1.5 x
  as long as the centre is deep, i.e. there is a barrel);
* **mounting face** (weight 1.5): the flat annulus around the bore that bolts onto the car
  stands proud of the spokes at the back; the front of the centre is recessed or flush;
* **dish** (weight 1): the spoke disc is displaced toward the front of the centre (a concave
  face; a convex face-only mesh without the other cues is therefore not decided by it alone).

The front is the side with the larger weighted vote; without any vote the mesh's own +axis is
kept and the decision says so (the user can override: ``front=+z/-z/+x/...``).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["FrontDecision", "decide_front", "front_from_user", "FRONT_CHOICES"]

log = logging.getLogger(__name__)

FRONT_CHOICES = ("auto", "+x", "-x", "+y", "-y", "+z", "-z")
_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class FrontDecision:
    """The front side relative to a provisional axis: ``sign`` +1 keeps it, -1 flips it.

    Attributes:
        sign: +1 or -1.
        decided_by: "cues", "user" or "default" (no cue voted).
        score: weighted vote for +1 (positive) or -1 (negative).
        evidence: one sentence per cue (what was measured and which way it points).
    """

    sign: int
    decided_by: str
    score: float
    evidence: list[str] = field(default_factory=list)

    def as_dict(self, axis_M: np.ndarray | None = None) -> dict:
        out = {"decided_by": self.decided_by, "score": round(self.score, 3),
               "evidence": list(self.evidence)}
        if axis_M is not None:
            out["axis_in_file"] = [round(float(v), 6) for v in axis_M]
        return out


def front_from_user(front: str, axis_M: np.ndarray) -> FrontDecision | None:
    """The user's ``--front`` (a file axis) as a decision for ``axis_M``; None for "auto".

    Raises:
        InputError: an unknown choice, or a file axis not along the hub axis.
    """
    if front in (None, "auto"):
        return None
    if front not in FRONT_CHOICES:
        raise InputError(f"--front {front!r}: choose from {', '.join(FRONT_CHOICES)}")
    d = np.zeros(3)
    d[_AXES[front[1]]] = 1.0 if front[0] == "+" else -1.0
    c = float(np.asarray(axis_M, float) @ d)
    if abs(c) < 0.7:
        raise InputError(f"--front {front}: the hub axis is along {np.round(axis_M, 3)} in the "
                         f"file, not along {front[1].upper()} (angle "
                         f"{math.degrees(math.acos(min(1.0, abs(c)))):.0f} deg)")
    return FrontDecision(1 if c > 0 else -1, "user", float(np.sign(c)),
                         [f"given by the user: the front faces {front} of the file"])


def _ring_rays(centre: np.ndarray, r0: float, r1: float) -> np.ndarray:
    r = np.linspace(r0, r1, 10)
    a = np.linspace(0.0, 2 * np.pi, 48, endpoint=False)
    rr, aa = np.meshgrid(r, a)
    return centre + np.column_stack([(rr * np.cos(aa)).ravel(), (rr * np.sin(aa)).ravel()])


def _cast(scene, xy: np.ndarray, z0: float, down: bool):
    import open3d as o3d

    rays = np.zeros((len(xy), 6), np.float32)
    rays[:, :2] = xy
    rays[:, 2] = z0 if down else -z0
    rays[:, 5] = -1.0 if down else 1.0
    ans = scene.cast_rays(o3d.core.Tensor(rays))
    t = ans["t_hit"].numpy().astype(float)
    n = ans["primitive_normals"].numpy().astype(float)
    z = z0 - t if down else -z0 + t
    return z, n, np.isfinite(t)


def _seat_share(scene, centre: np.ndarray, radius: float, z0: float, down: bool) -> float:
    """Share of a ring beside a hole whose facets face the viewer and lean 15-75 deg toward
    the hole's axis (a countersink or ball seat seen from that side)."""
    xy = _ring_rays(centre, radius + 0.4e-3, radius + 6e-3)
    _, n, hit = _cast(scene, xy, z0, down)
    view = np.array([0.0, 0.0, 1.0 if down else -1.0])  # from the surface toward the viewer
    n = np.where((n @ view < 0)[:, None], -n, n)
    tilt = np.degrees(np.arccos(np.clip(n @ view, -1.0, 1.0)))
    inward = np.einsum("ij,ij->i", n[:, :2], centre - xy) > 0
    return float(np.mean(hit & (tilt > 15) & (tilt < 75) & inward))


def _lug_seat_vote(scene, lugs: list, z0: float) -> tuple[float, str]:
    if not lugs:
        return 0.0, ""
    votes = []
    for o in lugs:
        up, dn = (_seat_share(scene, o.center_xy, 0.5 * o.width, z0, down)
                  for down in (True, False))
        votes.append(1 if up >= 0.5 and up >= dn + 0.3 else -1 if dn >= 0.5 and dn >= up + 0.3
                     else 0)
    plus, minus = votes.count(1), votes.count(-1)
    if max(plus, minus) < 0.6 * len(votes):
        return 0.0, (f"lug seats: none clear ({plus} of {len(votes)} bolt holes seated from +axis,"
                     f" {minus} from -axis)")
    v = 1.0 if plus > minus else -1.0
    return v, (f"lug seats: {max(plus, minus)} of {len(votes)} bolt holes have a conical or "
               f"ball seat on the {'+' if v > 0 else '-'}axis side")


def _barrel_vote(V: np.ndarray, r: np.ndarray, r_max: float) -> tuple[float, str]:
    outer, inner = r > 0.85 * r_max, r < 0.55 * r_max
    if outer.sum() < 10 or inner.sum() < 10:
        return 0.0, ""
    zo = np.percentile(V[outer, 2], [1, 99])
    zi = np.percentile(V[inner, 2], [1, 99])
    ext_o, ext_i = zo[1] - zo[0], zi[1] - zi[0]
    if ext_o < 0.06 or ext_o < 1.5 * ext_i:
        return 0.0, (f"barrel: none (outer ring {ext_o * 1e3:.0f} mm long, centre "
                     f"{ext_i * 1e3:.0f} mm deep)")
    offset = float(np.mean(V[inner, 2]) - 0.5 * (zo[0] + zo[1]))
    strength = abs(offset) / (0.5 * ext_o)
    if strength < 0.2:
        return 0.0, (f"barrel: {ext_o * 1e3:.0f} mm long, the spoke disc near its middle "
                     f"({offset * 1e3:+.0f} mm)")
    v = math.copysign(min(1.0, strength), offset)
    return v, (f"barrel: {ext_o * 1e3:.0f} mm long; the spoke disc sits {abs(offset) * 1e3:.0f}"
               f" mm toward its {'+' if offset > 0 else '-'}axis end")


def _centre_vs_spokes(scene, r_bore: float, r_centre: float, r_max: float, z0: float):
    """Per side (+1: seen from +axis, -1: from -axis): how far the centre annulus stands
    beyond the spoke region toward that side [m], its flat share, and mean heights."""
    a = np.linspace(0.0, 2 * np.pi, 90, endpoint=False)
    out = {}
    for side in (1, -1):
        res = {}
        for name, (r0, r1) in (("centre", (r_bore + 2e-3, r_centre)),
                               ("spokes", (0.45 * r_max, 0.7 * r_max))):
            rr, aa = np.meshgrid(np.linspace(r0, max(r1, r0 + 1e-3), 6), a)
            xy = np.column_stack([(rr * np.cos(aa)).ravel(), (rr * np.sin(aa)).ravel()])
            z, n, hit = _cast(scene, xy, z0, side > 0)
            res[name] = (side * z[hit], np.abs(n[hit, 2]))
        (zc, nc), (zs, _) = res["centre"], res["spokes"]
        if len(zc) < 20 or len(zs) < 20:
            return None
        out[side] = {"protrude": float(np.median(zc) - np.percentile(zs, 90)),
                     "flat": float(np.mean(nc > math.cos(math.radians(3.0)))),
                     "centre": float(np.median(zc)) * side, "spokes": float(np.median(zs)) * side}
    return out


def _mounting_vote(cvs: dict | None) -> tuple[float, str]:
    if cvs is None:
        return 0.0, ""
    sides = [s for s in (1, -1) if cvs[s]["flat"] >= 0.6 and cvs[s]["protrude"] >= 2e-3
             and cvs[s]["protrude"] >= cvs[-s]["protrude"] + 2e-3]
    if len(sides) != 1:
        return 0.0, ("mounting face: not clear (centre beyond the spokes by "
                     f"{cvs[1]['protrude'] * 1e3:+.0f} mm toward +axis, "
                     f"{cvs[-1]['protrude'] * 1e3:+.0f} mm toward -axis)")
    back = sides[0]
    return -float(back), (f"mounting face: a flat annulus around the bore stands "
                          f"{cvs[back]['protrude'] * 1e3:.0f} mm beyond the spokes on the "
                          f"{'+' if back > 0 else '-'}axis side (the back)")


def _dish_vote(cvs: dict | None) -> tuple[float, str]:
    if cvs is None:
        return 0.0, ""
    mid_c = 0.5 * (cvs[1]["centre"] + cvs[-1]["centre"])
    mid_s = 0.5 * (cvs[1]["spokes"] + cvs[-1]["spokes"])
    d = mid_s - mid_c
    if abs(d) < 5e-3:
        return 0.0, f"dish: none ({d * 1e3:+.0f} mm between spokes and centre)"
    return float(np.sign(d)), (f"dish: the spoke disc is {abs(d) * 1e3:.0f} mm toward "
                               f"{'+' if d > 0 else '-'}axis of the centre (concave face)")


def decide_front(scene, V_H0: np.ndarray, scan, *, source: str = "mesh") -> FrontDecision:
    """Vote on the front side of a mesh in a provisional hub frame H0 (axis +Z_H0).

    Args:
        scene: open3d RaycastingScene of the mesh in H0 [m].
        V_H0: (N, 3) mesh vertices in H0 [m].
        scan: the :class:`~drakedeburr.hub.openings.OpeningScan` in H0 (lug holes, bore).
        source: name for messages.
    """
    r = np.hypot(V_H0[:, 0], V_H0[:, 1])
    r_max = float(r.max())
    z0 = float(np.abs(V_H0[:, 2]).max()) + 0.05
    lugs = [o for o in scan.openings if o.kind == "lug hole"]
    bores = [o for o in scan.openings if o.kind == "centre bore"]
    r_bore = 0.5 * bores[0].width if bores else 0.0
    r_centre = (min(o.radius - 0.5 * o.width for o in lugs) - 1e-3 if lugs
                else r_bore + 0.15 * r_max)
    cvs = _centre_vs_spokes(scene, r_bore, max(r_centre, r_bore + 3e-3), r_max, z0)
    score, evidence = 0.0, []
    for weight, (vote, text) in ((3.0, _lug_seat_vote(scene, lugs, z0)),
                                 (2.0, _barrel_vote(V_H0, r, r_max)),
                                 (1.5, _mounting_vote(cvs)), (1.0, _dish_vote(cvs))):
        score += weight * vote
        if text:
            evidence.append(text + (f" -> {'+' if vote > 0 else '-'}axis (weight {weight:g})"
                                    if vote else " -> no vote"))
    if score == 0.0:
        log.warning("%s: front side undecided (%s); keeping the mesh's +axis; pass --front to "
                    "choose", source, "; ".join(evidence) or "no cue")
        return FrontDecision(1, "default", 0.0, evidence)
    sign = 1 if score > 0 else -1
    log.info("%s: front side %saxis (score %+.2f): %s", source, "+" if sign > 0 else "-",
             score, "; ".join(evidence))
    return FrontDecision(sign, "cues", score, evidence)
