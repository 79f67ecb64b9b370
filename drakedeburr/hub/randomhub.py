"""A seeded random catalogue of realistic hubs (``drakedeburr hub random``).

``random_spec(seed, index)`` draws one :class:`HubSpec` from the ranges below (where they come
from: docs/hub.md, "Random catalogue"); the same (seed, index) gives the same spec on any
machine (numpy's PCG64 seeded by ``SeedSequence([seed, index, attempt])``).
``random_catalogue(seed, count, out)`` generates the hub folders like ``hub generate`` does and
exports each mesh as a binary STL in millimetres or metres, in a CAD-like pose
(``export.json`` says which).

Every drawn spec is checked before it is used: ``HubSpec.validate`` (spokes overlapping,
fillets, pad, bolts ...), the window outlines are built, and every window's narrowest passage
(largest inscribed circle of the outline, less the draft's narrowing at the back of the face)
must be at least ``min_width_factor`` x the burr diameter. A spec that fails is *repaired*
(spokes made narrower, up to ``_REPAIRS`` times) and otherwise drawn again with the next
attempt number: deterministic either way.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_bytes, atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.hub.openings import DEFAULT_BURR_DIAMETER
from drakedeburr.hub.spec import HubSpec

__all__ = ["random_spec", "random_catalogue", "export_mesh", "export_choice",
           "spec_window_widths",
           "BOLT_PATTERNS", "RIM_DIAMETERS_IN", "DEFAULT_BURR_DIAMETER", "MIN_WIDTH_FACTOR",
           "STYLES"]

log = logging.getLogger(__name__)

#: the generator's design rule (issue 16): it draws windows >= this x the burr diameter. A
#: property of this catalogue, not of the tool: openings are judged by the burrs' needs
#: (hub.openings.burr_need)
MIN_WIDTH_FACTOR = 2.5
RIM_DIAMETERS_IN = (15, 16, 17, 18, 19, 20)
#: (bolts, PCD [mm], centre bores [mm]) of common passenger cars
BOLT_PATTERNS = (
    (4, 98.0, (58.1,)), (4, 100.0, (54.1, 56.1, 57.1, 60.1)), (4, 108.0, (63.4, 65.1)),
    (4, 114.3, (66.1, 67.1)), (5, 100.0, (54.1, 56.1, 57.1)), (5, 108.0, (63.4, 65.1)),
    (5, 110.0, (65.1,)), (5, 112.0, (57.1, 66.6)), (5, 114.3, (60.1, 64.1, 66.1, 67.1)),
    (5, 115.0, (70.1,)), (5, 120.0, (64.1, 72.6)), (5, 127.0, (71.5,)), (5, 130.0, (71.6,)),
    (6, 114.3, (66.1,)), (6, 139.7, (67.1,)),
)
#: spoke styles and their share of the catalogue; "twisted" = straight spokes with a twist
STYLES = (("straight", 0.22), ("curved", 0.18), ("twisted", 0.15), ("split", 0.23),
          ("twin", 0.22))
_ATTEMPTS = 40
_REPAIRS = 6
_EXPORT_POSES = ("+z", "-z", "+y", "-y", "+x")

Progress = Callable[[int, int, str], None] | None


def _mm(x: float) -> float:
    """A length drawn in mm, rounded to 0.1 mm, as metres."""
    return round(float(x), 1) / 1e3


def _deg(x: float) -> float:
    return math.radians(round(float(x), 1))


def _rim(rng) -> dict:
    """Rim (ETRTO/TRA: the diameter code is the bead seat diameter in inches; J flange)."""
    d_in = int(rng.choice(RIM_DIAMETERS_IN))
    barrel = d_in * 25.4
    width_in = float(rng.choice(np.arange(max(6.0, 0.37 * d_in), 0.5 * d_in + 0.01, 0.5)))
    return {"rim_barrel_diameter": _mm(barrel),
            "rim_outer_diameter": _mm(barrel + 2 * rng.uniform(17.0, 19.5)),
            "rim_thickness": _mm(rng.uniform(5.0, 8.0)),
            "rim_width": _mm(width_in * 25.4),
            "rim_lip_height": _mm(rng.uniform(0.0, 10.0)),
            "rim_flange_thickness": _mm(rng.uniform(10.0, 14.0))}, d_in


def _centre(rng) -> dict:
    """Bolt pattern, bore, lug seats (60 deg cone) and the pad behind the face."""
    n, pcd, bores = BOLT_PATTERNS[int(rng.integers(len(BOLT_PATTERNS)))]
    hole = rng.uniform(13.0, 16.0)  # M12 / M14 studs or bolts
    seat = hole + rng.uniform(7.0, 10.0) if rng.random() < 0.8 else 0.0
    pad_r = pcd / 2 + max(seat, hole) / 2 + rng.uniform(4.0, 12.0)
    return {"bolt_count": n, "bolt_circle_diameter": _mm(pcd),
            "center_bore_diameter": _mm(float(rng.choice(bores))),
            "bolt_hole_diameter": _mm(hole), "bolt_seat_diameter": _mm(seat),
            "hub_pad_radius": _mm(pad_r), "hub_pad_depth": _mm(rng.uniform(8.0, 30.0))}


def _style(rng) -> str:
    names, p = zip(*STYLES, strict=True)
    return str(rng.choice(names, p=np.array(p) / sum(p)))


def _spokes(rng, style: str, r_in: float, r_out: float, bound: float) -> dict:
    """Spoke count and widths [mm] sized from the pitch so the windows keep ``bound`` [mm]."""
    forked = style in ("split", "twin")
    n = int(rng.integers(4, 7 if forked else 11))
    pitch_in = 2 * r_in * math.sin(math.pi / n)
    pitch_out = 2 * r_out * math.sin(math.pi / n)
    out = {"spoke_count": n, "spoke_style": "straight" if style == "twisted" else style}
    w_in = min(rng.uniform(0.28, 0.55) * pitch_in, pitch_in - bound - 8.0)
    out["spoke_width"] = _mm(max(w_in, 16.0))
    if style == "split":
        arm = rng.uniform(15.0, 24.0)
        gap_small = rng.uniform(bound + 6.0, bound + 25.0)
        half = math.asin(min(0.95, (gap_small + arm) / (2 * r_out)))
        out.update(spoke_width_outer=_mm(arm), split_angle=_deg(math.degrees(half)),
                   split_radius=_mm(r_in + rng.uniform(0.2, 0.45) * (r_out - r_in)))
    elif style == "twin":
        arm = rng.uniform(14.0, 22.0)
        out.update(spoke_width_outer=_mm(arm), twin_gap=_mm(rng.uniform(bound + 3.0,
                                                                        bound + 18.0)),
                   split_radius=_mm(r_in + rng.uniform(0.05, 0.3) * (r_out - r_in)))
    else:
        w_out = min(rng.uniform(0.18, 0.45) * pitch_out, pitch_out - bound - 10.0)
        out["spoke_width_outer"] = _mm(max(w_out, 16.0))
        if style == "curved":
            out["spoke_sweep"] = _deg(rng.choice([-1, 1]) * rng.uniform(10.0, 40.0))
        if style == "twisted" or (style == "curved" and rng.random() < 0.3):
            out["spoke_twist"] = _deg(rng.choice([-1, 1]) * rng.uniform(5.0, 22.0))
    return out


def _draw(rng, index: int, seed: int, bound: float) -> HubSpec:
    """One unchecked spec (lengths in mm inside, metres out)."""
    rim, d_in = _rim(rng)
    centre = _centre(rng)
    barrel_in = rim["rim_barrel_diameter"] * 500 - rim["rim_thickness"] * 1e3
    pad_r = centre["hub_pad_radius"] * 1e3
    r_in = pad_r + rng.uniform(2.0, 15.0)
    r_out = barrel_in - rng.uniform(8.0, 25.0)
    style = _style(rng)
    spokes = _spokes(rng, style, r_in, r_out, bound)
    dish_in = pad_r + rng.uniform(0.0, 0.5) * (r_in - pad_r)
    dish_out = rng.uniform(r_out + 2.0, barrel_in)
    depth = min(rng.uniform(0.0, 90.0), 0.9 * (dish_out - dish_in))
    forked = spokes["spoke_style"] in ("split", "twin")
    fillet = rng.uniform(7.0, min(20.0, 0.2 * (r_out - r_in)))
    small = rng.uniform(4.5, 8.0) if forked else 4.0
    blend = rng.uniform(3.0, 8.0)
    round_r = rng.uniform(0.5, 2.0) if rng.random() < 0.5 else 0.0
    round_r = min(round_r, 0.6 * blend, 0.4 * small)
    features = {
        "face_rise_angle": _deg(rng.uniform(5.0, 30.0)) if rng.random() < 0.6 else 0.0,
        "face_rise_band": _mm(rng.uniform(5.0, 12.0)),
        "wall_draft": _deg(rng.uniform(0.5, 4.0)) if rng.random() < 0.5 else 0.0,
        "edge_round_radius": _mm(round_r),
    }
    desc = (f"random hub (seed {seed}, #{index}): {d_in} in, {spokes['spoke_count']} "
            f"{style} spokes, dish {depth:.0f} mm")
    return HubSpec(
        name=f"r{seed}_{index:03d}", description=desc, **rim, **centre, **spokes, **features,
        face_thickness=_mm(rng.uniform(16.0, 30.0)), dish_depth=_mm(depth),
        dish_inner_radius=_mm(dish_in), dish_outer_radius=_mm(dish_out),
        window_inner_radius=_mm(r_in), window_outer_radius=_mm(r_out),
        fillet_radius=_mm(fillet), fillet_radius_small=_mm(small), blend_radius=_mm(blend))


def spec_window_widths(spec: HubSpec) -> list[tuple[str, float]]:
    """(kind, narrowest passage [m]) per window: the largest circle inside the outline,
    less the draft's narrowing over the face thickness (both sides)."""
    from drakedeburr.hub.outline import build_window_outlines, inscribed_width

    shrink = 2 * spec.face_thickness * math.tan(spec.wall_draft)
    return [(w.kind, inscribed_width(w.poly_mm) * 1e-3 - shrink)
            for w in build_window_outlines(spec)]


def _checked(spec: HubSpec, bound: float) -> tuple[HubSpec | None, str]:
    """The spec, repaired when its windows are too narrow; (None, reason) when it cannot be."""
    for _ in range(_REPAIRS):
        try:
            spec.validate()
            widths = spec_window_widths(spec)
        except InputError as exc:
            return None, str(exc)
        narrow = min(w for _, w in widths)
        if narrow >= bound:
            return spec, ""
        # repair: narrower spokes (arms) by 12 %, fillets kept
        spec = dataclasses.replace(
            spec, spoke_width=_mm(spec.spoke_width * 880),
            spoke_width_outer=_mm(max(spec.spoke_width_outer * 880, 14.0)))
    return None, f"windows narrower than {bound * 1e3:.1f} mm after {_REPAIRS} repairs"


def random_spec(seed: int, index: int, *, burr_diameter: float = DEFAULT_BURR_DIAMETER,
                min_width_factor: float = MIN_WIDTH_FACTOR, first_attempt: int = 0) -> HubSpec:
    """The ``index``-th hub of the random catalogue ``seed`` (see module doc).

    Args:
        seed: catalogue seed (>= 0).
        index: hub number in the catalogue (>= 0).
        burr_diameter: the burr the windows must admit [m].
        min_width_factor: narrowest window >= this x ``burr_diameter``.
        first_attempt: skip the draws before this attempt (used when a drawn spec could not
            be meshed).

    Returns:
        A validated HubSpec named ``r<seed>_<index:03d>``.
    """
    return _spec_and_attempt(seed, index, burr_diameter, min_width_factor, first_attempt)[0]


def _spec_and_attempt(seed: int, index: int, burr_diameter: float, min_width_factor: float,
                      first_attempt: int) -> tuple[HubSpec, int]:
    if seed < 0 or index < 0:
        raise InputError(f"random hub: seed and index must be >= 0, got {seed}, {index}")
    bound = min_width_factor * burr_diameter
    reasons = []
    for attempt in range(first_attempt, first_attempt + _ATTEMPTS):
        rng = np.random.default_rng(np.random.SeedSequence([seed, index, attempt]))
        spec, why = _checked(_draw(rng, index, seed, bound * 1e3), bound)
        if spec is not None:
            if attempt:
                log.info("random hub %d/%d: attempt %d (earlier draws rejected: %s)", seed,
                         index, attempt, "; ".join(reasons[-3:]))
            return spec, attempt
        reasons.append(why)
    raise RuntimeError(f"random hub seed {seed} index {index}: no valid spec in {_ATTEMPTS} "
                       f"draws; last reasons: {reasons[-3:]}")


def export_choice(seed: int, index: int) -> tuple[str, np.ndarray, str]:
    """(unit, X_MH (4, 4) [m], front file axis) of hub ``index``'s STL export: 60 % in mm,
    the axle along a file axis, a random origin offset along it (seeded)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, 1 << 20]))
    unit = "mm" if rng.random() < 0.6 else "m"
    front, X_MH = _export_pose(rng)
    return unit, X_MH, front


def _export_pose(rng) -> tuple[str, np.ndarray]:
    """A CAD-like pose of H in the exported file M: axle along a file axis, origin on the
    axle at a random offset (e.g. the rim's centre plane)."""
    choice = str(rng.choice(_EXPORT_POSES))
    z = {"+z": (0, 0, 1), "-z": (0, 0, -1), "+y": (0, 1, 0), "-y": (0, -1, 0),
         "+x": (1, 0, 0)}[choice]
    z = np.array(z, float)
    x = np.array([1.0, 0, 0]) if abs(z[0]) < 0.5 else np.array([0, 1.0, 0])
    X = np.eye(4)
    X[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    X[:3, 3] = z * round(float(rng.uniform(-0.12, 0.05)), 4)
    return choice, X


def export_mesh(hub_dir: Path, unit: str, X_MH: np.ndarray, front: str) -> dict:
    """Write ``<name>_<unit>.stl`` (binary, the hub moved by ``X_MH``, scaled to ``unit``) and
    ``export.json`` into a generated hub folder; returns the export.json content."""
    from drakedeburr.hub.files import stl_bytes
    from drakedeburr.hub.model import read_obj

    V_H, F = read_obj(hub_dir / "hub.obj")
    V_M = V_H @ X_MH[:3, :3].T + X_MH[:3, 3]
    scale = 1e3 if unit == "mm" else 1.0
    name = f"{hub_dir.name}_{unit}.stl"
    atomic_write_bytes(hub_dir / name, stl_bytes(V_M * scale, F, f"drakedeburr hub "
                                                 f"{hub_dir.name} ({unit})"))
    info = {"file": name, "unit": unit, "front": front,
            "X_MH_m": np.round(X_MH, 9).tolist(),
            "note": "the hub mesh as a user's CAD export: p_M = R_MH p_H + p_MH (metres), "
                    "then scaled to the unit; the front face looks along the 'front' axis"}
    atomic_write_text(hub_dir / "export.json", json.dumps(info, indent=2) + "\n")
    return info


def random_catalogue(seed: int, count: int, out: str | Path, *, start: int = 0,
                     burr_diameter: float = DEFAULT_BURR_DIAMETER,
                     with_collision: bool = True, export: bool = True,
                     progress: Progress = None) -> list:
    """Generate hubs ``start .. start + count - 1`` of catalogue ``seed`` into ``out/<name>``.

    Each folder is a hub model like ``hub generate`` writes, plus (``export``) an STL of the
    mesh in mm or m and a CAD-like pose, described by ``export.json``.

    Returns:
        The list of :class:`~drakedeburr.hub.generate.GeneratedHub`.
    """
    from drakedeburr.hub.generate import generate_hub

    if count < 1:
        raise InputError(f"random hub catalogue: count must be >= 1, got {count}")
    out = Path(out)
    results = []
    for k, index in enumerate(range(start, start + count)):
        if progress is not None:
            progress(k, count, f"hub {index}")
        attempt = 0
        for _ in range(_ATTEMPTS):
            spec, attempt = _spec_and_attempt(seed, index, burr_diameter, MIN_WIDTH_FACTOR,
                                              attempt)
            try:
                res = generate_hub(spec, out / spec.name, with_collision=with_collision)
                break
            except (RuntimeError, InputError) as exc:  # geometry the mesher refuses
                log.warning("random hub %s (attempt %d): %s; drawing again", spec.name,
                            attempt, exc)
                attempt += 1
        else:
            raise RuntimeError(f"random hub seed {seed} index {index}: no spec could be "
                               f"meshed in {_ATTEMPTS} attempts")
        if export:
            export_mesh(res.dir, *export_choice(seed, index))
        results.append(res)
    if progress is not None:
        progress(count, count, "done")
    return results
