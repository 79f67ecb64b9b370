"""The program as the controller runs it, checked like a plan (``verify --program`` and the
export gate): the file read back equals the plan's program line by line
(:func:`program_file_item`), and the motion the controller makes of it
(:func:`drakedeburr.programs.controller.controller_motion`: joints from the written poses and
configuration by the vendor's rule, straight lines, the vendor's corners) reaches the verified
joints, runs within the path tolerance of the verified motion and keeps its zones; that motion
is then sampled like a plan (:func:`controller_sampled`: the same
:class:`~drakedeburr.verify.types.SampledPlan` every plan check reads) and the registry's own
checks run on it: the clearance certificate, the cone, the edge deviation, the burr's contact
and the joint limits (:data:`CONTROLLER_CHECKS`); the values the cell must hold are named
(:func:`controller_items`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plan_program", "program_file_item", "controller_items", "program_items",
           "controller_sampled",
           "CONTROLLER_CHECKS"]

#: the registry checks (:mod:`drakedeburr.verify.registry`) run on the controller's motion,
#: reported as ``controller_<name>``
CONTROLLER_CHECKS = ("clearance_certificate", "cone", "edge_deviation", "burr_contact",
                     "joint_position")


def plan_program(plan, name: str, *, flag: str = "", flag_reason: str = "",
                 verified: bool = False, robot: str | None = None, cell=None):
    """The plan's program with the loads of its cell's tool (and workpiece) models (``cell``:
    the plan's cell already loaded, else it is loaded here)."""
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.errors import InputError
    from drakedeburr.programs import program_from_plan

    try:  # the plan's own cell: its arm, burr and hub pose (the workpiece's centre of mass)
        cell = cell if cell is not None else load_plan_cell(plan)
    except FileNotFoundError as exc:
        raise InputError(f"the plan's cell ({plan.scenario}, hub {plan.hub}) is needed for the "
                         f"tool's mass and centre of gravity: {exc}") from exc
    return program_from_plan(plan, name, robot=robot, loads=cell.flange_loads(),
                             verified=verified, flag=flag, flag_reason=flag_reason)


def program_file_item(plan, actual, cell=None, expected=None):
    """A required report item: the program (a file, or as read by :func:`_read_program_file`)
    compared with the plan's own program (``expected``, default
    :func:`plan_program`; :func:`drakedeburr.programs.compare_programs`),
    every difference named by line."""
    from drakedeburr.programs import compare_programs
    from drakedeburr.verify.report import CheckItem

    if isinstance(actual, (str, Path)):
        from drakedeburr.programs import read_program

        actual = read_program(str(actual))
    path = actual.files[0]
    expected = expected if expected is not None else plan_program(plan, actual.name, cell=cell)
    found = compare_programs(expected, actual)
    lines = [f"{d.file}:{d.line}: {d.item}: expected {d.expected}, got {d.got}" for d in found]
    return CheckItem("program_file", not found, float(len(found)), 0.0, "count", "<=",
                     detail=("; ".join(lines[:8]) + (" ..." if len(lines) > 8 else "")) or
                     f"{path}: every move, frame and load as the plan's program")


def _mm_deg(X) -> str:
    from drakedeburr.programs.common import euler_zyx_deg

    a, b, c = euler_zyx_deg(np.asarray(X)[:3, :3])
    x, y, z = np.asarray(X)[:3, 3] * 1e3
    return f"({x:.3f}, {y:.3f}, {z:.3f}) mm, (A {a:.4f}, B {b:.4f}, C {c:.4f}) deg"


def _cell_values(expected, actual) -> str:
    """Every value the controller must hold for the program to run as verified."""
    X_RO = np.linalg.solve(expected.X_BR, expected.X_WO)
    m = expected.tool_mass + expected.workpiece_mass
    cog = (expected.tool_mass * np.asarray(expected.tool_cog)
           + expected.workpiece_mass * np.asarray(expected.workpiece_cog)) / m
    fixed = "stationary tool (external TCP)" if expected.stationary_tool else "work object"
    carried = "held work object" if expected.stationary_tool else "tool (TCP)"
    out = [f"{carried} in the flange frame {_mm_deg(expected.X_FT)}",
           f"{fixed} in the robot frame {_mm_deg(X_RO)}",
           f"load {m:.3f} kg at ({', '.join(f'{v * 1e3:.3f}' for v in cog)}) mm in the flange"]
    if actual.format == "ls":
        from drakedeburr.programs.common import LS_ACCEL_TIME

        out.append(f"ACC100 acceleration time <= {LS_ACCEL_TIME * 1e3:.0f} ms (CNT bound)")
        if expected.stationary_tool:
            out.append("Remote TCP option (RTCP)")
    if actual.format == "rapid" and expected.stationary_tool:
        out.append("a stationary-tool (robhold FALSE) tooldata and a robot-held (robhold TRUE) "
                   "wobjdata")
    if actual.format == "krl" and expected.stationary_tool:
        out.append("external TCP ($IPO_MODE #TCP)")
    return "the cell must hold: " + "; ".join(out)


def _target_moves(plan, expected) -> dict[int, int]:
    """Plan target index -> program move index (the program adds via points on bent joint
    moves; a target's move carries its joints exactly)."""
    out, j = {}, 0
    for k, t in enumerate(plan.targets):
        q = np.asarray(t.q, float)
        while j < len(expected.moves) and not np.array_equal(expected.moves[j].q, q):
            j += 1
        if j == len(expected.moves):
            break
        out[k] = j
        j += 1
    return out


def _path_item(plan, expected, actual, n, tol):
    """The straight lines the controller runs on cuts vs the verified motion: every point of
    a cut move within the path tolerance of the verified path, or within the zone the plan
    verified around a target (where the plan blends and the controller may run the corner)."""
    from drakedeburr.programs.program import JOINT
    from drakedeburr.robots import fk_opw
    from drakedeburr.verify.geometry import point_segment
    from drakedeburr.verify.report import CheckItem

    X_OB = np.linalg.inv(expected.X_WO)
    targ = np.array([m.X_OT for m in actual.moves])  # flange-carried frame in the fixed one
    pts = np.linalg.inv(targ)[:, :3, 3] if expected.stationary_tool else targ[:, :3, 3]
    zones = np.array([m.zone for m in expected.moves])
    dev = None
    pd = tol.path_deviation
    move_of = _target_moves(plan, expected)
    cut_moves = [move_of[k] for s in plan.segments if s.kind == "cut"
                 for k in range(s.target_range[0] + 1, s.target_range[1])
                 if k in move_of and move_of[k] < n and move_of[k] - 1 == move_of.get(k - 1)
                 and actual.moves[move_of[k]].move_type != JOINT]
    if cut_moves:
        segs = [s for s in plan.segments if s.kind == "cut"]
        t = np.concatenate([np.append(np.arange(s.t_range[0], s.t_range[1], 0.004),
                                      s.t_range[1]) for s in segs])
        P = X_OB @ fk_opw(expected.kinematics.opw, plan.trajectory.value(t)) @ expected.X_FT
        p_plan = np.linalg.inv(P)[:, :3, 3] if expected.stationary_tool else P[:, :3, 3]
        q_pts, allow = [], []
        for k in cut_moves:
            a, b = pts[k - 1], pts[k]
            m_ = max(2, int(np.ceil(np.linalg.norm(b - a) / 2.5e-4)) + 1)
            f = np.linspace(0.0, 1.0, m_)[:, None]
            c = a + f * (b - a)
            al = np.full(m_, pd)
            for end, z in ((a, zones[k - 1]), (b, zones[k])):
                near = np.linalg.norm(c - end, axis=1) <= z + pd
                al[near] = np.maximum(al[near], z + pd)
            q_pts.append(c)
            allow.append(al)
        c, al = np.concatenate(q_pts), np.concatenate(allow)
        d = point_segment(c, p_plan[:-1], p_plan[1:])
        d = d[0] if isinstance(d, tuple) else d
        dev = float(np.max(d - al))
    return CheckItem(
        "controller_path", dev is not None and dev <= 0.0, dev, 0.0, "m", "<=",
        detail="the straight lines the controller runs on cuts vs the verified motion, less "
        f"the path tolerance ({pd * 1e3:.3f} mm; the verified zone near a target)"
        if dev is not None else "no linear cut moves to compare")


def _zones_item(expected, actual, n):
    """Zones the controller keeps: each within half the adjacent moves as written (FANUC: CNT
    only where its bound holds)."""
    from drakedeburr.programs.common import ls_cnts
    from drakedeburr.verify.report import CheckItem

    p_read = np.array([m.X_OT[:3, 3] for m in actual.moves])
    if actual.stationary_tool:
        p_read = np.linalg.inv(np.array([m.X_OT for m in actual.moves]))[:, :3, 3]
    dd = np.linalg.norm(np.diff(p_read, axis=0), axis=1)
    half = np.zeros(len(p_read))
    if len(p_read) >= 2:
        half[0], half[-1] = 0.5 * dd[0], 0.5 * dd[-1]
        half[1:-1] = 0.5 * np.minimum(dd[:-1], dd[1:])
    z = np.array([m.zone for m in actual.moves])
    if actual.format == "ls":  # CNT: the bound, not the nominal label, must fit
        bad = np.flatnonzero((z > 0) & (ls_cnts(expected)[:len(z)] == 0)) if n == len(z) else \
            np.flatnonzero(z > 0)
    else:
        bad = np.flatnonzero(z > half + 1e-9)
    return CheckItem(
        "controller_zones", not bad.size, float(bad.size), 0.0, "count", "<=",
        detail=(f"{bad.size} corner(s) the controller would make otherwise, first "
                f"{actual.moves[bad[0]].file}:{actual.moves[bad[0]].zone_line}") if bad.size else
        "every zone within half of its adjacent moves (FANUC: CNT only where its bound holds)")


def _controller_trajectory(motion, actual, velocity: np.ndarray):
    """The controller's joints as a :class:`~drakedeburr.plan.types.JointTrajectory`: between
    consecutive samples the quadratic through the joints at both and halfway
    (:attr:`~drakedeburr.programs.controller.ControllerMotion.q_mid`: solved there on a linear
    move; a joint move is straight in joint space), so the certificate's rate bounds and the
    joint limits' extremes cover the joints between the samples; timed at the programmed TCP
    speed or the joints' top speed, whichever is slower (the timing only orders the samples:
    no timing check reads it)."""
    from drakedeburr.plan.types import JointTrajectory

    q = motion.q_path
    qa, qb, qm = q[:-1], q[1:], motion.q_mid[1:]
    dq = np.maximum(np.abs(qb - qa), 2.0 * np.abs(qm - 0.5 * (qa + qb)))
    dp = np.linalg.norm(np.diff(motion.X_path[:, :3, 3], axis=0), axis=1)
    v = np.array([actual.moves[int(i)].speed or np.inf for i in motion.move[1:]])
    dt = np.maximum.reduce([(dq / velocity).max(axis=1), dp / v, np.full(len(dp), 1e-4)])
    t = np.concatenate([[0.0], np.cumsum(dt)])
    h = dt[:, None]
    c = np.zeros((4, len(dt), 6))  # cubic layout, quadratic pieces, highest power first
    c[1] = (2.0 * qa - 4.0 * qm + 2.0 * qb) / h ** 2
    c[2] = (-3.0 * qa + 4.0 * qm - qb) / h
    c[3] = qa
    return JointTrajectory(t=t, c=c)


def controller_sampled(plan, expected, actual, motion, cell, config, hub_model=None):
    """The controller's motion as a :class:`~drakedeburr.verify.types.SampledPlan`: the plan
    with its trajectory replaced by the controller's joints (:func:`_controller_trajectory`)
    and its segments timed on them, sampled by
    :func:`~drakedeburr.verify.sampling.sample_plan` as a plan is -> (sampled, None), or
    (None, why not) where the controller's motion stops before the program's end."""
    from dataclasses import replace

    from drakedeburr.plan.types import PlanSegment
    from drakedeburr.verify.sampling import sample_plan
    from drakedeburr.verify.types import JointLimits

    move_of = _target_moves(plan, expected)
    if len(move_of) < len(plan.targets) or not len(motion.q_path):
        return None, "the plan's targets are not all moves of the program"
    last = {int(j): i for i, j in enumerate(motion.move)}
    missing = [k for k, j in move_of.items() if j not in last or np.isnan(motion.q[j]).any()]
    if missing:
        return None, (f"the controller's motion stops before target {missing[0]} (move "
                      f"{move_of[missing[0]] + 1})")
    traj = _controller_trajectory(motion, actual, JointLimits.of_cell(cell).velocity)
    T = np.array([traj.t[last[move_of[k]]] for k in range(len(plan.targets))])
    segments = tuple(PlanSegment(s.window_index, s.kind, s.target_range,
                                 (float(T[max(s.target_range[0] - 1, 0)]),
                                  float(T[s.target_range[1] - 1])))
                     for s in plan.segments)
    c_plan = replace(plan, trajectory=traj, segments=segments)
    windows = sorted({s.window_index for s in plan.segments if s.kind == "cut"})
    return sample_plan(c_plan, config, cell=cell, hub_model=hub_model,
                       expected_windows=windows), None


def _controller_checks(sp, config, why: str | None) -> list:
    """:data:`CONTROLLER_CHECKS` on the controller's sampled motion, as ``controller_<name>``;
    between its samples the motion is the quadratic through the joints solved at both and
    halfway (:func:`_controller_trajectory`)."""
    from dataclasses import replace

    from drakedeburr.verify.registry import CHECKS
    from drakedeburr.verify.report import CheckItem

    by_name = {c.name: c for c in CHECKS}
    if sp is None:
        return [CheckItem(f"controller_{n}", False, None, None, "-", "<=",
                          detail=f"not measurable: {why}") for n in CONTROLLER_CHECKS]
    out = []
    for n in CONTROLLER_CHECKS:
        item = by_name[n].run(sp, config)
        out.append(replace(item, name=f"controller_{n}", required=True,
                           detail=f"on the controller's motion: {item.detail}"))
    return out


def controller_items(plan, actual, cell=None, tol=None, config=None, hub_model=None,
                     expected=None) -> list:
    """Report items of the program as the controller runs it
    (:func:`drakedeburr.programs.controller.controller_motion`): joints solved from the written
    poses and configuration equal the verified ones, no stop or jump on the way, the straight
    lines it runs within the path tolerance of the verified motion, the registry's checks on
    its motion (:data:`CONTROLLER_CHECKS`: clearance certificate, cone, edge deviation, burr
    contact, joint limits), zones the controller keeps, and (information) every value the
    cell must hold. ``config``: the run's (default: the plan's recipe with ``tol``);
    ``cell``/``hub_model``/``expected`` (the plan's program): already made (default: here)."""
    from drakedeburr.programs.controller import controller_motion
    from drakedeburr.verify.report import CheckItem

    if config is None:
        from drakedeburr.verify.checks import config_for_plan

        config = config_for_plan(plan, tolerances=tol)
    tol = tol or config.tolerances
    if cell is None:
        from drakedeburr.cell.station import load_plan_cell

        cell = load_plan_cell(plan)
    if expected is None:
        expected = plan_program(plan, actual.name, cell=cell)
    X_RO = np.linalg.solve(expected.X_BR, expected.X_WO)
    motion = controller_motion(actual, expected.spec, X_FT=expected.X_FT, X_RO=X_RO,
                               step=tol.dense_step)
    n = min(len(expected.moves), len(actual.moves))
    q_plan = np.array([m.q for m in expected.moves[:n]])
    err = np.abs(motion.q[:n] - q_plan).max(axis=1)
    err = np.where(np.isnan(err), np.inf, err)
    worst = int(np.argmax(err)) if n else 0
    items = [CheckItem(
        "controller_joints", bool(n) and float(err.max()) <= 1e-3, float(err.max()) if n else None,
        1e-3, "rad", "<=",
        detail=(f"joints the controller solves from the written pose and configuration vs the "
                f"verified ones; worst move {worst + 1} ({actual.moves[worst].name}, "
                f"{actual.moves[worst].configuration})") if n else "no moves")]
    items.append(CheckItem(
        "controller_motion", not motion.problems, float(len(motion.problems)), 0.0, "count", "<=",
        detail="; ".join(motion.problems[:6]) or "every move reached the way the controller "
        "runs it: no stop, jump or unreachable point"))
    items.append(_path_item(plan, expected, actual, n, tol))
    cfg = config if config.tolerances is tol else _with_tolerances(config, tol)
    sp, why = controller_sampled(plan, expected, actual, motion, cell, cfg, hub_model)
    items += _controller_checks(sp, cfg, why)
    items.append(_zones_item(expected, actual, n))
    used = ", ".join(f"{k} from the {v}" for k, v in motion.frames_used.items())
    items.append(CheckItem("controller_setup", True, None, None, "-", "info", required=False,
                           detail=f"{_cell_values(expected, actual)} ({used})"))
    return items


def _with_tolerances(config, tol):
    from dataclasses import replace

    return replace(config, tolerances=tol)


def program_items(plan, actual, cell=None, tol=None, config=None, hub_model=None) -> list:
    """Every program item: :func:`program_file_item` then :func:`controller_items` (the plan's
    program made once for both)."""

    if isinstance(actual, (str, Path)):
        from drakedeburr.programs import read_program

        actual = read_program(str(actual))
    if cell is None:
        from drakedeburr.cell.station import load_plan_cell

        cell = load_plan_cell(plan)
    expected = plan_program(plan, actual.name, cell=cell)
    return [program_file_item(plan, actual, cell, expected),
            *controller_items(plan, actual, cell, tol, config, hub_model, expected)]
