"""Time-optimal timing of a sampled path under axis speed/acceleration and feed limits.

Uses Drake's TOPP-RA (:class:`pydrake.multibody.optimization.Toppra`). The path is a cubic
spline q(s) of the axis positions over the TCP arc length s. A last, extra path row equals s
itself, so a velocity limit on that row caps the TCP speed ds/dt at the feed rate and an
acceleration limit caps the tangential acceleration. The path is split at corners (tangent
jumps): the axes must stop there under finite acceleration, and a smooth spline through a
corner would round it off.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

__all__ = ["AxisLimits", "TimedPath", "time_path"]


@dataclass(frozen=True)
class AxisLimits:
    """Limits for :func:`time_path`.

    Attributes:
        velocity: per-axis speed limits (rad/s for servos, m/s for Cartesian axes).
        acceleration: per-axis acceleration limits (rad/s^2 or m/s^2).
        feed: TCP speed cap along the path [m/s] (the programmed cutting speed).
        feed_acceleration: tangential TCP acceleration cap [m/s^2].
    """

    velocity: tuple[float, ...]
    acceleration: tuple[float, ...]
    feed: float
    feed_acceleration: float


@dataclass(frozen=True, eq=False)
class TimedPath:
    """A path q(s) with its timing s(t), piecewise between corners.

    Attributes:
        segments: list of (q_of_s, s_of_t, t0, s0): Drake PiecewisePolynomials of each
            corner-to-corner piece; q_of_s has the axes plus s as the last row; t0/s0 are the
            start time [s] and start arc length [m] of the piece.
        duration: total time [s].
        knot_s: (N,) arc length of the input samples [m].
        knot_t: (N,) time at which each input sample is passed [s].
        success: False when TOPP-RA found no parameterisation for some piece.
    """

    segments: list
    duration: float
    knot_s: np.ndarray
    knot_t: np.ndarray
    success: bool

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Axis positions and velocities at times t.

        Args:
            t: (M,) times in [0, duration] [s].

        Returns:
            (q, qd, sd): (M, n) positions, (M, n) velocities, (M,) TCP path speed ds/dt [m/s].
        """
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        starts = np.array([seg[2] for seg in self.segments])
        which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        n = self.segments[0][0].rows() - 1
        q, qd, sd = np.empty((len(t), n)), np.empty((len(t), n)), np.empty(len(t))
        for k, (q_s, s_t, t0, _s0) in enumerate(self.segments):
            idx = np.flatnonzero(which == k)
            if not len(idx):
                continue
            # s(t) keeps the path's start break as its own start time
            tl = np.clip(t[idx] - t0 + s_t.start_time(), s_t.start_time(), s_t.end_time())
            s = np.clip(s_t.vector_values(tl)[0], q_s.start_time(), q_s.end_time())
            sd_k = s_t.derivative(1).vector_values(tl)[0]
            qs = q_s.vector_values(s)[:n].T
            dq = q_s.derivative(1)
            qds = dq.vector_values(s)[:n].T
            q[idx], qd[idx], sd[idx] = qs, qds * sd_k[:, None], sd_k
        return q, qd, sd


@functools.cache
def _axis_plant(n: int):
    """A MultibodyPlant with n prismatic axes in series (TOPP-RA needs a plant whose
    positions match the path rows; only velocity/acceleration limits are used)."""
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.multibody.tree import PrismaticJoint, SpatialInertia

    plant = MultibodyPlant(0.0)
    parent = plant.world_body()
    for i in range(n):
        body = plant.AddRigidBody(f"axis_{i}", SpatialInertia.SolidSphereWithMass(1.0, 0.01))
        plant.AddJoint(PrismaticJoint(f"axis_{i}", parent.body_frame(), body.body_frame(),
                                      [1.0, 0.0, 0.0], -1e6, 1e6))
        parent = body
    plant.Finalize()
    return plant


def time_path(s: np.ndarray, q: np.ndarray, corner: np.ndarray, limits: AxisLimits,
              grid_step: float | None = None) -> TimedPath:
    """Time-optimal timing (TOPP-RA) of axis samples q(s), stopping at corners.

    Args:
        s: (N,) increasing arc length of the TCP at the samples [m].
        q: (N, n) axis positions at the samples.
        corner: (N,) True where the path has a tangent jump (the axes stop there); the first
            and last samples are always stops.
        limits: axis and feed limits.
        grid_step: TOPP-RA grid spacing along s [m]; default: the sample spacing.

    Returns:
        TimedPath; ``success`` False when some piece could not be parameterised.
    """
    from pydrake.multibody.optimization import Toppra
    from pydrake.trajectories import PiecewisePolynomial

    s = np.asarray(s, dtype=float)
    q = np.asarray(q, dtype=float)
    n = q.shape[1]
    plant = _axis_plant(n + 1)
    stops = sorted({0, len(s) - 1, *np.flatnonzero(corner).tolist()})
    v_max = np.array([*limits.velocity, limits.feed], dtype=float)
    a_max = np.array([*limits.acceleration, limits.feed_acceleration], dtype=float)
    segments, knot_t = [], np.zeros(len(s))
    t0, ok = 0.0, True
    for i0, i1 in zip(stops[:-1], stops[1:], strict=True):
        ss = s[i0:i1 + 1]
        rows = np.vstack([q[i0:i1 + 1].T, ss])
        if len(ss) >= 3:
            q_s = PiecewisePolynomial.CubicWithContinuousSecondDerivatives(ss, rows, False)
        else:
            q_s = PiecewisePolynomial.FirstOrderHold(ss, rows)
        step = grid_step or max(float(np.min(np.diff(ss))), 1e-9)
        m = int(np.clip(np.ceil((ss[-1] - ss[0]) / step), 4, 4000)) + 1
        grid = np.linspace(ss[0], ss[-1], m)
        toppra = Toppra(q_s, plant, grid)
        toppra.AddJointVelocityLimit(-v_max, v_max)
        toppra.AddJointAccelerationLimit(-a_max, a_max)
        s_t = toppra.SolvePathParameterization()
        if s_t is None:
            ok = False
            # fall back to a slow constant-speed timing so callers still get a trajectory
            dur = 10.0 * (ss[-1] - ss[0]) / limits.feed
            s_t = PiecewisePolynomial.FirstOrderHold([0.0, dur], [[ss[0], ss[-1]]])
        dur = s_t.end_time() - s_t.start_time()
        tt = np.linspace(s_t.start_time(), s_t.end_time(), 20 * len(ss) + 1)
        sv = s_t.vector_values(tt)[0]
        knot_t[i0:i1 + 1] = t0 + np.interp(ss, np.maximum.accumulate(sv), tt - s_t.start_time())
        segments.append((q_s, s_t, t0, ss[0]))
        t0 += dur
    return TimedPath(segments=segments, duration=t0, knot_s=s, knot_t=knot_t, success=ok)
