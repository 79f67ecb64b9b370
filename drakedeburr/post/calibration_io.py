"""Cell calibration as a procedure (source 002): touch files in, frames out.

A touch file (YAML or CSV, mm and deg, poses ``x, y, z, rx, ry, rz`` with R = Rz Ry Rx as
the controller shows them in its robot frame) holds what a cell engineer records with a
calibration tip on the flange:

- ``tcp``: the tip held on one fixed point in >= 4 orientations (pivot method) -> the
  calibration tool's own TCP (:func:`~drakedeburr.post.calibration.fit_pivot_tcp`);
- ``table`` / ``holder``: touches of known features, each the nominal feature point (in the
  target's frame: the frame the scenario welds to the world) and the pose the robot reported
  -> the target's frame (:func:`~drakedeburr.post.calibration.fit_touch_points`);
- ``part`` (per target, optional): points of the part that will sit on the target (e.g. its
  bounding-box corners) -> the predicted error there and a warning when they lie outside the
  touched region (:func:`~drakedeburr.post.calibration.extrapolation_error`).

The reported poses were computed by the controller with the tool it had set (``tool``); the
touched tip is the flange pose times the calibrated TCP. :func:`calibrate` fits everything,
:func:`write_calibrated_scenario` writes a scenario with the fitted frames,
:func:`check_program` builds a program that visits the nominal features through the fitted
work object and tool (``drakedeburr calibrate``).
"""

from __future__ import annotations

import csv
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.post.calibration import (
    CalibrationFit,
    PivotFit,
    extrapolation_error,
    fit_pivot_tcp,
    fit_touch_points,
)
from drakedeburr.post.cl_post import pose_from_mm_deg

__all__ = ["TouchTarget", "TouchData", "CellCalibration", "TargetResult", "read_touches",
           "calibrate", "write_calibrated_scenario", "check_program", "TARGETS"]

log = logging.getLogger(__name__)

TARGETS = ("table", "holder")
_CSV_HEADER = ["target", "fx", "fy", "fz", "x", "y", "z", "rx", "ry", "rz"]


@dataclass(frozen=True)
class TouchTarget:
    """Touches of one target. Arrays in SI units.

    Attributes:
        name: "table" or "holder".
        features: (N, 3) nominal feature points in the target frame [m].
        X_RT: (N, 4, 4) the TCP poses the controller reported, in its robot frame R [m].
        part: (M, 3) points of the part on the target, in the target frame [m] (may be empty).
    """

    name: str
    features: np.ndarray
    X_RT: np.ndarray
    part: np.ndarray


@dataclass(frozen=True)
class TouchData:
    """A read touch file: the tool set on the controller, pivot poses, targets."""

    source: str
    tool: np.ndarray | None
    robot: str | None
    tcp: np.ndarray
    targets: tuple[TouchTarget, ...]


def _pose(v, where: str) -> np.ndarray:
    try:
        return pose_from_mm_deg(list(v), where)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected 6 numbers x,y,z,rx,ry,rz (mm, deg), got "
                         f"{v!r}") from None


def _point(v, where: str) -> np.ndarray:
    try:
        p = np.array([float(x) for x in v])
    except (TypeError, ValueError):
        p = np.zeros(0)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise InputError(f"{where}: expected 3 finite numbers x,y,z (mm), got {v!r}")
    return p * 1e-3


def _target(name: str, touches: list, part: list, src: str) -> TouchTarget:
    f = np.array([t[0] for t in touches]).reshape(-1, 3)
    X = np.array([t[1] for t in touches]).reshape(-1, 4, 4)
    return TouchTarget(name, f, X, np.array(part).reshape(-1, 3))


def _read_yaml(path: Path) -> TouchData:
    import yaml

    try:
        doc = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not YAML: {str(exc).splitlines()[0]}") from exc
    if not isinstance(doc, dict):
        raise InputError(f"{path}: expected a mapping with tcp / table / holder")
    unknown = sorted(set(doc) - {"robot", "tool", "tcp", *TARGETS})
    if unknown:
        raise InputError(f"{path}: unknown key {unknown[0]!r} (robot, tool, tcp, table, holder)")
    tool = None if doc.get("tool") is None else _pose(doc["tool"], f"{path}: tool")
    tcp = [_pose(v, f"{path}: tcp[{i + 1}]") for i, v in enumerate(doc.get("tcp") or [])]
    targets = []
    for name in TARGETS:
        sec = doc.get(name)
        if sec is None:
            continue
        if not isinstance(sec, dict) or not isinstance(sec.get("points"), list):
            raise InputError(f"{path}: {name}: expected a mapping with a list 'points'")
        touches = []
        for i, t in enumerate(sec["points"]):
            where = f"{path}: {name}.points[{i + 1}]"
            if not isinstance(t, dict) or set(t) != {"feature", "pose"}:
                raise InputError(f"{where}: expected 'feature: [x, y, z]' and 'pose: [x, y, z, "
                                 "rx, ry, rz]'")
            touches.append((_point(t["feature"], f"{where}.feature"),
                            _pose(t["pose"], f"{where}.pose")))
        part = [_point(v, f"{path}: {name}.part[{i + 1}]")
                for i, v in enumerate(sec.get("part") or [])]
        targets.append(_target(name, touches, part, str(path)))
    robot = doc.get("robot")
    return TouchData(str(path), tool, None if robot is None else str(robot),
                     np.array(tcp).reshape(-1, 4, 4), tuple(targets))


def _read_csv(path: Path) -> TouchData:
    rows = list(csv.reader(path.read_text().splitlines()))
    if not rows or [c.strip().lower() for c in rows[0]] != _CSV_HEADER:
        raise InputError(f"{path}:1: expected the header {','.join(_CSV_HEADER)}")
    tcp, touches, parts = [], {t: [] for t in TARGETS}, {t: [] for t in TARGETS}
    for k, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) != len(_CSV_HEADER):
            raise InputError(f"{path}:{k}: expected {len(_CSV_HEADER)} columns, got {len(row)}")
        kind = row[0].strip().lower()
        feature, pose = row[1:4], row[4:10]
        if kind == "tcp":
            tcp.append(_pose(pose, f"{path}:{k}: pose"))
        elif kind in TARGETS:
            touches[kind].append((_point(feature, f"{path}:{k}: feature"),
                                  _pose(pose, f"{path}:{k}: pose")))
        elif kind.endswith("-part") and kind[:-5] in TARGETS:
            parts[kind[:-5]].append(_point(feature, f"{path}:{k}: part point"))
        else:
            raise InputError(f"{path}:{k}: target {row[0]!r}: use tcp, table, holder, "
                             "table-part or holder-part")
    targets = tuple(_target(t, touches[t], parts[t], str(path)) for t in TARGETS if touches[t])
    return TouchData(str(path), None, None, np.array(tcp).reshape(-1, 4, 4), targets)


def read_touches(path: str | Path) -> TouchData:
    """Read a touch file (``.yaml``/``.yml`` or ``.csv``; module docstring).

    Raises:
        InputError: missing file, bad format, or a bad entry (named with its place).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: touch file not found")
    data = _read_csv(path) if path.suffix.lower() == ".csv" else _read_yaml(path)
    if not data.targets and len(data.tcp) == 0:
        raise InputError(f"{path}: no touches (tcp, table or holder)")
    return data


@dataclass(frozen=True)
class TargetResult:
    """One calibrated target.

    Attributes:
        fit: the rigid fit (X_WT = the target frame in the robot base B) and its residuals;
        scaled: the same touches with a scale (the systematic error growing with distance).
        part_error: (M,) predicted error at the part points [m].
        part_outside: (M,) distance of each part point outside the touched region [m] (0
            inside), in the touches' plane.
    """

    name: str
    fit: CalibrationFit
    scaled: CalibrationFit
    part_error: np.ndarray
    part_outside: np.ndarray


@dataclass(frozen=True)
class CellCalibration:
    """Result of :func:`calibrate` (frames in the robot base B of the model, [m])."""

    X_FT: np.ndarray
    pivot: PivotFit | None
    targets: tuple[TargetResult, ...] = field(default_factory=tuple)

    def target(self, name: str) -> TargetResult:
        for t in self.targets:
            if t.name == name:
                return t
        raise InputError(f"no {name} touches in the calibration")


def _outside(features: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance of points outside the convex hull of the features, in their best plane."""
    import shapely

    if len(points) == 0:
        return np.zeros(0)
    c = features.mean(0)
    _, _, Vt = np.linalg.svd(features - c)
    E = Vt[:2].T
    hull = shapely.MultiPoint((features - c) @ E).convex_hull
    q = (points - c) @ E
    return np.array([hull.distance(shapely.Point(x)) for x in q])


def calibrate(data: TouchData, X_BR: np.ndarray | None = None,
              tool: np.ndarray | None = None) -> CellCalibration:
    """Fit the calibration tool's TCP (if pivot poses are given) and every target's frame.

    Args:
        data: the touches (:func:`read_touches`).
        X_BR: (4, 4) the controller's robot frame R in the model's base B (``RobotSpec.X_BR``;
            None: identity).
        tool: (4, 4) the tool set on the controller when the poses were reported (default the
            file's; one of the two is needed).

    Returns:
        :class:`CellCalibration`: the calibrated TCP (the nominal tool's orientation, the
        pivot's tip; the nominal tool without pivot poses) and each target in B.
    """
    X_FT0 = tool if tool is not None else data.tool
    if X_FT0 is None:
        raise InputError(f"{data.source}: give the tool set on the controller when the poses "
                         "were reported (tool: in the file or --tool)")
    X_FT0 = np.asarray(X_FT0, float)
    X_BR = np.eye(4) if X_BR is None else np.asarray(X_BR, float)
    inv_tool = np.linalg.inv(X_FT0)
    X_FT = X_FT0.copy()
    pivot = None
    if len(data.tcp):
        pivot = fit_pivot_tcp(X_BR[None] @ data.tcp @ inv_tool[None])
        X_FT[:3, 3] = pivot.p_FT
    results = []
    for t in data.targets:
        X_BF = X_BR[None] @ t.X_RT @ inv_tool[None]
        tips = X_BF[:, :3, :3] @ X_FT[:3, 3] + X_BF[:, :3, 3]
        try:
            fit = fit_touch_points(t.features, tips)
            scaled = fit_touch_points(t.features, tips, estimate_scale=True)
        except InputError as exc:
            raise InputError(f"{data.source}: {t.name}: {exc}") from exc
        results.append(TargetResult(t.name, fit, scaled, extrapolation_error(fit, t.part),
                                    _outside(t.features, t.part)))
    return CellCalibration(X_FT=X_FT, pivot=pivot, targets=tuple(results))


def _weld(items: list, child: str, scenario: Path):
    for d in items:
        if d.add_weld is not None and d.add_weld.child == child:
            if d.add_weld.parent != "world":
                raise InputError(f"{scenario}: {child} is welded to {d.add_weld.parent}, not to "
                                 "world: only a frame welded to the world can be calibrated")
            return d.add_weld
    raise InputError(f"{scenario}: no weld with child {child!r} (name the calibrated frame's "
                     "weld with --table-weld / --holder-weld)")


def write_calibrated_scenario(scenario: str | Path, out: str | Path, cal: CellCalibration,
                              welds: dict[str, str], note: str = "", robot=None) -> Path:
    """Copy a scenario (Drake model directives) with each calibrated target's weld to the world
    set to the fitted frame (``welds``: target name -> the weld's child frame, whose frame the
    touch features are given in). The robot's own weld gives W -> B. Written atomically.
    ``robot`` (the arm that touched) is compared with the scenario's arm: a different one is
    warned about (the frames are in the touching arm's base)."""
    from pydrake.common.schema import Transform
    from pydrake.common.yaml import yaml_dump_typed
    from pydrake.math import RigidTransform
    from pydrake.multibody.parsing import LoadModelDirectives

    from drakedeburr._io import atomic_write_text
    from drakedeburr.resources import scenario_path
    from drakedeburr.robots import BASE_FRAME_NAME, ROBOT_MODEL_NAME, robot_for_model_url

    src = scenario_path(scenario)
    try:
        directives = LoadModelDirectives(str(src))
    except RuntimeError as exc:
        raise InputError(f"{src}: cannot load model directives: {exc}") from exc
    items = list(directives.directives)
    base = _weld(items, f"{ROBOT_MODEL_NAME}::{BASE_FRAME_NAME}", src)
    arm = next((robot_for_model_url(d.add_model.file) for d in items
                if d.add_model is not None and d.add_model.name == ROBOT_MODEL_NAME), None)
    if robot is not None and arm is not None and arm.name != robot.name:
        log.warning("%s places the %s, the touches were made with the %s: the frames are "
                    "written relative to the scenario's robot base", src.name, arm.name,
                    robot.name)
    X_WB = base.X_PC.GetDeterministicValue().GetAsMatrix4() if base.X_PC else np.eye(4)
    for name, child in welds.items():
        weld = _weld(items, child, src)
        weld.X_PC = Transform(RigidTransform(X_WB @ cal.target(name).fit.X_WT))
    directives.directives = items
    header = (f"# {src.name} with frames calibrated by drakedeburr calibrate"
              + (f" ({note})" if note else "") + "\n# calibrated welds: "
              + ", ".join(f"{n} = {c}" for n, c in welds.items()) + "\n")
    return atomic_write_text(out, header + yaml_dump_typed(directives))


def check_program(cal: CellCalibration, data: TouchData, target: str, robot, name: str,
                  approach: float = 0.01, speed: float = 0.05):
    """A program visiting every nominal feature of ``target`` through the fitted frames: work
    object = the fitted target frame, tool = the calibrated TCP, each feature at its nominal
    position with the orientation it was touched in, from ``approach`` [m] back along the
    tool axis (joint move), in and out by linear moves at ``speed`` [m/s], stop points.

    Args:
        robot: the arm (:class:`~drakedeburr.robots.RobotSpec`).

    Raises:
        InputError: a feature the arm cannot reach with the fitted frames.
    """
    from drakedeburr.post.tool_axis import READY_POSE
    from drakedeburr.programs.program import JOINT, LINEAR, MoveDetails, RobotProgram
    from drakedeburr.robots import solve_path

    res = cal.target(target)
    touches = next(t for t in data.targets if t.name == target)
    X_BR = np.asarray(robot.X_BR)
    X_BT = res.fit.X_WT
    poses, kinds, notes = [], [], []
    for i, (f, X_R) in enumerate(zip(touches.features, touches.X_RT, strict=True)):
        X = np.eye(4)
        X[:3, :3] = (X_BR @ X_R)[:3, :3]
        X[:3, 3] = X_BT[:3, :3] @ f + X_BT[:3, 3]
        back = X.copy()
        back[:3, 3] -= approach * X[:3, 2]
        poses += [back, X, back]
        kinds += [JOINT, LINEAR, LINEAR]
        notes += [f"{target} feature {i + 1}", "", ""]
    X_WT = np.array(poses)
    path = solve_path(robot.kinematics, X_WT @ np.linalg.inv(cal.X_FT)[None], q_start=READY_POSE)
    if not path.ok:
        raise InputError(f"{data.source}: {target} feature {path.failed[0] // 3 + 1} is out of "
                         "reach through the fitted frames")
    return RobotProgram.from_poses(
        name, X_WT, path.q, speed=speed, zone=0.0, move_type=kinds,
        details=MoveDetails(comments=notes),
        X_FT=cal.X_FT, X_WO=X_BT, robot=robot, tool_name="tCalib", wobj_name=f"w{target}",
        source=Path(data.source).name, flag="UNVERIFIED",
        flag_reason="calibration check program: joint limits checked; collisions NOT checked",
        notes=("visits each nominal feature through the calibrated work object and tool",))
