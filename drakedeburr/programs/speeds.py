"""The TCP speeds a program may carry: within what the arm can move and what the language
can hold (issue 41 item 7; docs/post.md "Speeds").

* The arm: no motion within the joint speed limits moves the TCP faster than
  ``sum_i v_max_i * r_i``, where ``r_i`` bounds the TCP's distance from joint axis i (joint i
  moves the TCP at ``|omega_i x r|``). :func:`tcp_speed_bound` takes ``r_i`` from the arm's
  OPW lengths (registry) and the TCP offset by the triangle inequality; it is an upper bound,
  not the vendor's rated figure, so a speed above it can never be run, whatever the pose.
* The language: RAPID ``speeddata`` up to ``v7000`` (7000 mm/s, the largest predefined
  speeddata, RAPID reference "speeddata"); KRL ``$VEL.CP`` up to ``$VEL_MA.CP`` (machine data,
  2 m/s on KR C4 arms: KUKA System Variables; industrialmonitordirect.com "KUKA robot $VEL /
  axis speed settings": $VEL.CP 0.0-2.0 m/s); FANUC TP ``mm/sec`` up to 2000 mm/sec
  (``$MRR_GRP.$SPEEDLIM`` default; not confirmed against a FANUC manual here). At the low
  end: RAPID and KRL hold 0.001 mm/s; LS whole mm/sec, at least 1 mm/sec (a slower speed
  would be written faster than planned).

:func:`speed_range` gives (low, high) [m/s]; :func:`check_program_speeds` refuses a program
whose moves leave it (the writers call it), and the post CLI checks ``--feed`` against the same
range before any work.
"""

from __future__ import annotations

import math

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.units import mm_from_m

__all__ = ["LANGUAGE_SPEED_RANGE", "tcp_speed_bound", "speed_range", "check_speed",
           "check_program_speeds"]

#: (lowest, highest) TCP speed [m/s] each language holds (module docstring)
LANGUAGE_SPEED_RANGE = {"rapid": (1e-6, 7.0), "krl": (1e-6, 2.0), "ls": (1e-3, 2.0)}


def _spec(robot):
    """The registered arm of a RobotSpec or RobotKinematics (None: not registered)."""
    from drakedeburr.robots import ROBOTS, RobotSpec

    if isinstance(robot, RobotSpec):
        return robot
    spec = ROBOTS.get(getattr(robot, "name", ""))
    return spec if spec is not None and spec.opw == robot.opw else None


def tcp_speed_bound(robot, X_FT: np.ndarray | None = None) -> float:
    """Upper bound [m/s] of the speed of the point ``X_FT`` (TCP in the flange frame [m];
    default the flange centre) over every pose, with every joint at its speed limit
    (``inf`` for an arm without joint speed limits in the registry).

    Args:
        robot: a registered arm (:class:`~drakedeburr.robots.RobotSpec`, or its
            kinematics): OPW lengths and joint speed limits.
        X_FT: (4, 4) TCP in the flange frame [m].
    """
    spec = _spec(robot)
    if spec is None:
        return math.inf
    o = spec.opw
    v_max = np.abs(np.asarray(spec.v_max, float))
    tcp = 0.0 if X_FT is None else float(np.linalg.norm(np.asarray(X_FT, float)[:3, 3]))
    wrist = o.c4 + tcp  # TCP from the wrist centre (on axes 4 and 5)
    elbow = math.hypot(o.a2, o.c3) + wrist  # from axis 3
    shoulder = o.c2 + elbow  # from axis 2
    r = np.array([abs(o.a1) + abs(o.b) + shoulder, shoulder, elbow, wrist, wrist, tcp])
    return float(v_max @ r)


def speed_range(kinematics, fmt: str, X_FT: np.ndarray | None = None) -> tuple[float, float]:
    """(lowest, highest) TCP speed [m/s] a ``fmt`` program for this arm and TCP may carry."""
    lo, hi = LANGUAGE_SPEED_RANGE[fmt]
    return lo, min(hi, tcp_speed_bound(kinematics, X_FT))


def _describe(kinematics, fmt: str, X_FT) -> str:
    lo, hi = speed_range(kinematics, fmt, X_FT)
    spec = _spec(kinematics)
    text = (f"allowed {mm_from_m(lo):g} to {mm_from_m(hi):.0f} mm/s: {fmt.upper()} holds up to "
            f"{mm_from_m(LANGUAGE_SPEED_RANGE[fmt][1]):.0f} mm/s")
    if spec is None:
        return text
    arm = mm_from_m(tcp_speed_bound(spec, X_FT))
    return (text + f", the {spec.title} cannot move this TCP faster than {arm:.0f} mm/s at its "
            "joint speed limits")


def check_speed(speed: float, kinematics, fmt: str, item: str,
                X_FT: np.ndarray | None = None) -> float:
    """``speed`` [m/s] if it is finite and within :func:`speed_range`.

    Raises:
        InputError: naming ``item``, the speed in mm/s and the allowed range.
    """
    lo, hi = speed_range(kinematics, fmt, X_FT)
    if not (isinstance(speed, (int, float)) and math.isfinite(speed) and lo <= speed <= hi):
        raise InputError(f"{item}: TCP speed {mm_from_m(speed):g} mm/s is out of range: it must "
                         f"be > 0 and finite, {_describe(kinematics, fmt, X_FT)}")
    return float(speed)


def check_program_speeds(program, fmt: str) -> None:
    """Refuse a program with a move faster than the arm or the language allows (linear
    moves; joint moves too in RAPID, whose MoveJ carries a TCP speed).

    Raises:
        InputError: naming the first such move (and its source line).
    """
    lo, hi = speed_range(program.kinematics, fmt, program.X_FT)
    for i, m in enumerate(program.moves):
        if m.move_type != "linear" and fmt != "rapid":
            continue
        if not lo <= m.speed <= hi:
            where = f" (source line {m.source_line})" if m.source_line is not None else ""
            check_speed(m.speed, program.kinematics, fmt, f"program {program.name}: move "
                        f"{i + 1}{where}", program.X_FT)
