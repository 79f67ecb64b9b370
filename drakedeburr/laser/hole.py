"""Small holes (diameter 1-25 mm) cut by the Cutting Tool alone while the robot holds still.

Pipeline: shape -> contour in the part plane -> head positions in the tool frame C (the shape
origin sits at the tool's home point, plus the shape's ``center`` offset) -> servo angles by
inverse kinematics (with workspace/singularity checks) -> time-optimal servo trajectory
(TOPP-RA under servo speed/acceleration limits and the feed) -> TCP speed -> laser command
-> the segments the controller runs: whole interpolation periods, the feed capped so one
period's chord keeps the chord tolerance, the command re-planned per segment
(:mod:`drakedeburr.laser.itp`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.laser.itp import FANUC_TIMING, ControllerTiming, ItpSegments, quantise
from drakedeburr.laser.kinematics import (
    FiveBarGeometry,
    check_reach,
    forward_kinematics,
    tcp_speed,
)
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
        limits: servo limits used for timing (the feed capped for the controller timing).
        power: speed -> command map.
        p_CJ5: (N, 2) head targets in C [m].
        q: (N, 2) servo angles at the targets [rad].
        t: (N,) time at which each target is passed [s].
        v_tcp: (N,) TCP speed at the targets [m/s].
        command: (N,) laser command at the targets [V].
        timed: the continuous timed servo trajectory.
        segments: the program as the controller runs it (whole interpolation periods);
            None when planned without a controller timing.
        feed_requested: the feed asked for [m/s] (``limits.feed`` may be lower: the cap).
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
    segments: ItpSegments | None = None
    feed_requested: float = 0.0

    @property
    def duration(self) -> float:
        """Cycle time [s]: as the controller runs it when ``segments`` exist."""
        return self.segments.duration if self.segments is not None else self.timed.duration

    def sample(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, PowerProfile]:
        """Dense samples of the timed trajectory every ``dt`` [s].

        Returns:
            (t, q, p_CJ5, power): (M,) times, (M, 2) servo angles, (M, 2) head positions in C
            by forward kinematics, and the TCP speed / command profile (speed = |J qdot|).
        """
        T = self.timed.duration
        t = np.arange(0.0, T + 0.5 * dt, dt)
        t[-1] = min(t[-1], T)
        q, qd, _ = self.timed.sample(t)
        p = forward_kinematics(self.geometry, q).p_CJ5
        v = tcp_speed(self.geometry, q, qd)
        return t, q, p, power_profile(t, v, self.power)


def tool_path_points(g: FiveBarGeometry, contour: Contour) -> np.ndarray:
    """(N, 2) head targets in C [m] for a contour: P origin at the tool's home point."""
    return g.p_CHome + contour.p_P


def plan_hole(shape: ShapeBase, spacing: float = 0.2e-3,
              geometry: FiveBarGeometry | None = None, limits: ServoLimits | None = None,
              power: PowerMap | None = None,
              timing: ControllerTiming | None = FANUC_TIMING,
              mirror_y: bool = False) -> HoleProgram:
    """Plan a hole cut by the Cutting Tool alone.

    Args:
        shape: the hole (Circle, Slot, ...), sizes in metres, centred on the tool's home.
        spacing: point spacing along the contour [m].
        geometry, limits, power: tool, servo limits and power map (defaults if None).
        timing: the controller's interpolation period and chord tolerance: the feed is
            capped so one period's chord keeps the tolerance and the program is cut into
            whole periods (``segments``); None = the continuous plan only.
        mirror_y: the shape is given in the plate frame and the tool looks into the plate
            (its y = the plate's -y, :mod:`drakedeburr.laser.robot_job`): the contour is
            mirrored (y -> -y) into the tool's plane.

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
    if mirror_y:
        flip = np.array([1.0, -1.0])
        contour = replace(contour, p_P=contour.p_P * flip, t_P=contour.t_P * flip)
    p = tool_path_points(g, contour)
    reach = check_reach(g, p)
    k = reach.first_failure
    if k is not None:
        n_bad = int(np.count_nonzero(~reach.reachable))
        raise InputError(
            f"{shape.kind}: point {k} of {len(p)} at ({p[k, 0] * 1e3:.3f}, {p[k, 1] * 1e3:.3f}) "
            f"mm in the tool frame is unreachable ({reach.reason[k]}; {n_bad} points fail); "
            f"the Cutting Tool's working disc is {2e3 * g.work_radius:.1f} mm across")
    feed_requested = limits.feed
    if timing is not None:
        cap = timing.feed_cap(contour.p_P, contour.corner, limits.feed)
        if cap < limits.feed:
            log.info("%s: feed %.3f m/min capped to %.3f m/min (%g ms period, %.3g mm chord "
                     "tolerance)", shape.kind, limits.feed * 60, cap * 60, timing.period * 1e3,
                     timing.chord_tolerance * 1e3)
            limits = replace(limits, feed=cap)
    timed = time_path(contour.s, reach.q, contour.corner, limits.axis_limits())
    if not timed.success:
        log.warning("%s: TOP-RA failed on a piece; a slow fallback timing is used", shape.kind)
    _, qd, _ = timed.sample(timed.knot_t)
    v = tcp_speed(g, reach.q, qd)
    command, _ = power.command(v)
    segments = None if timing is None else quantise(timed, g, power, timing)
    return HoleProgram(contour=contour, geometry=g, limits=limits, power=power, p_CJ5=p,
                       q=reach.q, t=timed.knot_t, v_tcp=v, command=command, timed=timed,
                       segments=segments, feed_requested=feed_requested)
