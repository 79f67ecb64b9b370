"""Build a deburring cell (a Drake ``RobotDiagram``) from a scenario file and a hub.

A scenario (``models/scenarios/*.yaml``) is a list of Drake model directives. It must contain

* the arm as model instance ``robot``: a registered arm's model (:mod:`drakedeburr.robots`,
  e.g. ``robots/irb1600_10_120.sdf``) welded to the world by its ``base`` frame at its mount
  (the bundled cells: W = the IRB1600's base), with its home configuration given as the
  model's ``default_joint_positions``;
* exactly one frame named ``tool_tip`` (the tool frame T of a tool model);
* exactly one frame named ``hub_mount``: where the hub frame H goes.

The hub is *not* in the scenario: :func:`load_cell` parses the chosen hub SDF (model ``hub``,
body ``hub`` whose body frame is H) and welds H onto ``hub_mount``. Whether ``tool_tip`` or
``hub_mount`` moves with the robot decides the mode: ``"tool"`` (tool-in-hand: spindle on the
flange, hub on a fixture) or ``"workpiece"`` (workpiece-in-hand: hub on a flange gripper, spindle
on a stand; T is then the fixed "virtual TCP" of source S0). Everything else is the same code.

``load_cell(..., robot=NAME)`` builds a bundled cell with another registered arm: its model,
base pose, home and pedestal come from the arm's mount in that cell (``RobotSpec.mount``); the
fixture, stand and tools stay where the scenario puts them. ``Cell.arm`` is the arm's spec.

Collision filtering done here: bodies joined by a joint or welded together (Drake's default,
so the flange/spindle, spindle/burr, fixture/table pairs) and the hub against the body that
holds it (chuck or gripper: a clamped contact is intended). The burr head against the hub is
NOT filtered: that contact is the process, and the planner decides (see ``Cell.burr_head_ids``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from drakedeburr._io import load_yaml
from drakedeburr.cell.recipe import CellMemo, cell_recipe, plan_cell_args
from drakedeburr.cell.tools import apply_tool
from drakedeburr.errors import InputError
from drakedeburr.resources import add_package_to, hub_dir, hub_names, models_dir, scenario_path
from drakedeburr.robots import (
    BASE_FRAME_NAME,
    FLANGE_FRAME_NAME,
    JOINT_NAMES,
    ROBOT_MODEL_NAME,
    RobotSpec,
    get_robot,
    robot_for_model_url,
)

__all__ = [
    "Cell",
    "load_cell",
    "load_plan_cell",
    "bundled_cell_name",
    "resolve_hub_sdf",
    "TOOL_FRAME_NAME",
    "HUB_MOUNT_FRAME_NAME",
    "HUB_MODEL_NAME",
    "BURR_HEAD_GEOMETRY_NAME",
]

log = logging.getLogger(__name__)

TOOL_FRAME_NAME = "tool_tip"
HUB_MOUNT_FRAME_NAME = "hub_mount"
HUB_MODEL_NAME = "hub"
#: collision geometry name of the cutting head in the tool models
BURR_HEAD_GEOMETRY_NAME = "burr_head"


@dataclass(frozen=True)
class Cell:
    """A loaded deburring cell. Arrays are (6,) in joint order ``joint_1..joint_6``.

    Attributes:
        diagram: the ``pydrake.planning.RobotDiagram`` (plant + scene graph).
        plant: its ``MultibodyPlant`` (finalized; its positions are exactly the 6 robot joints).
        scene_graph: its ``SceneGraph``.
        robot: model instance of the robot.
        hub_instance: model instance of the hub.
        mode: ``"tool"`` (tool-in-hand) or ``"workpiece"`` (workpiece-in-hand).
        tool_frame: frame T (``tool_tip``): origin at the cutting point, +Z along the burr axis
            pointing out of the tool (spindle -> tip).
        hub_frame: frame H (body frame of the hub): origin on the hub axis at the front face,
            +Z out of the visible face.
        flange_frame: frame F (the vendor's flange frame, +Z out). base_frame: robot base B
            (at the arm's mount; ``X_WB()``).
        arm: the arm's :class:`~drakedeburr.robots.RobotSpec` (kinematics, conventions,
            controller).
        q_lower, q_upper: position limits [rad].
        v_lower, v_upper: velocity limits [rad/s].
        a_lower, a_upper: acceleration limits [rad/s^2] (assumed values, see the arm's spec).
        q_home: home configuration [rad]: the scenario's, or a plan's (``load_cell(q_home=)``).
        burr_head_ids: proximity geometries of the burr's cutting head.
        hub_ids: proximity geometries of the hub.
        robot_ids: every other geometry that moves with the robot (robot links, spindle body,
            bracket, collet, shank; or the hub gripper).
        environment_ids: every other geometry fixed in the world (pedestal, fixture, stand...).
            The four sets partition all proximity geometries.
        moving_model_instances: model instances moving with the robot (robot + tool, or robot +
            gripper + hub): the ``robot_model_instances`` of a SceneGraphCollisionChecker.
        scenario: the scenario file. hub_sdf: the hub model file.
        tool: the burr variant the bundled spindle carries (``drakedeburr.cell.tools``), or
            None for a scenario with its own tool model.
        recipe: the ``load_cell`` arguments that build this cell again (:mod:`.recipe`).
        memo: what later stages derive from the cell once (:class:`~.recipe.CellMemo`).
    """

    diagram: object
    plant: object
    scene_graph: object
    robot: object
    hub_instance: object
    mode: Literal["tool", "workpiece"]
    tool_frame: object
    hub_frame: object
    flange_frame: object
    base_frame: object
    arm: RobotSpec
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_lower: np.ndarray
    v_upper: np.ndarray
    a_lower: np.ndarray
    a_upper: np.ndarray
    q_home: np.ndarray
    burr_head_ids: frozenset
    hub_ids: frozenset
    robot_ids: frozenset
    environment_ids: frozenset
    moving_model_instances: tuple
    scenario: Path
    hub_sdf: Path
    tool: str | None = None
    recipe: dict | None = field(default=None, repr=False, compare=False)
    memo: CellMemo = field(default_factory=CellMemo, repr=False, compare=False)

    @property
    def num_joints(self) -> int:
        return len(self.q_home)

    def create_context(self, q: np.ndarray | None = None):
        """A fresh diagram context with the robot at ``q`` (default ``q_home``)."""
        context = self.diagram.CreateDefaultContext()
        self.plant.SetPositions(
            self.plant.GetMyMutableContextFromRoot(context),
            self.q_home if q is None else self._check_q(q),
        )
        return context

    def _plant_context(self, q: np.ndarray):
        # one cached context for pose queries (not thread-safe; use create_context for that)
        if self.memo.context is None:
            self.memo.context = self.diagram.CreateDefaultContext()
        plant_context = self.plant.GetMyMutableContextFromRoot(self.memo.context)
        self.plant.SetPositions(plant_context, self._check_q(q))
        return plant_context

    def _check_q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self.num_joints,):
            raise InputError(f"joint vector must have shape ({self.num_joints},), got {q.shape}")
        return q

    def X_WT(self, q: np.ndarray):
        """Pose of the tool frame T in world at joints ``q`` [rad] (a RigidTransform)."""
        return self.tool_frame.CalcPoseInWorld(self._plant_context(q))

    def X_WH(self, q: np.ndarray):
        """Pose of the hub frame H in world at joints ``q`` [rad]."""
        return self.hub_frame.CalcPoseInWorld(self._plant_context(q))

    def X_WF(self, q: np.ndarray):
        """Pose of the robot flange F (tool0) in world at joints ``q`` [rad]."""
        return self.flange_frame.CalcPoseInWorld(self._plant_context(q))

    def X_WB(self):
        """Pose of the robot base frame B in world (the arm's mount; independent of q)."""
        return self.base_frame.CalcPoseInWorld(self._plant_context(self.q_home))

    def flange_loads(self):
        """What the arm carries, from the cell's models: the equipment bolted to the flange
        (spindle, or gripper) and the workpiece held (workpiece in hand), masses [kg] and
        centres of gravity in the flange frame F [m] (a
        :class:`~drakedeburr.programs.FlangeLoads` for the program writers)."""
        from drakedeburr.programs import FlangeLoads

        plant_context = self._plant_context(self.q_home)
        X_FW = self.flange_frame.CalcPoseInWorld(plant_context).inverse()
        parts = {"tool": [0.0, np.zeros(3), []], "workpiece": [0.0, np.zeros(3), []]}
        for instance in self.moving_model_instances:
            if instance == self.robot:
                continue
            key = "workpiece" if instance == self.hub_instance else "tool"
            for index in self.plant.GetBodyIndices(instance):
                body = self.plant.get_body(index)
                m = body.default_mass()
                p_BoBcm = body.CalcCenterOfMassInBodyFrame(plant_context)
                p_F = X_FW.multiply(body.EvalPoseInWorld(plant_context).multiply(p_BoBcm))
                parts[key][0] += m
                parts[key][1] += m * p_F
            parts[key][2].append(self.plant.GetModelInstanceName(instance))
        (mt, st, nt), (mw, sw, nw) = parts["tool"], parts["workpiece"]
        if mt <= 0:
            raise InputError(f"{self.scenario}: nothing with mass is mounted on the flange")
        source = f"cell models ({', '.join(nt + nw)}), {self.scenario.name}"
        return FlangeLoads(tool_mass=float(mt), tool_cog=tuple(map(float, st / mt)),
                           workpiece_mass=float(mw),
                           workpiece_cog=tuple(map(float, sw / mw)) if mw > 0 else (0.0, 0.0, 0.0),
                           source=source)

    def X_HT(self, q: np.ndarray):
        """Pose of the tool frame T in the hub frame H at joints ``q``: the process pose."""
        return self.tool_frame.CalcPose(self._plant_context(q), self.hub_frame)

    def collision_pairs(self, q: np.ndarray, *, ignore_burr_hub: bool = True) -> list[tuple]:
        """Penetrating pairs at ``q`` as (name_a, name_b, depth [m]), filters applied.

        ``ignore_burr_hub`` drops burr-head/hub contacts (the process contact).
        """
        context = self.create_context(q)
        sg_context = self.scene_graph.GetMyContextFromRoot(context)
        query = self.scene_graph.get_query_output_port().Eval(sg_context)
        inspector = query.inspector()
        out = []
        for pair in query.ComputePointPairPenetration():
            ids = {pair.id_A, pair.id_B}
            if ignore_burr_hub and ids & self.burr_head_ids and ids & self.hub_ids:
                continue
            out.append((_geometry_label(self, inspector, pair.id_A),
                        _geometry_label(self, inspector, pair.id_B), float(pair.depth)))
        return out

    def min_distance(self, q: np.ndarray, *, ignore_burr_hub: bool = True,
                     max_distance: float = 1.0) -> tuple[float, tuple[str, str]]:
        """Smallest signed distance [m] between unfiltered geometry pairs at ``q`` and its pair.

        Distances above ``max_distance`` are not computed (returned as ``max_distance``).
        """
        context = self.create_context(q)
        sg_context = self.scene_graph.GetMyContextFromRoot(context)
        query = self.scene_graph.get_query_output_port().Eval(sg_context)
        inspector = query.inspector()
        best, names = float(max_distance), ("", "")
        for d in query.ComputeSignedDistancePairwiseClosestPoints(max_distance):
            ids = {d.id_A, d.id_B}
            if ignore_burr_hub and ids & self.burr_head_ids and ids & self.hub_ids:
                continue
            if d.distance < best:
                best = float(d.distance)
                names = (_geometry_label(self, inspector, d.id_A),
                         _geometry_label(self, inspector, d.id_B))
        return best, names


def _geometry_label(cell: Cell, inspector, geometry_id) -> str:
    body = cell.plant.GetBodyFromFrameId(inspector.GetFrameId(geometry_id))
    model = cell.plant.GetModelInstanceName(body.model_instance())
    return f"{model}::{body.name()}/{inspector.GetName(geometry_id)}"


def resolve_hub_sdf(hub: str | Path | None) -> Path:
    """Hub model file from a bundled hub name, a hub folder or an SDF path.

    ``None`` picks the hub stage's default hub (``drakedeburr.hub.DEFAULT_HUB``) when it is
    bundled, else the first bundled hub (alphabetical).
    """
    if hub is None:
        names = hub_names() if _hubs_dir_exists() else []
        if not names:
            raise FileNotFoundError("no bundled hub models (models/hubs/*/hub.yaml); pass hub=")
        try:
            from drakedeburr.hub.catalogue import DEFAULT_HUB
        except ImportError:  # hub stage without a catalogue
            DEFAULT_HUB = None
        hub = DEFAULT_HUB if DEFAULT_HUB in names else names[0]
    path = Path(hub)
    if path.suffix == ".sdf":
        if not path.is_file():
            raise FileNotFoundError(f"hub model {path} does not exist")
        return path.resolve()
    if path.is_dir() and (path / "hub.sdf").is_file():
        return (path / "hub.sdf").resolve()
    sdf = hub_dir(str(hub)) / "hub.sdf"
    if not sdf.is_file():
        raise FileNotFoundError(f"bundled hub {hub!r} has no hub.sdf ({sdf})")
    return sdf


def _hubs_dir_exists() -> bool:
    from drakedeburr.resources import hubs_dir

    return hubs_dir().is_dir()


def _unique_frame(plant, name: str, scenario: Path):
    from pydrake.multibody.tree import ModelInstanceIndex

    frames = [plant.get_frame(i) for m in range(plant.num_model_instances())
              for i in plant.GetFrameIndices(ModelInstanceIndex(m))
              if plant.get_frame(i).name() == name]
    if len(frames) != 1:
        owners = ", ".join(plant.GetModelInstanceName(f.model_instance()) for f in frames)
        raise InputError(f"{scenario}: a scenario needs exactly one frame named {name!r}, "
                         f"found {len(frames)}" + (f" ({owners})" if frames else ""))
    return frames[0]


def bundled_cell_name(scenario_file: str | Path) -> str | None:
    """The bundled cell name of a scenario file (``tool_in_hand``), None for a user file."""
    scenario_file = Path(scenario_file)
    bundled = models_dir() / "scenarios"
    return scenario_file.stem if scenario_file.parent.resolve() == bundled.resolve() else None


_bundled_cell_name = bundled_cell_name


def _robot_directive(items: list, scenario_file: Path):
    """(add_model, base weld, pedestal add_model or None) of the arm in a scenario's
    directive list (the objects in ``items``, so they can be changed in place)."""
    model = weld = pedestal = None
    base = f"{ROBOT_MODEL_NAME}::{BASE_FRAME_NAME}"
    for d in items:
        if d.add_model is not None and d.add_model.name == ROBOT_MODEL_NAME:
            model = d.add_model
        elif d.add_model is not None and d.add_model.name == "pedestal":
            pedestal = d.add_model
        elif d.add_weld is not None and d.add_weld.child == base:
            weld = d.add_weld
    if model is None:
        raise InputError(f"{scenario_file}: no model instance named {ROBOT_MODEL_NAME!r} (the arm)")
    if weld is None or weld.parent != "world":
        raise InputError(f"{scenario_file}: the arm must be welded to 'world' by "
                         f"'{ROBOT_MODEL_NAME}::{BASE_FRAME_NAME}'")
    return model, weld, pedestal


def _apply_arm(directives, scenario_file: Path, robot: str | RobotSpec | None) -> RobotSpec:
    """The scenario's arm; with ``robot`` given, the directives are changed to place that arm
    at its mount in this (bundled) cell. Returns the arm's spec."""
    from pydrake.common.schema import Transform
    from pydrake.math import RigidTransform

    items = list(directives.directives)  # (the bindings hand out copies: edit, then set back)
    model, weld, pedestal = _robot_directive(items, scenario_file)
    scenario_arm = robot_for_model_url(model.file)
    if robot is None:
        if scenario_arm is None:
            raise InputError(f"{scenario_file}: the arm model {model.file} is not a registered "
                             "arm (drakedeburr robots lists them)")
        return scenario_arm
    spec = get_robot(robot)
    if scenario_arm is spec:
        return spec
    cell_name = _bundled_cell_name(scenario_file)
    if cell_name is None:
        raise InputError(f"{scenario_file}: places the arm {model.file}; to use {spec.name} "
                         "write a scenario that places it (base pose, home) or use a bundled cell")
    mount = spec.mount(cell_name)
    model.file = spec.model_url
    model.default_joint_positions = {n: np.array([q]) for n, q in zip(
        JOINT_NAMES, mount.q_home, strict=True)}
    weld.X_PC = Transform(RigidTransform(mount.X_WB))
    if pedestal is not None:
        pedestal.file = mount.pedestal_url
    directives.directives = items
    return spec


def load_plan_cell(plan) -> Cell:
    """The cell a plan was made in (:func:`drakedeburr.cell.recipe.plan_cell_args`), built
    here for the first time in this run: its payload warned about."""
    return load_cell(**{**plan_cell_args(plan), "warn_payload": True})


def load_cell(
    scenario: str | Path,
    hub: str | Path | None = None,
    *,
    robot: str | RobotSpec | None = None,
    hub_pose: np.ndarray | None = None,
    tool: str | None = None,
    time_step: float = 0.0,
    q_home: np.ndarray | None = None,
    warn_payload: bool = True,
) -> Cell:
    """Build the cell of a scenario with a hub.

    Args:
        scenario: bundled scenario name (``"tool_in_hand"``, ``"workpiece_in_hand"``) or a path
            to a model-directives YAML file (see module docstring for what it must contain).
        hub: bundled hub name, hub folder, or path to a hub SDF (model ``hub``, body ``hub``
            with its body frame = H). ``None``: the first bundled hub.
        robot: registered arm name (``drakedeburr robots``) or spec; ``None``: the scenario's
            own arm. A bundled cell is built with the arm at its mount there.
        hub_pose: (4, 4) pose of the hub frame H in the ``hub_mount`` frame [m] (where a
            placement search put it: :mod:`drakedeburr.plan.placement`); ``None``: identity.
        tool: the burr on the scenario's bundled spindle (``TOOL_VARIANTS``); None: standard.
        time_step: MultibodyPlant time step [s]; 0 = continuous (planning needs no dynamics).
        q_home: (6,) home [rad] in place of the mount's (where a hub leaves that one without
            clearance: :mod:`drakedeburr.plan.home`); ``None``: the mount's.
        warn_payload: warn (once) when the arm is not rated for what it carries; False for a
            look at the load only (:func:`drakedeburr.cell.loads.rated_default_arm`).

    Returns:
        The :class:`Cell`.

    Raises:
        FileNotFoundError: unknown scenario or hub.
        InputError: the scenario or hub breaks the conventions above, or the arm has no mount in
            the cell (the message names the file).
    """
    from pydrake.multibody.parsing import LoadModelDirectives, ProcessModelDirectives
    from pydrake.planning import RobotDiagramBuilder

    scenario_file = scenario_path(scenario)
    hub_sdf = resolve_hub_sdf(hub)

    builder = RobotDiagramBuilder(time_step=time_step)
    plant = builder.plant()
    parser = builder.parser()
    add_package_to(parser.package_map())
    load_yaml(scenario_file, "scenario", local_tags=True)  # bounded: aliases, size, UTF-8
    try:
        directives = LoadModelDirectives(str(scenario_file))
    except RuntimeError as exc:  # Drake reports parse errors as RuntimeError
        raise InputError(f"{scenario_file}: cannot load model directives: {exc}") from exc
    arm = _apply_arm(directives, scenario_file, robot)
    tool_name = apply_tool(directives, scenario_file, tool)
    try:
        ProcessModelDirectives(directives, plant, parser)
    except RuntimeError as exc:
        raise InputError(f"{scenario_file}: cannot load model directives: {exc}") from exc
    robot_instance = plant.GetModelInstanceByName(ROBOT_MODEL_NAME)
    if plant.HasModelInstanceNamed(HUB_MODEL_NAME):
        raise InputError(f"{scenario_file}: the model name {HUB_MODEL_NAME!r} is reserved for "
                         "the hub that load_cell adds")
    hub_instance, hub_body, hub_mount, tool_frame = _add_hub(plant, parser, hub_sdf, scenario_file,
                                                             hub_pose)
    plant.Finalize()
    _check_joints(plant, robot_instance, scenario_file)
    if q_home is not None:
        plant.SetDefaultPositions(robot_instance, np.asarray(q_home, float))
    mode, world_group = _mode(plant, tool_frame, hub_body, scenario_file)
    sets, moving = _geometry_sets(builder.scene_graph(), plant, robot_instance, hub_instance,
                                  world_group, scenario_file, hub_sdf)
    _filter_holder(builder.scene_graph(), plant, hub_mount, hub_body, sets["hub"])
    diagram = builder.Build()
    plant = diagram.plant()
    cell = Cell(
        diagram=diagram, plant=plant, scene_graph=diagram.scene_graph(), robot=robot_instance,
        hub_instance=hub_instance, mode=mode, tool_frame=tool_frame,
        hub_frame=hub_body.body_frame(),
        flange_frame=plant.GetFrameByName(FLANGE_FRAME_NAME, robot_instance),
        base_frame=plant.GetFrameByName(BASE_FRAME_NAME, robot_instance), arm=arm,
        q_lower=plant.GetPositionLowerLimits(), q_upper=plant.GetPositionUpperLimits(),
        v_lower=plant.GetVelocityLowerLimits(), v_upper=plant.GetVelocityUpperLimits(),
        a_lower=plant.GetAccelerationLowerLimits(), a_upper=plant.GetAccelerationUpperLimits(),
        q_home=plant.GetDefaultPositions(),
        burr_head_ids=frozenset(sets["burr"]), hub_ids=frozenset(sets["hub"]),
        robot_ids=frozenset(sets["robot"]), environment_ids=frozenset(sets["env"]),
        moving_model_instances=tuple(sorted(moving, key=int)),
        scenario=scenario_file, hub_sdf=hub_sdf, tool=tool_name,
        # how to build this cell again (a planner's worker process builds the same one)
        recipe=cell_recipe(scenario, hub, robot=robot, tool=tool, time_step=time_step,
                           hub_pose=hub_pose, q_home=q_home),
    )
    for arr in (cell.q_lower, cell.q_upper, cell.v_lower, cell.v_upper, cell.a_lower,
                cell.a_upper, cell.q_home):
        arr.setflags(write=False)
    if warn_payload:
        _check_payload(cell)
    log.debug("loaded cell %s (%s-in-hand) with hub %s, arm %s", scenario_file.name, mode,
              hub_sdf, arm.name)
    return cell


def _add_hub(plant, parser, hub_sdf: Path, scenario_file: Path, hub_pose=None):
    """Parse the hub and weld its frame H onto ``hub_mount``; returns (instance, body,
    hub_mount frame, tool frame)."""
    try:
        hub_models = parser.AddModels(str(hub_sdf))
    except RuntimeError as exc:
        raise InputError(f"{hub_sdf}: cannot parse hub model: {exc}") from exc
    hub_instance = next(
        (m for m in hub_models if plant.GetModelInstanceName(m) == HUB_MODEL_NAME), None)
    if hub_instance is None or not plant.HasBodyNamed(HUB_MODEL_NAME, hub_instance):
        raise InputError(f"{hub_sdf}: a hub model must be named {HUB_MODEL_NAME!r} with a body "
                         f"{HUB_MODEL_NAME!r} (its body frame is the hub frame H)")
    hub_body = plant.GetBodyByName(HUB_MODEL_NAME, hub_instance)
    hub_mount = _unique_frame(plant, HUB_MOUNT_FRAME_NAME, scenario_file)
    from pydrake.math import RigidTransform

    X_MH = RigidTransform() if hub_pose is None else RigidTransform(np.asarray(hub_pose, float))
    plant.WeldFrames(hub_mount, hub_body.body_frame(), X_MH)
    tool_frame = _unique_frame(plant, TOOL_FRAME_NAME, scenario_file)
    return hub_instance, hub_body, hub_mount, tool_frame


def _check_joints(plant, robot_instance, scenario_file: Path) -> None:
    if plant.num_positions() != len(JOINT_NAMES):
        raise InputError(
            f"{scenario_file}: the cell must have exactly the {len(JOINT_NAMES)} robot joints as "
            f"degrees of freedom, found {plant.num_positions()} (is every other model welded?)"
        )
    for i, name in enumerate(JOINT_NAMES):
        joint = plant.GetJointByName(name, robot_instance)
        if joint.position_start() != i:
            raise InputError(
                f"{scenario_file}: joint {name} is at position {joint.position_start()}, not {i}")


def _mode(plant, tool_frame, hub_body, scenario_file: Path):
    """("tool" | "workpiece", indices of the bodies welded to the world)."""
    world_group = {b.index() for b in plant.GetBodiesWeldedTo(plant.world_body())}
    tool_fixed = tool_frame.body().index() in world_group
    hub_fixed = hub_body.index() in world_group
    if tool_fixed == hub_fixed:
        raise InputError(
            f"{scenario_file}: exactly one of {TOOL_FRAME_NAME!r} and the hub must move with the "
            f"robot (tool fixed: {tool_fixed}, hub fixed: {hub_fixed})"
        )
    return ("workpiece" if tool_fixed else "tool"), world_group


def _geometry_sets(scene_graph, plant, robot_instance, hub_instance, world_group,
                   scenario_file: Path, hub_sdf: Path):
    """Partition the proximity geometries: {"burr", "hub", "robot", "env"} and the model
    instances moving with the robot."""
    from pydrake.geometry import Role

    inspector = scene_graph.model_inspector()
    sets: dict[str, set] = {"burr": set(), "hub": set(), "robot": set(), "env": set()}
    moving = {robot_instance}
    for gid in inspector.GetAllGeometryIds(Role.kProximity):
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        if body.model_instance() == hub_instance:
            sets["hub"].add(gid)
        elif inspector.GetName(gid).split("::")[-1] == BURR_HEAD_GEOMETRY_NAME:
            sets["burr"].add(gid)
        elif body.index() in world_group:
            sets["env"].add(gid)
        else:
            sets["robot"].add(gid)
        if body.index() not in world_group:
            moving.add(body.model_instance())
    if not sets["burr"]:
        raise InputError(f"{scenario_file}: no collision geometry named "
                         f"{BURR_HEAD_GEOMETRY_NAME!r} (the burr's cutting head)")
    if not sets["hub"]:
        raise InputError(f"{hub_sdf}: the hub has no collision geometry")
    return sets, moving


def _filter_holder(scene_graph, plant, hub_mount, hub_body, hub_ids) -> None:
    """The hub is clamped by the body carrying hub_mount: that contact is intended."""
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet, Role

    inspector = scene_graph.model_inspector()
    holder = plant.GetBodiesWeldedTo(hub_mount.body())
    holder_frames = {plant.GetBodyFrameIdOrThrow(b.index()) for b in holder
                     if b.index() != hub_body.index()}
    holder_ids = [gid for gid in inspector.GetAllGeometryIds(Role.kProximity)
                  if inspector.GetFrameId(gid) in holder_frames and gid not in hub_ids]
    # welded groups: the hub holder may be the whole world group (fixture) -> restrict to the
    # fixture model that owns hub_mount
    holder_ids = [gid for gid in holder_ids
                  if plant.GetBodyFromFrameId(inspector.GetFrameId(gid)).model_instance()
                  == hub_mount.model_instance()]
    if holder_ids:
        scene_graph.collision_filter_manager().Apply(
            CollisionFilterDeclaration().ExcludeBetween(
                GeometrySet(list(hub_ids)), GeometrySet(holder_ids)))


_PAYLOAD_WARNED: set = set()


def _check_payload(cell: Cell) -> None:
    """Warn once per process when what the arm carries (every moving body that is not an arm
    link) exceeds the arm's rated payload: planning is kinematic and goes on, the verifier's
    required ``payload`` item fails (drakedeburr.verify.checks_payload) and no program is
    written. Not for an arm that only stood in while the default was chosen (``warn_payload``)."""
    plant = cell.plant
    carried = 0.0
    for instance in cell.moving_model_instances:
        if instance == cell.robot:
            continue
        carried += sum(plant.get_body(b).default_mass() for b in plant.GetBodyIndices(instance))
    key = (cell.scenario.name, cell.arm.name, round(carried, 1))
    if carried > cell.arm.payload_kg and key not in _PAYLOAD_WARNED:
        _PAYLOAD_WARNED.add(key)  # once per process: planning loads the cell many times
        log.warning("%s: the arm %s carries %.1f kg (tool/gripper/hub models) but is rated for "
                    "%.1f kg: the payload check fails and no program is written "
                    "(docs/robots.md)", cell.scenario.name, cell.arm.name, carried,
                    cell.arm.payload_kg)
