"""Laser programs timed as the controller runs them: segments of whole interpolation periods.

A FANUC controller plans motion in steps of its interpolation period (ITP, 8 ms on the
R-30iA/R-30iB; 16 ms selectable at Controlled Start): a timed motion instruction lasts a whole
number of ITPs, rounded *up* (FANUC "ITP" knowledge-base note, cited in docs/laser.md: a
100 ms time step runs as 13 ITP = 104 ms). A hole planned in 1.19 ms steps and written as
``0.001sec`` therefore runs at most one 0.2 mm step per 8 ms (<= 1.5 m/min) while the laser
command stays at the full-speed value: ~6.7 x the energy per length.

This module chooses the other way round (issue 44 item 6, option 1: segment times that are
multiples of the interpolation period, with the path and the power re-planned for that):

1. the feed is capped so one ITP step stays within the chord tolerance on the tightest curve
   of the contour (chord c on radius r has sagitta c^2 / (8 r)): :meth:`ControllerTiming.feed_cap`;
2. the TOPP-RA trajectory is re-timed under that feed, then every corner-to-corner piece is
   stretched to a whole number of ITPs (never faster than the time-optimal plan) and cut at
   every ITP: each written segment lasts exactly one period;
3. the laser command of a segment is the planned speed-proportional command integrated over
   the segment and divided by its time, so the energy a segment deposits (command x time) is
   the plan's, and the energy per length equals the plan's segment by segment.

The alternative (the controller's own TCP-speed analogue output, which updates the AO every
ITP from the actual TCP speed) needs the controller option and its setup screens; it is not
written here (docs/laser.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["ControllerTiming", "ItpSegments", "quantise", "min_curve_radius",
           "FANUC_ITP", "FANUC_TIMING", "TP_MSEC_MAX"]

FANUC_ITP = 0.008  # [s] FANUC R-30iA/R-30iB interpolation period (default)
TP_MSEC_MAX = 32000  # FANUC TP timed motion: 1 .. 32000 msec per instruction
_SUB = 24  # sub-samples per segment for the energy integral


@dataclass(frozen=True)
class ControllerTiming:
    """The controller's timing rules for a laser program.

    Attributes:
        period: interpolation period [s] (FANUC default 8 ms); every segment lasts a whole
            number of periods.
        chord_tolerance: largest sagitta of one period's chord on the contour's tightest
            curve [m]; caps the feed at sqrt(8 r tol) / period.
    """

    period: float = FANUC_ITP
    chord_tolerance: float = 0.01e-3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.period) and 0.5e-3 <= self.period <= 0.1):
            raise InputError(f"interpolation period must be 0.5 .. 100 ms, got "
                             f"{self.period * 1e3!r} ms")
        if round(self.period * 1e3, 9) != round(self.period * 1e3):
            raise InputError(f"interpolation period must be whole milliseconds (TP msec), got "
                             f"{self.period * 1e3!r} ms")
        if not (math.isfinite(self.chord_tolerance) and self.chord_tolerance > 0):
            raise InputError(f"chord tolerance must be > 0, got {self.chord_tolerance!r} m")

    @property
    def period_ms(self) -> int:
        return int(round(self.period * 1e3))

    def feed_cap(self, p: np.ndarray, corner: np.ndarray, feed: float) -> float:
        """The feed [m/s] at which one period's chord on the tightest curve of the points
        p (N, 2) [m] has the chord tolerance as sagitta; at most ``feed``."""
        r = min_curve_radius(p, corner)
        if not math.isfinite(r):
            return float(feed)
        return float(min(feed, math.sqrt(8.0 * r * self.chord_tolerance) / self.period))


#: the FANUC default: 8 ms, 0.01 mm chord
FANUC_TIMING = ControllerTiming()


def min_curve_radius(p: np.ndarray, corner: np.ndarray) -> float:
    """Smallest circumradius [m] of three consecutive points p (N, 2), the middle one not a
    corner (inf for straight lines)."""
    p = np.asarray(p, float)
    if len(p) < 3:
        return math.inf
    a, b, c = p[:-2], p[1:-1], p[2:]
    ab, bc, ca = (np.linalg.norm(x, axis=1) for x in (b - a, c - b, a - c))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        r = ab * bc * ca / (2.0 * cross)
    r = np.where(np.asarray(corner, bool)[1:-1] | ~np.isfinite(r), np.inf, r)
    return float(r.min())


@dataclass(frozen=True, eq=False)
class ItpSegments:
    """The program as the controller runs it: K segments of whole periods.

    Attributes:
        timing: the controller timing used.
        q: (K + 1, 2) servo angles at the segment ends [rad] (row 0 = start).
        t: (K + 1,) time at the segment ends [s], multiples of the period.
        ticks: (K,) periods per segment (1 here).
        stop: (K + 1,) True where the tool stops (start, corners, end): FINE points.
        command: (K,) laser command of each segment [V].
        energy: (K,) planned command x time over each segment [V s].
        length: (K,) planned path length of each segment [m].
        stretch: per piece, written duration / time-optimal duration (>= 1).
    """

    timing: ControllerTiming
    q: np.ndarray
    t: np.ndarray
    ticks: np.ndarray
    stop: np.ndarray
    command: np.ndarray
    energy: np.ndarray
    length: np.ndarray
    stretch: tuple[float, ...]

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def __len__(self) -> int:
        return len(self.ticks)


def quantise(timed, geometry, power, timing: ControllerTiming) -> ItpSegments:
    """Cut a timed servo trajectory into whole interpolation periods (module docstring).

    Args:
        timed: :class:`~drakedeburr.laser.timing.TimedPath` of the servo angles.
        geometry: the five-bar (FK for the TCP path and speed).
        power: :class:`~drakedeburr.laser.power.PowerMap` (speed -> command).
        timing: the controller's period.

    Returns:
        ItpSegments.
    """
    from drakedeburr.laser.kinematics import forward_kinematics

    T = timing.period
    qs, ts, stops, cmd, energy, length, stretch = [], [], [], [], [], [], []
    t_out = 0.0
    for k, (_q_s, s_t, t0, _s0) in enumerate(timed.segments):
        dur = float(s_t.end_time() - s_t.start_time())
        n = max(1, math.ceil(dur / T - 1e-9))
        c = n * T / dur if dur > 0 else 1.0
        stretch.append(c)
        tau = t0 + np.linspace(0.0, dur, n * _SUB + 1)  # planned (time-optimal) times
        q, qd, _ = timed.sample(tau)
        p = forward_kinematics(geometry, q).p_CJ5
        ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
        # stretched by c: speed / c; the command follows the speed actually run
        v = _speed(geometry, q, qd) / c
        P, _ = power.command(v)
        dt = c * dur / (n * _SUB)
        e_sub = 0.5 * (P[:-1] + P[1:]) * dt
        e = e_sub.reshape(n, _SUB).sum(axis=1)
        L = ds.reshape(n, _SUB).sum(axis=1)
        idx = np.arange(0, n * _SUB + 1, _SUB)
        if k == 0:
            qs.append(q[idx[:1]])
            ts.append([0.0])
            stops.append([True])
        qs.append(q[idx[1:]])
        ts.append(t_out + T * np.arange(1, n + 1))
        st = np.zeros(n, bool)
        st[-1] = True
        stops.append(st)
        energy.append(e)
        length.append(L)
        cmd.append(e / T)
        t_out += n * T
    energy_all = np.concatenate(energy)
    return ItpSegments(
        timing=timing, q=np.concatenate(qs), t=np.concatenate(ts),
        ticks=np.ones(len(energy_all), int), stop=np.concatenate(stops),
        command=np.concatenate(cmd), energy=energy_all, length=np.concatenate(length),
        stretch=tuple(stretch))


def _speed(g, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    from drakedeburr.laser.kinematics import tcp_speed

    return tcp_speed(g, q, qd)
