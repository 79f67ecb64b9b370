"""Writes our Drake models of the registered arms (``python -m drakedeburr.robots``).

The kinematic chain of each model is derived from the arm's :class:`RobotSpec` alone: joint
points from the OPW geometry at the model's zero pose, joint axes = the OPW axis directions
times the sign corrections, the flange frame = the OPW end frame, limits from the spec. So the
model's forward kinematics equals :func:`~drakedeburr.robots.opw.fk_opw` by construction (and
``tests/test_robots.py`` checks it to 1e-9 m). Collision geometry is primitive shapes (capsules,
cylinders, boxes) enveloping each link as drawn in the vendor's data sheet: estimated
envelopes, not vendor CAD; masses and inertias are plausible estimates, not vendor data.

The ABB IRB1600 model (``irb1600_10_120.sdf``) is hand-written (older); every other arm of the
registry is generated here (numbers rounded to :data:`DIGITS` decimals: the same text on every
machine). All link frames are parallel to the base at q = 0 and sit on their joint
axes, as in the IRB1600 file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drakedeburr.robots.opw import fk_opw
from drakedeburr.robots.spec import RobotSpec

__all__ = ["DIGITS", "ArmEnvelope", "ENVELOPES", "JointPoints", "joint_points", "arm_sdf",
           "write_arm_models"]


@dataclass(frozen=True)
class ArmEnvelope:
    """Link envelope sizes [m] and masses [kg] of an arm (estimated from its data sheet).

    Attributes:
        foot: (x, y, z) size of the base box on the mounting face.
        turret_radius: rotating column (link 1) radius, from the foot to the shoulder.
        shoulder_radius, shoulder_width: J2 housing (cylinder along the J2 axis).
        upper_arm_radius: capsule from J2 to J3.
        elbow_radius, elbow_width: J3 housing.
        forearm_radius: capsule from J4's point to the wrist centre.
        wrist_radius, wrist_width: J5 housing at the wrist centre.
        flange_radius: flange disc (10 mm thick) behind the flange face.
        masses: (7,) link masses base, link_1 .. link_6.
        color: visual RGBA.
    """

    foot: tuple[float, float, float]
    turret_radius: float
    shoulder_radius: float
    shoulder_width: float
    upper_arm_radius: float
    elbow_radius: float
    elbow_width: float
    forearm_radius: float
    wrist_radius: float
    wrist_width: float
    flange_radius: float
    masses: tuple[float, ...]
    color: str


# data sheet envelopes (rounded up): KR 6 R700 sixx foot 320 x 320 mm, total ~50 kg;
# LR Mate 200iC foot ~ 240 x 190 mm, ~27 kg; M-10iA foot ~ 450 x 450 mm, ~130 kg;
# IRB 2600 foot ~ 680 x 510 mm, ~280 kg; KR 20 R1810-2 foot ~ 530 x 530 mm, ~250 kg;
# M-20iA foot ~ 560 x 560 mm, ~250 kg; M-710iC/50 foot ~ 720 x 720 mm, ~560 kg (ESTIMATES of
# the data sheets' outline drawings, not vendor CAD)
ENVELOPES: dict[str, ArmEnvelope] = {
    "kr6_r700": ArmEnvelope(
        foot=(0.32, 0.32, 0.13), turret_radius=0.10, shoulder_radius=0.085, shoulder_width=0.20,
        upper_arm_radius=0.065, elbow_radius=0.075, elbow_width=0.17, forearm_radius=0.055,
        wrist_radius=0.045, wrist_width=0.10, flange_radius=0.025,
        masses=(13.0, 12.0, 9.0, 7.0, 4.0, 2.0, 0.3), color="0.95 0.45 0.0 1"),
    "lrmate200ic": ArmEnvelope(
        foot=(0.24, 0.20, 0.12), turret_radius=0.09, shoulder_radius=0.075, shoulder_width=0.18,
        upper_arm_radius=0.055, elbow_radius=0.065, elbow_width=0.15, forearm_radius=0.045,
        wrist_radius=0.04, wrist_width=0.09, flange_radius=0.02,
        masses=(8.0, 7.0, 5.0, 3.5, 2.0, 1.0, 0.2), color="0.95 0.85 0.1 1"),
    "m10ia": ArmEnvelope(
        foot=(0.45, 0.45, 0.20), turret_radius=0.16, shoulder_radius=0.12, shoulder_width=0.28,
        upper_arm_radius=0.09, elbow_radius=0.11, elbow_width=0.24, forearm_radius=0.075,
        wrist_radius=0.06, wrist_width=0.14, flange_radius=0.04,
        masses=(40.0, 35.0, 22.0, 15.0, 10.0, 4.0, 0.5), color="0.95 0.85 0.1 1"),
    "irb2600": ArmEnvelope(
        foot=(0.68, 0.51, 0.20), turret_radius=0.22, shoulder_radius=0.15, shoulder_width=0.36,
        upper_arm_radius=0.11, elbow_radius=0.14, elbow_width=0.32, forearm_radius=0.09,
        wrist_radius=0.065, wrist_width=0.16, flange_radius=0.04,
        masses=(90.0, 70.0, 45.0, 35.0, 20.0, 6.0, 1.0), color="0.95 0.45 0.0 1"),
    "kr20_r1810": ArmEnvelope(
        foot=(0.53, 0.53, 0.20), turret_radius=0.22, shoulder_radius=0.15, shoulder_width=0.36,
        upper_arm_radius=0.11, elbow_radius=0.14, elbow_width=0.32, forearm_radius=0.09,
        wrist_radius=0.07, wrist_width=0.16, flange_radius=0.04,
        masses=(80.0, 65.0, 40.0, 30.0, 20.0, 6.0, 1.0), color="0.95 0.45 0.0 1"),
    "m20ia": ArmEnvelope(
        foot=(0.56, 0.56, 0.20), turret_radius=0.22, shoulder_radius=0.15, shoulder_width=0.36,
        upper_arm_radius=0.11, elbow_radius=0.14, elbow_width=0.32, forearm_radius=0.09,
        wrist_radius=0.07, wrist_width=0.16, flange_radius=0.045,
        masses=(80.0, 65.0, 40.0, 30.0, 20.0, 6.0, 1.0), color="0.95 0.85 0.1 1"),
    "m710ic50": ArmEnvelope(
        foot=(0.72, 0.72, 0.22), turret_radius=0.26, shoulder_radius=0.18, shoulder_width=0.44,
        upper_arm_radius=0.14, elbow_radius=0.17, elbow_width=0.40, forearm_radius=0.11,
        wrist_radius=0.09, wrist_width=0.20, flange_radius=0.065,
        masses=(180.0, 140.0, 90.0, 70.0, 50.0, 15.0, 3.0), color="0.95 0.85 0.1 1"),
}



@dataclass(frozen=True)
class JointPoints:
    """Points of the chain at the model's zero pose, in the base frame [m], (3,) each.

    Attributes:
        j1..j6: a point on each joint axis (j4 at the forearm's offset corner, j5 = wrist
            centre, j6 = flange centre).
        axes: (6, 3) unit joint axes (model positive direction).
        R_BF0: (3, 3) flange orientation at q = 0.
    """

    j1: np.ndarray
    j2: np.ndarray
    j3: np.ndarray
    j4: np.ndarray
    j5: np.ndarray
    j6: np.ndarray
    axes: np.ndarray
    R_BF0: np.ndarray


def joint_points(spec: RobotSpec) -> JointPoints:
    """The chain of ``spec`` at q = 0 from its OPW parameters (see module docstring)."""
    p = spec.opw
    if p.b != 0.0 or np.any(np.asarray(p.offsets)[[0, 3, 4]] != 0.0):
        raise ValueError(f"{spec.name}: the generator supports b = 0 and zero offsets on "
                         "axes 1, 4, 5")
    q_opw = p.q_opw_from_robot(np.zeros(6))
    q1, q2 = q_opw[1], q_opw[2]
    j2 = np.array([p.a1, 0.0, p.c1])
    j3 = j2 + p.c2 * np.array([math.sin(q1), 0.0, math.cos(q1)])
    u = np.array([math.sin(q1 + q2), 0.0, math.cos(q1 + q2)])  # forearm direction
    n = np.array([math.cos(q1 + q2), 0.0, -math.sin(q1 + q2)])
    j4 = j3 + p.a2 * n
    j5 = j4 + p.c3 * u
    j6 = j5 + p.c4 * u
    nominal = np.array([[0, 0, 1], [0, 1, 0], [0, 1, 0], u, [0, 1, 0], u], dtype=float)
    axes = nominal * np.asarray(p.sign_corrections, float)[:, None]
    X0 = fk_opw(p, np.zeros(6))
    if np.abs(X0[:3, 3] - j6).max() > 1e-12:
        raise AssertionError(f"{spec.name}: chain points disagree with fk_opw")
    return JointPoints(j1=np.array([0.0, 0.0, p.c1]), j2=j2, j3=j3, j4=j4, j5=j5, j6=j6,
                       axes=axes, R_BF0=X0[:3, :3])


#: decimals of the geometry written (poses, axes, sizes, inertias): 1e-10 m / rad is far below
#: every tolerance (the FK test's 1e-9 m) and far above the last-bit differences of
#: sin/cos/atan2 between machines, so the text is the same everywhere
#: (tests/test_robots_arms.py::test_generated_arm_models_are_committed). Joint limits are the
#: spec's numbers written exactly (they come from the arm file by exact arithmetic).
DIGITS = 10


def _f(x: float, digits: int | None = DIGITS) -> str:
    x = float(x) if digits is None else round(float(x), digits) + 0.0  # + 0.0: no "-0"
    return "0" if x == 0.0 else (str(int(x)) if x.is_integer() else repr(x))


def _exact(x: float) -> str:
    return _f(x, None)


def _v(v) -> str:
    return " ".join(_f(x) for x in v)


def _rpy_from_R(R: np.ndarray) -> np.ndarray:
    import warnings

    from scipy.spatial.transform import Rotation

    with warnings.catch_warnings():  # gimbal lock at pitch +-90 deg: still the same rotation
        warnings.simplefilter("ignore", UserWarning)
        rpy = Rotation.from_matrix(R).as_euler("xyz")  # SDFormat rpy: R = Rz(y) Ry(p) Rx(r)
    if np.abs(Rotation.from_euler("xyz", rpy).as_matrix() - R).max() > 1e-12:
        raise AssertionError("rpy round trip failed")
    return rpy


def _segment(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Pose (xyz, rpy) of a z-aligned shape from a to b (in the x-z plane) and its length."""
    d = b - a
    length = float(np.linalg.norm(d))
    pitch = math.atan2(d[0], d[2]) if length > 0 else 0.0
    return 0.5 * (a + b), np.array([0.0, pitch, 0.0]), length


def _shape(name: str, xyz, rpy, geometry: str, color: str) -> str:
    pose = f"<pose>{_v(xyz)} {_v(rpy)}</pose>"
    return (f'      <visual name="{name}">{pose}<geometry>{geometry}</geometry>'
            f"<material><diffuse>{color}</diffuse></material></visual>\n"
            f'      <collision name="{name}">{pose}<geometry>{geometry}</geometry></collision>\n')


def _cyl(r: float, length: float) -> str:
    return f"<cylinder><radius>{_f(r)}</radius><length>{_f(length)}</length></cylinder>"


def _capsule(r: float, length: float) -> str:
    return f"<capsule><radius>{_f(r)}</radius><length>{_f(length)}</length></capsule>"


def _link(name: str, origin: np.ndarray, mass: float, extent: float, shapes: str) -> str:
    i = max(mass * extent * extent / 6.0, 1e-5)  # solid-cube estimate
    pose = f"    <pose>{_v(origin)} 0 0 0</pose>\n" if np.any(origin) else ""
    return (f'    <link name="{name}">\n{pose}'
            f"      <inertial><mass>{_f(mass)}</mass><inertia><ixx>{_f(i)}</ixx><iyy>{_f(i)}"
            f"</iyy><izz>{_f(i)}</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>"
            f"</inertial>\n{shapes}    </link>\n")


def _links(spec: RobotSpec, env: ArmEnvelope, jp: JointPoints) -> str:
    c, m = env.color, env.masses
    along_y = np.array([math.pi / 2, 0.0, 0.0])
    fx, fy, fz = env.foot
    out = _link("base_link", np.zeros(3), m[0], max(fx, fz),
                _shape("foot", (0, 0, fz / 2), (0, 0, 0), f"<box><size>{_v(env.foot)}</size>"
                       "</box>", c))
    turret_top = jp.j2[2] - env.shoulder_radius
    shapes = _shape("turret", (0, 0, 0.5 * (fz + turret_top)), (0, 0, 0),
                    _cyl(env.turret_radius, turret_top - fz), c)
    shapes += _shape("shoulder", jp.j2, along_y, _cyl(env.shoulder_radius, env.shoulder_width), c)
    out += _link("link_1", np.zeros(3), m[1], jp.j2[2], shapes)
    xyz, rpy, length = _segment(jp.j2, jp.j3)
    out += _link("link_2", jp.j2, m[2], length,
                 _shape("upper_arm", xyz - jp.j2, rpy, _capsule(env.upper_arm_radius, length), c))
    # the forearm housing up to where the rolling tube (link 4) starts, clear of the elbow
    u = (jp.j5 - jp.j4) / np.linalg.norm(jp.j5 - jp.j4)
    tube_start = jp.j4 + (env.elbow_radius + env.forearm_radius + 0.01) * u
    shapes = _shape("elbow", (0, 0, 0), along_y, _cyl(env.elbow_radius, env.elbow_width), c)
    xyz, rpy, length = _segment(jp.j3, tube_start)
    shapes += _shape("forearm_root", xyz - jp.j3, rpy, _capsule(env.forearm_radius, length), c)
    out += _link("link_3", jp.j3, m[3], env.elbow_width, shapes)
    wrist_start = jp.j5 - (env.wrist_radius + 0.005) * u
    xyz, rpy, length = _segment(tube_start, wrist_start)
    out += _link("link_4", jp.j4, m[4], length,
                 _shape("forearm", xyz - jp.j4, rpy, _capsule(env.forearm_radius, length), c))
    out += _link("link_5", jp.j5, m[5], env.wrist_width,
                 _shape("wrist", (0, 0, 0), along_y, _cyl(env.wrist_radius, env.wrist_width), c))
    xyz, rpy, _ = _segment(jp.j6 - 0.01 * u, jp.j6)
    out += _link("link_6", jp.j6, m[6], 0.05,
                 _shape("flange", xyz - jp.j6, rpy, _cyl(env.flange_radius, 0.01),
                        "0.3 0.3 0.3 1"))
    return out


def _joints(spec: RobotSpec, jp: JointPoints) -> str:
    parents = ["base_link"] + [f"link_{i}" for i in range(1, 6)]
    out = ""
    for i in range(6):
        out += (f'    <joint name="joint_{i + 1}" type="revolute">\n'
                f"      <parent>{parents[i]}</parent><child>link_{i + 1}</child>\n"
                f"      <axis><xyz>{_v(jp.axes[i])}</xyz>\n"
                f"        <limit><lower>{_exact(spec.q_lower[i])}</lower><upper>"
                f"{_exact(spec.q_upper[i])}</upper>\n          <velocity>{_exact(spec.v_max[i])}"
                "</velocity><effort>0</effort>\n"
                f"          <drake:acceleration>{_exact(spec.a_max[i])}</drake:acceleration>"
                "</limit></axis>\n    </joint>\n")
    return out


def arm_sdf(spec: RobotSpec, env: ArmEnvelope) -> str:
    """SDFormat text of ``spec``'s arm with the link envelopes ``env``."""
    jp = joint_points(spec)
    rpy = _rpy_from_R(jp.R_BF0)
    header = (f"<?xml version=\"1.0\"?>\n<!--\n  {spec.title} for drakedeburr, GENERATED by "
              "drakedeburr/robots/arm_models.py\n  (python -m drakedeburr.robots): do not edit.\n"
              "  Kinematics and limits from the arm's RobotSpec (drakedeburr/robots/arms.py, "
              "sources there);\n  acceleration limits ASSUMED. Collision/visual shapes: "
              "estimated envelopes of the\n  data-sheet drawing, not vendor CAD; masses are "
              "estimates.\n  Frames: \"base\" (mounting face, z up) and \"flange\" (the "
              "vendor's flange frame, +Z out of\n  the flange) = the end frame of fk_opw.\n-->\n")
    return (header + '<sdf version="1.9" xmlns:drake="http://drake.mit.edu">\n'
            f'  <model name="{spec.name}">\n    <frame name="base" attached_to="base_link"/>\n'
            + _links(spec, env, jp) + _joints(spec, jp)
            + f'    <frame name="flange" attached_to="link_6">\n      <pose relative_to='
            f'"link_6">0 0 0 {_v(rpy)}</pose>\n    </frame>\n  </model>\n</sdf>\n')


def write_arm_models(out_dir: str | Path | None = None) -> list[Path]:
    """(Re)write the generated arm models (atomically). Default: the bundled ``models/robots``."""
    from drakedeburr._io import atomic_write_text
    from drakedeburr.resources import models_dir, resolve_package_url
    from drakedeburr.robots.arms import ROBOTS

    paths = []
    for name, env in ENVELOPES.items():
        spec = ROBOTS[name]
        target = resolve_package_url(spec.model_url)
        if out_dir is not None:
            target = Path(out_dir) / target.name
        elif not target.is_relative_to(models_dir()):
            raise ValueError(f"{spec.model_url} is outside the models folder")
        paths.append(atomic_write_text(target, arm_sdf(spec, env)))
    return paths
