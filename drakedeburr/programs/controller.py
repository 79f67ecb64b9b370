"""The controller's motion re-simulated from a program as written (not from the plan).

A controller does not read joints from a Cartesian program: it solves them from the written
target pose, the frames it holds and the configuration data, by its own rule:

* joint moves (MoveJ, PTP, J) and the first move: the IK solution with the written
  configuration (ABB confdata, KUKA S/T, FANUC CONFIG; :func:`joints_from_configuration`);
* linear moves (MoveL, LIN, L): the TCP runs a straight line (orientation interpolated) from
  the previous target and the joints follow it continuously from where the arm is. ABB with
  ``ConfL \\On`` (our RAPID) then stops if the joints reached do not have the written confdata;
  KUKA takes S/T of a LIN target from the start (KSS: "LIN/CIRC: Status and Turn are taken
  from the start point"); FANUC's L moves keep the posture they start in.

The motion is sampled (``samples`` per move) and solved with the analytic IK (nearest
continuation, :func:`drakedeburr.robots.select_solution`); a jump of the joints between samples
means the controller passes a singularity or changes posture on a linear move. Corners are
re-made by the vendor's rule in :mod:`drakedeburr.programs.common` (zones within half the
adjacent moves, FANUC CNT bound); the samples follow the programmed lines.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from drakedeburr.programs.program import JOINT
from drakedeburr.robots import (
    JointLimits,
    RobotSpec,
    configuration_of,
    fk_opw,
    ik_opw,
    joints_from_configuration,
    select_solution,
    travel_weights,
)

__all__ = ["ControllerMotion", "controller_motion", "JUMP"]

#: [rad] a joint step between two samples of a linear move larger than this is a posture
#: change (or a singularity) the controller cannot make on a straight line
JUMP = 0.5
_TWO_PI = 2.0 * np.pi
_VENDOR = {"rapid": "abb", "krl": "kuka", "ls": "fanuc"}


@dataclass(frozen=True, eq=False)
class ControllerMotion:
    """What the controller does with a program.

    Attributes:
        q: (N, 6) model joints [rad] at each move's target (NaN where none was found).
        q_path: (M, 6) joints along the motion, ``samples`` per move, target last.
        X_path: (M, 4, 4) the flange pose in the robot base B along it [m].
        move: (M,) the move (0-based) each sample belongs to.
        problems: one line each, "file:line: move n: what".
        frames_used: item -> "program" (stated in the file) or "cell" (not stated: assumed).
        q_mid: (M, 6) [rad] per sample, the joints halfway along the motion from the previous
            sample (solved there on a linear move; the mean of the two on a joint move, which
            is straight in joint space; the sample itself at the first).
    """

    q: np.ndarray
    q_path: np.ndarray
    X_path: np.ndarray
    move: np.ndarray
    problems: tuple[str, ...]
    frames_used: dict
    q_mid: np.ndarray | None = None


def _beyond(limits: JointLimits) -> JointLimits:
    """The limits widened by half a turn: the joints a controller's continuous motion can be
    driven to before it stops at a limit (the joint item reports where they leave the limits;
    within half a turn every 2 pi variant is a different configuration)."""
    return JointLimits(tuple(np.asarray(limits.lower) - np.pi),
                       tuple(np.asarray(limits.upper) + np.pi))


def _nearest(spec: RobotSpec, X_BF: np.ndarray, q_prev: np.ndarray) -> np.ndarray | None:
    """The IK solution nearest ``q_prev`` (the joints follow continuously), inside the limits or
    beyond them (:func:`_beyond`: a straight line that drives a joint past its limit is shown,
    not replaced by a jump to another turn)."""
    return _nearest_of(spec, ik_opw(spec.opw, X_BF).q[0], q_prev)


def _nearest_of(spec: RobotSpec, sols: np.ndarray, q_prev: np.ndarray) -> np.ndarray | None:
    """:func:`drakedeburr.robots.select_solution` over every 2 pi turn of the IK branches
    ``sols`` (8, 6) inside :func:`_beyond` limits (:func:`drakedeburr.robots.joint_candidates`),
    without listing the turns: the rule's costs add up per joint, so per branch the turn of
    each joint nearest ``q_prev`` within the limits is the branch's best candidate."""
    lim = _beyond(spec.kinematics.limits)
    lo, hi = np.asarray(lim.lower), np.asarray(lim.upper)
    sols = sols[~np.any(np.isnan(sols), axis=1)]
    kmin = np.ceil((lo - sols) / _TWO_PI - 1e-12)
    kmax = np.floor((hi - sols) / _TWO_PI + 1e-12)
    ok = np.all(kmin <= kmax, axis=1)
    if not ok.any():
        return None
    sols, kmin, kmax = sols[ok], kmin[ok], kmax[ok]
    k = np.clip(np.round((np.asarray(q_prev) - sols) / _TWO_PI), kmin, kmax)
    cand = sols + _TWO_PI * k
    return cand[select_solution(cand, q_prev, travel_weights(spec.opw))]


def _corner(C, u_in, u_out, r, dist, incoming: bool):
    """The corner path at C (quadratic Bezier E -> C -> X, E = C - r u_in, X = C + r u_out)
    at a point ``dist`` from C on the incoming or outgoing line (dist <= r)."""
    s = (r - dist) / (2 * r) if incoming else 0.5 + dist / (2 * r)
    E, X = C - r * u_in, C + r * u_out
    return (1 - s) ** 2 * E + 2 * s * (1 - s) * C + s ** 2 * X


def _frames(read, X_FT, X_RO, problems: list) -> tuple[dict, dict]:
    """The tool and fixed frame: the program's, else the cell's (noted), else identity (a
    problem)."""
    used, frames = {}, {}
    for item, got, cell in (("tool", read.X_FT, X_FT), ("work object", read.X_RO, X_RO)):
        if got is not None:
            frames[item], used[item] = np.asarray(got, float), "program"
        elif cell is not None:
            frames[item], used[item] = np.asarray(cell, float), "cell"
        else:
            frames[item], used[item] = np.eye(4), "none"
            problems.append(f"{read.files[0]}: the {item} is neither in the program nor given")
    return frames, used


def _line_poses(X_I, zone, linear, i, samples, step, fractions=None):
    """Sample poses (4, 4) of linear move i in the interpolated frame: the straight line from
    target i-1 to i, orientation slerped, the corners at both ends blended by their zones;
    every ``step`` of travel (at least ``samples``), and in each corner at a quarter, half,
    three quarters and all of its zone from the target (its chords then follow the
    parabola); or at the shares ``fractions`` of the move."""
    n = len(X_I)
    A, B = X_I[i - 1][:3, 3], X_I[i][:3, 3]
    L = float(np.linalg.norm(B - A))
    u = (B - A) / L if L > 0 else np.zeros(3)
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([X_I[i - 1][:3, :3],
                                                               X_I[i][:3, :3]])))
    r_in = zone[i - 1] if i >= 2 and linear[i - 1] and zone[i - 1] > 0 else 0.0
    r_out = zone[i] if i + 1 < n and linear[i + 1] and zone[i] > 0 else 0.0

    def unit(d):
        return d / max(float(np.linalg.norm(d)), 1e-15)

    u_prev = unit(A - X_I[i - 2][:3, 3]) if r_in else None
    u_next = unit(X_I[i + 1][:3, 3] - B) if r_out else None
    k_n = max(samples, int(np.ceil(L / step)))
    f_all = np.arange(1, k_n + 1) / k_n
    if L > 0:  # the corners' own points: where each leaves / joins the line and between
        share = np.array([0.25, 0.5, 0.75, 1.0])
        f_all = np.concatenate([f_all, share * r_in / L, 1.0 - share * r_out / L])
        f_all = np.unique(f_all[(f_all > 0) & (f_all <= 1)])
    if fractions is not None:
        f_all = np.asarray(fractions, float)
    out = []
    R_all = slerp(f_all).as_matrix()
    for f, R in zip(f_all, R_all, strict=True):
        p = A + f * (B - A)
        if r_in and f * L < r_in:
            p = _corner(A, u_prev, u, r_in, f * L, incoming=False)
        elif r_out and (1 - f) * L < r_out:
            p = _corner(B, u, u_next, r_out, (1 - f) * L, incoming=True)
        X = np.eye(4)
        X[:3, :3] = R
        X[:3, 3] = p
        out.append((f, X))
    return out


def _follow_line(spec, flange, poses, q_prev, where: str, problems: list):
    """The joints along the sample poses of a linear move, each the IK solution nearest the
    one before (from ``q_prev``) -> (joints, flange poses), or None where the line leaves the
    arm's reach (noted in ``problems``, as jumps of more than :data:`JUMP` are)."""
    qs, Xs, q_run = [], [], q_prev
    X_BF = [flange(X) for _, X in poses]
    sols = ik_opw(spec.opw, np.array(X_BF)).q  # every pose at once
    for (f, _), X_f, sol in zip(poses, X_BF, sols, strict=True):
        q = _nearest_of(spec, sol, q_run)
        if q is None:
            problems.append(f"{where}: the straight line to the target leaves the arm's "
                            f"reach or limits at {f:.0%} of the move")
            return None
        jump = float(np.abs(q - q_run).max())
        if jump > JUMP:
            problems.append(f"{where}: the joints jump {np.degrees(jump):.1f} deg on the "
                            f"straight line at {f:.0%} of the move (posture change or "
                            "singularity)")
        qs.append(q)
        Xs.append(X_f)
        q_run = q
    return qs, Xs


def controller_motion(read, spec: RobotSpec, X_FT: np.ndarray | None = None,
                      X_RO: np.ndarray | None = None, samples: int = 4,
                      step: float = 2.5e-4) -> ControllerMotion:
    """Re-simulate ``read`` (:class:`~drakedeburr.programs.ReadProgram`) on arm ``spec``.

    Linear moves are sampled every ``step`` of TCP travel (at least ``samples`` per move);
    where a linear move runs into a linear move with a zone r, the corner is the controller's
    blend: it leaves the line r before the target and joins the next r after it (a parabola
    through the corner's tangent points, within r / 2 of the target; ABB zonedata, KUKA C_DIS
    as written, which the writers keep within half the adjacent moves; FANUC FINE is the sharp
    corner). Target joints are solved at the exact targets.

    Args:
        read: the program as read back.
        spec: the arm.
        X_FT, X_RO: the tool (flange-carried frame in F) and fixed frame (in the controller's
            robot frame) the cell holds, used where the program does not state them.
        samples: least samples per move (>= 1; the last is the target).
        step: [m] longest TCP travel between samples of a linear move.
    """
    vendor = _VENDOR[read.format]
    kin = spec.kinematics
    problems: list[str] = []
    frames, used = _frames(read, X_FT, X_RO, problems)
    X_BO = np.asarray(spec.X_BR) @ frames["work object"]
    X_FTm = frames["tool"]
    X_TF = np.linalg.inv(X_FTm)
    moves = read.moves
    n = len(moves)
    # the interpolated frame: the TCP in the work object (tool in hand), or the fixed TCP in
    # the held work object (stationary tool: KUKA #TCP, ABB robhold FALSE, FANUC RTCP)
    X_OT = np.array([m.X_OT for m in moves])
    X_I = np.linalg.inv(X_OT) if read.stationary_tool else X_OT

    def flange(X_i):
        X_ot = np.linalg.inv(X_i) if read.stationary_tool else X_i
        return X_BO @ X_ot @ X_TF

    linear = np.array([m.move_type != JOINT for m in moves])
    zone = np.array([m.zone for m in moves])
    q_t = np.full((n, 6), np.nan)
    q_path, X_path, move, chord = [], [], [], []
    q_prev = None
    for i, m in enumerate(moves):
        where = f"{m.target_file}:{m.config_line or m.target_line}: move {i + 1}"
        X_target = flange(X_I[i])
        q_conf = None
        try:
            q_conf = joints_from_configuration(kin, X_target, vendor, m.configuration)
        except Exception as exc:  # InputError: no solution has that configuration
            try:  # one beyond the limits: the controller refuses it at the limit (joint item)
                q_conf = joints_from_configuration(replace(kin, limits=_beyond(kin.limits)),
                                                   X_target, vendor, m.configuration)
            except Exception:
                if not linear[i] or q_prev is None or vendor == "abb":
                    problems.append(f"{where}: {exc}")
        if not linear[i] or q_prev is None:
            if q_conf is None:
                break
            qs = [q_conf] if q_prev is None else \
                [q_prev + (q_conf - q_prev) * k / samples for k in range(1, samples + 1)]
            q_t[i] = q_conf
            q_path += qs
            X_path += [fk_opw(spec.opw, q) for q in qs]
            move += [i] * len(qs)
            chord += [q_conf] if q_prev is None else \
                [0.5 * (a + b) for a, b in zip([q_prev, *qs[:-1]], qs, strict=True)]
            q_prev = q_conf
            continue
        poses = _line_poses(X_I, zone, linear, i, samples, step)
        line = _follow_line(spec, flange, poses, q_prev, where, problems)
        if line is None:
            break
        qs, Xs = line
        f_all = np.array([f for f, _ in poses])
        f_mid = 0.5 * (np.concatenate([[0.0], f_all[:-1]]) + f_all)
        q_a = [q_path[-1]] + qs[:-1]
        mids = _line_poses(X_I, zone, linear, i, samples, step, f_mid)
        sols = ik_opw(spec.opw, np.array([flange(X) for _, X in mids])).q
        for sol, qa, qb in zip(sols, q_a, qs, strict=True):
            q_m = _nearest_of(spec, sol, qa)
            chord.append(0.5 * (qa + qb) if q_m is None else q_m)
        q_exact = _nearest(spec, X_target, q_prev)
        q_t[i] = q_exact if q_exact is not None else np.nan
        if vendor == "abb" and q_exact is not None and \
                configuration_of(kin, q_exact, "abb") != m.configuration:
            problems.append(f"{where}: ConfL \\On: the arm arrives with confdata "
                            f"{configuration_of(kin, q_exact, 'abb')}, the target says "
                            f"{m.configuration}: the controller stops")
        q_prev = q_t[i] if q_exact is not None else qs[-1]
        q_path += qs
        X_path += Xs
        move += [i] * len(qs)
    return ControllerMotion(q=q_t, q_path=np.array(q_path).reshape(-1, 6),
                            X_path=np.array(X_path).reshape(-1, 4, 4),
                            move=np.array(move, dtype=int), problems=tuple(problems),
                            frames_used=used, q_mid=np.array(chord).reshape(-1, 6))
