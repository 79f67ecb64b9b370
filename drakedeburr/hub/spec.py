"""HubSpec: the parameters of a parametric car-wheel hub, with YAML round trip and validation.

All fields are SI (metres, radians). The YAML file ``models/hubs/<name>/hub.yaml`` speaks the
industry's millimetres and degrees (keys end in ``_mm`` / ``_deg``); conversion happens here
only, through :mod:`drakedeburr.units`.

Geometry in the hub frame H (origin on the hub axis at the centre of the front face, +Z along the
axle out of the visible face):

* the **face plate** is a disc of thickness ``face_thickness`` whose front surface is
  ``z = z_face(r)``: flat (z = 0) for r <= ``dish_inner_radius``, rising smoothly (C1
  smoothstep) to ``dish_depth`` at ``dish_outer_radius`` and flat beyond. A positive
  ``dish_depth`` gives the usual concave wheel (centre recessed behind the rim lip).
* **windows** are the through-openings between the spokes inside the annulus
  ``window_inner_radius < r < window_outer_radius``; their convex corners are rounded with
  ``fillet_radius`` (``fillet_radius_small`` for the small windows of split spokes); reflex
  corners (where a split spoke forks, or a curved spoke's side meets a fillet) are blended with
  ``blend_radius`` (at most the window's fillet radius). Window side walls are parallel to the
  hub axis (no draft).
* **spokes**: ``spoke_count`` spokes of style ``straight`` (tapered from ``spoke_width`` at the
  window inner radius to ``spoke_width_outer`` at the outer radius), ``curved`` (the same band
  swept by ``spoke_sweep`` about the axis between the inner and outer window radius) or
  ``split`` (a stem up to ``split_radius`` that forks into two arms of width
  ``spoke_width_outer`` reaching ``+-split_angle`` about the stem at the window outer radius;
  the opening between the two arms is a *small* window, the one between neighbouring spokes a
  *large* window).
* the **rim** is a barrel (outer diameter ``rim_barrel_diameter``, wall ``rim_thickness``,
  axial width ``rim_width``) with a front flange (outer diameter ``rim_outer_diameter``) whose
  top stands ``rim_lip_height`` proud of the face edge; a back flange closes the barrel.
* the **hub pad** is a boss of radius ``hub_pad_radius`` and depth ``hub_pad_depth`` behind the
  face with the centre bore and ``bolt_count`` bolt holes on the bolt circle; with
  ``bolt_seat_diameter`` > 0 each hole has a 60 deg conical lug seat on the front.

Optional features (off by default; written to YAML only when set):

* ``twin`` spokes: a stem up to ``split_radius`` that forks into two parallel arms of width
  ``spoke_width_outer`` with a slot ``twin_gap`` wide between them (a *small* window).
* ``spoke_twist``: straight, curved and twin spokes turn about their radial centre line, by
  ``spoke_twist * sin^2(pi u)`` (u = 0 at the window inner radius, 1 at the outer one), so the
  face height changes across the spoke.
* ``face_rise_angle``: within ``face_rise_band`` of a window edge the front face falls toward
  the edge; it meets the edge at this angle (the face *rises* away from the window).
* ``wall_draft``: window walls lean so the opening narrows toward the back (cast draft).
* ``edge_round_radius``: the edge between the front face and a window wall is rounded; the
  deburring edge (``p_HE``) is then the line where the face meets the round.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import yaml

from drakedeburr.errors import InputError
from drakedeburr.units import deg_from_rad, m_from_mm, mm_from_m, rad_from_deg

__all__ = ["SpokeStyle", "SPOKE_STYLES", "HubSpec", "load_spec", "spec_to_yaml",
           "spec_from_mapping", "LUG_SEAT_HALF_ANGLE"]

SpokeStyle = Literal["straight", "curved", "split", "twin"]
SPOKE_STYLES = ("straight", "curved", "split", "twin")
LUG_SEAT_HALF_ANGLE = math.radians(30.0)  # 60 deg cone seat of lug nuts/bolts (DIN 74361)

# fields given in the YAML in millimetres / degrees (key gets the suffix)
_ANGLE_FIELDS = ("spoke_sweep", "split_angle", "spoke_twist", "face_rise_angle", "wall_draft")
# written to the YAML only when they differ from their default (hub.yaml of the bundled hubs,
# written before these existed, stays byte-identical)
_OPTIONAL_FIELDS = ("twin_gap", "spoke_twist", "face_rise_angle", "face_rise_band",
                    "wall_draft", "edge_round_radius", "bolt_seat_diameter")
_PLAIN_FIELDS = ("name", "description", "spoke_count", "spoke_style", "bolt_count",
                 "density")


@dataclass(frozen=True)
class HubSpec:
    """Parameters of one parametric hub. SI units: metres, radians, kg/m^3.

    See the module docstring for the meaning of each group of fields.
    """

    name: str
    description: str = ""
    spoke_count: int = 5
    spoke_style: SpokeStyle = "straight"
    # rim
    rim_outer_diameter: float = 0.470  # front flange outer diameter
    rim_barrel_diameter: float = 0.432  # barrel outer diameter (17 in bead seat)
    rim_thickness: float = 0.006  # barrel wall
    rim_width: float = 0.190  # axial length of the barrel (7.5 in)
    rim_lip_height: float = 0.006  # flange top above the face edge
    rim_flange_thickness: float = 0.012  # axial thickness of the front/back flanges
    # face
    face_thickness: float = 0.020
    dish_depth: float = 0.030
    dish_inner_radius: float = 0.085
    dish_outer_radius: float = 0.200
    # windows and spokes
    window_inner_radius: float = 0.085
    window_outer_radius: float = 0.180
    spoke_width: float = 0.040  # at window_inner_radius
    spoke_width_outer: float = 0.034  # at window_outer_radius (also the arm width of split)
    spoke_sweep: float = 0.0  # curved: angular sweep of the centre line [rad]
    split_radius: float = 0.120  # split: radius where the stem forks
    split_angle: float = math.radians(12.0)  # split: arms' half-spread at window_outer_radius
    fillet_radius: float = 0.010  # large windows
    fillet_radius_small: float = 0.004  # small windows (split style)
    blend_radius: float = 0.005  # reflex (concave) outline corners, e.g. where a split spoke forks
    twin_gap: float = 0.020  # twin: slot width between the two arms
    spoke_twist: float = 0.0  # twist of the spokes about their centre line at mid-span [rad]
    face_rise_angle: float = 0.0  # face meets the window edge at this angle [rad]
    face_rise_band: float = 0.008  # ... over this distance from the edge
    wall_draft: float = 0.0  # window walls lean by this angle (opening narrower at the back)
    edge_round_radius: float = 0.0  # round between the front face and the window walls
    # centre
    center_bore_diameter: float = 0.0571
    bolt_count: int = 5
    bolt_circle_diameter: float = 0.1143
    bolt_hole_diameter: float = 0.015
    bolt_seat_diameter: float = 0.0  # 60 deg lug seat on the front; 0: plain holes
    hub_pad_radius: float = 0.080
    hub_pad_depth: float = 0.030
    # meshing and material
    mesh_edge_length: float = 0.008  # refinement of the face before dishing
    edge_sample_spacing: float = 0.0005  # max spacing of window-edge points
    density: float = 2700.0  # aluminium [kg/m^3]

    # ------------------------------------------------------------------ derived
    @property
    def rim_barrel_inner_radius(self) -> float:
        return 0.5 * self.rim_barrel_diameter - self.rim_thickness

    @property
    def spoke_phase(self) -> float:
        """Angle of spoke 0 about +Z_H [rad]: chosen so window 0 is the first large window CCW
        from +X_H (for split spokes the windows alternate large, small, large, ...)."""
        forked = self.spoke_style in ("split", "twin")
        return -math.pi / (2 * self.spoke_count) if forked else 0.0

    @property
    def window_count(self) -> int:
        return self.spoke_count * (2 if self.spoke_style in ("split", "twin") else 1)

    def z_face(self, r):
        """Front-face height z_face(r) [m] at radius r [m] (scalar or array)."""
        import numpy as np

        u = np.clip((np.asarray(r, float) - self.dish_inner_radius)
                    / (self.dish_outer_radius - self.dish_inner_radius), 0.0, 1.0)
        return self.dish_depth * u * u * (3.0 - 2.0 * u)

    def dz_face_dr(self, r):
        """d z_face / d r [-] at radius r [m]."""
        import numpy as np

        span = self.dish_outer_radius - self.dish_inner_radius
        u = (np.asarray(r, float) - self.dish_inner_radius) / span
        inside = (u > 0.0) & (u < 1.0)
        return np.where(inside, self.dish_depth * 6.0 * u * (1.0 - u) / span, 0.0)

    def uses_optional_features(self) -> bool:
        """True when a field added after the bundled hubs were made is set (twin spokes,
        twist, face rise, draft, edge round, lug seats)."""
        return self.spoke_style == "twin" or any(
            getattr(self, f) != getattr(HubSpec, f) for f in _OPTIONAL_FIELDS)

    # --------------------------------------------------------------- validation
    def validate(self, source: str = "") -> HubSpec:
        """Check the parameters; raise InputError naming the field. Returns self."""
        where = f"{source}: " if source else ""
        where += f"hub {self.name!r}: "

        def bad(field: str, msg: str) -> InputError:
            return InputError(f"{where}field {field!r}: {msg}")

        _check_kinds(self, bad)
        _check_rim_and_face(self, bad)
        _check_centre(self, bad)
        _check_spokes(self, bad)
        _check_edge_features(self, bad)
        return self


def _check_kinds(s: HubSpec, bad) -> None:
    from drakedeburr._io import check_path_name

    try:  # the name becomes the hub's folder: no separators, '..', control or shell characters
        check_path_name(s.name, "the name")
    except InputError as exc:
        raise bad("name", str(exc)) from None
    if s.spoke_style not in SPOKE_STYLES:
        raise bad("spoke_style", f"must be one of {', '.join(SPOKE_STYLES)}, got "
                  f"{s.spoke_style!r}")
    if not isinstance(s.spoke_count, int) or not 3 <= s.spoke_count <= 12:
        raise bad("spoke_count", f"must be an integer 3..12, got {s.spoke_count!r}")
    if not isinstance(s.bolt_count, int) or not 0 <= s.bolt_count <= 10:
        raise bad("bolt_count", f"must be an integer 0..10, got {s.bolt_count!r}")
    for f in dataclasses.fields(s):
        v = getattr(s, f.name)
        if f.type in ("float",) and not (isinstance(v, int | float) and math.isfinite(v)):
            raise bad(f.name, f"must be a finite number, got {v!r}")
    positive = ("rim_outer_diameter", "rim_barrel_diameter", "rim_thickness", "rim_width",
                "rim_flange_thickness", "face_thickness", "window_inner_radius",
                "window_outer_radius", "spoke_width", "spoke_width_outer", "fillet_radius",
                "fillet_radius_small", "blend_radius", "center_bore_diameter",
                "hub_pad_radius", "mesh_edge_length", "edge_sample_spacing", "density",
                "dish_outer_radius", "face_rise_band")
    for name in positive:
        if getattr(s, name) <= 0:
            raise bad(name, f"must be > 0, got {getattr(s, name)!r}")
    for name in ("rim_lip_height", "hub_pad_depth", "dish_inner_radius", "edge_round_radius",
                 "bolt_seat_diameter"):
        if getattr(s, name) < 0:
            raise bad(name, f"must be >= 0, got {getattr(s, name)!r}")
    if s.edge_sample_spacing > 0.002:
        raise bad("edge_sample_spacing", "must be <= 2 mm")
    if s.mesh_edge_length > 0.02:
        raise bad("mesh_edge_length", "must be <= 20 mm (the dish would be faceted)")


def _check_rim_and_face(s: HubSpec, bad) -> None:
    if s.rim_outer_diameter <= s.rim_barrel_diameter:
        raise bad("rim_outer_diameter", "must exceed rim_barrel_diameter (flange)")
    if s.rim_thickness >= 0.25 * s.rim_barrel_diameter:
        raise bad("rim_thickness", "too thick for the barrel diameter")
    if s.window_outer_radius <= s.window_inner_radius:
        raise bad("window_outer_radius", "must exceed window_inner_radius")
    if s.window_outer_radius > s.rim_barrel_inner_radius - 0.005:
        raise bad("window_outer_radius",
                  f"must stay >= 5 mm inside the barrel (inner radius "
                  f"{mm_from_m(s.rim_barrel_inner_radius):.1f} mm)")
    if s.hub_pad_radius > s.window_inner_radius:
        raise bad("hub_pad_radius", "the boss behind the face must not reach under the windows"
                  " (hub_pad_radius <= window_inner_radius)")
    if s.dish_inner_radius < s.hub_pad_radius:
        raise bad("dish_inner_radius", "must be >= hub_pad_radius (the pad is flat)")
    if s.dish_outer_radius <= s.dish_inner_radius:
        raise bad("dish_outer_radius", "must exceed dish_inner_radius")
    if s.dish_outer_radius > s.rim_barrel_inner_radius:
        raise bad("dish_outer_radius", "must not exceed the barrel inner radius")
    span = s.dish_outer_radius - s.dish_inner_radius
    if abs(s.dish_depth) * 1.5 / span > 1.5:
        raise bad("dish_depth", "face slope above 56 deg; the dish is too deep for its span")


def _check_centre(s: HubSpec, bad) -> None:
    """Bore, bolts and pad."""
    if s.center_bore_diameter / 2 >= s.bolt_circle_diameter / 2 - s.bolt_hole_diameter:
        raise bad("center_bore_diameter", "bore reaches the bolt holes")
    if not s.bolt_count:
        return
    if s.bolt_hole_diameter <= 0:
        raise bad("bolt_hole_diameter", "must be > 0")
    if s.bolt_circle_diameter / 2 + s.bolt_hole_diameter > s.hub_pad_radius:
        raise bad("bolt_circle_diameter", "bolt holes must lie inside the hub pad")
    pitch = s.bolt_circle_diameter * math.sin(math.pi / s.bolt_count)
    if s.bolt_count > 1 and pitch < 1.5 * s.bolt_hole_diameter:
        raise bad("bolt_hole_diameter", "bolt holes overlap each other")
    if s.bolt_seat_diameter:
        if s.bolt_seat_diameter <= s.bolt_hole_diameter:
            raise bad("bolt_seat_diameter", "the lug seat must be wider than the bolt hole")
        if s.bolt_count > 1 and pitch < 1.1 * s.bolt_seat_diameter:
            raise bad("bolt_seat_diameter", "lug seats overlap each other")
        if s.bolt_circle_diameter / 2 + s.bolt_seat_diameter / 2 > s.dish_inner_radius:
            raise bad("bolt_seat_diameter", "lug seats must lie on the flat pad face "
                      "(inside dish_inner_radius)")
        if s.bolt_circle_diameter / 2 - s.bolt_seat_diameter / 2 <= s.center_bore_diameter / 2:
            raise bad("bolt_seat_diameter", "lug seats reach the centre bore")
        depth = 0.5 * (s.bolt_seat_diameter - s.bolt_hole_diameter) / math.tan(LUG_SEAT_HALF_ANGLE)
        if depth >= s.face_thickness + s.hub_pad_depth - 0.002:
            raise bad("bolt_seat_diameter", "the lug seat cone is deeper than the pad")


def _check_spokes(s: HubSpec, bad) -> None:
    radial = s.window_outer_radius - s.window_inner_radius
    if 2 * s.fillet_radius + 0.002 > radial:
        raise bad("fillet_radius", "larger than half the radial size of the windows")
    if s.fillet_radius_small > s.fillet_radius:
        raise bad("fillet_radius_small", "must not exceed fillet_radius")
    # spokes: the gap between spokes at the window inner radius must hold a window
    n = s.spoke_count
    gap_in = 2 * s.window_inner_radius * math.sin(math.pi / n) - s.spoke_width
    gap_out = 2 * s.window_outer_radius * math.sin(math.pi / n) - s.spoke_width_outer
    if s.spoke_style in ("split", "twin"):
        if not s.window_inner_radius < s.split_radius < s.window_outer_radius:
            raise bad("split_radius", "must lie between the window inner and outer radius")
    if s.spoke_style == "split":
        # two arms per spoke share the pitch at the outer radius
        arm_gap = 2 * s.window_outer_radius * math.sin(s.split_angle) - s.spoke_width_outer
        gap_out = 2 * s.window_outer_radius * math.sin(math.pi / n - s.split_angle) \
            - s.spoke_width_outer
        if not 0 < s.split_angle < math.pi / n:
            raise bad("split_angle", f"must be in (0, {deg_from_rad(math.pi / n):.1f} deg)")
        if arm_gap < 2 * s.fillet_radius_small + 0.002:
            raise bad("spoke_width_outer", "arms of a split spoke too wide for split_angle: "
                      "no room for the small window")
    if s.spoke_style == "twin":
        span = s.twin_gap + 2 * s.spoke_width_outer  # both arms and the slot
        gap_out = 2 * s.window_outer_radius * math.sin(math.pi / n) - span
        if s.twin_gap < 2 * s.fillet_radius_small + 0.002:
            raise bad("twin_gap", "the slot between twin arms cannot hold its fillets")
        if s.split_radius + 0.5 * (s.twin_gap + s.spoke_width_outer) + 2 * s.fillet_radius_small \
                + 0.002 > s.window_outer_radius:
            raise bad("split_radius", "twin arms fork too close to the window outer radius")
    if gap_in < 2 * s.fillet_radius + 0.002:
        raise bad("spoke_width", f"too wide for {n} spokes at the window inner radius: the "
                  f"gap {mm_from_m(gap_in):.1f} mm cannot hold a window with "
                  f"{mm_from_m(s.fillet_radius):.1f} mm fillets")
    if gap_out < 2 * s.fillet_radius + 0.002:
        raise bad("spoke_width_outer", f"too wide for {n} spokes at the window outer radius")
    if abs(s.spoke_sweep) > math.radians(60):
        raise bad("spoke_sweep", "must be within +-60 deg")
    if s.spoke_sweep and s.spoke_style != "curved":
        raise bad("spoke_sweep", "only curved spokes are swept")


def _check_edge_features(s: HubSpec, bad) -> None:
    """Twist, face rise, draft and edge round."""
    if abs(s.spoke_twist) > math.radians(30):
        raise bad("spoke_twist", "must be within +-30 deg")
    if s.spoke_twist and s.spoke_style == "split":
        raise bad("spoke_twist", "Y (split) spokes are not twisted")
    if not 0 <= s.face_rise_angle <= math.radians(35):
        raise bad("face_rise_angle", "must be in [0, 35] deg")
    if s.face_rise_band > 0.03:
        raise bad("face_rise_band", "must be <= 30 mm")
    if not 0 <= s.wall_draft <= math.radians(8):
        raise bad("wall_draft", "must be in [0, 8] deg (the opening narrows toward the back)")
    if s.edge_round_radius > min(0.004, 0.6 * s.blend_radius, 0.4 * s.fillet_radius_small):
        raise bad("edge_round_radius", "must be <= 4 mm, <= 0.6 blend_radius and <= 0.4 "
                  "fillet_radius_small")
    shrink = s.face_thickness * math.tan(s.wall_draft)
    if shrink >= 0.5 * s.fillet_radius_small:
        raise bad("wall_draft", "the draft closes the small fillets at the back of the face")


# --------------------------------------------------------------------------- YAML
def _yaml_key(field: str) -> str:
    if field in _PLAIN_FIELDS:
        return field
    return field + ("_deg" if field in _ANGLE_FIELDS else "_mm")


def spec_to_mapping(spec: HubSpec) -> dict:
    """HubSpec -> dict in the YAML's units (mm, deg), field order kept."""
    out: dict = {}
    for f in dataclasses.fields(spec):
        v = getattr(spec, f.name)
        if f.name in _OPTIONAL_FIELDS and v == f.default:
            continue
        if f.name in _PLAIN_FIELDS:
            out[f.name] = v
        elif f.name in _ANGLE_FIELDS:
            out[_yaml_key(f.name)] = _short(deg_from_rad(v), lambda d, v=v: rad_from_deg(d) == v)
        else:
            out[_yaml_key(f.name)] = _short(mm_from_m(v), lambda d, v=v: m_from_mm(d) == v)
    return out


def _short(value: float, exact) -> float:
    """The shortest decimal rounding of ``value`` that converts back exactly (YAML round trip)."""
    for digits in range(0, 17):
        cand = round(value, digits)
        if exact(cand):
            return cand
    return value


def spec_to_yaml(spec: HubSpec) -> str:
    """The hub.yaml text of a spec (deterministic)."""
    head = ("# drakedeburr parametric hub (see docs/hub.md). Lengths in mm, angles in deg.\n"
            "# Regenerate the assets with: drakedeburr hub generate " + spec.name + "\n")
    return head + yaml.safe_dump(spec_to_mapping(spec), sort_keys=False, default_flow_style=False)


def spec_from_mapping(data: dict, source: str = "") -> HubSpec:
    """dict in the YAML's units -> validated HubSpec. Unknown keys raise InputError."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a mapping of HubSpec fields")
    by_key = {_yaml_key(f.name): f for f in dataclasses.fields(HubSpec)}
    kwargs = {}
    for key, value in data.items():
        if key in ("window_summary", "generated"):
            continue  # informative sections written by the generator
        if key not in by_key:
            raise InputError(f"{source}: unknown hub field {key!r}; known: {sorted(by_key)}")
        f = by_key[key]
        if f.name in ("spoke_count", "bolt_count"):
            if not isinstance(value, int) or isinstance(value, bool):
                raise InputError(f"{source}: field {key!r} must be an integer, got {value!r}")
        elif f.name in ("name", "description", "spoke_style"):
            value = str(value)
        elif f.name in _PLAIN_FIELDS:
            value = float(value)
        else:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InputError(f"{source}: field {key!r} must be a number, got {value!r}")
            value = rad_from_deg(float(value)) if f.name in _ANGLE_FIELDS else m_from_mm(
                float(value))
        kwargs[f.name] = value
    if "name" not in kwargs:
        raise InputError(f"{source}: hub spec needs a 'name'")
    return HubSpec(**kwargs).validate(source)


def load_spec(path: str | Path) -> HubSpec:
    """Read a hub.yaml (or a hub folder holding one) into a validated HubSpec."""
    path = Path(path)
    if path.is_dir():
        path = path / "hub.yaml"
    from drakedeburr._io import load_yaml

    data = load_yaml(path, "hub spec")  # bounded: size, aliases, duplicate keys, encoding
    return spec_from_mapping(data, str(path))
