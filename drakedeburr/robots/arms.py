"""The arm registry: four OPW arms with their sources (``drakedeburr robots`` lists them).

Every number carries its source; ``extdata`` below is ``../shared/extdata/kinematics/`` (its
README names each upstream file, commit and license).

* OPW parameters, offsets, sign corrections: ``robot_kinematics_reference.json``
  ``opw_parameters`` (ros-industrial support packages, Jmeyer1292/opw_kinematics).
* Joint position and speed limits: the ros-industrial URDF/xacro of each arm (ABB and KUKA
  values recorded in the reference JSON ``urdf_joints``; FANUC from ros-industrial/fanuc
  ``fanuc_lrmate200ic_support/urdf/lrmate200ic_macro.xacro`` @61ecc5c and
  ``fanuc_m10ia_support/urdf/m10ia_macro.xacro`` @e9bafce, BSD).
* Acceleration limits: ASSUMED for every arm. Vendors publish none (their controllers limit
  acceleration through a dynamic model of arm and payload). Rule: each axis reaches its top
  speed in about 0.3 s (``a = floor(v / 0.3 s)``); the IRB1600's older values (10/10/10/20/20/25)
  follow the same rule rounded down further.
* FANUC J2/J3 linkage (controller J3 = model J3 - J2) and the FANUC world frame at the J2
  height: ros-industrial/fanuc (``J23_factor`` = 1 in ``robot_interface_streaming_*.launch``;
  ``base_link-base`` joint "base_link to Fanuc World Coordinates transform").
* Payloads: the arm's rated payload from its name (IRB 1600-**10**, KR **6**, LR Mate 200iC:
  5 kg, M-**10**iA).
"""

from __future__ import annotations

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots.opw import OpwParameters
from drakedeburr.robots.spec import CellMount, RobotSpec
from drakedeburr.units import rad_from_deg

__all__ = [
    "IRB1600_10_120",
    "KR6_R700_SIXX",
    "LRMATE_200IC",
    "M_10IA",
    "IRB1600",
    "KR6_R700",
    "LRMATE200IC",
    "M10IA",
    "IRB1600_10_120_ROBOT",
    "ROBOTS",
    "DEFAULT_ROBOT",
    "robot_names",
    "get_robot",
    "robot_for_model_url",
]

_HALF_PI = 0.5 * np.pi
_PEDESTAL = "package://drakedeburr/fixtures/pedestal.sdf"


def _translation(x: float, y: float, z: float) -> np.ndarray:
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def _mount(arm: str, cell: str, xyz: tuple[float, float, float], q_home: tuple,
           study: str) -> tuple[str, CellMount]:
    """A bundled-cell mount: base at ``xyz`` in W (facing +X), the study's home, the arm's
    generated pedestal (``drakedeburr.cell.mounts``)."""
    short = cell.split("_")[0]
    return cell, CellMount(X_WB=_translation(*xyz), q_home=q_home,
                           pedestal_url=f"package://drakedeburr/fixtures/pedestal_{arm}_{short}.sdf",
                           study=study)


def _accel(v_max: np.ndarray) -> np.ndarray:
    """The assumed acceleration rule (module docstring): top speed in ~0.3 s, rounded down."""
    return np.floor(np.asarray(v_max) / 0.3)


_A_NOTE = ("ASSUMED: the vendor publishes none; each axis reaches its top speed in about 0.3 s "
           "(a = floor(v / 0.3 s))")

# ------------------------------------------------------------------ ABB IRB 1600-10/1.2
#: the 1.2 m arm geometry of irb1600_6_12 (ros-industrial/abb opw_parameters_irb1600_6_120.yaml)
IRB1600_10_120 = OpwParameters(
    a1=0.150, a2=0.0, b=0.0, c1=0.4865, c2=0.475, c3=0.600, c4=0.065,
    offsets=(0.0, 0.0, -_HALF_PI, 0.0, 0.0, 0.0), sign_corrections=(1, 1, 1, 1, 1, 1),
    name="ABB IRB1600-10/1.2")

IRB1600 = RobotSpec(
    name="irb1600", title="ABB IRB 1600-10/1.2", vendor="ABB", controller="abb",
    controller_model="IRC5", opw=IRB1600_10_120,
    q_lower=(-np.pi, -1.0995, -4.1015, -3.4906, -2.0071, -6.9813),
    q_upper=(np.pi, 1.9198, 0.9599, 3.4906, 2.0071, 6.9813),
    v_max=rad_from_deg(np.array([180.0, 180.0, 185.0, 385.0, 400.0, 460.0])),
    a_max=(10.0, 10.0, 10.0, 20.0, 20.0, 25.0),
    a_max_note="ASSUMED: ABB publishes none; each axis reaches top speed in about 0.3 s",
    j23_coupling=0.0, X_BR=np.eye(4), payload_kg=10.0,
    flange="tool0: flange face centre, +Z out of the flange, +X down at all axes 0",
    model_url="package://drakedeburr/robots/irb1600_10_120.sdf",
    mounts=(
        ("tool_in_hand", CellMount(
            X_WB=np.eye(4), q_home=(0.0, 0.6, 0.6, 0.0, -0.4146, 0.0), pedestal_url=_PEDESTAL,
            study="the cell's reference arm: W = its base on a 0.8 m pedestal")),
        ("workpiece_in_hand", CellMount(
            X_WB=np.eye(4), q_home=(0.0, 0.3671, -0.6265, 0.0, 1.8303, 0.0),
            pedestal_url=_PEDESTAL,
            study="the cell's reference arm: W = its base on a 0.8 m pedestal")),
    ),
    conventions=("ABB: all axes 0 = upper arm vertical, forearm horizontal pointing +X; axes "
                 "about +Z, +Y, +Y, +X, +Y, +X (axis 2 positive tilts the arm forward, axis 3 "
                 "positive tilts the forearm down); axis 3 is measured from the upper arm."),
    sources=(
        "geometry, position limits: ros-industrial/abb irb1600_6_12_macro.xacro @a465818 "
        "(extdata urdf_joints.ABB_IRB1600_6_12)",
        "speeds 180/180/185/385/400/460 deg/s: irb1600_10_145_macro.xacro @526bd40; 1.2 m "
        "geometry + 10 kg speeds is an INFERENCE (extdata IRB1600_10_12_note)",
    ),
)

# ------------------------------------------------------------------ KUKA KR 6 R700 sixx
KR6_R700_SIXX = OpwParameters(
    a1=0.025, a2=-0.035, b=0.0, c1=0.400, c2=0.315, c3=0.365, c4=0.080,
    offsets=(0.0, -_HALF_PI, 0.0, 0.0, 0.0, 0.0), sign_corrections=(-1, 1, 1, -1, 1, -1),
    name="KUKA KR 6 R700 sixx")

_KR6_V = rad_from_deg(np.array([360.0, 300.0, 360.0, 381.0, 388.0, 615.0]))
KR6_R700 = RobotSpec(
    name="kr6_r700", title="KUKA KR 6 R700 sixx", vendor="KUKA", controller="kuka",
    controller_model="KR C4 compact (KSS 8)", opw=KR6_R700_SIXX,
    q_lower=rad_from_deg(np.array([-170.0, -190.0, -120.0, -185.0, -120.0, -350.0])),
    q_upper=rad_from_deg(np.array([170.0, 45.0, 156.0, 185.0, 120.0, 350.0])),
    v_max=_KR6_V, a_max=_accel(_KR6_V), a_max_note=_A_NOTE,
    j23_coupling=0.0, X_BR=np.eye(4), payload_kg=6.0,
    flange="$FLANGE: flange face centre, +Z out of the flange (= ROS tool0)",
    model_url="package://drakedeburr/robots/kr6_r700_sixx.sdf",
    mounts=(
        _mount("kr6_r700", "tool_in_hand", (0.20, 0.0, -0.30),
               (0.0, -1.5109, 1.9084, 0.0, 0.3978, 0.0),
               "rim survey 33/35 (best of x 0.15-0.25, z -0.4..-0.2; the column must clear the "
               "fixture table); docs/cell.md"),
        _mount("kr6_r700", "workpiece_in_hand", (0.30, 0.0, 0.30),
               (0.0, -0.8149, 0.6378, 0.0, 1.7379, 0.0),
               "rim survey 35/35 (x 0.3-0.5, z 0.1-0.3); docs/cell.md"),
    ),
    conventions=("KUKA: all axes 0 = arm stretched horizontally forward (+X); the mastering "
                 "pose is A2 = -90 deg (upper arm vertical), A3 = +90 deg; A1, A4, A6 turn about "
                 "-Z, -X, -X (A1 positive = clockwise seen from above), A2, A3, A5 about +Y."),
    sources=(
        "geometry, limits, speeds: ros-industrial/kuka_experimental kr6r700sixx_macro.xacro "
        "via rs-opw-kinematics @d61fd57 (extdata urdf_joints.KUKA_KR6_R700_sixx)",
        "OPW: Jmeyer1292/opw_kinematics opw_parameters_examples.h @8a32bda (tested there)",
    ),
)

# ------------------------------------------------------------------ FANUC LR Mate 200iC
LRMATE_200IC = OpwParameters(
    a1=0.075, a2=-0.075, b=0.0, c1=0.330, c2=0.300, c3=0.320, c4=0.080,
    offsets=(0.0, 0.0, -_HALF_PI, 0.0, 0.0, np.pi), sign_corrections=(1, 1, -1, -1, -1, -1),
    name="FANUC LR Mate 200iC")

_FANUC_CONV = ("FANUC: all axes 0 = upper arm vertical, forearm horizontal pointing +X; the "
               "controller measures J3 from the horizontal (J2/J3 linkage: controller J3 = "
               "model J3 - J2); J1, J2 about +Z, +Y, J3..J6 about -Y, -X, -Y, -X; faceplate = "
               "link 6 rotated rpy(pi, -pi/2, 0); world frame at the J2 axis height.")
_LRM_V = np.array([6.1087, 6.1087, 6.9813, 7.8540, 7.8540, 12.5664])
LRMATE200IC = RobotSpec(
    name="lrmate200ic", title="FANUC LR Mate 200iC", vendor="FANUC", controller="fanuc",
    controller_model="R-30iA Mate", opw=LRMATE_200IC,
    q_lower=(-2.9671, -1.0472, -2.4784, -3.3161, -2.0944, -6.2832),
    q_upper=(2.9671, 2.4435, 4.0143, 3.3161, 2.0944, 6.2832),
    v_max=_LRM_V, a_max=_accel(_LRM_V), a_max_note=_A_NOTE,
    j23_coupling=1.0, X_BR=_translation(0.0, 0.0, 0.330), payload_kg=5.0,
    flange="faceplate (UTOOL 0): +Z out of the faceplate (= ROS tool0)",
    model_url="package://drakedeburr/robots/lrmate200ic.sdf",
    mounts=(
        _mount("lrmate200ic", "tool_in_hand", (0.20, 0.0, -0.30),
               (0.0, -0.0294, -0.3341, 0.0, -0.4906, 3.1416),
               "rim survey 34/35 (x 0.20-0.25, z -0.4..-0.2); docs/cell.md"),
        _mount("lrmate200ic", "workpiece_in_hand", (0.35, 0.0, 0.30),
               (-0.0021, 0.6513, 0.9274, -0.0020, -1.8371, 0.0),
               "rim survey 35/35 (x 0.35-0.55, z 0.2-0.4); docs/cell.md"),
    ),
    conventions=_FANUC_CONV,
    sources=(
        "geometry, limits, speeds: ros-industrial/fanuc lrmate200ic_macro.xacro @61ecc5c (BSD)",
        "OPW: ros-industrial/fanuc opw_parameters_lrmate200ic.yaml @453d974 (extdata)",
        "limits apply to the model joints (ROS-Industrial practice); the controller's J2/J3 "
        "interference limit is not modelled",
    ),
)

# ------------------------------------------------------------------ FANUC M-10iA
M_10IA = OpwParameters(
    a1=0.150, a2=-0.200, b=0.0, c1=0.450, c2=0.600, c3=0.640, c4=0.100,
    offsets=(0.0, 0.0, -_HALF_PI, 0.0, 0.0, np.pi), sign_corrections=(1, 1, -1, -1, -1, -1),
    name="FANUC M-10iA")

_M10_V = np.array([3.67, 3.32, 3.67, 6.98, 6.98, 10.47])
M10IA = RobotSpec(
    name="m10ia", title="FANUC M-10iA", vendor="FANUC", controller="fanuc",
    controller_model="R-30iA", opw=M_10IA,
    q_lower=(-3.14, -1.57, -3.14, -3.31, -3.31, -6.28),
    q_upper=(3.14, 2.79, 4.61, 3.31, 3.31, 6.28),
    v_max=_M10_V, a_max=_accel(_M10_V), a_max_note=_A_NOTE,
    j23_coupling=1.0, X_BR=_translation(0.0, 0.0, 0.450), payload_kg=10.0,
    flange="faceplate (UTOOL 0): +Z out of the faceplate (= ROS tool0)",
    model_url="package://drakedeburr/robots/m10ia.sdf",
    mounts=(
        _mount("m10ia", "tool_in_hand", (0.0, 0.0, -0.20),
               (0.0, 0.0305, -1.1882, 0.0, 0.4334, 3.1416),
               "rim survey 35/35 everywhere in x -0.2..0, z -0.2..0; most clearance; "
               "docs/cell.md"),
        _mount("m10ia", "workpiece_in_hand", (0.0, 0.0, 0.0),
               (-0.0066, 0.1318, -0.0917, -0.0094, -1.3432, 0.0),
               "rim survey 35/35, most clearance (x -0.2..0, z -0.2..0); docs/cell.md"),
    ),
    conventions=_FANUC_CONV,
    sources=(
        "geometry, limits, speeds: ros-industrial/fanuc m10ia_macro.xacro @e9bafce (BSD)",
        "OPW: ros-industrial/fanuc opw_parameters_m10ia.yaml @1672b5b (extdata)",
        "limits apply to the model joints (ROS-Industrial practice); the controller's J2/J3 "
        "interference limit is not modelled",
    ),
)

#: registry name -> spec, in listing order
ROBOTS: dict[str, RobotSpec] = {r.name: r for r in (IRB1600, KR6_R700, LRMATE200IC, M10IA)}
DEFAULT_ROBOT = "irb1600"
#: kinematics of the default arm (the CL post's default robot)
IRB1600_10_120_ROBOT = IRB1600.kinematics


def robot_names() -> tuple[str, ...]:
    """Registry names, e.g. ``("irb1600", "kr6_r700", "lrmate200ic", "m10ia")``."""
    return tuple(ROBOTS)


def get_robot(name: str | RobotSpec | None) -> RobotSpec:
    """The spec of a registered arm (``None``: the default arm; a spec is returned as is).

    Raises:
        InputError: unknown name (the message lists the registered ones).
    """
    if isinstance(name, RobotSpec):
        return name
    key = DEFAULT_ROBOT if name is None else str(name).strip().lower()
    if key not in ROBOTS:
        raise InputError(f"unknown robot {name!r}: registered arms are "
                         f"{', '.join(ROBOTS)} (drakedeburr robots)")
    return ROBOTS[key]


def robot_for_model_url(url: str) -> RobotSpec | None:
    """The registered arm whose Drake model is ``url`` (``package://drakedeburr/...``)."""
    for spec in ROBOTS.values():
        if spec.model_url == url:
            return spec
    return None
