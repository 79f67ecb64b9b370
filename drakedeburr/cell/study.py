"""Cell-design study (issue 46): spindle mounts and fixture heights compared by the planned
cycle and the wrist travel, every required verification check passing.

A candidate cell is the bundled tool-in-hand scenario with two changes a cell builder can make:

* **the spindle mount**: the bundled floating spindle (its bracket holds the burr axis
  ``FLOATING_SPINDLE.mount_angle`` = 45 deg from the flange axis +Z_F, tilted about +Y_F) on a
  wedge adapter plate between the flange and the spindle's own adapter plate. The wedge turns
  the spindle model about +Y_F by ``mount_angle - 45 deg`` and stands it off along +Z_F by
  ``offset`` plus what the tilted plate needs to clear the flange face (its radius times the
  sine of the wedge angle). The mount is the weld ``robot::flange -> spindle::spindle``'s
  ``X_PC`` in the scenario file, so the file alone (and the cell fingerprint, which hashes it)
  says which mount a plan was made with;
* or **the coaxial straight bracket** (``coaxial``): the spindle turned so its burr axis is the
  flange axis +Z_F through the flange centre (:func:`drakedeburr.cell.tools.coaxial_X_FM`),
  the body's rear on the bracket's flange plate, the bracket a part of its own (model
  ``coaxial_bracket``, welded to the flange, collision geometry like every part) and the
  spindle model the bundled one without its 45 deg bracket (``floating_spindle_coaxial``).
  A spin about the burr axis is then J6 alone; a wedge at 0 deg leaves the axis parallel to
  the flange axis but 102.5 mm off it (the wedge turns the spindle about the flange centre);
* **the fixture height**: the chuck's weld ``world -> fixture::chuck_top`` moved by
  ``fixture_shift`` along +Z_W (the hub face with it).

Each candidate is written as a scenario file (the same model-directives format as
``models/scenarios/*.yaml``), planned and verified by an evaluator the caller passes (the
``cell study`` command plans with :func:`drakedeburr.plan.plan_hub` and verifies with
:func:`drakedeburr.verify.verify_plan`: this stage does not reach into later ones), and ranked:
candidates whose plan passes every required check first, then by cycle time, then by the worst
window's J4 + J5 + J6 travel, then by name (:func:`rank_key`). A candidate that fails a required
check is listed with the failing checks, never recommended.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from drakedeburr.cell.tools import (
    COAXIAL_BRACKET_URL,
    COAXIAL_SPINDLE_URL,
    FLOATING_SPINDLE,
    coaxial_X_FM,
)
from drakedeburr.errors import InputError

__all__ = ["MountCandidate", "candidate_grid", "quick_grid", "write_candidate_scenario",
           "candidate_from_scenario", "coaxial_candidates", "rank_key", "rank_results", "run_study",
           "SPINDLE_WELD", "FIXTURE_WELD", "BRACKET_MODEL"]

log = logging.getLogger(__name__)

#: the welds a candidate changes (parent, child) in the tool-in-hand scenario
SPINDLE_WELD = ("robot::flange", "spindle::spindle")
FIXTURE_WELD = ("world", "fixture::chuck_top")
#: the coaxial bracket's model instance (welded robot::flange -> coaxial_bracket::bracket)
BRACKET_MODEL = "coaxial_bracket"
BASE_SCENARIO = "tool_in_hand"
#: ranking resolution: cycles within 10 ms and travels within 0.1 deg count as equal
CYCLE_QUANTUM_S = 0.01
TRAVEL_QUANTUM_DEG = 0.1


@dataclass(frozen=True)
class MountCandidate:
    """One cell design. SI units.

    Attributes:
        mount_angle: burr axis +Z_T from the flange axis +Z_F, about +Y_F [rad].
        offset: stand-off of the wedge adapter along +Z_F beyond the least it needs [m].
        fixture_shift: the chuck (and the hub face) moved along +Z_W from the scenario's [m].
        coaxial: the coaxial straight bracket in place of a wedge (``mount_angle`` 0, burr axis
            on the flange axis; ``offset`` 0: the bracket has one length).
    """

    mount_angle: float = FLOATING_SPINDLE.mount_angle
    offset: float = 0.0
    fixture_shift: float = 0.0
    coaxial: bool = False

    def __post_init__(self) -> None:
        if self.coaxial and (self.mount_angle != 0.0 or self.offset != 0.0):
            raise InputError("the coaxial bracket has mount angle 0 and no offset, got "
                             f"{math.degrees(self.mount_angle):.1f} deg, "
                             f"{self.offset * 1e3:.1f} mm")
        if not 0.0 <= self.mount_angle <= math.pi / 2:
            raise InputError(f"mount angle must be within [0, 90] deg, got "
                             f"{math.degrees(self.mount_angle):.1f} deg")
        if not 0.0 <= self.offset <= 0.2:
            raise InputError(f"mount offset must be within [0, 200] mm, got "
                             f"{self.offset * 1e3:.1f} mm")
        if abs(self.fixture_shift) > 0.2:
            raise InputError(f"fixture height change must be within +-200 mm, got "
                             f"{self.fixture_shift * 1e3:.1f} mm")

    @property
    def name(self) -> str:
        """``m45_o000_f+000``: mount angle [deg], offset [mm], fixture shift [mm];
        ``coax_f+000``: the coaxial bracket, fixture shift [mm]."""
        if self.coaxial:
            return f"coax_f{round(self.fixture_shift * 1e3):+04d}"
        return (f"m{round(math.degrees(self.mount_angle)):02d}_o{round(self.offset * 1e3):03d}"
                f"_f{round(self.fixture_shift * 1e3):+04d}")

    @property
    def wedge(self) -> float:
        """The wedge adapter's angle: the turn of the bundled 45 deg spindle about +Y_F [rad]."""
        return self.mount_angle - FLOATING_SPINDLE.mount_angle

    def X_FM(self) -> np.ndarray:
        """(4, 4) the spindle model frame M in the flange frame F [m] (identity: the bundled
        mount)."""
        if self.coaxial:
            return coaxial_X_FM(FLOATING_SPINDLE)
        d = self.wedge
        c, s = math.cos(d), math.sin(d)
        X = np.eye(4)
        X[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
        X[2, 3] = self.offset + FLOATING_SPINDLE.plate_radius * abs(s)
        return X

    def is_bundled(self) -> bool:
        """The scenario's own cell (no wedge, no offset, fixture where it is)."""
        return (not self.coaxial and abs(self.wedge) < 1e-12 and self.offset == 0.0
                and self.fixture_shift == 0.0)


def candidate_grid(angles_deg: Sequence[float], offsets_mm: Sequence[float],
                   fixture_shifts_mm: Sequence[float]) -> list[MountCandidate]:
    """Every combination, fixture height outermost, then offset, then angle, each in the order
    given (the ranking does not depend on it; a study cut short has compared the mounts at the
    first height)."""
    return [MountCandidate(math.radians(a), o * 1e-3, f * 1e-3)
            for f in fixture_shifts_mm for o in offsets_mm for a in angles_deg]


def coaxial_candidates(fixture_shifts_mm: Sequence[float]) -> list[MountCandidate]:
    """The coaxial bracket at each fixture height [mm], in the order given."""
    return [MountCandidate(0.0, 0.0, f * 1e-3, coaxial=True) for f in fixture_shifts_mm]


def quick_grid() -> list[MountCandidate]:
    """The test grid: the bundled 45 deg mount and a 60 deg one."""
    return candidate_grid((45.0, 60.0), (0.0,), (0.0,))


def _rigid(X: np.ndarray):
    from pydrake.common.schema import Transform
    from pydrake.math import RigidTransform, RotationMatrix

    return Transform(RigidTransform(RotationMatrix(np.asarray(X[:3, :3], float)),
                                    np.asarray(X[:3, 3], float)))


def _weld(items, parent_child: tuple[str, str], where: Path):
    found = [d.add_weld for d in items if d.add_weld is not None
             and (d.add_weld.parent, d.add_weld.child) == parent_child]
    if len(found) != 1:
        raise InputError(f"{where}: expected one weld {parent_child[0]} -> {parent_child[1]}, "
                         f"found {len(found)}")
    return found[0]


def _X(transform) -> np.ndarray:
    return transform.GetDeterministicValue().GetAsMatrix4()


def _spindle_model(items, where: Path):
    name = SPINDLE_WELD[1].split("::")[0]
    found = [d.add_model for d in items if d.add_model is not None and d.add_model.name == name]
    if len(found) != 1:
        raise InputError(f"{where}: expected one model {name!r}, found {len(found)}")
    return found[0]


def _bracket_directives() -> list:
    from pydrake.multibody.parsing import AddModel, AddWeld, ModelDirective

    return [ModelDirective(add_model=AddModel(name=BRACKET_MODEL, file=COAXIAL_BRACKET_URL)),
            ModelDirective(add_weld=AddWeld(parent=SPINDLE_WELD[0],
                                            child=f"{BRACKET_MODEL}::bracket"))]


def write_candidate_scenario(candidate: MountCandidate, path: str | Path,
                             base: str | Path = BASE_SCENARIO, note: str = "") -> Path:
    """Write ``base`` with ``candidate``'s mount and fixture height as a scenario file.

    Args:
        candidate: the design.
        path: the YAML file to write (its folder is created).
        base: the scenario it starts from (bundled name or file; the tool-in-hand cell).
        note: lines for the header comment (e.g. the candidate's figures).

    Raises:
        InputError: ``base`` lacks the spindle weld or the fixture weld.
    """
    from pydrake.common.yaml import yaml_dump_typed
    from pydrake.multibody.parsing import LoadModelDirectives

    from drakedeburr._io import atomic_write_text
    from drakedeburr.resources import scenario_path

    base_file = scenario_path(base)
    directives = LoadModelDirectives(str(base_file))
    items = list(directives.directives)
    spindle = _weld(items, SPINDLE_WELD, base_file)
    X_PC = _X(spindle.X_PC) if spindle.X_PC is not None else np.eye(4)
    spindle.X_PC = _rigid(X_PC @ candidate.X_FM())
    fixture = _weld(items, FIXTURE_WELD, base_file)
    X_WC = _X(fixture.X_PC) if fixture.X_PC is not None else np.eye(4)
    X_WC[2, 3] += candidate.fixture_shift
    fixture.X_PC = _rigid(X_WC)
    if candidate.coaxial:
        _spindle_model(items, base_file).file = COAXIAL_SPINDLE_URL
        items += _bracket_directives()
    directives.directives = items
    mount = (f"coaxial straight bracket (burr axis on the flange axis, the bracket model "
             f"{BRACKET_MODEL} welded to {SPINDLE_WELD[0]})" if candidate.coaxial else
             f"spindle mount {math.degrees(candidate.mount_angle):.1f} deg (bundled 45 deg "
              f"spindle on a {math.degrees(candidate.wedge):+.1f} deg wedge adapter, offset "
              f"{candidate.offset * 1e3:.0f} mm)")
    header = [f"Cell-design study candidate {candidate.name} (drakedeburr.cell.study), from "
              f"{base_file.name}:",
              f"{mount}, fixture {candidate.fixture_shift * 1e3:+.0f} mm",
              *[line for line in note.splitlines() if line.strip()]]
    text = "".join(f"# {line}\n" for line in header) + yaml_dump_typed(directives)
    return atomic_write_text(Path(path), text)


def candidate_from_scenario(path: str | Path, base: str | Path = BASE_SCENARIO
                            ) -> MountCandidate:
    """Read a candidate back from a scenario file written by :func:`write_candidate_scenario`
    (the welds compared with ``base``'s).

    Raises:
        InputError: a weld is missing, or the spindle weld is not a turn about +Y_F with a
            stand-off along +Z_F.
    """
    from pydrake.multibody.parsing import LoadModelDirectives

    from drakedeburr.resources import scenario_path

    path, base_file = Path(path), scenario_path(base)
    got = list(LoadModelDirectives(str(path)).directives)
    ref = list(LoadModelDirectives(str(base_file)).directives)

    def pose(items, pc, where):
        w = _weld(items, pc, where)
        return _X(w.X_PC) if w.X_PC is not None else np.eye(4)

    X_FM = np.linalg.inv(pose(ref, SPINDLE_WELD, base_file)) @ pose(got, SPINDLE_WELD, path)
    shift = float(pose(got, FIXTURE_WELD, path)[2, 3] - pose(ref, FIXTURE_WELD, base_file)[2, 3])
    brackets = [d.add_model for d in got if d.add_model is not None
                and d.add_model.name == BRACKET_MODEL]
    if brackets:
        if not (len(brackets) == 1 and brackets[0].file == COAXIAL_BRACKET_URL
                and _spindle_model(got, path).file == COAXIAL_SPINDLE_URL
                and np.allclose(X_FM, coaxial_X_FM(FLOATING_SPINDLE), atol=1e-9)):
            raise InputError(f"{path}: the {BRACKET_MODEL} model is not the coaxial bracket "
                             "holding the spindle at drakedeburr.cell.tools.coaxial_X_FM")
        _weld(got, (SPINDLE_WELD[0], f"{BRACKET_MODEL}::bracket"), path)
        return MountCandidate(0.0, 0.0, round(shift, 9), coaxial=True)
    R, p = X_FM[:3, :3], X_FM[:3, 3]
    wedge = math.atan2(R[0, 2], R[0, 0])
    if not (np.allclose(R[:, 1], [0, 1, 0], atol=1e-9) and abs(p[0]) < 1e-9
            and abs(p[1]) < 1e-9):
        raise InputError(f"{path}: the spindle weld is not a wedge about +Y_F with a stand-off "
                         "along +Z_F")
    offset = float(p[2] - FLOATING_SPINDLE.plate_radius * abs(math.sin(wedge)))
    return MountCandidate(FLOATING_SPINDLE.mount_angle + wedge, round(offset, 9), round(shift, 9))


def rank_key(result: dict) -> tuple:
    """Passing first; then cycle [s] in steps of ``CYCLE_QUANTUM_S``; then the worst window's
    J4 + J5 + J6 travel [deg] in steps of ``TRAVEL_QUANTUM_DEG``; then the candidate's name."""
    ok = bool(result.get("passed"))
    cycle = result.get("cycle_s")
    travel = result.get("worst_wrist_travel_deg")
    return (not ok,
            math.inf if cycle is None else round(cycle / CYCLE_QUANTUM_S),
            math.inf if travel is None else round(travel / TRAVEL_QUANTUM_DEG),
            result["name"])


def rank_results(results: list[dict]) -> list[dict]:
    """``results`` in rank order, each with its ``rank`` (1 = recommended when it passed)."""
    ordered = sorted(results, key=rank_key)
    return [{**r, "rank": i + 1} for i, r in enumerate(ordered)]


Evaluator = Callable[[MountCandidate, Path], dict]


def run_study(candidates: Sequence[MountCandidate], evaluate: Evaluator, out_dir: str | Path,
              base: str | Path = BASE_SCENARIO) -> dict:
    """Write, evaluate and rank every candidate; write the recommended cell.

    Args:
        candidates: the designs (names must be distinct).
        evaluate: ``(candidate, scenario file) -> figures``: ``passed`` (every required check
            and no planning failure), ``failing`` (names of the failing required checks),
            ``cycle_s``, ``worst_wrist_travel_deg`` and any further figures.
        out_dir: folder for ``candidates/NAME.yaml`` and ``recommended.yaml``.
        base: the scenario the candidates start from.

    Returns:
        ``{"ranking": [...], "recommended": name or None, "recommended_scenario": path or
        None}``.
    """
    names = [c.name for c in candidates]
    if len(set(names)) != len(names):
        raise InputError(f"cell study: candidate names repeat: {names}")
    out = Path(out_dir)
    results = []
    for i, c in enumerate(candidates):
        file = write_candidate_scenario(c, out / "candidates" / f"{c.name}.yaml", base)
        log.info("cell study %d/%d: %s", i + 1, len(candidates), c.name)
        figures = dict(evaluate(c, file))
        row = {"name": c.name, **{k: v if isinstance(v, bool) else float(v)
                                      for k, v in asdict(c).items()},
               "scenario": str(file), **figures}
        log.info("cell study %d/%d: %s %s, cycle %s s, worst wrist travel %s deg", i + 1,
                 len(candidates), c.name, "passed" if row.get("passed") else
                 f"FAILED {', '.join(row.get('failing') or ['?'])}", row.get("cycle_s"),
                 row.get("worst_wrist_travel_deg"))
        results.append(row)
    ranking = rank_results(results)
    best = ranking[0] if ranking and ranking[0].get("passed") else None
    rec = None
    if best is not None:
        c = next(c for c in candidates if c.name == best["name"])
        note = (f"recommended by the cell study over {len(candidates)} candidates: cycle "
                f"{best['cycle_s']:.3f} s, worst window J4+J5+J6 travel "
                f"{best['worst_wrist_travel_deg']:.1f} deg")
        rec = str(write_candidate_scenario(c, out / "recommended.yaml", base, note))
    return {"ranking": ranking, "recommended": None if best is None else best["name"],
            "recommended_scenario": rec}
