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
           "plan_digest", "is_plan_folder"]

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


def _content(plan: Plan) -> tuple[dict, dict]:
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
        format=PLAN_FORMAT, version=PLAN_VERSION, scenario=plan.scenario, hub=plan.hub,
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


def _doc_text(doc: dict) -> str:
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def plan_digest(plan: Plan) -> str:
    """SHA-256 (hex) of the plan's content: its ``plan.json`` text and every array (name,
    dtype, shape, bytes), not the run's timings. Identical for a plan and its saved copy."""
    doc, arrays = _content(plan)
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


def save_plan(plan: Plan, path: str | Path) -> Path:
    """Write a plan folder as one transaction (:func:`drakedeburr._io.atomic_folder`):
    ``plan.json``, ``arrays.npz``, ``joints.csv`` and ``run.json`` (the run's timings, not part
    of the plan's content). An existing plan folder there is replaced whole (with its old
    report); any other existing folder is refused. Returns the folder."""
    doc, arrays = _content(plan)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    with atomic_folder(path, is_ours=is_plan_folder) as tmp:
        (tmp / "arrays.npz").write_bytes(buf.getvalue())
        write_joint_csv(plan, tmp / "joints.csv")
        (tmp / "run.json").write_text(json.dumps(jsonable(plan.run), indent=1, sort_keys=True))
        (tmp / "plan.json").write_text(_doc_text(doc))
    return Path(path)


def load_plan(path: str | Path) -> Plan:
    """Read a plan folder written by :func:`save_plan` (or its ``plan.json``).

    Raises:
        FileNotFoundError: no plan there. InputError: wrong format or version.
    """
    folder = Path(path)
    if folder.name == "plan.json":
        folder = folder.parent
    doc_path = folder / "plan.json"
    if not doc_path.is_file():
        raise FileNotFoundError(f"no plan at {folder} (missing plan.json)")
    try:
        doc = json.loads(doc_path.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"{doc_path}: not valid JSON ({exc})") from exc
    if doc.get("format") != PLAN_FORMAT:
        raise InputError(f"{doc_path}: not a drakedeburr plan (format {doc.get('format')!r})")
    if doc.get("version") not in (1, PLAN_VERSION):
        raise InputError(f"{doc_path}: plan version {doc.get('version')} is not supported "
                         f"(this drakedeburr reads versions 1 and {PLAN_VERSION})")
    npz_path = folder / "arrays.npz"
    if not npz_path.is_file():
        raise FileNotFoundError(f"{folder}: missing arrays.npz")
    with np.load(npz_path) as a:
        arr = {k: a[k] for k in a.files}
    if len(doc["targets"]) != len(arr["q_targets"]):
        raise InputError(f"{folder}: {len(doc['targets'])} targets in plan.json but "
                         f"{len(arr['q_targets'])} in arrays.npz")
    targets = []
    for i, t in enumerate(doc["targets"]):
        p, n = arr["p_HC"][i], arr["n_H"][i]
        targets.append(CartesianTarget(
            window_index=int(t["window_index"]), segment=t["segment"], cl_index=int(t["cl_index"]),
            X_HT=arr["X_HT"][i], X_WF=arr["X_WF"][i], q=arr["q_targets"][i],
            speed=float(t["speed"]), zone=float(t["zone"]), motion=t.get("motion", "linear"),
            p_HC=None if np.any(np.isnan(p)) else p, n_H=None if np.any(np.isnan(n)) else n))
    segments = tuple(PlanSegment(window_index=int(s["window_index"]), kind=s["kind"],
                                 target_range=tuple(s["target_range"]),
                                 t_range=tuple(s["t_range"])) for s in doc["segments"])
    records = []
    for d in doc.get("tool_paths", []):
        w = int(d["window_index"])
        for new, old in (("zT_H", "axis_H"), ("cone_zT_H", "cone_axis_H")):  # version 1 names
            if f"tp{w}_{new}" not in arr and f"tp{w}_{old}" in arr:
                arr[f"tp{w}_{new}"] = arr[f"tp{w}_{old}"]
        missing = [n for n in TOOL_PATH_ARRAYS if f"tp{w}_{n}" not in arr]
        if missing:
            raise InputError(f"{npz_path}: tool path of window {w} lacks {', '.join(missing)}")
        records.append(ToolPathRecord(
            window_index=w, kind=d["kind"], bounds=OrientationBounds(*d["bounds"]),
            cone_half_angle=float(d["cone_half_angle"]),
            cone_outer_half_angle=float(d["cone_outer_half_angle"]),
            depth_of_cut=float(d["depth_of_cut"]),
            **{n: arr[f"tp{w}_{n}"] for n in TOOL_PATH_ARRAYS}))
    return Plan(scenario=doc["scenario"], hub=doc["hub"], mode=doc["mode"], X_WH=arr["X_WH"],
                targets=tuple(targets), segments=segments,
                trajectory=(JointTrajectory(t=arr["t"], c=arr["c"]) if "c" in arr else
                            # version 1: a cubic Hermite spline through the knots
                            JointTrajectory.from_hermite(arr["t"], arr["q"], arr["qd"])),
                tool_path=tuple(records) or None,
                failures=tuple(FailureRecord.from_dict(f) for f in doc["failures"]),
                meta=doc["meta"], run=_run_record(folder))


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
    if dt is None:
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
