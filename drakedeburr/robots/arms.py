"""The arm registry: the arm files shipped with the package (``drakedeburr robots`` lists them).

Each arm is a YAML file ``models/robots/<name>.yaml`` (schema and validation:
:mod:`drakedeburr.robots.arm_file`) that cites the source of every group of values under
``sources``: OPW parameters and joint limits from the ROS-Industrial support packages (or
Jmeyer1292/opw_kinematics), rated payloads and wrist ratings from the vendors' data, the FANUC
J2/J3 linkage and world frame from ros-industrial/fanuc. Acceleration limits are ASSUMED for
every arm (vendors publish none): each axis reaches its top speed in about 0.3 s.
``--robot FILE`` loads a user's own arm file the same way (:func:`get_robot`).
"""

from __future__ import annotations

from pathlib import Path

from drakedeburr.errors import InputError
from drakedeburr.resources import arm_file_path
from drakedeburr.robots.arm_file import is_arm_file, load_arm
from drakedeburr.robots.spec import RobotSpec

__all__ = [
    "IRB1600_10_120",
    "KR6_R700_SIXX",
    "LRMATE_200IC",
    "M_10IA",
    "IRB1600",
    "KR6_R700",
    "LRMATE200IC",
    "M10IA",
    "IRB2600",
    "KR20_R1810",
    "M20IA",
    "M710IC50",
    "BUILTIN_ARMS",
    "IRB1600_10_120_ROBOT",
    "ROBOTS",
    "DEFAULT_ROBOT",
    "robot_names",
    "get_robot",
    "robot_for_model_url",
]

#: the registry's arms, in listing order: ``models/robots/<name>.yaml`` (arm files, schema in
#: :mod:`drakedeburr.robots.arm_file`; every value cited there)
BUILTIN_ARMS: tuple[str, ...] = ("irb1600", "kr6_r700", "lrmate200ic", "m10ia", "irb2600",
                                 "kr20_r1810", "m20ia", "m710ic50")


def _builtin(name: str) -> RobotSpec:
    return load_arm(arm_file_path(name), builtin=True)


#: registry name -> spec, in listing order
ROBOTS: dict[str, RobotSpec] = {n: _builtin(n) for n in BUILTIN_ARMS}
DEFAULT_ROBOT = "irb1600"

IRB1600, KR6_R700, LRMATE200IC, M10IA = (ROBOTS[n] for n in BUILTIN_ARMS[:4])
IRB2600, KR20_R1810, M20IA, M710IC50 = (ROBOTS[n] for n in BUILTIN_ARMS[4:])
#: OPW parameters of the registry's first four arms (older names)
IRB1600_10_120, KR6_R700_SIXX, LRMATE_200IC, M_10IA = (
    s.opw for s in (IRB1600, KR6_R700, LRMATE200IC, M10IA))
#: kinematics of the default arm (the CL post's default robot)
IRB1600_10_120_ROBOT = IRB1600.kinematics


def robot_names() -> tuple[str, ...]:
    """Registry names, e.g. ``("irb1600", "kr6_r700", "lrmate200ic", "m10ia")``."""
    return tuple(ROBOTS)


def get_robot(name: str | Path | RobotSpec | None) -> RobotSpec:
    """The spec of a registered arm, or of an arm file (``*.yaml``: ``--robot FILE``);
    ``None``: the default arm; a spec is returned as is.

    Raises:
        InputError: unknown name (the message lists the registered ones), or an arm file
            that is missing or has a bad field (the message names the file and the field).
    """
    if isinstance(name, RobotSpec):
        return name
    if is_arm_file(name):
        return load_arm(name)
    key = DEFAULT_ROBOT if name is None else str(name).strip().lower()
    if key not in ROBOTS:
        raise InputError(f"unknown robot {name!r}: registered arms are "
                         f"{', '.join(ROBOTS)} (drakedeburr robots), or an arm file "
                         "(*.yaml, docs/robots.md)")
    return ROBOTS[key]


def robot_for_model_url(url: str) -> RobotSpec | None:
    """The registered arm whose Drake model is ``url`` (``package://drakedeburr/...``)."""
    for spec in ROBOTS.values():
        if spec.model_url == url:
            return spec
    return None
