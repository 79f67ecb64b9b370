"""The robot's side of the laser cell (source 004): a plate frame, the arm's IK, one job.

Frames (SI inside):

* R: the FANUC controller's world frame (``RobotSpec.X_BR`` in the model base B);
* P: the plate (part) frame in R, ``X_RP``: the program's UFRAME. Contours and hole centres
  are given in P (x-y on the plate, +z out of it);
* F: the flange; C: the Cutting Tool's base on it, ``X_FC`` (default 60 mm along F z, axes
  aligned: :func:`drakedeburr.laser.display.default_X_FC`);
* T: the laser TCP with the five-bar at its home point: ``X_FT = X_FC * (home_x, l0/2,
  nozzle)`` with C's axes (beam = +z): the program's UTOOL. The robot cuts contours with the
  tool parked at home; for a hole it holds T over the hole centre, beam into the plate
  (``X_PH = (centre) * Rx(pi)``), and the tool cuts the hole in its own plane: the hole frame
  H has x along P's x and y along -P's y, so the hole's contour is mirrored into H
  (:func:`hole_shape_in_tool`), exactly for every shape.

Joints come from the arm's analytic IK with configuration continuity
(:func:`drakedeburr.robots.solve_path`) and the FANUC CONFIG of every point from
:mod:`drakedeburr.robots.configuration` (never a fixed string); a point the arm cannot reach
is an InputError naming it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.laser.kinematics import FiveBarGeometry

if TYPE_CHECKING:
    from drakedeburr.laser.feature import FeatureSettings
    from drakedeburr.laser.hole import ServoLimits
    from drakedeburr.laser.itp import ControllerTiming
    from drakedeburr.laser.power import PowerMap

__all__ = ["LaserCell", "LaserJob", "LaserProcess", "RobotMotion", "plan_job", "solve_robot",
           "hole_pose", "X_FT_of", "HOLE_R"]

#: largest joint step between two points of one cut [rad] (beyond: the short way round is
#: outside the joint range, the wrist would unwind)
_MAX_STEP = np.pi  # a corner turns the wrist < 180 deg; an unwind turns it ~360 deg
#: rotation of the hole frame H in P: beam (H z) into the plate, H x = P x
HOLE_R = np.diag([1.0, -1.0, -1.0])


def _default_X_FC() -> np.ndarray:
    X = np.eye(4)
    X[2, 3] = 0.060  # as drakedeburr.laser.display.default_X_FC
    return X


@dataclass(frozen=True, eq=False)
class LaserCell:
    """The robot, the plate and the tool's mounting.

    Attributes:
        robot: registered FANUC arm (``drakedeburr robots``), e.g. "m10ia".
        X_RP: (4, 4) plate frame P in the controller's world frame R [m] (the UFRAME).
        X_FC: (4, 4) Cutting Tool base C in the flange frame F [m].
        q_start: (6,) joints the robot starts from [rad] (None: the arm's zero pose).
        uframe, utool: the frame numbers the program selects.
    """

    robot: str = "m10ia"
    X_RP: np.ndarray = field(default_factory=lambda: np.eye(4))
    X_FC: np.ndarray = field(default_factory=_default_X_FC)
    q_start: np.ndarray | None = None
    uframe: int = 1
    utool: int = 1

    def __post_init__(self) -> None:
        from drakedeburr.programs.program import check_pose

        spec = self.spec
        if spec.controller != "fanuc":
            raise InputError(f"laser cell: {self.robot} has a {spec.controller} controller; the "
                             "laser programs are FANUC LS (use a FANUC arm, e.g. m10ia)")
        object.__setattr__(self, "X_RP", check_pose(self.X_RP, "plate frame (UFRAME)"))
        object.__setattr__(self, "X_FC", check_pose(self.X_FC, "Cutting Tool mounting X_FC"))
        for name in ("uframe", "utool"):
            if not 1 <= getattr(self, name) <= 9:
                raise InputError(f"laser cell: {name} must be 1..9, got {getattr(self, name)}")

    @property
    def spec(self):
        from drakedeburr.robots import get_robot

        return get_robot(self.robot)


def X_FT_of(cell: LaserCell, g: FiveBarGeometry) -> np.ndarray:
    """(4, 4) the laser TCP at the tool's home point in the flange frame (the UTOOL)."""
    from drakedeburr.laser.model import NOZZLE_LENGTH

    X_CT = np.eye(4)
    X_CT[:3, 3] = [g.p_CHome[0], g.p_CHome[1], NOZZLE_LENGTH]
    return cell.X_FC @ X_CT


def hole_pose(center_P: np.ndarray) -> np.ndarray:
    """(4, 4) X_PH: the TCP over a hole centre (x, y) [m] on the plate, beam into it."""
    X = np.eye(4)
    X[:3, :3] = HOLE_R
    X[:2, 3] = np.asarray(center_P, float)[:2]
    return X


@dataclass(frozen=True, eq=False)
class RobotMotion:
    """Joints and configuration for TCP poses in the plate frame.

    Attributes:
        X_PT: (N, 4, 4) TCP poses in P [m].
        q: (N, 6) model joints [rad].
        config: (N,) FANUC CONFIG strings ('N U T, 0, 0, 0' ...), from the joints.
        configuration_changes: indices where the arm's branch changes.
    """

    X_PT: np.ndarray
    q: np.ndarray
    config: tuple[str, ...]
    configuration_changes: tuple[int, ...]


def solve_robot(cell: LaserCell, X_PT: np.ndarray, g: FiveBarGeometry, what: str,
                q_start: np.ndarray | None = None, continuous: bool = True) -> RobotMotion:
    """Joints of the TCP poses X_PT (N, 4, 4) in P by the arm's analytic IK; ``continuous``:
    the poses are one cut (no joint may step by more than 180 deg between two of them).

    Raises:
        InputError: a pose out of reach or outside the joint limits (names ``what``, the
            point and its plate coordinates in mm).
    """
    from drakedeburr.robots import configuration_of, ik_opw, joint_candidates, solve_path

    spec = cell.spec
    X_PT = np.asarray(X_PT, float).reshape(-1, 4, 4)
    X_FT = X_FT_of(cell, g)
    X_BF = spec.X_BR @ cell.X_RP @ X_PT @ np.linalg.inv(X_FT)
    q0 = q_start if q_start is not None else cell.q_start
    q0 = np.zeros(6) if q0 is None else np.asarray(q0, float)
    # a contour turns the tool about its beam (a rectangle: once around): start on the IK
    # solution (branch and joint turn) from which the whole path stays inside the joint
    # range with the smallest joint step, so the wrist never unwinds in the middle of a cut;
    # ties go to the solution nearest q0
    first = joint_candidates(ik_opw(spec.kinematics.opw, X_BF[:1]).q[0], spec.kinematics.limits)
    starts = sorted(first, key=lambda c: float(np.abs(c - q0).max())) or [q0]
    best, best_step = None, np.inf
    for qs in starts if continuous else [q0]:
        res = solve_path(spec.kinematics, X_BF, q_start=qs)
        if res.failed:
            best = best or res
            continue
        step = float(np.abs(np.diff(res.q, axis=0)).max()) if len(res.q) > 1 else 0.0
        if best is None or best.failed or step < best_step - 1e-9:
            best, best_step = res, step
    res = best
    if res.failed:
        k = res.failed[0]
        x, y, z = X_PT[k, :3, 3] * 1e3
        raise InputError(f"{what}: point {k} of {len(X_PT)} at ({x:.1f}, {y:.1f}, {z:.1f}) mm "
                         f"in the plate frame is out of reach of {spec.title} ({len(res.failed)} "
                         "points fail): move the plate (UFRAME) or the tool mounting")
    if continuous and len(res.q) > 1 and best_step > _MAX_STEP:
        k = int(np.argmax(np.abs(np.diff(res.q, axis=0)).max(axis=1)))
        raise InputError(f"{what}: between points {k} and {k + 1} the arm must turn a joint by "
                         f"{np.rad2deg(best_step):.0f} deg (its range ends there): rotate the "
                         "plate (UFRAME) or start the contour elsewhere")
    config = tuple(configuration_of(spec.kinematics, q, "fanuc") for q in res.q)
    return RobotMotion(X_PT=X_PT, q=res.q, config=config,
                       configuration_changes=res.configuration_changes)


@dataclass(frozen=True, eq=False)
class LaserJob:
    """One part: its holes by the Cutting Tool, then its contour by the robot (inner features
    first, so the part is still held while they are cut).

    Attributes:
        cell: robot, plate frame, tool mounting.
        geometry: the Cutting Tool.
        holes: the hole programs (contours mirrored into the tool's plane).
        hole_centers: (K, 2) hole centres in P [m].
        hole_motion: the robot's poses over the holes (None without holes).
        contour: the robot contour's targets in P (None without a contour).
        contour_motion: its joints and configurations.
    """

    cell: LaserCell
    geometry: FiveBarGeometry
    holes: tuple
    hole_centers: np.ndarray
    hole_motion: RobotMotion | None
    contour: object | None
    contour_motion: RobotMotion | None


@dataclass(frozen=True)
class LaserProcess:
    """How a job's features are cut (each None: the module's default).

    Attributes:
        settings: the robot contour's feed, angles and acceleration
            (:class:`~drakedeburr.laser.feature.FeatureSettings`).
        power: the laser command for a speed (:class:`~drakedeburr.laser.power.PowerMap`).
        limits: the Cutting Tool's servo limits (:class:`~drakedeburr.laser.hole.ServoLimits`).
        timing: the controller's interpolation (:class:`~drakedeburr.laser.itp.
            ControllerTiming`; None: the default one).
        hole_spacing: the holes' point spacing [m].
    """

    settings: FeatureSettings | None = None
    power: PowerMap | None = None
    limits: ServoLimits | None = None
    timing: ControllerTiming | None = None
    hole_spacing: float = 0.2e-3


def plan_job(cell: LaserCell, contour_shape=None, holes=(), geometry: FiveBarGeometry | None = None,
             process: LaserProcess = LaserProcess()) -> LaserJob:
    """Plan a part: ``holes`` = [((x, y) centre in P [m], shape), ...] cut by the tool,
    ``contour_shape`` (in P) cut by the robot, as ``process`` says (:class:`LaserProcess`).

    Raises:
        InputError: a hole the tool cannot cut, or a pose the arm cannot reach (named).
    """
    from drakedeburr.laser.feature import plan_contour
    from drakedeburr.laser.hole import plan_hole
    from drakedeburr.laser.itp import ControllerTiming

    if contour_shape is None and not holes:
        raise InputError("laser job: nothing to cut (no contour and no holes)")
    g = geometry or FiveBarGeometry()
    settings, power, limits = process.settings, process.power, process.limits
    timing = process.timing if process.timing is not None else ControllerTiming()
    progs, centers = [], []
    for k, (center, shape) in enumerate(holes):
        try:
            progs.append(plan_hole(shape, process.hole_spacing, g, limits, power, timing,
                                   mirror_y=True))
        except InputError as exc:
            raise InputError(f"hole {k + 1}: {exc}") from exc
        centers.append(np.asarray(center, float)[:2])
    centers_a = np.array(centers).reshape(-1, 2)
    hole_motion = None
    if progs:
        hole_motion = solve_robot(cell, np.array([hole_pose(c) for c in centers_a]), g,
                                  "holes", continuous=False)
    targets = motion = None
    if contour_shape is not None:
        targets = plan_contour(contour_shape, None, settings, power)
        X_PT = np.tile(np.eye(4), (len(targets), 1, 1))
        X_PT[:, :3, :3] = targets.R_WT
        X_PT[:, :3, 3] = targets.p_WT
        q0 = hole_motion.q[-1] if hole_motion is not None else None
        motion = solve_robot(cell, X_PT, g, f"contour {contour_shape.kind}", q0)
    return LaserJob(cell=cell, geometry=g, holes=tuple(progs), hole_centers=centers_a,
                    hole_motion=hole_motion, contour=targets, contour_motion=motion)
