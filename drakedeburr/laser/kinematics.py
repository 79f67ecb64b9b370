"""Kinematics of the five-bar "Cutting Tool" (SPEC.md §S4, eqs. 1-9 of source 004).

Frame C (tool base, "cutting-tool frame"): origin at the servo axis J1, the linkage moves in
the C x-y plane, +z is the laser beam axis (towards the work). Conventions are the source's:

* crank 1 (length L1) turns about J1 = (0, 0): J3 = (L1 sin th1, -L1 cos th1)
* crank 2 (length L2) turns about J2 = (0, L0): J4 = (L2 sin th2, L0 - L2 cos th2)
* link 1 (L3) J3 -> J5 = J3 + L3 (sin th3, cos th3)         (eqs. 1, 2)
* link 2 (L4) J4 -> J5 = J4 + L4 (sin th4, -cos th4)        (loop closure, eqs. 3, 4)

th3 solves A cos th3 + B sin th3 = C (eqs. 7, 8) with A, B, C of the source; eq. 9 is
th3 = atan2(B, A) +- acos(C / sqrt(A^2 + B^2)); the sign is the *assembly mode* (which side
of the line J3->J4 the head J5 lies on). The *working mode* is the elbow side of each leg,
used by inverse kinematics. Both modes only change through a singularity, so fixing them
once for a tool makes FK and IK one-to-one inside the workspace.

Singularities (Gosselin & Angeles):
* serial / type I (workspace boundary): a crank and its link are aligned, one leg cannot
  move J5 along its link: ``cross(J3 - J1, J5 - J3) = 0`` or ``cross(J4 - J2, J5 - J4) = 0``.
* parallel / type II (loss of stiffness, FK branches merge): the two links are aligned:
  ``cross(J5 - J3, J5 - J4) = 0``, equivalently A^2 + B^2 = C^2 in eq. 8.

Everything is SI (metres, radians). Written by hand: the closed form is a few lines and no
maintained library solves five-bar linkages.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError

__all__ = [
    "FiveBarGeometry",
    "FiveBarState",
    "ReachReport",
    "forward_kinematics",
    "forward_kinematics_circles",
    "solve_theta3",
    "inverse_kinematics",
    "jacobian",
    "tcp_speed",
    "singularity_measures",
    "check_reach",
]


@dataclass(frozen=True)
class FiveBarGeometry:
    """Link lengths [m] and branch choices of the Cutting Tool.

    The source gives no link lengths. Defaults are a plausible symmetric design for a tool
    that cuts holes up to 25 mm diameter: servo spacing L0 = 30 mm, cranks 40 mm, links 75 mm,
    home 65 mm in front of the servo line. Chosen by a grid search (docs/laser.md) for the
    lowest worst-case Jacobian condition number over the 30 mm working disc (25 mm hole plus
    lead-in margin): condition <= 1.2, leg-angle sine >= 0.65, link-angle sine >= 0.98, so the
    disc is far from both kinds of singularity.

    Attributes:
        l0: distance between the servo axes J1-J2 [m].
        l1, l2: crank (rocker arm) lengths [m].
        l3, l4: link lengths (crank tip to the head J5) [m].
        working_mode: elbow sign of leg 1 and leg 2, ``sign(cross(J3 - J1, J5 - J1))`` and
            ``sign(cross(J4 - J2, J5 - J2))``; (+1, -1) = both cranks turned outwards.
        assembly_mode: ``sign(cross(J4 - J3, J5 - J3))``; -1 = head on the +x side.
        home_x: x of the home point (centre of the working disc) in frame C [m]; the home
            point is (home_x, l0 / 2).
        work_radius: radius of the guaranteed working disc around home [m].
        min_sin_serial: reject points whose leg angle sine |sin(crank, link)| is below this.
        min_sin_parallel: reject points whose link-link angle sine is below this.
    """

    l0: float = 0.030
    l1: float = 0.040
    l2: float = 0.040
    l3: float = 0.075
    l4: float = 0.075
    working_mode: tuple[int, int] = (1, -1)
    assembly_mode: int = -1
    home_x: float = 0.065
    work_radius: float = 0.015
    min_sin_serial: float = 0.15
    min_sin_parallel: float = 0.15

    def __post_init__(self) -> None:
        for name in ("l0", "l1", "l2", "l3", "l4", "work_radius"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"FiveBarGeometry.{name} must be > 0, got {value!r}")
        if tuple(abs(int(s)) for s in self.working_mode) != (1, 1):
            raise InputError(f"FiveBarGeometry.working_mode must be two signs, got "
                             f"{self.working_mode!r}")
        if abs(int(self.assembly_mode)) != 1:
            raise InputError(f"FiveBarGeometry.assembly_mode must be +1 or -1, got "
                             f"{self.assembly_mode!r}")

    @property
    def p_CJ1(self) -> np.ndarray:
        """(2,) servo 1 axis in C [m]."""
        return np.zeros(2)

    @property
    def p_CJ2(self) -> np.ndarray:
        """(2,) servo 2 axis in C [m]."""
        return np.array([0.0, self.l0])

    @property
    def p_CHome(self) -> np.ndarray:
        """(2,) home point (centre of the working disc) in C [m]."""
        return np.array([self.home_x, 0.5 * self.l0])


@dataclass(frozen=True, eq=False)
class FiveBarState:
    """All joint positions for servo angles ``q`` (N,2) [rad]; arrays are (N,2) in C [m].

    Attributes:
        q: (N, 2) servo angles th1, th2 [rad].
        theta3, theta4: (N,) link angles of eqs. 1-6 [rad].
        p_CJ3, p_CJ4, p_CJ5: (N, 2) crank tips and head in C [m]; NaN where not assembled.
        valid: (N,) True where the loop closes (|C| <= sqrt(A^2 + B^2)).
    """

    q: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    p_CJ3: np.ndarray
    p_CJ4: np.ndarray
    p_CJ5: np.ndarray
    valid: np.ndarray


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _crank_tips(g: FiveBarGeometry, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    th1, th2 = q[:, 0], q[:, 1]
    p_CJ3 = np.stack([g.l1 * np.sin(th1), -g.l1 * np.cos(th1)], axis=1)
    p_CJ4 = np.stack([g.l2 * np.sin(th2), g.l0 - g.l2 * np.cos(th2)], axis=1)
    return p_CJ3, p_CJ4


def solve_theta3(g: FiveBarGeometry, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both roots of eq. 8 (A cos th3 + B sin th3 = C) for servo angles q.

    Args:
        g: tool geometry.
        q: (N, 2) servo angles [rad].

    Returns:
        (theta3_plus, theta3_minus, valid): (N,) roots of eq. 9 with +acos and -acos [rad],
        and (N,) bool, False where |C| > sqrt(A^2 + B^2) (the loop cannot close; roots NaN).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    th1, th2 = q[:, 0], q[:, 1]
    L0, L1, L2, L3, L4 = g.l0, g.l1, g.l2, g.l3, g.l4
    A = 2 * L1 * L3 * np.cos(th1) - 2 * L2 * L3 * np.cos(th2) + 2 * L0 * L3  # eq. 7/8
    B = -2 * L1 * L3 * np.sin(th1) + 2 * L2 * L3 * np.sin(th2)
    C = (L0**2 + L1**2 + L2**2 + L3**2 - L4**2 + 2 * L0 * L1 * np.cos(th1)
         - 2 * L0 * L2 * np.cos(th2) - 2 * L1 * L2 * np.cos(th1 - th2))
    R = np.hypot(A, B)
    ratio = np.divide(C, R, out=np.full_like(C, np.inf), where=R > 0)
    valid = np.abs(ratio) <= 1.0
    phi = np.arctan2(B, A)
    delta = np.arccos(np.clip(ratio, -1.0, 1.0))
    plus = np.where(valid, phi + delta, np.nan)  # eq. 9
    minus = np.where(valid, phi - delta, np.nan)
    return plus, minus, valid


def forward_kinematics(g: FiveBarGeometry, q: np.ndarray) -> FiveBarState:
    """Head position J5 from the servo angles, by eqs. 1-9 of the source.

    Of the two roots of eq. 9 the one in ``g.assembly_mode`` is returned.

    Args:
        g: tool geometry.
        q: (N, 2) or (2,) servo angles [rad].

    Returns:
        FiveBarState with (N, 2) positions in C [m].
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    plus, minus, valid = solve_theta3(g, q)
    p_CJ3, p_CJ4 = _crank_tips(g, q)

    def head(th3: np.ndarray) -> np.ndarray:
        return p_CJ3 + g.l3 * np.stack([np.sin(th3), np.cos(th3)], axis=1)  # eqs. 1, 2

    p_plus, p_minus = head(plus), head(minus)
    s_plus = np.sign(_cross(p_CJ4 - p_CJ3, p_plus - p_CJ3))
    use_plus = s_plus == g.assembly_mode
    theta3 = np.where(use_plus, plus, minus)
    p_CJ5 = np.where(use_plus[:, None], p_plus, p_minus)
    d = p_CJ5 - p_CJ4  # = L4 (sin th4, -cos th4)
    theta4 = np.arctan2(d[:, 0], -d[:, 1])
    return FiveBarState(q=q, theta3=theta3, theta4=theta4, p_CJ3=p_CJ3, p_CJ4=p_CJ4,
                        p_CJ5=p_CJ5, valid=valid)


def forward_kinematics_circles(g: FiveBarGeometry, q: np.ndarray) -> np.ndarray:
    """Second, independent FK: intersect the circles (J3, L3) and (J4, L4).

    Args:
        g: tool geometry.
        q: (N, 2) servo angles [rad].

    Returns:
        (N, 2) head positions J5 in C [m] in ``g.assembly_mode``; NaN where not assembled.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    p_CJ3, p_CJ4 = _crank_tips(g, q)
    d_vec = p_CJ4 - p_CJ3
    d = np.linalg.norm(d_vec, axis=1)
    a = (g.l3**2 - g.l4**2 + d**2) / (2 * d)
    h2 = g.l3**2 - a**2
    h = np.sqrt(np.where(h2 >= 0, h2, np.nan))
    e = d_vec / d[:, None]
    n = np.stack([-e[:, 1], e[:, 0]], axis=1)  # left normal: cross(e, n) = +1
    return p_CJ3 + a[:, None] * e + (g.assembly_mode * h)[:, None] * n


def inverse_kinematics(g: FiveBarGeometry, p_CJ5: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Servo angles that put the head at ``p_CJ5`` in ``g.working_mode``.

    Angles are returned within +-pi of the home-point solution, so a path through the working
    disc gives continuous servo angles (no 2 pi jumps).

    Args:
        g: tool geometry.
        p_CJ5: (N, 2) or (2,) head positions in C [m].

    Returns:
        (q, reachable): (N, 2) servo angles [rad] (NaN where unreachable) and (N,) bool.
    """
    p = np.atleast_2d(np.asarray(p_CJ5, dtype=float))
    q, ok = _ik_raw(g, p)
    q_ref = _ik_raw(g, g.p_CHome[None, :])[0][0]
    if np.all(np.isfinite(q_ref)):
        q = q_ref + np.mod(q - q_ref + np.pi, 2 * np.pi) - np.pi
    return q, ok


def _ik_raw(g: FiveBarGeometry, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.empty((len(p), 2))
    ok = np.ones(len(p), dtype=bool)
    legs = ((g.p_CJ1, g.l1, g.l3, g.working_mode[0], 0),
            (g.p_CJ2, g.l2, g.l4, g.working_mode[1], 1))
    for p_base, la, lb, sigma, col in legs:
        v = p - p_base
        d = np.linalg.norm(v, axis=1)
        ok &= d > 0
        d = np.where(d > 0, d, 1.0)  # a point on the servo axis is unreachable (masked)
        # crank tip on circle (base, la) and (p, lb): distance a along v, offset h
        a = (la**2 - lb**2 + d**2) / (2 * d)
        h2 = la**2 - a**2
        ok &= h2 >= 0
        h = np.sqrt(np.clip(h2, 0.0, None))
        e = v / d[:, None]
        n = np.stack([-e[:, 1], e[:, 0]], axis=1)
        # cross(tip - base, p - base) = -h * sign * d  -> choose sign so it equals sigma
        tip = a[:, None] * e - (sigma * h)[:, None] * n
        # tip = (la sin th, -la cos th)
        q[:, col] = np.arctan2(tip[:, 0], -tip[:, 1])
    q[~ok] = np.nan
    return q, ok


def jacobian(g: FiveBarGeometry, q: np.ndarray) -> np.ndarray:
    """Velocity Jacobian J (N, 2, 2) with d p_CJ5 / dt = J @ dq/dt [m/rad].

    From the leg constraints |J5 - J3|^2 = L3^2, |J5 - J4|^2 = L4^2:
    Ax * v + Bq * qdot = 0 -> J = -Ax^-1 Bq. Infinite entries at type II singularities.
    """
    st = forward_kinematics(g, q)
    Ax, Bq = _constraint_matrices(g, st)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -np.linalg.solve(Ax, Bq)


def tcp_speed(g: FiveBarGeometry, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """(M,) TCP speed |J(q) qd| [m/s] for servo angles q (M, 2) and rates qd (M, 2)."""
    J = jacobian(g, q)
    return np.linalg.norm(np.einsum("nij,nj->ni", J, qd), axis=1)


def _constraint_matrices(g: FiveBarGeometry, st: FiveBarState) -> tuple[np.ndarray, np.ndarray]:
    th1, th2 = st.q[:, 0], st.q[:, 1]
    u = st.p_CJ5 - st.p_CJ3
    w = st.p_CJ5 - st.p_CJ4
    dJ3 = np.stack([g.l1 * np.cos(th1), g.l1 * np.sin(th1)], axis=1)
    dJ4 = np.stack([g.l2 * np.cos(th2), g.l2 * np.sin(th2)], axis=1)
    Ax = np.stack([u, w], axis=1)  # (N, 2, 2)
    Bq = np.zeros((len(u), 2, 2))
    Bq[:, 0, 0] = -np.sum(u * dJ3, axis=1)
    Bq[:, 1, 1] = -np.sum(w * dJ4, axis=1)
    return Ax, Bq


def singularity_measures(g: FiveBarGeometry, q: np.ndarray) -> dict[str, np.ndarray]:
    """Distance-to-singularity measures (sines of the critical angles) for servo angles q.

    Returns:
        dict of (N,) arrays: ``serial_1`` = |sin| of the angle crank 1 / link 1,
        ``serial_2`` likewise for leg 2 (0 at a type I / boundary singularity),
        ``parallel`` = |sin| of the angle link 1 / link 2 (0 at a type II singularity),
        ``condition`` = condition number of the Jacobian (inf at either kind).
    """
    st = forward_kinematics(g, q)
    c1 = st.p_CJ3 - g.p_CJ1
    c2 = st.p_CJ4 - g.p_CJ2
    u = st.p_CJ5 - st.p_CJ3
    w = st.p_CJ5 - st.p_CJ4
    serial_1 = np.abs(_cross(c1, u)) / (g.l1 * g.l3)
    serial_2 = np.abs(_cross(c2, w)) / (g.l2 * g.l4)
    parallel = np.abs(_cross(u, w)) / (g.l3 * g.l4)
    with np.errstate(divide="ignore", invalid="ignore"):
        J = jacobian(g, q)
        finite = np.all(np.isfinite(J), axis=(1, 2))
        cond = np.full(len(st.q), np.inf)
        if finite.any():
            cond[finite] = np.linalg.cond(J[finite])
    cond[(serial_1 == 0) | (serial_2 == 0) | (parallel == 0)] = np.inf
    return {"serial_1": serial_1, "serial_2": serial_2, "parallel": parallel,
            "condition": cond}


@dataclass(frozen=True, eq=False)
class ReachReport:
    """Which head positions the tool can reach safely.

    Attributes:
        q: (N, 2) servo angles [rad] (NaN where unreachable).
        reachable: (N,) bool: IK exists, away from both singularity kinds, inside the disc.
        reason: (N,) str per point: "" or why it failed ("out of reach", "serial
            singularity", "parallel singularity", "outside working disc").
    """

    q: np.ndarray
    reachable: np.ndarray
    reason: np.ndarray

    @property
    def first_failure(self) -> int | None:
        """Index of the first unreachable point, None when all are reachable."""
        bad = np.flatnonzero(~self.reachable)
        return int(bad[0]) if len(bad) else None


def check_reach(g: FiveBarGeometry, p_CJ5: np.ndarray, use_disc: bool = True) -> ReachReport:
    """IK plus workspace and singularity checks for head positions ``p_CJ5`` (N, 2) in C [m].

    A point fails when no IK exists, when a leg or the link pair is closer to a singularity
    than ``g.min_sin_serial`` / ``g.min_sin_parallel``, when FK does not return to the point
    (assembly mode crossed), or (``use_disc``) when it lies outside the working disc.
    """
    p = np.atleast_2d(np.asarray(p_CJ5, dtype=float))
    q, ok = inverse_kinematics(g, p)
    reason = np.full(len(p), "", dtype=object)
    reason[~ok] = "out of reach"
    if ok.any():
        m = singularity_measures(g, q[ok])
        r = reason[ok]
        r[(m["serial_1"] < g.min_sin_serial) | (m["serial_2"] < g.min_sin_serial)] = \
            "serial singularity"
        r[(m["parallel"] < g.min_sin_parallel) & (r == "")] = "parallel singularity"
        back = forward_kinematics(g, q[ok]).p_CJ5
        r[(~np.all(np.abs(back - p[ok]) < 1e-6, axis=1)) & (r == "")] = "assembly mode change"
        reason[ok] = r
    if use_disc:
        outside = np.linalg.norm(p - g.p_CHome, axis=1) > g.work_radius + 1e-12
        reason[outside & (reason == "")] = "outside working disc"
    reachable = reason == ""
    return ReachReport(q=q, reachable=reachable, reason=reason.astype(str))
