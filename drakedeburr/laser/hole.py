"""Small holes (diameter 1-25 mm) cut by the Cutting Tool alone while the robot holds still.

Pipeline: shape -> contour in the part plane -> head positions in the tool frame C (the shape
origin sits at the tool's home point, plus the shape's ``center`` offset) -> servo angles by
inverse kinematics (with workspace/singularity checks) -> time-optimal servo trajectory
(TOPP-RA under servo speed/acceleration limits and the feed) -> TCP speed -> laser command.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.laser.kinematics import FiveBarGeometry, check_reach, forward_kinematics, jacobian
from drakedeburr.laser.power import PowerMap, PowerProfile, power_profile
from drakedeburr.laser.shapes import Contour, ShapeBase, build_contour
from drakedeburr.laser.timing import AxisLimits, TimedPath, time_path

__all__ = ["ServoLimits", "HoleProgram", "plan_hole", "tool_path_points"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ServoLimits:
    """Cutting Tool servo limits (assumed; the source gives only the 10 m/min top speed).

    Attributes:
        velocity: servo output speed limit [rad/s] (10 rad/s ~ 95 rpm, a direct/low-ratio
            drive of a small FANUC servo).
        acceleration: servo output acceleration limit [rad/s^2].
        feed: programmed cutting speed [m/s] (10 m/min = the source's top speed).
        feed_acceleration: tangential TCP acceleration limit [m/s^2].
    """

    velocity: float = 10.0
    acceleration: float = 300.0
    feed: float = 10.0 / 60.0
    feed_acceleration: float = 20.0

    def axis_limits(self) -> AxisLimits:
        return AxisLimits(velocity=(self.velocity, self.velocity),
                          acceleration=(self.acceleration, self.acceleration),
                          feed=self.feed, feed_acceleration=self.feed_acceleration)


@dataclass(frozen=True, eq=False)
class HoleProgram:
    """A hole cut by the tool alone.

    Attributes:
        contour: the sampled shape (part plane P; P = C shifted to the tool's home point).
        geometry: the tool.
        limits: servo limits used for timing.
        power: speed -> command map.
        p_CJ5: (N, 2) head targets in C [m].
        q: (N, 2) servo angles at the targets [rad].
        t: (N,) time at which each target is passed [s].
        v_tcp: (N,) TCP speed at the targets [m/s].
        command: (N,) laser command at the targets [V].
        timed: the continuous timed servo trajectory.
    """

    contour: Contour
    geometry: FiveBarGeometry
    limits: ServoLimits
    power: PowerMap
    p_CJ5: np.ndarray
    q: np.ndarray
    t: np.ndarray
    v_tcp: np.ndarray
    command: np.ndarray
    timed: TimedPath

    @property
    def duration(self) -> float:
        return self.timed.duration

    def sample(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, PowerProfile]:
        """Dense samples of the timed trajectory every ``dt`` [s].

        Returns:
            (t, q, p_CJ5, power): (M,) times, (M, 2) servo angles, (M, 2) head positions in C
            by forward kinematics, and the TCP speed / command profile (speed = |J qdot|).
        """
        t = np.arange(0.0, self.duration + 0.5 * dt, dt)
        t[-1] = min(t[-1], self.duration)
        q, qd, _ = self.timed.sample(t)
        p = forward_kinematics(self.geometry, q).p_CJ5
        v = tcp_speed(self.geometry, q, qd)
        return t, q, p, power_profile(t, v, self.power)


def tcp_speed(g: FiveBarGeometry, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """(M,) TCP speed |J(q) qd| [m/s] for servo angles q (M, 2) and rates qd (M, 2)."""
    J = jacobian(g, q)
    return np.linalg.norm(np.einsum("nij,nj->ni", J, qd), axis=1)


def tool_path_points(g: FiveBarGeometry, contour: Contour) -> np.ndarray:
    """(N, 2) head targets in C [m] for a contour: P origin at the tool's home point."""
    return g.p_CHome + contour.p_P


def plan_hole(shape: ShapeBase, spacing: float = 0.2e-3,
              geometry: FiveBarGeometry | None = None, limits: ServoLimits | None = None,
              power: PowerMap | None = None) -> HoleProgram:
    """Plan a hole cut by the Cutting Tool alone.

    Args:
        shape: the hole (Circle, Slot, ...), sizes in metres, centred on the tool's home.
        spacing: point spacing along the contour [m].
        geometry, limits, power: tool, servo limits and power map (defaults if None).

    Returns:
        HoleProgram.

    Raises:
        InputError: the shape is malformed or a point is unreachable (names the shape, the
            first unreachable point and why).
    """
    g = geometry or FiveBarGeometry()
    limits = limits or ServoLimits()
    power = power or PowerMap()
    contour = build_contour(shape, spacing)
    p = tool_path_points(g, contour)
    reach = check_reach(g, p)
    k = reach.first_failure
    if k is not None:
        n_bad = int(np.count_nonzero(~reach.reachable))
        raise InputError(
            f"{shape.kind}: point {k} of {len(p)} at ({p[k, 0] * 1e3:.3f}, {p[k, 1] * 1e3:.3f}) "
            f"mm in the tool frame is unreachable ({reach.reason[k]}; {n_bad} points fail); "
            f"the Cutting Tool's working disc is {2e3 * g.work_radius:.1f} mm across")
    timed = time_path(contour.s, reach.q, contour.corner, limits.axis_limits())
    if not timed.success:
        log.warning("%s: TOP-RA failed on a piece; a slow fallback timing is used", shape.kind)
    _, qd, _ = timed.sample(timed.knot_t)
    v = tcp_speed(g, reach.q, qd)
    command, _ = power.command(v)
    return HoleProgram(contour=contour, geometry=g, limits=limits, power=power, p_CJ5=p,
                       q=reach.q, t=timed.knot_t, v_tcp=v, command=command, timed=timed)
