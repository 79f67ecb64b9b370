"""The one configuration of a run: process recipe, acceptance thresholds and tolerances.

Everything a run depends on besides its input files is here, defined once (SPEC.md §S3, Tab. 7
of the source), in frozen dataclasses:

* :class:`ProcessParameters` - the deburring process (speeds, depth of cut, tilt boxes, path
  thresholds); a part's ``process.yaml`` (beside its model) overrides the defaults;
* :class:`Acceptance` - thresholds on *process figures* (share of the cut at the feed, cycle
  ratio, theta-box share, J6 ranges): ``None`` (the default) reports the figure against its
  physical bound without judging it; a part's recipe may set a threshold under ``acceptance:``;
* :class:`Tolerances` - what the verifier and the planner accept (clearance, deviations,
  limits, sampling): the code's values, never a recipe's;
* :class:`Config` - all three plus the scenario, hub and robot of a run, loaded once by
  :func:`load_config` and passed explicitly through plan, verify and export.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["ProcessParameters", "Tolerances", "OrientationBounds", "Acceptance", "Recipe",
           "Config", "load_config", "load_recipe", "default_tolerances", "process_parameters",
           "dataclass_from_yaml", "recipe_from_record", "SOURCE_TARGETS", "PROCESS_FILE",
           "RecipeKey", "RECIPE_SCHEMA", "ACCEPTANCE_SCHEMA"]

#: a part's process recipe, beside its model (e.g. ``models/hubs/<name>/process.yaml``)
PROCESS_FILE = "process.yaml"


@dataclass(frozen=True)
class OrientationBounds:
    """Box bounds on (theta_A, theta_B) [rad] for one window class."""

    theta_min: float
    theta_max: float

    def __post_init__(self):
        lo, hi = float(self.theta_min), float(self.theta_max)
        # signed tilts (rotations about the local frame's axes, SPEC section 5)
        if not (np.isfinite(lo) and np.isfinite(hi) and -0.5 * np.pi < lo < hi < 0.5 * np.pi):
            raise ValueError(f"orientation bounds need -pi/2 < theta_min < theta_max < pi/2 rad, "
                             f"got [{self.theta_min}, {self.theta_max}]")


def _positive(obj, *names: str) -> None:
    for name in names:
        v = getattr(obj, name)
        if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise ValueError(f"{type(obj).__name__}.{name} must be a positive number, got {v!r}")


@dataclass(frozen=True)
class ProcessParameters:
    """Deburring process (source Tab. 7). SI units."""

    grinding_speed: float = 0.150  # [m/s] tool speed along a window edge (the feed)
    window_switch_speed: float = 0.450  # [m/s] moves between windows
    purge_speed: float = 0.600  # [m/s]
    home_speed: float = 0.600  # [m/s] return home
    approach_speed: float = 0.050  # [m/s] approach/retract along the tool axis
    # [m/s^2] TCP path acceleration the cut is timed with (ramps at its start and end); the
    # verifier counts it as a binding limit where the tool runs below the feed
    tcp_acceleration: float = 3.0
    spindle_air_pressure: float = 0.15e6  # [Pa] floating spindle radial compliance
    depth_of_cut_large: float = 1.5e-3  # [m] large windows
    depth_of_cut_small: float = 1.2e-3  # [m] small windows
    bounds_large: OrientationBounds = field(
        default_factory=lambda: OrientationBounds(0.26, 0.44)
    )
    bounds_small: OrientationBounds = field(
        default_factory=lambda: OrientationBounds(0.09, 0.26)
    )
    w1: float = 0.6  # weight of theta_A smoothness (eq. 11)
    w2: float = 0.4  # weight of theta_B smoothness (eq. 11)
    l_max: float = 10e-3  # [m] max chord length between CL points
    delta_max: float = 0.12e-3  # [m] max chord-height error
    key_point_curvature: float = 120.0  # [1/m] = 0.12 1/mm: key points get a surface fit
    normal_search_radius: float = 6e-3  # [m] radius search around a CL point
    ransac_threshold: float = 0.1e-3  # [m] RANSAC plane inlier distance
    chamfer_width_min: float = 0.50e-3  # [m] T/CAAMTB 126-2023
    chamfer_width_max: float = 1.50e-3  # [m]

    def __post_init__(self) -> None:
        _positive(self, "grinding_speed", "window_switch_speed", "purge_speed", "home_speed",
                  "approach_speed", "tcp_acceleration", "depth_of_cut_large",
                  "depth_of_cut_small", "l_max", "delta_max")

    def depth_of_cut(self, kind: str) -> float:
        """Depth of cut [m] of a "large" or "small" window."""
        return self.depth_of_cut_large if kind == "large" else self.depth_of_cut_small

    def bounds(self, kind: str) -> OrientationBounds:
        """The (theta_A, theta_B) box of a "large" or "small" window."""
        return self.bounds_large if kind == "large" else self.bounds_small


@dataclass(frozen=True)
class Acceptance:
    """Thresholds a part's recipe sets on process figures; None: reported with its bound, not
    judged. The source's own targets are :data:`SOURCE_TARGETS` (shown beside the figures)."""

    speed_band_fraction: float | None = None  # [-] share of cutting travel at the feed
    cycle_time_ratio: float | None = None  # [-] cycle time / edge length over the feed
    theta_box_share: float | None = None  # [-] share of cut samples inside the theta box
    j6_range_large: float | None = None  # [rad] J6 range over a large window's cut
    j6_range_small: float | None = None  # [rad] over a small window's cut


#: the source's targets for the process figures (SPEC S3 §7, Tab. 7): for reference only
SOURCE_TARGETS = Acceptance(speed_band_fraction=0.95, cycle_time_ratio=1.05,
                            theta_box_share=1.0, j6_range_large=0.3491, j6_range_small=0.1745)


@dataclass(frozen=True)
class Tolerances:
    """What verification (and planning, where it must meet it) accepts. SI units. The code's
    values: a part's recipe does not change them."""

    path_deviation: float = 0.05e-3  # [m] tool point vs commanded Cartesian path
    edge_deviation: float = 0.17e-3  # [m] tool point vs true edge (delta_max + 0.05 mm)
    min_clearance: float = 2e-3  # [m] except the burr contact pair
    speed_band: float = 0.05  # [-] +-5 %: "at the feed", and the overspeed allowance
    # [m/s] programs carry each move's planned speed rounded up to this (1 mm/s)
    speed_quantum: float = 1e-3
    # [-] wherever the tool runs below the feed (or below the programmed speed), some limit
    # must be used to at least this share there: a joint's speed or acceleration, or the TCP
    # acceleration (the planner times to 90 % of the joint accelerations, 95 % of the speeds)
    forced_slowdown: float = 0.85
    cone_slack: float = 1e-6  # [rad] numerical slack on cone checks
    dense_step: float = 0.5e-3  # [m] tool travel between dense re-check samples
    time_step: float = 0.02  # [s] longest time between trajectory samples
    # [m] tool travel between samples on home/transition joint moves (away from the edge)
    joint_move_step: float = 2e-3
    fk_match: float = 1e-9  # [m] model FK vs analytic FK
    on_surface: float = 1e-6  # [m] edge loops on the mesh surface
    registration_inlier_distance: float = 0.3e-3  # [m] scan point counts as on the hub model
    registration_fitness_min: float = 0.95  # [-] share of scan points on the model to accept
    registration_rmse_max: float = 0.1e-3  # [m] RMS point-to-model distance of those inliers
    # [rad] trajectory vs program tool orientation (verify): the executed cut turns the tool
    # smoothly where the program's slerp between targets kinks at each target (controllers
    # blend orientation in their zones too); the planner keeps the axis 10 mrad inside its
    # cone, so the program's own axis stays inside it as well
    orientation_match: float = 10e-3
    wrist_margin: float = 0.15  # [rad] smallest |J5| allowed (J5 = 0 is the wrist singularity)
    min_manipulability: float = 1e-4  # [-] |det J| of the flange Jacobian (advisory)
    query_distance: float = 0.02  # [m] distances above this are reported as "> this" (verify)
    # the clearance certificate refines between samples until its bound is within this [m]
    # of the smallest distance read, or within this share of that distance's margin above its
    # limit if larger (verify.certificate)
    certificate_gap: float = 0.01e-3
    certificate_share: float = 0.1
    # [s] shortest interval the certificate bisects
    certificate_floor: float = 1e-7
    # [m] Drake's narrow phase can read a distance too large (the burr shank's cylinder vs a
    # hub piece: 1.3 mm seen); every clearance/self reading is held to a separating-plane lower
    # bound, and solved exactly where that bound is within this of the class's limit
    # (cell.narrowphase)
    narrowphase_resolve: float = 0.1e-3
    # [m] how far a hub's convex collision pieces may reach past its true surface into a
    # window opening (the hub generator splits any piece reaching further; above the front face
    # it allows 1 mm near the windows, and burr_contact re-reads the true surface where the
    # pieces fail); allowed on top of the depth of cut when the burr head's penetration of the
    # pieces is checked
    collision_model_excess: float = 0.5e-3


def default_tolerances(**overrides: Any) -> Tolerances:
    """The tolerances (the one place they are constructed), with ``overrides`` (e.g. a coarse
    ``dense_step`` for a smoke test)."""
    return Tolerances(**overrides)


@dataclass(frozen=True)
class Recipe:
    """A part's process recipe: process parameters and acceptance thresholds, and where they
    came from (``source``: the recipe file, or "defaults")."""

    process: ProcessParameters = field(default_factory=ProcessParameters)
    acceptance: Acceptance = field(default_factory=Acceptance)
    source: str = "defaults"


@dataclass(frozen=True)
class Config:
    """One run's configuration (see module docstring).

    Attributes:
        scenario: bundled scenario name or YAML path.
        hub: hub name or folder ("" when not tied to a hub).
        recipe: the part's recipe.
        tolerances: acceptance tolerances and sampling.
        robot: arm name (None: the scenario's own arm).
        tool: the burr on the bundled spindle (``drakedeburr.cell.tools.TOOL_VARIANTS``); None:
            the standard burr, and the long-reach one where the standard cannot cut the hub
            (:func:`drakedeburr.plan.planner.plan_hub`).
    """

    scenario: str
    hub: str
    recipe: Recipe
    tolerances: Tolerances
    robot: str | None = None
    tool: str | None = None

    @property
    def process(self) -> ProcessParameters:
        return self.recipe.process

    @property
    def acceptance(self) -> Acceptance:
        return self.recipe.acceptance

    def to_record(self) -> dict:
        """JSON-ready record (what a plan keeps of the configuration it was made with)."""
        return {"scenario": str(self.scenario), "hub": str(self.hub), "robot": self.robot,
                **({"tool": self.tool} if self.tool else {}),
                "recipe_source": self.recipe.source,
                "process": dataclasses.asdict(self.recipe.process),
                "acceptance": dataclasses.asdict(self.recipe.acceptance),
                "tolerances": dataclasses.asdict(self.tolerances)}


@dataclass(frozen=True)
class RecipeKey:
    """What a recipe key may hold: a number in ``unit`` within [lo, hi] (an open end where
    ``lo_open``/``hi_open``); ``optional``: null allowed (an Acceptance threshold not set)."""

    unit: str
    lo: float
    hi: float
    lo_open: bool = False
    hi_open: bool = False
    optional: bool = False
    note: str = ""

    def range_text(self) -> str:
        u = f" {self.unit}" if self.unit not in ("", "-") else ""
        return (f"{self.lo:g} {'<' if self.lo_open else '<='} value "
                f"{'<' if self.hi_open else '<='} {self.hi:g}{u}")

    def check(self, value: Any, where: str, key: str) -> Any:
        if value is None and self.optional:
            return None
        shown = repr(value) if not isinstance(value, (dict, list)) else type(value).__name__
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            kind = "a boolean" if isinstance(value, bool) else type(value).__name__
            raise InputError(f"{where}: {key}: {shown[:60]} is {kind}, not a number; expected "
                             f"{self.range_text()}{self.note}")
        v = float(value)
        bad = not np.isfinite(v) or (v <= self.lo if self.lo_open else v < self.lo) or (
            v >= self.hi if self.hi_open else v > self.hi)
        if bad:
            raise InputError(f"{where}: {key}: {shown[:60]} is out of range; expected "
                             f"{self.range_text()}{self.note}")
        return v


_SPEED_NOTE = " (SI units: m/s, so 150 mm/s is 0.15)"
_M = " (SI units: metres, so 1.5 mm is 1.5e-3)"
K = RecipeKey
#: every key a part's ``process.yaml`` may set, with its unit and allowed range (docs/plan.md
#: lists them). The ranges are physical: a deburring feed is tens to hundreds of mm/s, a
#: robot's TCP a few m/s; lengths of a burr's cut are millimetres.
RECIPE_SCHEMA: dict[str, RecipeKey] = {
    "grinding_speed": K("m/s", 0.0, 1.0, lo_open=True, note=_SPEED_NOTE),
    "window_switch_speed": K("m/s", 0.0, 5.0, lo_open=True, note=_SPEED_NOTE),
    "purge_speed": K("m/s", 0.0, 5.0, lo_open=True, note=_SPEED_NOTE),
    "home_speed": K("m/s", 0.0, 5.0, lo_open=True, note=_SPEED_NOTE),
    "approach_speed": K("m/s", 0.0, 1.0, lo_open=True, note=_SPEED_NOTE),
    "tcp_acceleration": K("m/s^2", 0.0, 50.0, lo_open=True),
    "spindle_air_pressure": K("Pa", 0.0, 1.0e6, lo_open=True, note=" (0.15 MPa is 0.15e6)"),
    "depth_of_cut_large": K("m", 0.0, 5e-3, lo_open=True, note=_M),
    "depth_of_cut_small": K("m", 0.0, 5e-3, lo_open=True, note=_M),
    "w1": K("-", 0.0, 1.0),
    "w2": K("-", 0.0, 1.0),
    "l_max": K("m", 0.0, 0.1, lo_open=True, note=_M),
    "delta_max": K("m", 0.0, 1e-3, lo_open=True, note=_M),
    "key_point_curvature": K("1/m", 0.0, 1e4, lo_open=True),
    "normal_search_radius": K("m", 0.0, 0.05, lo_open=True, note=_M),
    "ransac_threshold": K("m", 0.0, 1e-3, lo_open=True, note=_M),
    "chamfer_width_min": K("m", 0.0, 5e-3, lo_open=True, note=_M),
    "chamfer_width_max": K("m", 0.0, 5e-3, lo_open=True, note=_M),
    # theta boxes: mappings {theta_min, theta_max} [rad], -pi/2 < min < max < pi/2
    "theta_min": K("rad", -0.5 * np.pi, 0.5 * np.pi, lo_open=True, hi_open=True),
    "theta_max": K("rad", -0.5 * np.pi, 0.5 * np.pi, lo_open=True, hi_open=True),
}
#: the keys of ``acceptance:`` (null: not judged)
ACCEPTANCE_SCHEMA: dict[str, RecipeKey] = {
    "speed_band_fraction": K("-", 0.0, 1.0, optional=True),
    "cycle_time_ratio": K("-", 1.0, 100.0, optional=True),
    "theta_box_share": K("-", 0.0, 1.0, optional=True),
    "j6_range_large": K("rad", 0.0, 2 * np.pi, optional=True),
    "j6_range_small": K("rad", 0.0, 2 * np.pi, optional=True),
}
del K


def _value(cls, key: str, value: Any, where: str) -> Any:
    if key.startswith("bounds_"):
        if not isinstance(value, dict) or set(value) != {"theta_min", "theta_max"}:
            shown = sorted(value) if isinstance(value, dict) else type(value).__name__
            raise InputError(f"{where}: {key}: expected {{theta_min: .., theta_max: ..}} [rad] "
                             f"(got {str(shown)[:80]})")
        lo, hi = (RECIPE_SCHEMA[k].check(value[k], where, f"{key}.{k}")
                  for k in ("theta_min", "theta_max"))
        try:
            return OrientationBounds(lo, hi)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{where}: {key}: expected {{theta_min: .., theta_max: ..}} [rad] "
                             f"({exc})") from exc
    schema = ACCEPTANCE_SCHEMA if cls is Acceptance else RECIPE_SCHEMA
    if key in schema:
        return schema[key].check(value, where, key)
    return value


def _fields(cls, data: Any, where: str, skip: tuple[str, ...] = ()) -> dict:
    """The fields of dataclass ``cls`` set by mapping ``data``, unknown keys refused."""
    if not isinstance(data, dict):
        raise InputError(f"{where}: expected a mapping of {cls.__name__} fields, "
                         f"got {type(data).__name__}")
    names = {f.name for f in dataclasses.fields(cls)}
    out = {}
    for key, value in data.items():
        if key in skip:
            continue
        if key not in names:
            raise InputError(f"{where}: unknown {cls.__name__} field {str(key)[:60]!r}; "
                             f"known: {sorted(names)}")
        out[key] = _value(cls, key, value, where)
    return out


def _read_yaml(path: Path) -> Any:
    """A recipe document, bounded and strict (:func:`drakedeburr._io.load_yaml`: size,
    encoding, duplicate keys, aliases); an empty one is {}."""
    from drakedeburr._io import load_yaml

    try:
        return load_yaml(path, "recipe") or {}
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror})") from exc


def _build(cls, kwargs: dict, where: str):
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: {exc}") from exc


def dataclass_from_yaml(cls, path: str | Path):
    """Instantiate dataclass ``cls`` from a YAML mapping, overriding its defaults.

    Unknown keys are an error that names the file and the key.
    """
    path = Path(path)
    return _build(cls, _fields(cls, _read_yaml(path), str(path)), str(path))


def load_recipe(folder: str | Path | None = None, **process_overrides: Any) -> Recipe:
    """A part's recipe: the defaults (source Tab. 7 and the theta boxes of its section 2.3),
    then ``process.yaml`` in the part's folder when it has one (ProcessParameters fields, and
    an optional ``acceptance:`` mapping of :class:`Acceptance` fields), then
    ``process_overrides`` that are not None (e.g. a command-line grinding speed).

    A part's recipe lives beside its model because it belongs to the part; the planner and the
    verifier both read it from the :class:`Config`.

    Raises:
        InputError: the file is malformed (names the file and the field).
    """
    kwargs: dict = {}
    acceptance = Acceptance()
    source = "defaults"
    if folder is not None:
        f = Path(folder) / PROCESS_FILE
        if f.is_file():
            data = _read_yaml(f)
            kwargs = _fields(ProcessParameters, data, str(f), skip=("acceptance",))
            if isinstance(data, dict) and "acceptance" in data:
                acc = _fields(Acceptance, data["acceptance"] or {}, f"{f}: acceptance")
                acceptance = _build(Acceptance, acc, f"{f}: acceptance")
            source = str(f)
            lo, hi = (kwargs.get(k, getattr(ProcessParameters, k))
                      for k in ("chamfer_width_min", "chamfer_width_max"))
            if lo > hi:
                raise InputError(f"{f}: chamfer_width_min {lo:g} m is more than "
                                 f"chamfer_width_max {hi:g} m")
    given = {k: v for k, v in process_overrides.items() if v is not None}
    kwargs.update(given)
    where = source + (f" with {sorted(given)} given" if given else "")
    return Recipe(process=_build(ProcessParameters, kwargs, where), acceptance=acceptance,
                  source=where)


def process_parameters(folder: str | Path | None = None, **overrides: Any) -> ProcessParameters:
    """The process parameters of a part's recipe (:func:`load_recipe`)."""
    return load_recipe(folder, **overrides).process


def load_config(scenario: str, hub: str | Path, *,
                robot: str | None = None, tool: str | None = None,
                tolerances: Tolerances | None = None,
                recipe: Recipe | None = None, **process_overrides: Any) -> Config:
    """Load a run's configuration once: the hub's recipe (``process.yaml`` in its folder, with
    ``process_overrides``, or ``recipe`` as given) and the tolerances.

    Args:
        scenario: bundled scenario name or YAML path.
        hub: bundled hub name or folder.
        robot: arm name (None: the scenario's own).
        tool: burr variant (None: the standard, long reach where it cannot cut; ``Config``).
        tolerances: replaces the default tolerances (e.g. coarse sampling for a smoke test).
        recipe: use this recipe instead of reading the hub's (e.g. the one a plan recorded).
        process_overrides: ProcessParameters fields over the hub's recipe (None: not given).
    """
    from drakedeburr.resources import resolve_hub_dir

    if recipe is None:
        recipe = load_recipe(resolve_hub_dir(hub), **process_overrides)
    elif any(v is not None for v in process_overrides.values()):
        recipe = dataclasses.replace(recipe, process=dataclasses.replace(
            recipe.process, **{k: v for k, v in process_overrides.items() if v is not None}))
    return Config(scenario=str(scenario), hub=str(hub), recipe=recipe,
                  tolerances=tolerances or default_tolerances(), robot=robot, tool=tool)


def recipe_from_record(record: dict, where: str = "plan") -> Recipe:
    """The recipe a plan recorded (:meth:`Config.to_record`)."""
    proc = _fields(ProcessParameters, dict(record.get("process") or {}), f"{where}: process")
    acc = _fields(Acceptance, dict(record.get("acceptance") or {}), f"{where}: acceptance")
    return Recipe(process=_build(ProcessParameters, proc, where),
                  acceptance=_build(Acceptance, acc, where),
                  source=str(record.get("recipe_source", where)))
