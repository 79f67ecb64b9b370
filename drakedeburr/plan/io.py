"""Plan files: save/load (a folder: ``plan.json`` + ``arrays.npz``) and the joint CSV (the robot
program of a plan: :func:`drakedeburr.programs.program_from_plan`).

Folder layout (format version 2, written as one transaction: :func:`save_plan`):

* ``arrays.npz``: trajectory knot times ``t`` (K,) and polynomial pieces ``c`` (D + 1, K - 1,
  6) (:class:`~drakedeburr.plan.types.JointTrajectory`); target arrays ``X_HT``
  (N, 4, 4), ``X_WF`` (N, 4, 4), ``q_targets`` (N, 6), ``p_HC`` (N, 3) and ``n_H`` (N, 3) (NaN
  where a target has none); ``X_WH`` (4, 4). SI units.
* ``plan.json``: ``format``, ``version``, scenario, hub, mode, per-target scalars, segments,
  failures, meta, and per window the orientation stage's reference (``tool_paths``: kind,
  bounds, cone half-angles, depth of cut; the arrays ``tp<w>_<name>`` in ``arrays.npz``: CL
  points, local frames, axes, angles, cone axes). After loading, ``plan.tool_path`` is a tuple
  of :class:`~drakedeburr.plan.types.ToolPathRecord` - what verification needs of a ToolPath.

The joint CSV is for people and controllers that take joint streams: ``t_s, q1_deg .. q6_deg``
(degrees at the boundary, :mod:`drakedeburr.units`).
"""

from __future__ import annotations

import hashlib
import io
import json
import re
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_folder, atomic_write_text
from drakedeburr.config import OrientationBounds
from drakedeburr.errors import InputError
from drakedeburr.plan.types import (
    TOOL_PATH_ARRAYS,
    CartesianTarget,
    FailureRecord,
    JointTrajectory,
    Plan,
    PlanSegment,
    ToolPathRecord,
)
from drakedeburr.units import deg_from_rad

__all__ = ["PLAN_FORMAT", "PLAN_VERSION", "save_plan", "load_plan", "write_joint_csv", "jsonable",
           "plan_digest", "plan_content", "is_plan_folder", "hub_reference",
           "check_hub_reference"]

PLAN_FORMAT = "drakedeburr-plan"
PLAN_VERSION = 2


def jsonable(obj):
    """``obj`` with numpy values as Python ones and non-finite floats as None."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


def plan_content(plan: Plan) -> tuple[dict, dict]:
    """What a plan folder holds of the plan: (plan.json document, arrays.npz arrays)."""
    n = len(plan.targets)
    nan3 = np.full(3, np.nan)
    arrays = dict(
        t=np.asarray(plan.trajectory.t, float), c=np.asarray(plan.trajectory.c, float),
        X_HT=np.array([tg.X_HT for tg in plan.targets]).reshape(n, 4, 4),
        X_WF=np.array([tg.X_WF for tg in plan.targets]).reshape(n, 4, 4),
        q_targets=np.array([tg.q for tg in plan.targets]).reshape(n, 6),
        p_HC=np.array([nan3 if tg.p_HC is None else tg.p_HC for tg in plan.targets]).reshape(n, 3),
        n_H=np.array([nan3 if tg.n_H is None else tg.n_H for tg in plan.targets]).reshape(n, 3),
        X_WH=np.asarray(plan.X_WH, float),
    )
    tp_docs = []
    for tp in _tool_paths(plan):
        w = int(tp.window_index)
        for name in TOOL_PATH_ARRAYS:
            arrays[f"tp{w}_{name}"] = np.asarray(getattr(tp, name), float)
        tp_docs.append(dict(window_index=w, kind=str(tp.kind),
                            bounds=[float(tp.bounds.theta_min), float(tp.bounds.theta_max)],
                            cone_half_angle=float(tp.cone_half_angle),
                            cone_outer_half_angle=float(tp.cone_outer_half_angle),
                            depth_of_cut=float(tp.depth_of_cut)))
    doc = dict(
        format=PLAN_FORMAT, version=PLAN_VERSION, scenario=_absolute(plan.scenario),
        hub=_absolute(plan.hub),
        mode=plan.mode,
        targets=[dict(window_index=tg.window_index, segment=tg.segment, cl_index=tg.cl_index,
                      speed=tg.speed, zone=tg.zone, motion=tg.motion) for tg in plan.targets],
        segments=[dict(window_index=s.window_index, kind=s.kind,
                       target_range=list(s.target_range), t_range=list(s.t_range))
                  for s in plan.segments],
        failures=[jsonable(f.to_dict()) for f in plan.failures],
        meta=jsonable(plan.meta),
        tool_paths=tp_docs,
    )
    return doc, arrays


def _absolute(ref: str) -> str:
    """A hub or scenario as a plan records it: a bundled name as it is, a folder or file as
    its absolute path (a path relative to where the plan was made would name another hub, or
    none, from another folder)."""
    p = Path(ref)
    if p.exists() and (len(p.parts) > 1 or p.is_dir() or p.suffix in (".yaml", ".yml")):
        return str(p.resolve())
    return ref


def hub_reference(hub: str) -> dict | None:
    """``{"path": absolute hub folder, "sha256": its content hash}``
    (:func:`drakedeburr.cell.fingerprint.hub_digest`), None for a hub that cannot be found."""
    from drakedeburr.cell.fingerprint import hub_digest
    from drakedeburr.resources import resolve_hub_dir

    try:
        return {"path": str(resolve_hub_dir(hub)), "sha256": hub_digest(hub)}
    except (FileNotFoundError, NotADirectoryError):
        return None


def check_hub_reference(doc: dict, doc_path: Path) -> None:
    """Refuse (InputError naming ``plan.json`` and both hashes) a plan whose hub folder is
    gone or whose content is not the content the plan was made for. Plans written before
    hub references (no ``hub_ref``) pass: their hub is found as before."""
    ref = doc.get("hub_ref")
    if ref is None:
        return
    if not (isinstance(ref, dict) and isinstance(ref.get("path"), str)
            and isinstance(ref.get("sha256"), str)):
        raise InputError(f"{doc_path}: hub_ref: expected {{path, sha256}}")
    from drakedeburr.cell.fingerprint import hub_digest

    hub = doc.get("hub") if isinstance(doc.get("hub"), str) else ref["path"]
    try:
        now = hub_digest(hub)
    except (FileNotFoundError, NotADirectoryError):
        raise InputError(f"{doc_path}: the plan's hub {hub} is not there any more (it was "
                         f"made for {ref['path']}, content sha256 {ref['sha256']})") from None
    if now != ref["sha256"]:
        raise InputError(f"{doc_path}: the hub {hub} has changed since the plan was made: its "
                         f"content is sha256 {now}, the plan was made for sha256 "
                         f"{ref['sha256']}; plan the hub again")


def _doc_text(doc: dict) -> str:
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def plan_digest(plan: Plan) -> str:
    """SHA-256 (hex) of the plan's content: its ``plan.json`` text and every array (name,
    dtype, shape, bytes), not the run's timings. Identical for a plan and its saved copy."""
    doc, arrays = plan_content(plan)
    h = hashlib.sha256(_doc_text(doc).encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def is_plan_folder(folder: Path) -> bool:
    """Does ``folder`` hold a plan (its ``plan.json`` says so)?"""
    doc = Path(folder) / "plan.json"
    try:
        return json.loads(doc.read_text()).get("format") == PLAN_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def save_plan(plan: Plan, path: str | Path, *, is_ours=is_plan_folder) -> Path:
    """Write a plan folder as one transaction (:func:`drakedeburr._io.atomic_folder`):
    ``plan.json``, ``arrays.npz``, ``joints.csv`` and ``run.json`` (the run's timings, not part
    of the plan's content). An existing plan folder there (or any folder ``is_ours`` accepts)
    is replaced whole (with its old report); any other existing folder is refused. Returns the
    folder."""
    doc, arrays = plan_content(plan)
    ref = hub_reference(plan.hub)
    if ref is not None:  # not part of the plan's digest: where its hub is and what it holds
        doc = {**doc, "hub_ref": ref}
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    with atomic_folder(path, is_ours=is_ours) as tmp:
        (tmp / "arrays.npz").write_bytes(buf.getvalue())
        write_joint_csv(plan, tmp / "joints.csv")
        (tmp / "run.json").write_text(json.dumps(jsonable(plan.run), indent=1, sort_keys=True))
        (tmp / "plan.json").write_text(_doc_text(doc))
    return Path(path)


def load_plan(path: str | Path) -> Plan:
    """Read a plan folder written by :func:`save_plan` (or its ``plan.json``), checking every
    item a consumer uses: types, shapes, finite values, indices in range.

    Raises:
        FileNotFoundError: no plan there (no ``plan.json``).
        InputError: anything else wrong, naming the file and the item.
    """
    folder = Path(path)
    if folder.name == "plan.json":
        folder = folder.parent
    doc_path = folder / "plan.json"
    if not doc_path.is_file():
        raise FileNotFoundError(f"no plan at {folder} (missing plan.json)")
    doc = _read_doc(doc_path)
    check_hub_reference(doc, doc_path)
    npz_path = folder / "arrays.npz"
    if not npz_path.is_file():
        raise InputError(f"{folder}: missing arrays.npz (the plan's arrays): not a complete "
                         "plan folder")
    arr = _read_arrays(npz_path)
    try:
        return _plan_from(doc, arr, folder, _Where(doc_path), _Where(npz_path))
    except _Bad as exc:
        raise InputError(str(exc)) from None


def _read_doc(doc_path: Path) -> dict:
    try:
        from drakedeburr._io import read_bounded

        doc = json.loads(read_bounded(doc_path, "plan", "json").decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise InputError(f"{doc_path}: not valid JSON ({type(exc).__name__}: "
                         f"{str(exc)[:120]})") from None
    if not isinstance(doc, dict):
        raise InputError(f"{doc_path}: not a drakedeburr plan (a JSON {type(doc).__name__}, "
                         "not an object)")
    if doc.get("format") != PLAN_FORMAT:
        raise InputError(f"{doc_path}: not a drakedeburr plan (format "
                         f"{str(doc.get('format'))[:40]!r}, expected {PLAN_FORMAT!r})")
    if doc.get("version") not in (1, PLAN_VERSION) or isinstance(doc.get("version"), bool):
        raise InputError(f"{doc_path}: plan version {str(doc.get('version'))[:20]} is not "
                         f"supported (this drakedeburr reads versions 1 and {PLAN_VERSION})")
    return doc


#: the arrays an ``arrays.npz`` may hold (format versions 1 and 2); any other member is refused
#: before anything is decompressed
_ARRAY_NAME = re.compile(r"(t|c|q|qd|X_HT|X_WF|q_targets|p_HC|n_H|X_WH|"
                         r"tp\d{1,6}_(?:" + "|".join(TOOL_PATH_ARRAYS) + r"|axis_H|cone_axis_H))")
#: the most a plan's arrays may take decompressed (a whole hub's plan is ~1 MB)
NPZ_LIMIT = 256 << 20


def _check_npz_members(npz_path: Path) -> None:
    """Every member of ``arrays.npz`` checked from its zip entry and .npy header before
    anything is decompressed (:func:`drakedeburr._io.check_npz_members`): a plan's array
    name, numbers, a size matching the header's shape, :data:`NPZ_LIMIT` in all."""
    from drakedeburr._io import check_npz_members

    check_npz_members(npz_path, _ARRAY_NAME, NPZ_LIMIT, "plan arrays",
                      "t, c, X_HT, X_WF, q_targets, p_HC, n_H, X_WH, tp<w>_*")


def _read_arrays(npz_path: Path) -> dict[str, np.ndarray]:
    """The arrays of ``arrays.npz``; anything numpy or zipfile cannot read (truncated,
    corrupt, pickled objects, not an archive) is an InputError naming the file. The members
    are checked before anything is decompressed (:func:`_check_npz_members`)."""
    _check_npz_members(npz_path)
    try:
        with np.load(npz_path, allow_pickle=False) as a:
            if not hasattr(a, "files"):
                raise ValueError("a single array, not an .npz archive")
            return {str(k): a[k] for k in a.files}
    except InputError:
        raise
    except Exception as exc:  # zipfile, zlib, numpy's format reader raise many kinds
        raise InputError(f"{npz_path}: not a readable .npz archive ({type(exc).__name__}: "
                         f"{str(exc)[:120]})") from None


class _Bad(Exception):
    """An item of a plan file that is wrong (turned into InputError by load_plan)."""


class _Where:
    """A file name for messages: ``where["targets[3].speed"]`` -> ``file: targets[3].speed``."""

    def __init__(self, path: Path):
        self.path = path

    def __getitem__(self, item: str) -> str:
        return f"{self.path}: {item}"


_INT_LIMIT = 2**31
#: the longest plan read [s] (a whole hub's cycle is under two minutes; a plan of 1e12 s
#: would be sampled into petabytes by the verifier)
PLAN_MAX_DURATION = 3600.0


def _get(d, key: str, kind, where: str, default=...):
    """``d[key]`` of type ``kind`` (int: not bool; float: a finite int or float)."""
    if not isinstance(d, dict):
        raise _Bad(f"{where}: expected an object, got {type(d).__name__}")
    if key not in d:
        if default is not ...:
            return default
        raise _Bad(f"{where}.{key}: missing")
    return _value(d[key], kind, f"{where}.{key}")


def _value(v, kind, where: str):
    if kind is float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise _Bad(f"{where}: expected a finite number, got {str(v)[:40]!r}")
        return float(v)
    if kind is int:
        if isinstance(v, bool) or not isinstance(v, int):
            raise _Bad(f"{where}: expected an integer, got {str(v)[:40]!r}")
        if not -_INT_LIMIT <= v < _INT_LIMIT:  # an index or a count: fits numpy's int32
            raise _Bad(f"{where}: {str(v)[:40]} is out of range (an index, |value| < 2**31)")
        return v
    if not isinstance(v, kind):
        name = getattr(kind, "__name__", None) or "/".join(k.__name__ for k in kind)
        raise _Bad(f"{where}: expected {name}, got {type(v).__name__}")
    return v


def _choice(v, allowed, where: str):
    if not isinstance(v, str) or v not in allowed:
        raise _Bad(f"{where}: {str(v)[:40]!r} is not one of {', '.join(allowed)}")
    return v


def _array(arr: dict, name: str, shape: tuple, where, nan_rows: bool = False) -> np.ndarray:
    """Array ``name`` as floats with ``shape`` (None: any length), finite (``nan_rows``: rows
    may be all NaN, meaning none)."""
    if name not in arr:
        raise _Bad(where[f"array {name!r}: missing"])
    a = arr[name]
    if a.dtype.kind not in "biuf":
        raise _Bad(where[f"array {name!r}: expected numbers, got dtype {a.dtype}"])
    a = a.astype(float)
    if a.ndim != len(shape) or any(n is not None and n != m
                                   for n, m in zip(shape, a.shape, strict=True)):
        want = "(" + ", ".join("N" if n is None else str(n) for n in shape) + ")"
        raise _Bad(where[f"array {name!r}: shape {a.shape}, expected {want}"])
    bad = ~np.isfinite(a)
    if nan_rows and a.ndim > 1:
        rows = bad.reshape(len(a), -1)
        bad = rows.any(axis=1) & ~(np.isnan(a).reshape(len(a), -1).all(axis=1))
    if bad.any():
        first = np.argwhere(bad)[0]
        raise _Bad(where[f"array {name!r}: not finite at {tuple(int(i) for i in first)}"])
    return a


_KINDS = ("home", "approach", "cut", "retract", "transition")
_POSES = ("X_WB", "X_FT", "X_FH", "X_WT", "hub_pose")


def _targets(doc: dict, arr: dict, jw, aw) -> tuple[CartesianTarget, ...]:
    items = _get(doc, "targets", list, jw["plan"])
    n = len(items)
    X_HT = _array(arr, "X_HT", (n, 4, 4), aw)
    X_WF = _array(arr, "X_WF", (n, 4, 4), aw)
    q = _array(arr, "q_targets", (n, 6), aw)
    p_HC = _array(arr, "p_HC", (n, 3), aw, nan_rows=True)
    n_H = _array(arr, "n_H", (n, 3), aw, nan_rows=True)
    out = []
    for i, t in enumerate(items):
        w = jw[f"targets[{i}]"]
        speed, zone = _get(t, "speed", float, w), _get(t, "zone", float, w)
        if speed < 0 or zone < 0:
            raise _Bad(f"{w}: speed and zone must be >= 0, got {speed}, {zone}")
        p, nn = p_HC[i], n_H[i]
        out.append(CartesianTarget(
            window_index=_get(t, "window_index", int, w),
            segment=_choice(_get(t, "segment", str, w), _KINDS, f"{w}.segment"),
            cl_index=_get(t, "cl_index", int, w), X_HT=X_HT[i], X_WF=X_WF[i], q=q[i],
            speed=speed, zone=zone,
            motion=_choice(t.get("motion", "linear"), ("linear", "joint"), f"{w}.motion"),
            p_HC=None if np.isnan(p).any() else p, n_H=None if np.isnan(nn).any() else nn))
    return tuple(out)


def _segments(doc: dict, n_targets: int, jw, t_span) -> tuple[PlanSegment, ...]:
    out = []
    for i, s in enumerate(_get(doc, "segments", list, jw["plan"])):
        w = jw[f"segments[{i}]"]
        tr, trange = _get(s, "target_range", list, w), _get(s, "t_range", list, w)
        if len(tr) != 2 or len(trange) != 2:
            raise _Bad(f"{w}: target_range and t_range need 2 values each")
        a, b = (_value(v, int, f"{w}.target_range") for v in tr)
        if not 0 <= a <= b <= n_targets:
            raise _Bad(f"{w}.target_range: [{a}, {b}] is not within the {n_targets} targets")
        t0, t1 = (_value(v, float, f"{w}.t_range") for v in trange)
        if not (t_span[0] - 1e-9 <= t0 <= t1 <= t_span[1] + 1e-9):
            raise _Bad(f"{w}.t_range: [{t0:g}, {t1:g}] s is not within the trajectory's "
                       f"[{t_span[0]:g}, {t_span[1]:g}] s")
        out.append(PlanSegment(window_index=_get(s, "window_index", int, w),
                               kind=_choice(_get(s, "kind", str, w), _KINDS, f"{w}.kind"),
                               target_range=(a, b), t_range=(t0, t1)))
    return tuple(out)


def _failures(doc: dict, jw) -> tuple[FailureRecord, ...]:
    out = []
    for i, f in enumerate(_get(doc, "failures", list, jw["plan"])):
        w = jw[f"failures[{i}]"]
        _get(f, "window", int, w, -1)
        _get(f, "point", int, w, -1)
        for key in ("value", "limit"):
            if f.get(key) is not None:
                _get(f, key, float, w)
        _get(f, "where", (dict, type(None)), w, None)
        _get(f, "tried", (list, type(None)), w, None)
        out.append(FailureRecord.from_dict(f))
    return tuple(out)


def _meta(doc: dict, jw) -> dict:
    meta = _get(doc, "meta", dict, jw["plan"])
    w = jw["meta"]
    for key in _POSES:
        if meta.get(key) is not None:
            try:
                X = np.asarray(meta[key], float)
            except (TypeError, ValueError):
                X = np.zeros(0)
            if X.shape != (4, 4) or not np.isfinite(X).all():
                raise _Bad(f"{w}.{key}: expected a 4x4 pose of finite numbers")
    _get(meta, "robot", (str, type(None)), w, None)
    tool = _get(meta, "tool", (str, type(None)), w, None)
    if tool is not None:
        from drakedeburr.cell.tools import TOOL_VARIANTS

        if tool not in TOOL_VARIANTS:
            raise _Bad(f"{w}.tool: {tool!r} is not a known burr ({', '.join(TOOL_VARIANTS)})")
    _get(meta, "planner", (str, type(None)), w, None)
    _get(meta, "config", (dict, type(None)), w, None)
    for i, row in enumerate(_get(meta, "windows", list, w, [])):
        if isinstance(row, dict):  # the planner's per-window figures (a list of numbers also)
            _get(row, "window", int, f"{w}.windows[{i}]", -1)
            _get(row, "cone_half_angle_rad", float, f"{w}.windows[{i}]", 0.0)
    return meta


def _check_duration(t: np.ndarray, aw) -> None:
    if t[-1] - t[0] > PLAN_MAX_DURATION or abs(t[0]) > PLAN_MAX_DURATION:
        raise _Bad(aw[f"array 't': spans {t[0]:g} to {t[-1]:g} s, more than the plan "
                      f"duration limit of {PLAN_MAX_DURATION:g} s"])


def _trajectory(doc: dict, arr: dict, aw) -> JointTrajectory:
    if "c" not in arr and doc["version"] == 1:  # version 1: cubic Hermite through the knots
        t = _array(arr, "t", (None,), aw)
        q, qd = _array(arr, "q", (len(t), 6), aw), _array(arr, "qd", (len(t), 6), aw)
        if len(t) < 2 or np.any(np.diff(t) <= 0):
            raise _Bad(aw["array 't': knot times must increase strictly (at least 2)"])
        _check_duration(t, aw)
        return JointTrajectory.from_hermite(t, q, qd)
    t = _array(arr, "t", (None,), aw)
    if len(t) < 1 or np.any(np.diff(t) <= 0):
        raise _Bad(aw["array 't': knot times must increase strictly"])
    _check_duration(t, aw)
    c = _array(arr, "c", (None, len(t) - 1, 6), aw)
    if len(c) < 1:
        raise _Bad(aw["array 'c': no polynomial coefficients"])
    return JointTrajectory(t=t, c=c)


def _records(doc: dict, arr: dict, jw, aw) -> tuple[ToolPathRecord, ...]:
    records = []
    for i, d in enumerate(_get(doc, "tool_paths", list, jw["plan"], [])):
        w = jw[f"tool_paths[{i}]"]
        win = _get(d, "window_index", int, w)
        for new, old in (("zT_H", "axis_H"), ("cone_zT_H", "cone_axis_H")):  # version 1 names
            if f"tp{win}_{new}" not in arr and f"tp{win}_{old}" in arr:
                arr[f"tp{win}_{new}"] = arr[f"tp{win}_{old}"]
        missing = [n for n in TOOL_PATH_ARRAYS if f"tp{win}_{n}" not in arr]
        if missing:
            raise _Bad(aw[f"tool path of window {win} lacks {', '.join(missing)}"])
        m = len(arr[f"tp{win}_p_HC"])
        shapes = dict(p_HC=(m, 3), R_HL=(m, 3, 3), zT_H=(m, 3), theta_A=(m,), theta_B=(m,),
                      cone_zT_H=(m, 3))
        arrays = {n: _array(arr, f"tp{win}_{n}", shapes[n], aw) for n in TOOL_PATH_ARRAYS}
        bounds = _get(d, "bounds", list, w)
        try:
            box = OrientationBounds(*(_value(b, float, f"{w}.bounds") for b in bounds))
        except (TypeError, ValueError) as exc:
            raise _Bad(f"{w}.bounds: {exc}") from None
        records.append(ToolPathRecord(
            window_index=win, kind=_choice(_get(d, "kind", str, w), ("large", "small"),
                                           f"{w}.kind"),
            bounds=box, cone_half_angle=_get(d, "cone_half_angle", float, w),
            cone_outer_half_angle=_get(d, "cone_outer_half_angle", float, w),
            depth_of_cut=_get(d, "depth_of_cut", float, w), **arrays))
    return tuple(records)


def _plan_from(doc: dict, arr: dict, folder: Path, jw, aw) -> Plan:
    targets = _targets(doc, arr, jw, aw)
    tr = _trajectory(doc, arr, aw)
    return Plan(scenario=_get(doc, "scenario", str, jw["plan"]),
                hub=_get(doc, "hub", str, jw["plan"]),
                mode=_choice(doc.get("mode"), ("tool", "workpiece"), jw["mode"]),
                X_WH=_array(arr, "X_WH", (4, 4), aw), targets=targets,
                segments=_segments(doc, len(targets), jw, (tr.t[0], tr.t[-1])),
                trajectory=tr,
                tool_path=_records(doc, arr, jw, aw) or None,
                failures=_failures(doc, jw), meta=_meta(doc, jw), run=_run_record(folder))


def _run_record(folder: Path) -> dict:
    """The run's record beside a plan (``run.json``), {} when missing or unreadable (it is
    not part of the plan)."""
    try:
        run = json.loads((folder / "run.json").read_text())
    except (OSError, ValueError):
        return {}
    return run if isinstance(run, dict) else {}


def _tool_paths(plan: Plan) -> list:
    """The plan's ToolPaths (tuple, dict by window or None) that carry everything a record
    needs; stand-ins without cone axes are skipped."""
    tp = plan.tool_path
    if tp is None:
        return []
    items = list(tp.values()) if isinstance(tp, dict) else list(tp)
    need = (*TOOL_PATH_ARRAYS, "bounds", "cone_half_angle", "cone_outer_half_angle")
    return [x for x in items if x is not None and all(hasattr(x, n) for n in need)]


def write_joint_csv(plan: Plan, path: str | Path, dt: float | None = None) -> Path:
    """Joint CSV ``t_s,q1_deg,...,q6_deg``: the trajectory knots, or samples every ``dt`` [s]."""
    tr = plan.trajectory
    if len(tr.t) < 2:  # nothing could be planned: the plan stands at its first target (home)
        t = np.asarray(tr.t, float)[:1]
        q = np.array([tg.q for tg in plan.targets[:1]]).reshape(-1, 6)[:len(t)]
    elif dt is None:
        t, q = tr.t, tr.q
    else:
        t = np.arange(0.0, tr.duration + 0.5 * dt, dt)
        t[-1] = min(t[-1], tr.t[-1])
        q = tr.value(t)
    rows = ["t_s,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg"]
    qd = deg_from_rad(np.asarray(q))
    rows += [f"{ti:.6f}," + ",".join(f"{v:.6f}" for v in row)
             for ti, row in zip(t, qd, strict=True)]
    return atomic_write_text(path, "\n".join(rows) + "\n")
