"""Arms as data: one YAML file per arm (``--robot FILE`` wherever ``--robot NAME`` is taken).

The registry's arms are such files (``models/robots/<name>.yaml``, shipped with the package);
a cell engineer copies one, changes what differs on their variant, cites where each number
comes from, and passes the file. Schema ``drakedeburr.arm/1``::

    schema: drakedeburr.arm/1
    name: kr20_r1810            # identifier: letters, digits, _ (the registry's --robot NAME)
    title: KUKA KR 20 R1810-2
    vendor: KUKA                # ABB | KUKA | FANUC
    controller: kuka            # abb | kuka | fanuc: configuration data and program language
    controller_model: KR C4
    program_language: krl       # must be the controller's (rapid | krl | ls)
    opw:                        # Brandstoetter et al. 2014; q_opw = q * sign - offset
      a1: 0.160  a2: -0.150  b: 0.0  c1: 0.520  c2: 0.780  c3: 0.860  c4: 0.153   # [m]
      offsets_deg: [0, -90, 0, 0, 0, 0]       # or offsets_rad
      sign_corrections: [-1, 1, 1, -1, 1, -1]
    joints:                     # model joints (module docstring of robots.spec)
      lower_deg: [...]          # or lower_rad; the same for upper, speed (speed_deg_s or
      upper_deg: [...]          #   speed_rad_s) and acceleration_rad_s2
      speed_deg_s: [...]
      acceleration_rad_s2: [...]
      acceleration_note: "ASSUMED: ..."
    j23_coupling: 0             # controller J3 = q3 - j23_coupling * q2 (FANUC: 1)
    robot_frame_m: [0, 0, 0]    # the controller's robot frame R in the mounting face B
    payload:
      mass_kg: 20               # rated payload: tool + gripper + part
      wrist_moment_Nm: [J4, J5, J6]      # optional, where the vendor publishes them
      wrist_inertia_kgm2: [J4, J5, J6]   # optional
    flange: "..."
    model: package://drakedeburr/robots/kr20_r1810_2.sdf   # or a path relative to this file
    mounts:                     # optional: where it stands in the bundled cells
      workpiece_in_hand: {base_m: [x, y, z], home_rad: [...], pedestal: package://..., study: ""}
    conventions: "..."
    sources:                    # a citation for each group of values (required keys:
      opw: "..."                #   opw, joints, payload; wrist_moment_Nm / wrist_inertia_kgm2
      joints: "..."             #   when given)
      payload: "..."

Every field is checked; a bad one raises :class:`~drakedeburr.errors.InputError` naming the
file, the field and what is wrong (the CLI prints that one line and exits 2).
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np

from drakedeburr.errors import InputError
from drakedeburr.robots.opw import OpwParameters
from drakedeburr.robots.spec import CONTROLLERS, CellMount, RobotSpec

__all__ = ["SCHEMA", "load_arm", "is_arm_file", "arm_file_text", "loaded_spec_for"]

SCHEMA = "drakedeburr.arm/1"
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
_VENDORS = {"abb": "ABB", "kuka": "KUKA", "fanuc": "FANUC"}
_TOP_KEYS = {"schema", "name", "title", "vendor", "controller", "controller_model",
             "program_language", "opw", "joints", "j23_coupling", "robot_frame_m", "payload",
             "flange", "model", "mounts", "conventions", "sources"}
_REQUIRED_SOURCES = ("opw", "joints", "payload")


def is_arm_file(name) -> bool:
    """True when ``name`` names an arm file (``*.yaml`` / ``*.yml``), not a registry name."""
    return isinstance(name, str | Path) and Path(str(name)).suffix.lower() in (".yaml", ".yml")


class _Doc:
    """One arm file's mapping with field-named errors."""

    def __init__(self, path: Path, data: dict, check_model: bool = True):
        self.path, self.data, self.check_model = path, data, check_model

    def fail(self, field: str, what: str):
        raise InputError(f"{self.path}: field {field}: {what}")

    def get(self, mapping: dict, key: str, field: str, required: bool = True):
        if key not in mapping or mapping[key] is None:
            if required:
                self.fail(field, "missing")
            return None
        return mapping[key]

    def text(self, mapping: dict, key: str, field: str, required: bool = True) -> str:
        v = self.get(mapping, key, field, required)
        if v is None:
            return ""
        if not isinstance(v, str) or not v.strip() or "\n" in v.strip():
            self.fail(field, f"expected one line of text, got {v!r}")
        return v.strip()

    def number(self, mapping: dict, key: str, field: str, *, positive=False) -> float:
        v = self.get(mapping, key, field)
        if isinstance(v, bool) or not isinstance(v, int | float) or not np.isfinite(v):
            self.fail(field, f"expected a finite number, got {v!r}")
        if positive and v <= 0:
            self.fail(field, f"must be > 0, got {v!r}")
        return float(v)

    def vector(self, mapping: dict, key: str, field: str, n: int, *, required=True,
               positive=False) -> np.ndarray | None:
        v = self.get(mapping, key, field, required)
        if v is None:
            return None
        if not isinstance(v, list) or len(v) != n or not all(
                isinstance(x, int | float) and not isinstance(x, bool) and np.isfinite(x)
                for x in v):
            self.fail(field, f"expected a list of {n} finite numbers, got {v!r}")
        arr = np.array(v, dtype=float)
        if positive and np.any(arr <= 0):
            self.fail(field, f"every value must be > 0, got {v!r}")
        return arr

    def angles(self, mapping: dict, stem: str, field: str, *, per_s: str = "",
               required=True, positive=False) -> np.ndarray | None:
        """``<stem>_deg<per_s>`` or ``<stem>_rad<per_s>`` (exactly one) -> radians."""
        keys = [f"{stem}_deg{per_s}", f"{stem}_rad{per_s}"]
        given = [k for k in keys if mapping.get(k) is not None]
        if len(given) != 1:
            if not given and not required:
                return None
            self.fail(f"{field}.{stem}", f"give exactly one of {' or '.join(keys)}")
        v = self.vector(mapping, given[0], f"{field}.{given[0]}", 6, positive=positive)
        return np.deg2rad(v) if "_deg" in given[0] else v

    def section(self, key: str, *, required=True) -> dict:
        v = self.get(self.data, key, key, required)
        if v is None:
            return {}
        if not isinstance(v, dict):
            self.fail(key, f"expected a mapping, got {type(v).__name__}")
        return v


def _opw(doc: _Doc, title: str) -> OpwParameters:
    m = doc.section("opw")
    unknown = set(m) - {"a1", "a2", "b", "c1", "c2", "c3", "c4", "offsets_deg", "offsets_rad",
                        "sign_corrections", "name"}
    if unknown:
        doc.fail(f"opw.{sorted(unknown)[0]}", "unknown key")
    geo = {k: doc.number(m, k, f"opw.{k}") for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")}
    for k in ("c2", "c3"):
        if geo[k] <= 0:
            doc.fail(f"opw.{k}", f"a link length must be > 0, got {geo[k]}")
    offsets = doc.angles(m, "offsets", "opw", required=False)
    signs = doc.vector(m, "sign_corrections", "opw.sign_corrections", 6)
    if not np.all(np.isin(signs, (-1, 1))):
        doc.fail("opw.sign_corrections", f"each must be 1 or -1, got {signs.tolist()}")
    name = doc.text(m, "name", "opw.name", required=False) or title
    return OpwParameters(**geo, offsets=tuple(float(v) for v in (
        np.zeros(6) if offsets is None else offsets)),
        sign_corrections=tuple(int(v) for v in signs), name=name)


def _joints(doc: _Doc):
    m = doc.section("joints")
    lower = doc.angles(m, "lower", "joints")
    upper = doc.angles(m, "upper", "joints")
    bad = np.flatnonzero(lower >= upper)
    if bad.size:
        doc.fail("joints", f"joint {bad[0] + 1}: lower limit {lower[bad[0]]:.6g} rad is not "
                 f"below the upper {upper[bad[0]]:.6g} rad")
    speed = doc.angles(m, "speed", "joints", per_s="_s", positive=True)
    accel = doc.vector(m, "acceleration_rad_s2", "joints.acceleration_rad_s2", 6, positive=True)
    note = doc.text(m, "acceleration_note", "joints.acceleration_note")
    return lower, upper, speed, accel, note


def _payload(doc: _Doc):
    m = doc.section("payload")
    mass = doc.number(m, "mass_kg", "payload.mass_kg", positive=True)
    moment = doc.vector(m, "wrist_moment_Nm", "payload.wrist_moment_Nm", 3, required=False,
                        positive=True)
    inertia = doc.vector(m, "wrist_inertia_kgm2", "payload.wrist_inertia_kgm2", 3,
                         required=False, positive=True)
    return mass, moment, inertia


def _model_url(doc: _Doc) -> str:
    v = doc.text(doc.data, "model", "model")
    if v.startswith("package://"):
        from drakedeburr.resources import resolve_package_url

        try:
            target = resolve_package_url(v)
        except ValueError as exc:
            doc.fail("model", str(exc))
    else:
        target = (doc.path.parent / v).resolve()
        v = target.as_uri()
    if doc.check_model and not target.is_file():
        doc.fail("model", f"no model file {target}")
    return v


def _mounts(doc: _Doc) -> tuple:
    m = doc.section("mounts", required=False)
    out = []
    for cell, d in m.items():
        field = f"mounts.{cell}"
        if not isinstance(d, dict):
            doc.fail(field, "expected a mapping with base_m, home_rad, pedestal")
        X = np.eye(4)
        X[:3, 3] = doc.vector(d, "base_m", f"{field}.base_m", 3)
        home = doc.vector(d, "home_rad", f"{field}.home_rad", 6)
        pedestal = doc.text(d, "pedestal", f"{field}.pedestal")
        if not pedestal.startswith("package://"):
            pedestal = (doc.path.parent / pedestal).resolve().as_uri()
        out.append((str(cell), CellMount(X_WB=X, q_home=home, pedestal_url=pedestal,
                                         study=doc.text(d, "study", f"{field}.study",
                                                        required=False))))
    return tuple(out)


def _sources(doc: _Doc, payload) -> tuple[str, ...]:
    m = doc.section("sources")
    need = list(_REQUIRED_SOURCES)
    need += [k for k, v in zip(("wrist_moment_Nm", "wrist_inertia_kgm2"), payload[1:],
                               strict=True) if v is not None]
    for k in need:
        doc.text(m, k, f"sources.{k}")
    return tuple(f"{k}: {doc.text(m, k, f'sources.{k}')}" for k in m)


def _spec_from_doc(doc: _Doc) -> RobotSpec:
    d = doc.data
    unknown = set(d) - _TOP_KEYS
    if unknown:
        doc.fail(sorted(unknown)[0], "unknown key (schema drakedeburr.arm/1)")
    if d.get("schema") != SCHEMA:
        doc.fail("schema", f"expected {SCHEMA!r}, got {d.get('schema')!r}")
    name = doc.text(d, "name", "name")
    if not _NAME.fullmatch(name):
        doc.fail("name", f"{name!r} is not an identifier (a letter, then letters, digits, _; "
                 "at most 32)")
    controller = doc.text(d, "controller", "controller").lower()
    if controller not in CONTROLLERS:
        doc.fail("controller", f"{controller!r} is not one of {', '.join(CONTROLLERS)}")
    vendor = doc.text(d, "vendor", "vendor")
    if vendor.upper() != _VENDORS[controller]:
        doc.fail("vendor", f"{vendor!r} does not make a {controller} controller "
                 f"({_VENDORS[controller]})")
    language = doc.text(d, "program_language", "program_language").lower()
    if language != CONTROLLERS[controller]:
        doc.fail("program_language", f"a {controller} controller runs "
                 f"{CONTROLLERS[controller]}, not {language!r}")
    title = doc.text(d, "title", "title")
    lower, upper, speed, accel, note = _joints(doc)
    payload = _payload(doc)
    j23 = doc.number(d, "j23_coupling", "j23_coupling")
    if j23 not in (0.0, 1.0):
        doc.fail("j23_coupling", f"expected 0 (ABB, KUKA) or 1 (FANUC), got {j23}")
    X_BR = np.eye(4)
    X_BR[:3, 3] = doc.vector(d, "robot_frame_m", "robot_frame_m", 3)
    return RobotSpec(
        name=name, title=title, vendor=_VENDORS[controller], controller=controller,
        controller_model=doc.text(d, "controller_model", "controller_model"),
        opw=_opw(doc, title), q_lower=lower, q_upper=upper, v_max=speed, a_max=accel,
        a_max_note=note, j23_coupling=j23, X_BR=X_BR, payload_kg=payload[0],
        flange=doc.text(d, "flange", "flange"), model_url=_model_url(doc),
        mounts=_mounts(doc), conventions=doc.text(d, "conventions", "conventions",
                                                   required=False),
        sources=_sources(doc, payload),
        wrist_moment_Nm=None if payload[1] is None else tuple(payload[1]),
        wrist_inertia_kgm2=None if payload[2] is None else tuple(payload[2]),
        source_file=str(doc.path))


def _read(path: Path) -> dict:
    import yaml

    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the arm file: {exc}") from exc
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise InputError(f"{path}: not a YAML arm file{where}: "
                         f"{getattr(exc, 'problem', None) or exc}") from exc
    if not isinstance(data, dict):
        raise InputError(f"{path}: an arm file is a YAML mapping (schema {SCHEMA})")
    return data


#: id(spec.kinematics) -> spec of every arm file read (the cache below keeps them alive)
_BY_KINEMATICS: dict[int, RobotSpec] = {}


@functools.lru_cache(maxsize=64)
def _load_cached(path: str, _stamp: tuple, check_model: bool) -> RobotSpec:
    p = Path(path)
    spec = _spec_from_doc(_Doc(p, _read(p), check_model))
    _BY_KINEMATICS[id(spec.kinematics)] = spec
    return spec


def loaded_spec_for(kinematics) -> RobotSpec | None:
    """The arm file's spec whose kinematics object this is (a program made from an arm file's
    kinematics finds its robot frame and conventions), None if none."""
    spec = _BY_KINEMATICS.get(id(kinematics))
    return spec if spec is not None and spec.kinematics is kinematics else None


def load_arm(path: str | Path, *, builtin: bool = False) -> RobotSpec:
    """The arm of an arm file (schema in the module docstring).

    The same unchanged file gives the same spec object (so ``get_robot(FILE) is spec``).

    Args:
        path: the YAML file.
        builtin: a registry file (its spec keeps no ``source_file``: plans name it by name;
            its generated model is checked by the tests, not here, so that
            ``python -m drakedeburr.robots`` can write it).

    Raises:
        InputError: no such file, or a field is missing or wrong (the message names both).
    """
    p = Path(path).expanduser().resolve()
    if not p.is_file():
        raise InputError(f"{path}: no such arm file")
    st = p.stat()
    spec = _load_cached(str(p), (st.st_mtime_ns, st.st_size), not builtin)
    if builtin:
        from dataclasses import replace

        return replace(spec, source_file="")
    return spec


def _list(v, digits: int = 12) -> str:
    return "[" + ", ".join(repr(round(float(x), digits)) if not float(x).is_integer()
                           else str(int(x)) for x in v) + "]"


def arm_file_text(spec: RobotSpec) -> str:
    """An arm file for ``spec`` (angles in radians, exact to the float): a starting point for
    a new arm's file (``drakedeburr robots --dump NAME``); add its citations under
    ``sources``."""
    import yaml

    p = spec.opw

    def q(s: str) -> str:
        return yaml.safe_dump(s, width=10_000, allow_unicode=True).strip().removesuffix("\n...")

    lines = [f"schema: {SCHEMA}", f"name: {spec.name}", f"title: {q(spec.title)}",
             f"vendor: {spec.vendor}", f"controller: {spec.controller}",
             f"controller_model: {q(spec.controller_model)}",
             f"program_language: {spec.program_format}", "opw:"]
    lines += [f"  {k}: {getattr(p, k)!r}" for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")]
    lines += [f"  offsets_rad: {_list(p.offsets, 17)}",
              f"  sign_corrections: {_list(p.sign_corrections)}", f"  name: {q(p.name)}",
              "joints:", f"  lower_rad: {_list(spec.q_lower, 17)}",
              f"  upper_rad: {_list(spec.q_upper, 17)}",
              f"  speed_rad_s: {_list(spec.v_max, 17)}",
              f"  acceleration_rad_s2: {_list(spec.a_max, 17)}",
              f"  acceleration_note: {q(spec.a_max_note)}",
              f"j23_coupling: {spec.j23_coupling!r}",
              f"robot_frame_m: {_list(spec.X_BR[:3, 3])}", "payload:",
              f"  mass_kg: {spec.payload_kg!r}"]
    for key in ("wrist_moment_Nm", "wrist_inertia_kgm2"):
        if getattr(spec, key) is not None:
            lines.append(f"  {key}: {_list(getattr(spec, key))}")
    lines += [f"flange: {q(spec.flange)}", f"model: {spec.model_url}"]
    if spec.mounts:
        lines.append("mounts:")
        for cell, m in spec.mounts:
            lines += [f"  {cell}:", f"    base_m: {_list(m.X_WB[:3, 3])}",
                      f"    home_rad: {_list(m.q_home, 17)}", f"    pedestal: {m.pedestal_url}",
                      f"    study: {q(m.study)}"]
    lines += [f"conventions: {q(spec.conventions)}", "sources:"]
    for s in spec.sources:
        key, _, text = s.partition(": ")
        lines.append(f"  {key}: {q(text)}")
    return "\n".join(lines) + "\n"
