"""Tool geometry: the conical carbide burr, the floating spindle and the spindle stand.

The numbers here are the single source of the tool models. ``models/tools/*.sdf`` and
``models/tools/burr_head.obj`` are *generated* from them by :func:`write_tool_models`
(``python -m drakedeburr.cell`` regenerates them; a test checks the committed files are
identical), so the planner, the verifier and the Drake models cannot drift apart.

Frames (DESIGN.md conventions):

* S, spindle nose: origin at the centre of the collet face, +Z_S along the burr axis pointing
  out of the spindle (spindle -> tip). The ``burr`` body frame of each tool model is S.
* T, ``tool_tip``: the cutting point. It lies on the burr axis at the axial height of the
  *nominal contact circle*: the circle of radius ``contact_radius`` on the 45 deg flank of the
  cone. +Z_T = +Z_S. The window edge is cut by that circle: with the tool axis through the
  edge's inner side and T offset by ``contact_radius`` from the edge along the inner normal
  (in the plane normal to the axis), the flank touches the edge at its nominal radius.
* A, ``burr_apex``: the cone apex, ``apex_offset`` ahead of T along +Z_T.

Floating spindle (tool-in-hand): mounted on the flange F through a bracket with its axis tilted
by ``mount_angle`` from the flange axis +Z_F (about +Y_F, tip towards +X_F). Why 45 deg: with a
straight mount (0 deg) a vertical burr over a hub in front of the robot fixes J5 = 90 deg minus
the forearm pitch, so a steeply pitched forearm drives J5 to its singularity at 0 and the
process tilt of up to 0.44 rad pushes it towards either the singularity or the 115 deg limit;
with a right-angle mount (90 deg) the flange axis is horizontal and J5 = 0 is reached whenever
the tool spin lines the flange up with the forearm. At 45 deg, J5 stays at least
45 deg - |forearm pitch| away from 0 for *every* spin about the burr axis, and the spin (free for
a rotationally symmetric burr) moves J5 across [45 deg - pitch, 135 deg - pitch], so the planner
can centre it. It also keeps the spindle body clear of the wrist.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text, round_numbers

__all__ = [
    "BurrGeometry",
    "BURR_HEADS",
    "FloatingSpindle",
    "SpindleStand",
    "BURR",
    "FLOATING_SPINDLE",
    "SPINDLE_STAND",
    "X_FS_floating",
    "COAXIAL_BRACKET_URL",
    "COAXIAL_SPINDLE_URL",
    "coaxial_X_FM",
    "ToolVariant",
    "TOOL_VARIANTS",
    "DEFAULT_TOOL",
    "tool_variant",
    "variant_model_url",
    "apply_tool",
    "write_tool_models",
    "tool_model_texts",
]


@dataclass(frozen=True)
class BurrGeometry:
    """Conical carbide burr (90 deg included angle) in the spindle nose frame S. SI units.

    Attributes:
        cone_half_angle: half of the included cone angle [rad] (pi/4 for a 90 deg burr).
        head_diameter: diameter of the cone base, the widest part of the head [m].
        contact_radius: radius of the nominal contact circle on the flank [m]; T sits on the
            axis at the height of that circle.
        shank_diameter: [m].
        stick_out: exposed shank length between the collet face and the head base [m].
        collet_diameter: diameter of the collet nut [m].
        collet_length: collet nut length ahead of the spindle body [m] (z_S in [0, this]).
        segments: polygon count of the cone mesh.
    """

    cone_half_angle: float = math.pi / 4
    head_diameter: float = 12e-3
    contact_radius: float = 3e-3
    shank_diameter: float = 6e-3
    stick_out: float = 25e-3
    collet_diameter: float = 30e-3
    collet_length: float = 20e-3
    segments: int = 48

    def __post_init__(self) -> None:
        if not 0.0 < self.cone_half_angle < math.pi / 2:
            raise ValueError(f"cone_half_angle must be in (0, pi/2), got {self.cone_half_angle}")
        if not 0.0 < self.contact_radius < self.head_diameter / 2:
            raise ValueError(
                f"contact_radius {self.contact_radius} must lie on the flank "
                f"(0, head_diameter/2 = {self.head_diameter / 2})"
            )

    @property
    def head_radius(self) -> float:
        return self.head_diameter / 2

    @property
    def head_length(self) -> float:
        """Axial length of the cone from its base to the apex [m]."""
        return self.head_radius / math.tan(self.cone_half_angle)

    @property
    def apex_offset(self) -> float:
        """Distance from T to the apex along +Z_T [m]."""
        return self.contact_radius / math.tan(self.cone_half_angle)

    @property
    def z_head_base(self) -> float:
        """z_S of the cone base (head starts here) [m]."""
        return self.collet_length + self.stick_out

    @property
    def z_apex(self) -> float:
        """z_S of the apex [m]."""
        return self.z_head_base + self.head_length

    @property
    def z_tool_tip(self) -> float:
        """z_S of the cutting point T [m]."""
        return self.z_apex - self.apex_offset

    def flank_radius(self, z_T: np.ndarray | float) -> np.ndarray | float:
        """Cone radius at axial coordinate z_T along +Z_T measured from T [m].

        Zero at the apex, ``contact_radius`` at z_T = 0, ``head_radius`` at the base; NaN
        outside the head.
        """
        z = np.asarray(z_T, dtype=float)
        r = (self.apex_offset - z) * math.tan(self.cone_half_angle)
        return np.where((r >= -1e-15) & (r <= self.head_radius + 1e-15), r, np.nan)


@dataclass(frozen=True)
class FloatingSpindle:
    """Radially compliant deburring spindle on the flange (tool-in-hand). SI units.

    The mount frame M of the model equals the flange frame F (welded to ``irb1600::flange``).

    Attributes:
        body_diameter, body_length: spindle body cylinder [m]; it ends at the nose S.
        mount_angle: angle between +Z_F and the burr axis +Z_S [rad], a rotation about +Y_F.
        p_FC: (3,) centre of the spindle body in F [m].
        plate_radius, plate_thickness: flange adapter plate (z_F in [0, thickness]) [m].
        mass: spindle + bracket mass [kg] (RC-340 class spindles weigh about 2.5 kg).
        burr: the burr.
    """

    body_diameter: float = 80e-3
    body_length: float = 250e-3
    mount_angle: float = math.pi / 4
    p_FC: tuple[float, float, float] = (-0.02, 0.0, 0.125)
    plate_radius: float = 0.05
    plate_thickness: float = 0.02
    mass: float = 3.0
    burr: BurrGeometry = field(default_factory=BurrGeometry)

    @property
    def axis_F(self) -> np.ndarray:
        """(3,) unit burr axis +Z_S in F."""
        return np.array([math.sin(self.mount_angle), 0.0, math.cos(self.mount_angle)])

    @property
    def p_FS(self) -> np.ndarray:
        """(3,) spindle nose origin in F [m]."""
        return np.asarray(self.p_FC) + 0.5 * self.body_length * self.axis_F

    @property
    def p_FT(self) -> np.ndarray:
        """(3,) cutting point T in F [m]."""
        return self.p_FS + self.burr.z_tool_tip * self.axis_F


@dataclass(frozen=True)
class SpindleStand:
    """Fixed spindle on a floor stand (workpiece-in-hand). SI units.

    Stand frame: origin on the floor at the column axis, +Z up. The spindle axis is vertical,
    burr pointing up, nose at height ``nose_height`` (1.20 m: with the robot on its 0.8 m pedestal
    the cutting point is 0.45 m above the robot base, where the forearm presents the face-down
    hub with the wrist far from its singularity; docs/cell.md, "Workpiece cell layout study").
    """

    column_width: float = 0.14
    base_size: float = 0.40
    base_thickness: float = 0.03
    nose_height: float = 1.20
    body_diameter: float = 80e-3
    body_length: float = 250e-3
    burr: BurrGeometry = field(default_factory=BurrGeometry)

    @property
    def p_ST_stand(self) -> np.ndarray:
        """(3,) cutting point T in the stand frame [m]."""
        return np.array([0.0, 0.0, self.nose_height + self.burr.z_tool_tip])


BURR = BurrGeometry()
#: The burr heads of the tool library, largest first: the standard 12 mm head and the small
#: 6 mm head (a 6 mm, 90 deg carbide cone on a 3 mm shank, as burr makers sell them for
#: narrow slots). The hub stage judges an opening by them (hub.openings.burr_need: head + 2 x
#: clearance, smallest need tried before an opening is refused; DEFAULT_BURR_DIAMETERS there
#: is tested equal). The cell's spindle models carry the standard head.
BURR_HEADS = {"standard": BURR,
              "small": replace(BURR, head_diameter=6e-3, contact_radius=1.5e-3,
                               shank_diameter=3e-3)}
FLOATING_SPINDLE = FloatingSpindle(burr=BURR)
SPINDLE_STAND = SpindleStand(burr=BURR)


@dataclass(frozen=True)
class ToolVariant:
    """One burr the cell can carry: the same head on another shank length. SI units.

    Attributes:
        name: the variant's name (``plan.meta["tool"]``, ``drakedeburr plan --tool``).
        title: one line for reports and program headers.
        burr: its geometry; the head is the standard one (the same cut, the same
            ``burr_head.obj``), only the stick-out differs.
        suffix: file name suffix of its models (``floating_spindle{suffix}.sdf``).
    """

    name: str
    title: str
    burr: BurrGeometry
    suffix: str


#: The long-reach burr: the standard head on a 6 mm shank with 75 mm stick-out (the standard
#: 25 mm + 50 mm), as carbide burr makers sell them (100-150 mm overall length) for deep
#: pockets. It keeps the 80 mm spindle body 50 mm further back along the burr axis, which is
#: what a deep dish needs: tilted 0.44 rad (the source's largest tilt) over the opening, the
#: standard body's near side is ~16 mm beyond the cutting point towards the rim, ~60 mm above
#: it, so an 80-90 mm dish wall beside a window meets it. Its cost is stiffness: a carbide
#: shank (E ~ 600 GPa, d = 6 mm) deflects F L^3 / (3 E I) ~ 0.08 mm at 20 N radial force with
#: the contact 78 mm out, against ~0.004 mm at 28 mm; the floating spindle's radial stroke
#: (millimetres) takes both, the chamfer width tolerance (0.5-1.5 mm) the difference.
#: The planner uses it only for a hub the standard burr cannot cut (docs/cell.md, "Tools").
TOOL_VARIANTS = {
    "standard": ToolVariant("standard", "standard burr (25 mm stick-out)", BURR, ""),
    "long_reach": ToolVariant("long_reach", "long-reach burr (75 mm stick-out)",
                              replace(BURR, stick_out=75e-3), "_long_reach"),
}
DEFAULT_TOOL = "standard"

#: the bundled tool models a variant replaces in a scenario (their file names' stems)
_VARIANT_MODELS = ("floating_spindle", "spindle_stand", "floating_spindle_coaxial")


def tool_variant(name: str | None) -> ToolVariant:
    """The variant called ``name`` (None: the standard burr); ValueError for an unknown one."""
    try:
        return TOOL_VARIANTS[name or DEFAULT_TOOL]
    except KeyError:
        raise ValueError(f"unknown tool {name!r}; known: {', '.join(TOOL_VARIANTS)}") from None


def variant_model_url(url: str, name: str | None) -> str | None:
    """The model URL of tool variant ``name`` for a scenario's tool model ``url``, or None
    when ``url`` is not one of the bundled tool models (then no variant of it exists)."""
    prefix = "package://drakedeburr/tools/"
    if not url.startswith(prefix):
        return None
    stem = url[len(prefix):].removesuffix(".sdf")
    for base in _VARIANT_MODELS:
        if stem in (base + v.suffix for v in TOOL_VARIANTS.values()):
            return f"{prefix}{base}{tool_variant(name).suffix}.sdf"
    return None


def apply_tool(directives, scenario_file: Path, name: str | None) -> str | None:
    """Swap a scenario's bundled tool model (floating spindle or spindle stand) for variant
    ``name`` in its model directives (in place). Returns the variant's name, or None for a
    scenario without a bundled tool model when ``name`` asks for none.

    Raises:
        InputError: ``name`` is unknown, or names a variant for a scenario that carries its own
            tool model (its variants are the scenario author's to write).
    """
    from drakedeburr.errors import InputError

    try:
        variant = tool_variant(name)
    except ValueError as exc:
        raise InputError(f"{scenario_file}: {exc}") from None
    items = list(directives.directives)  # (the bindings hand out copies: edit, then set back)
    found = None
    for d in items:
        url = None if d.add_model is None else variant_model_url(d.add_model.file, variant.name)
        if url is not None:
            d.add_model.file, found = url, variant.name
    if found is None and name not in (None, DEFAULT_TOOL):
        raise InputError(f"{scenario_file}: no bundled spindle model to fit the {variant.title} "
                         "to; a scenario with its own tool model carries its own burr")
    directives.directives = items
    return found


def X_FS_floating(spindle: FloatingSpindle = FLOATING_SPINDLE) -> np.ndarray:
    """(4, 4) pose of the spindle nose frame S in the flange frame F [m]."""
    X = np.eye(4)
    c, s = math.cos(spindle.mount_angle), math.sin(spindle.mount_angle)
    X[:3, :3] = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    X[:3, 3] = spindle.p_FS
    return X


#: the coaxial straight bracket's model and the spindle it holds (the bundled spindle without
#: its 45 deg bracket: adapter plate and bracket block), placed by :func:`coaxial_X_FM`
#: (``drakedeburr cell study``)
COAXIAL_BRACKET_URL = "package://drakedeburr/tools/coaxial_bracket.sdf"
COAXIAL_SPINDLE_URL = "package://drakedeburr/tools/floating_spindle_coaxial.sdf"


def coaxial_X_FM(spindle: FloatingSpindle = FLOATING_SPINDLE) -> np.ndarray:
    """(4, 4) the spindle model frame M in the flange frame F on the coaxial straight bracket [m].

    The bundled model (its burr axis ``mount_angle`` from +Z_M about +Y_M) turned by
    ``-mount_angle`` about +Y_F, so the burr axis is +Z_F, and moved normal to it so the axis
    runs through the flange centre; along it, the body's rear face stands on the bracket's
    flange plate (``plate_thickness`` thick). The burr tip then lies on the flange axis: a spin
    about the burr axis is J6 alone. The coaxial spindle model (``COAXIAL_SPINDLE_URL``) is the
    bundled one without its 45 deg bracket, so the body's rear is its lowest point.
    """
    a = spindle.mount_angle
    axis = spindle.axis_F  # the burr axis in M
    normal = np.array([math.cos(a), 0.0, -math.sin(a)])  # in M, turned onto +X_F
    p_c = np.asarray(spindle.p_FC, float)
    lowest = float(axis @ p_c) - spindle.body_length / 2
    c, s = math.cos(-a), math.sin(-a)
    X = np.eye(4)
    X[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    X[:3, 3] = (-float(normal @ p_c), 0.0, spindle.plate_thickness - lowest)
    return X


def _coaxial_bracket_sdf(sp: FloatingSpindle) -> str:
    """The coaxial straight bracket (model frame = F): a flange plate and a clamp ring round the
    spindle body's rear (the body stands on the plate), both collision geometry."""
    r_body = sp.body_diameter / 2
    ring_len = 0.05
    return (
        _HEADER
        + '  <model name="coaxial_bracket">\n'
        "    <!-- Model frame = the flange frame F (ABB tool0); drakedeburr.cell.tools."
        "coaxial_X_FM places the spindle on it. -->\n"
        '    <link name="bracket">\n'
        f"      {_inertia(0.6, 6e-4, 6e-4, 5e-4, (0, 0, sp.plate_thickness))}\n"
        + _shape("c", "flange_plate", (0, 0, sp.plate_thickness / 2), (0, 0, 0),
                 _cyl(sp.plate_radius, sp.plate_thickness), _DARK, True)
        + _shape("c", "clamp_ring", (0, 0, sp.plate_thickness + ring_len / 2), (0, 0, 0),
                 _cyl(r_body + 0.008, ring_len), _DARK, True)
        + "    </link>\n  </model>\n</sdf>\n"
    )


# --------------------------------------------------------------------------- model writers
def _f(x: float) -> str:
    return repr(float(x))


def _pose(xyz, rpy=(0.0, 0.0, 0.0)) -> str:
    return " ".join(_f(v) for v in (*xyz, *rpy))


def _inertia(mass: float, ixx: float, iyy: float, izz: float, xyz=(0, 0, 0), rpy=(0, 0, 0)) -> str:
    return (
        f"<inertial><pose>{_pose(xyz, rpy)}</pose><mass>{_f(mass)}</mass><inertia>"
        f"<ixx>{_f(ixx)}</ixx><iyy>{_f(iyy)}</iyy><izz>{_f(izz)}</izz>"
        "<ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>"
    )


def _shape(kind: str, name: str, xyz, rpy, geometry: str, color: str, collide: bool) -> str:
    out = (
        f'      <visual name="{name}"><pose>{_pose(xyz, rpy)}</pose><geometry>{geometry}</geometry>'
        f"<material><diffuse>{color}</diffuse></material></visual>\n"
    )
    if collide:
        out += (
            f'      <collision name="{name}"><pose>{_pose(xyz, rpy)}</pose>'
            f"<geometry>{geometry}</geometry></collision>\n"
        )
    return out


def _cyl(r: float, length: float) -> str:
    return f"<cylinder><radius>{_f(r)}</radius><length>{_f(length)}</length></cylinder>"


def _box(x: float, y: float, z: float) -> str:
    return f"<box><size>{_f(x)} {_f(y)} {_f(z)}</size></box>"


_STEEL = "0.7 0.7 0.72 1"
_DARK = "0.15 0.15 0.17 1"
_CARBIDE = "0.85 0.75 0.2 1"
_BLUE = "0.2 0.35 0.7 1"


def _burr_link(burr: BurrGeometry, pose_xml: str) -> str:
    """The ``burr`` link in nose frame S: collet nut, shank, head (cone mesh)."""
    shank_mid = burr.collet_length + burr.stick_out / 2
    head_mesh = (
        '<mesh><uri>package://drakedeburr/tools/burr_head.obj</uri>'
        "<drake:declare_convex/></mesh>"
    )
    return (
        '    <link name="burr">\n'
        f"      {pose_xml}\n"
        f"      {_inertia(0.05, 2e-5, 2e-5, 1e-5, (0, 0, burr.collet_length / 2))}\n"
        + _shape("c", "collet", (0, 0, burr.collet_length / 2), (0, 0, 0),
                 _cyl(burr.collet_diameter / 2, burr.collet_length), _STEEL, True)
        + _shape("c", "burr_shank", (0, 0, shank_mid), (0, 0, 0),
                 _cyl(burr.shank_diameter / 2, burr.stick_out), _STEEL, True)
        + _shape("c", "burr_head", (0, 0, burr.z_head_base), (0, 0, 0), head_mesh, _CARBIDE, True)
        + "    </link>\n"
    )


def _tool_frames(burr: BurrGeometry) -> str:
    return (
        '    <frame name="spindle_nose" attached_to="burr"><pose relative_to="burr">'
        "0 0 0 0 0 0</pose></frame>\n"
        '    <frame name="tool_tip" attached_to="burr"><pose relative_to="burr">'
        f"{_pose((0, 0, burr.z_tool_tip))}</pose></frame>\n"
        '    <frame name="burr_apex" attached_to="burr"><pose relative_to="burr">'
        f"{_pose((0, 0, burr.z_apex))}</pose></frame>\n"
    )


_HEADER = """<?xml version="1.0"?>
<!-- GENERATED by drakedeburr.cell.tools.write_tool_models from the dataclasses in
     drakedeburr/cell/tools.py. Do not edit by hand: change the dataclass and regenerate with
     `python -m drakedeburr.cell`. -->
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
"""


def _floating_spindle_sdf(sp: FloatingSpindle, own_bracket: bool = True) -> str:
    """The floating spindle; ``own_bracket`` False: without its adapter plate and bracket block
    (held by the coaxial bracket, :func:`coaxial_X_FM`)."""
    burr = sp.burr
    a = sp.mount_angle
    c = np.asarray(sp.p_FC)
    # bracket: a block from the adapter plate to the body clamp, along the mount direction
    clamp_len = 0.07
    block_top = c[2] - 0.5 * sp.body_diameter * math.sin(a) - 0.005
    block_h = max(block_top - sp.plate_thickness, 0.02) + 0.02
    block_z = sp.plate_thickness + block_h / 2 - 0.01
    return (
        _HEADER
        + '  <model name="floating_spindle">\n'
        "    <!-- Model frame = mount frame, welded to the robot flange F (ABB tool0). -->\n"
        '    <link name="spindle">\n'
        f"      {_inertia(sp.mass, 0.017, 0.017, 0.003, tuple(c), (0, a, 0))}\n"
        + (_shape("c", "adapter_plate", (0, 0, sp.plate_thickness / 2), (0, 0, 0),
                  _cyl(sp.plate_radius, sp.plate_thickness), _DARK, True)
           + _shape("c", "bracket", (0.0, 0, block_z), (0, 0, 0),
                    _box(0.07, 0.07, block_h), _DARK, True) if own_bracket else "")
        + _shape("c", "clamp", tuple(c), (0, a, 0),
                 _cyl(sp.body_diameter / 2 + 0.008, clamp_len), _DARK, True)
        + _shape("c", "spindle_body", tuple(c), (0, a, 0),
                 _cyl(sp.body_diameter / 2, sp.body_length), _BLUE, True)
        + "    </link>\n"
        + _burr_link(burr, f'<pose relative_to="spindle">{_pose(sp.p_FS, (0, a, 0))}</pose>')
        + '    <joint name="burr_weld" type="fixed"><parent>spindle</parent>'
        "<child>burr</child></joint>\n"
        + _tool_frames(burr)
        + "  </model>\n</sdf>\n"
    )


def _spindle_stand_sdf(st: SpindleStand) -> str:
    burr = st.burr
    col_h = st.nose_height - st.body_length * 0.6 - st.base_thickness
    body_z = st.nose_height - st.body_length / 2
    return (
        _HEADER
        + '  <model name="spindle_stand">\n'
        "    <!-- Model frame: on the floor at the column axis, +Z up. -->\n"
        '    <link name="stand">\n'
        f"      {_inertia(80.0, 3.0, 3.0, 1.0, (0, 0, 0.3))}\n"
        + _shape("c", "base_plate", (0, 0, st.base_thickness / 2), (0, 0, 0),
                 _box(st.base_size, st.base_size, st.base_thickness), _DARK, True)
        + _shape("c", "column", (0, 0, st.base_thickness + col_h / 2), (0, 0, 0),
                 _box(st.column_width, st.column_width, col_h), _DARK, True)
        + _shape("c", "spindle_body", (0, 0, body_z), (0, 0, 0),
                 _cyl(st.body_diameter / 2, st.body_length), _BLUE, True)
        + "    </link>\n"
        + _burr_link(burr, f'<pose relative_to="stand">{_pose((0, 0, st.nose_height))}</pose>')
        + '    <joint name="burr_weld" type="fixed"><parent>stand</parent>'
        "<child>burr</child></joint>\n"
        + _tool_frames(burr)
        + "  </model>\n</sdf>\n"
    )


def _cone_obj(burr: BurrGeometry) -> str:
    """Cone head as a closed convex OBJ: base circle at z = 0, apex at z = head_length [m]."""
    n = burr.segments
    lines = ["# GENERATED by drakedeburr.cell.tools: burr head cone, base at z=0, apex on +z",
             "# units: metres"]
    for i in range(n):
        phi = 2 * math.pi * i / n
        lines.append(f"v {_f(burr.head_radius * math.cos(phi))} "
                     f"{_f(burr.head_radius * math.sin(phi))} 0")
    lines.append(f"v 0 0 {_f(burr.head_length)}")
    lines.append("v 0 0 0")
    apex, centre = n + 1, n + 2
    for i in range(n):
        j = (i + 1) % n
        lines.append(f"f {i + 1} {j + 1} {apex}")
        lines.append(f"f {j + 1} {i + 1} {centre}")
    return "\n".join(lines) + "\n"


def tool_model_texts(
    spindle: FloatingSpindle = FLOATING_SPINDLE, stand: SpindleStand = SPINDLE_STAND
) -> dict[str, str]:
    """File name under ``models/tools/`` -> text, for every generated tool model."""
    if spindle.burr != stand.burr:
        raise ValueError("the floating spindle and the stand must carry the same burr "
                         "(burr_head.obj is shared)")
    texts = {"burr_head.obj": _cone_obj(spindle.burr),
             "floating_spindle.sdf": _floating_spindle_sdf(spindle),
             "spindle_stand.sdf": _spindle_stand_sdf(stand),
             "coaxial_bracket.sdf": _coaxial_bracket_sdf(spindle),
             "floating_spindle_coaxial.sdf": _floating_spindle_sdf(spindle, own_bracket=False)}
    for v in TOOL_VARIANTS.values():
        if v.suffix:  # the same head: burr_head.obj serves every variant
            texts[f"floating_spindle{v.suffix}.sdf"] = _floating_spindle_sdf(
                replace(spindle, burr=replace(spindle.burr, stick_out=v.burr.stick_out)))
            texts[f"floating_spindle_coaxial{v.suffix}.sdf"] = _floating_spindle_sdf(
                replace(spindle, burr=replace(spindle.burr, stick_out=v.burr.stick_out)),
                own_bracket=False)
            texts[f"spindle_stand{v.suffix}.sdf"] = _spindle_stand_sdf(
                replace(stand, burr=replace(stand.burr, stick_out=v.burr.stick_out)))
    # numbers to FILE_DIGITS: the same bytes on every machine (issue 43)
    return {name: round_numbers(text) for name, text in texts.items()}


def write_tool_models(out_dir: str | Path | None = None) -> list[Path]:
    """(Re)write the generated tool models (atomically). Default: the bundled ``models/tools``."""
    if out_dir is None:
        from drakedeburr.resources import models_dir

        out_dir = models_dir() / "tools"
    out_dir = Path(out_dir)
    return [atomic_write_text(out_dir / name, text) for name, text in tool_model_texts().items()]
