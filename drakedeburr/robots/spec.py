"""The arm registry's record type: everything plan, verify, cell and programs need of an arm.

Joint conventions (one choice, used everywhere):

* **model joints** ``q`` (the plant's positions, plans, verification): the joint values of our
  Drake model ``joint_1..joint_6``. They equal the controller's axis values for ABB and KUKA.
  FANUC controllers measure J3 from the horizontal (the J2/J3 "linkage"): the controller's J3
  is ``q3 - q2`` (``j23_coupling`` = 1, the ROS-Industrial fanuc_driver's ``J23_factor``).
* **OPW joints**: ``q_opw = q * sign_corrections - offsets`` (:class:`OpwParameters`).
* The model's ``flange`` frame is the vendor's flange frame (ABB tool0, KUKA $FLANGE, FANUC
  faceplate, +Z out of the flange) and the end frame of :func:`~drakedeburr.robots.opw.fk_opw`.
* The model's ``base`` frame B is the mounting face on axis 1. The controller's own robot frame
  R (ABB base frame, KUKA $ROBROOT, FANUC world frame) is ``X_BR`` in it: identity for ABB and
  KUKA, raised to the J2 axis height for FANUC.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots.opw import OpwParameters
from drakedeburr.robots.opw_ik import JointLimits, RobotKinematics

__all__ = ["CONTROLLERS", "CellMount", "RobotSpec"]

#: controller families and the program format each one runs
CONTROLLERS: dict[str, str] = {"abb": "rapid", "kuka": "krl", "fanuc": "ls"}


def _frozen(a, shape: tuple[int, ...], what: str) -> np.ndarray:
    arr = np.array(a, dtype=float)
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise InputError(f"{what}: expected finite values of shape {shape}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class CellMount:
    """Where an arm stands in one bundled cell and where it waits.

    Attributes:
        X_WB: (4, 4) pose of the arm's base frame B in the cell's world W [m] (W is the
            cell's frame: z up, floor at z = -0.8 m; the fixture and stand stay put).
        q_home: (6,) home configuration, model joints [rad]; collision-free.
        pedestal_url: the riser model welded under the base (its ``top`` frame at B).
        study: one line on how the mount was chosen (docs/cell.md has the table).
    """

    X_WB: np.ndarray
    q_home: np.ndarray
    pedestal_url: str
    study: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "X_WB", _frozen(self.X_WB, (4, 4), "CellMount.X_WB"))
        object.__setattr__(self, "q_home", _frozen(self.q_home, (6,), "CellMount.q_home"))


@dataclass(frozen=True, eq=False)
class RobotSpec:
    """One arm of the registry (see module docstring for the joint conventions).

    Attributes:
        name: registry name, e.g. ``"kr6_r700"`` (``--robot NAME``).
        title: human name, e.g. ``"KUKA KR 6 R700 sixx"``.
        vendor: ``"ABB"``, ``"KUKA"`` or ``"FANUC"``.
        controller: ``"abb"``, ``"kuka"`` or ``"fanuc"``: configuration data and program format
            (RAPID, KRL, LS; :data:`CONTROLLERS`).
        controller_model: the controller the limits/conventions refer to (e.g. ``"IRC5"``).
        opw: OPW parameters (model joints -> OPW joints).
        q_lower, q_upper: (6,) joint position limits, model joints [rad].
        v_max: (6,) joint speed limits [rad/s].
        a_max: (6,) joint acceleration limits [rad/s^2] (ASSUMED for every arm: vendors publish
            none; see ``a_max_note``).
        a_max_note: where ``a_max`` comes from.
        j23_coupling: controller J3 = model J3 - ``j23_coupling`` * model J2 (FANUC: 1).
        X_BR: (4, 4) the controller's robot frame R in the model base B [m].
        payload_kg: rated payload [kg] (everything on the flange: tool, gripper, part).
        flange: the mechanical interface (e.g. ISO 9409-1 designation).
        model_url: ``package://drakedeburr/robots/...`` Drake model written by us.
        mounts: ``(scenario name, CellMount)`` for the bundled cells.
        conventions: zero pose and positive directions in words (vendor documentation).
        sources: where each number comes from.
        wrist_moment_Nm: (3,) allowable static load moments about J4, J5, J6 [N m] where the
            vendor publishes them (None: not published / not found).
        wrist_inertia_kgm2: (3,) allowable load inertias about J4, J5, J6 [kg m^2] (None: not
            published / not found).
        source_file: the arm file it was read from (``--robot FILE``); "" for a spec made in
            code.
    """

    name: str
    title: str
    vendor: str
    controller: str
    controller_model: str
    opw: OpwParameters
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    a_max_note: str
    j23_coupling: float
    X_BR: np.ndarray
    payload_kg: float
    flange: str
    model_url: str
    mounts: tuple[tuple[str, CellMount], ...] = ()
    conventions: str = ""
    sources: tuple[str, ...] = ()
    wrist_moment_Nm: tuple[float, float, float] | None = None
    wrist_inertia_kgm2: tuple[float, float, float] | None = None
    source_file: str = ""
    kinematics: RobotKinematics = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise InputError(f"robot {self.name}: controller {self.controller!r} is not one of "
                             f"{', '.join(CONTROLLERS)}")
        for key in ("q_lower", "q_upper", "v_max", "a_max"):
            object.__setattr__(self, key, _frozen(getattr(self, key), (6,), f"{self.name}.{key}"))
        object.__setattr__(self, "X_BR", _frozen(self.X_BR, (4, 4), f"{self.name}.X_BR"))
        if np.any(self.q_lower >= self.q_upper) or np.any(self.v_max <= 0) or np.any(
                self.a_max <= 0):
            raise InputError(f"robot {self.name}: limits must satisfy lower < upper, v, a > 0")
        if not (np.isfinite(self.payload_kg) and self.payload_kg > 0):
            raise InputError(f"robot {self.name}: payload_kg must be > 0, got {self.payload_kg}")
        for key in ("wrist_moment_Nm", "wrist_inertia_kgm2"):
            v = getattr(self, key)
            if v is not None:
                arr = _frozen(v, (3,), f"{self.name}.{key}")
                if np.any(arr <= 0):
                    raise InputError(f"robot {self.name}: {key} must be > 0, got {v}")
                object.__setattr__(self, key, tuple(float(x) for x in arr))
        object.__setattr__(self, "kinematics", RobotKinematics(
            opw=self.opw, limits=JointLimits(tuple(self.q_lower), tuple(self.q_upper)),
            controller=self.controller, name=self.name))

    @property
    def ref(self) -> str:
        """How a plan names this arm so that :func:`~drakedeburr.robots.get_robot` finds it
        again: the arm file's absolute path for an arm read from a file, else its name."""
        return self.source_file or self.name

    @property
    def program_format(self) -> str:
        """The program format this arm's controller runs: "rapid", "krl" or "ls"."""
        return CONTROLLERS[self.controller]

    @property
    def cells(self) -> tuple[str, ...]:
        """Names of the bundled cells this arm has a mount in."""
        return tuple(k for k, _ in self.mounts)

    def mount(self, scenario: str) -> CellMount:
        """The arm's mount in a bundled cell.

        Raises:
            InputError: the arm has no mount in that cell.
        """
        for key, m in self.mounts:
            if key == scenario:
                return m
        raise InputError(f"robot {self.name}: no mount in cell {scenario!r} (it has: "
                         f"{', '.join(self.cells) or 'none'}); write a scenario that places it")

    def controller_joints(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) model joints -> the controller's axis values [rad]."""
        out = np.array(q, dtype=float)
        out[..., 2] = out[..., 2] - self.j23_coupling * out[..., 1]
        return out

    def model_joints(self, q_controller: np.ndarray) -> np.ndarray:
        """(..., 6) controller axis values -> model joints [rad] (inverse of
        :meth:`controller_joints`)."""
        out = np.array(q_controller, dtype=float)
        out[..., 2] = out[..., 2] + self.j23_coupling * out[..., 1]
        return out

    def within_limits(self, q: np.ndarray, slack: float = 1e-9) -> np.ndarray:
        """(..., 6) model joints -> (...,) bool inside the position limits."""
        return self.kinematics.limits.contains(q, slack)

    def configuration(self, q: np.ndarray):
        """The controller's configuration data of model joints ``q`` (6,): ABB confdata
        ``(cf1, cf4, cf6, cfx)``, KUKA ``(S, T)`` or FANUC ``'N U T, t1, t4, t6'``."""
        from drakedeburr.robots.configuration import configuration_of

        return configuration_of(self.kinematics, np.asarray(q, float), self.controller)
