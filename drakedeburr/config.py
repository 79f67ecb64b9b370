"""Process numbers and tolerances, each defined once (SPEC.md §S3, Tab. 7 of the source).

Frozen dataclasses; load overrides from YAML with :func:`load_config`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from drakedeburr.errors import InputError

__all__ = ["ProcessParameters", "Tolerances", "OrientationBounds", "load_config",
           "process_parameters", "PROCESS_FILE"]

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


@dataclass(frozen=True)
class ProcessParameters:
    """Deburring process (source Tab. 7). SI units."""

    grinding_speed: float = 0.150  # [m/s] tool speed along a window edge
    window_switch_speed: float = 0.450  # [m/s] moves between windows
    purge_speed: float = 0.600  # [m/s]
    home_speed: float = 0.600  # [m/s] return home
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


@dataclass(frozen=True)
class Tolerances:
    """Acceptance tolerances used by planning and verification. SI units."""

    path_deviation: float = 0.05e-3  # [m] tool point vs commanded Cartesian path
    edge_deviation: float = 0.17e-3  # [m] tool point vs true edge (delta_max + 0.05 mm)
    min_clearance: float = 2e-3  # [m] except the burr contact pair
    speed_band: float = 0.05  # [-] +-5 % of the grinding speed
    speed_band_fraction: float = 0.95  # [-] share of cutting inside the band
    # [-] every slow stretch inside a cut has a joint at this share of its acceleration or
    # speed limit (advisory; the planner times to 90 % of the accelerations, 95 % of the speeds)
    forced_slowdown: float = 0.85
    cone_slack: float = 1e-6  # [rad] numerical slack on cone checks
    dense_step: float = 0.5e-3  # [m] tool travel between dense re-check samples
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
    cycle_time_ratio: float = 1.05  # [-] cycle time / physical limit target (advisory)
    j6_range_large: float = 0.3491  # [rad] 20 deg: paper's J6 range on large windows (advisory)
    j6_range_small: float = 0.1745  # [rad] 10 deg: on small windows (advisory)
    query_distance: float = 0.02  # [m] distances above this are reported as "> this" (verify)
    # [m] how far a hub's convex collision pieces may reach past its true surface (the hub
    # generator splits any piece reaching > 0.5 mm into a window opening); allowed on top of
    # the depth of cut when the burr head's penetration of the pieces is checked
    collision_model_excess: float = 0.5e-3


def _overrides(cls, path: Path) -> dict:
    """The fields of dataclass ``cls`` set by the YAML mapping in ``path``, validated."""
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        raise InputError(f"{path}: not valid YAML ({exc})") from exc
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a mapping of {cls.__name__} fields, "
                         f"got {type(data).__name__}")
    names = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for key, value in data.items():
        if key not in names:
            raise InputError(f"{path}: unknown {cls.__name__} field {key!r}; "
                             f"known: {sorted(names)}")
        if key.startswith("bounds_"):
            try:
                value = OrientationBounds(**value)
            except (TypeError, ValueError) as exc:
                raise InputError(f"{path}: {key}: expected {{theta_min: .., theta_max: ..}} "
                                 f"[rad] ({exc})") from exc
        kwargs[key] = value
    return kwargs


def load_config(cls, path: str | Path):
    """Instantiate dataclass ``cls`` from a YAML mapping, overriding its defaults.

    Unknown keys are an error that names the file and the key.
    """
    path = Path(path)
    return cls(**_overrides(cls, path))


def process_parameters(folder: str | Path | None = None, **overrides) -> ProcessParameters:
    """One part's process parameters: the defaults (source Tab. 7 and the theta boxes of its
    section 2.3), then ``process.yaml`` in the part's folder when it has one, then
    ``overrides`` (e.g. a command-line grinding speed).

    A part's recipe lives beside its model because it belongs to the part: a deep-dish hub
    needs a smaller tilt than the source's flat-faced hub so the spindle body clears the dish
    (``models/hubs/h5_deepdish/process.yaml``). The planner and the verifier both read it.

    Raises:
        InputError: the file is malformed (names the file and the field).
    """
    kwargs = {}
    if folder is not None:
        f = Path(folder) / PROCESS_FILE
        if f.is_file():
            kwargs = _overrides(ProcessParameters, f)
    kwargs.update({k: v for k, v in overrides.items() if v is not None})
    return ProcessParameters(**kwargs)
