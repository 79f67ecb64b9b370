"""Vendor configuration data from joint values, and joints back from pose + configuration.

A Cartesian robot target is ambiguous (up to 8 IK branches, plus 2*pi turns of wide-range
joints); controllers resolve it with configuration data stored next to the pose:

- ABB ``confdata [cf1, cf4, cf6, cfx]``: cf1/cf4/cf6 are the quadrants of axes 1/4/6
  (``floor(q / 90 deg)``); cfx = 4*(wrist centre behind axis 1) + 2*(wrist centre behind the
  lower arm) + (axis 5 negative), as in ABB's technical reference for 6-axis robots.
- KUKA ``S`` (status) and ``T`` (turn): S bit 0 = wrist centre behind axis 1 (overhead area),
  bit 1 = wrist centre in front of the lower arm (A3 >= phi), bit 2 = A5 <= 0; T bit i = 1 when
  axis i+1 < 0.
- FANUC ``CONFIG : 'F/N U/D T/B, t1, t4, t6'``: F (flip) if J5 >= 0, N (no flip) if J5 < 0
  (FANUC's J5 sign, which is the model's: the ROS-Industrial FANUC models use the controller's
  joint directions); U if the elbow is in its up branch (wrist centre in front of the lower
  arm); T if the wrist centre is in front of axis 1, B behind; t1/t4/t6 the turn numbers of
  J1/J4/J6: 0 for -180 < q < 180 deg, +1 for 180 <= q < 540, -1 for -540 < q <= -180.

Every rule is checked against cases from public sources (vendor manuals, a worked FANUC
example, RoboDK's post-processors) in ``tests/data/vendor_config_reference.yaml``.

The geometric bits come from :func:`drakedeburr.robots.opw_ik.arm_branches`, so the same code
serves every OPW robot; joint signs and turns are taken in the robot's own convention.
"""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots.opw_ik import RobotKinematics, arm_branches, ik_opw, joint_candidates

__all__ = [
    "abb_confdata",
    "kuka_status_turn",
    "fanuc_config",
    "configuration_of",
    "joints_from_configuration",
]

_HALF_PI = 0.5 * math.pi


def _quadrant(q: float) -> int:
    # tiny round-off below a multiple of 90 deg must not change the quadrant
    return int(math.floor(q / _HALF_PI + 1e-12))


def abb_confdata(robot: RobotKinematics, q: np.ndarray) -> tuple[int, int, int, int]:
    """ABB confdata (cf1, cf4, cf6, cfx) of joints ``q`` (6,) [rad]."""
    q = np.asarray(q, float)
    shoulder, elbow, _ = arm_branches(robot.opw, q)
    cfx = 4 * int(shoulder < 0) + 2 * int(elbow < 0) + int(q[4] < 0)
    return (_quadrant(q[0]), _quadrant(q[3]), _quadrant(q[5]), cfx)


def kuka_status_turn(robot: RobotKinematics, q: np.ndarray) -> tuple[int, int]:
    """KUKA (S, T) of joints ``q`` (6,) [rad] (see module docstring)."""
    q = np.asarray(q, float)
    shoulder, elbow, _ = arm_branches(robot.opw, q)
    s = int(shoulder < 0) + 2 * int(elbow > 0) + 4 * int(q[4] <= 0)
    t = sum(1 << i for i in range(6) if q[i] < 0)
    return s, t


#: joint offsets [rad] within which a solution on a configuration boundary still counts as
#: having the written configuration (J1, J4, J5, J6 by +-1e-6 rad: a pose written with 6
#: decimals moves an exact 0 or 90 deg joint by about that)
_NUDGES = [np.array([a, 0.0, 0.0, b, c, d]) * 1e-6
           for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1) for d in (-1, 0, 1)
           if (a, b, c, d) != (0, 0, 0, 0)]


def _turn(q: float) -> int:
    """FANUC turn number: floor((q + 180 deg) / 360 deg) for q >= 0, mirrored for q < 0 (as
    RoboDK's FANUC post writes it), so the turn is 0 strictly inside (-180, 180) deg."""
    k = math.floor((abs(q) + math.pi) / (2 * math.pi) + 1e-12)
    return int(k if q >= 0 else -k)


def fanuc_config(robot: RobotKinematics, q: np.ndarray) -> str:
    """FANUC configuration string, e.g. ``'N U T, 0, 0, 0'``, of joints ``q`` (6,) [rad]."""
    q = np.asarray(q, float)
    shoulder, elbow, _ = arm_branches(robot.opw, q)
    f = "F" if q[4] >= 0 else "N"
    u = "U" if elbow > 0 else "D"
    t = "T" if shoulder > 0 else "B"
    return f"{f} {u} {t}, {_turn(q[0])}, {_turn(q[3])}, {_turn(q[5])}"


def configuration_of(robot: RobotKinematics, q: np.ndarray, vendor: str):
    """Configuration of ``q`` for ``vendor`` in ('abb', 'kuka', 'fanuc')."""
    if vendor == "abb":
        return abb_confdata(robot, q)
    if vendor == "kuka":
        return kuka_status_turn(robot, q)
    if vendor == "fanuc":
        return fanuc_config(robot, q)
    raise InputError(f"unknown vendor {vendor!r}: use abb, kuka or fanuc")


def joints_from_configuration(robot: RobotKinematics, X_BF: np.ndarray, vendor: str,
                              config) -> np.ndarray:
    """The joints a controller reaches for a flange pose and configuration data.

    All IK branches and 2*pi turns inside the joint limits are computed; the ones whose
    configuration equals ``config`` are kept. ABB confdata and FANUC CONFIG identify one
    solution; KUKA S/T leave 360 deg turns of joints with a range over +-360 deg open: then the
    solution with the smallest absolute joint values is returned (KUKA's range for A6 is
    normally within +-360 deg).

    Args:
        robot: kinematics and limits.
        X_BF: (4, 4) flange pose in the robot base [m].
        vendor: 'abb', 'kuka' or 'fanuc'.
        config: as returned by :func:`configuration_of`.

    Returns:
        (6,) joints [rad].

    Raises:
        InputError: no solution has this configuration (unreachable or wrong data).
    """
    sols = ik_opw(robot.opw, X_BF)
    cand = joint_candidates(sols.q[0], robot.limits)
    match = [c for c in cand if configuration_of(robot, c, vendor) == config]
    if not match:  # a joint on a boundary (0, +-90 deg, ...) within round-off of the pose read
        match = [c for c in cand if any(configuration_of(robot, c + d, vendor) == config
                                        for d in _NUDGES)]
    if not match:
        raise InputError(f"no IK solution with {vendor} configuration {config!r}")
    match_arr = np.array(match)
    return match_arr[np.argmin(np.abs(match_arr).sum(axis=1))]
