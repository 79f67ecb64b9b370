"""Benchmark of the post stage: CAM files posted end to end against the previous
implementation (same run), a 10^6-line file streamed (time, peak memory), CL parsing, the
analytic IK and the spin rules.

    python benchmarks/bench_post.py [--quick]

Baseline: the previous ``cl_reader``, ``tool_axis`` and ``cl_post`` (commit
``BASELINE_COMMIT``, before the complete-CAM-post work) loaded from git into this process.
The program writers are the same for both (unchanged by this work); their time is shown
separately. Big CL files are generated here (seeded) in a temporary folder, never committed.
Memory is the peak resident set of a child process running one job.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import re
import resource
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from drakedeburr.post.cl_post import (  # noqa: E402
    PostOutput,
    PostSettings,
    pose_from_mm_deg,
    post_cl_file,
    program_from_cl,
)
from drakedeburr.post.cl_reader import parse_cl_text, read_cl  # noqa: E402
from drakedeburr.post.tool_axis import path_travel, solve_tool_axis_path  # noqa: E402
from drakedeburr.programs.writers import write_program  # noqa: E402
from drakedeburr.resources import extdata_dir  # noqa: E402
from drakedeburr.robots import IRB1600_10_120, fk_opw  # noqa: E402
from drakedeburr.robots import IRB1600_10_120_ROBOT as ROBOT  # noqa: E402
from drakedeburr.robots.opw_ik import ik_opw  # noqa: E402

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--quick",)

BASELINE_COMMIT = "9ccafa3"  # main before the complete-CAM-post work
WOBJ = [700.0, 0.0, 300.0, 0.0, 0.0, 30.0]
GOTO = re.compile(r"^\s*GOTO\s*/\s*([^,]+),([^,]+),([^,\s]+)")


def make_cam_file(path: Path, n: int, seed: int = 0) -> Path:
    """A Creo-style 5-axis CL file with ``n`` GOTO targets (a wandering spiral, tool axis
    tilted up to 15 deg), deterministic for the seed."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 20 * np.pi, n) + rng.normal(0, 1e-4, n)
    r = 60 + 10 * np.sin(0.37 * t)
    x, y, z = r * np.cos(t), r * np.sin(t), 5 * np.sin(0.11 * t)
    tilt = np.radians(15) * np.sin(0.05 * t)
    ax = np.stack([np.sin(tilt) * np.cos(t), np.sin(tilt) * np.sin(t), np.cos(tilt)], 1)
    with path.open("w") as f:
        f.write("$$* Pro/CLfile  Version 8.0 (synthetic)\nPARTNO / BENCH\nUNITS / MM\n"
                "LOADTL / 1\nSPINDL / RPM, 9000, CLW\nFEDRAT / 400, MMPM\nMULTAX / ON\n")
        rows = np.column_stack([x, y, z, ax])
        for k in range(0, n, 65536):
            f.writelines(f"GOTO / {a:.4f}, {b:.4f}, {c:.4f}, {i:.7f}, {j:.7f}, {kk:.7f}\n"
                         for a, b, c, i, j, kk in rows[k:k + 65536])
        f.write("FINI\n")
    return path


def load_baseline() -> types.SimpleNamespace | None:
    """The previous reader, spin solver and CL post, from git, as modules of this process,
    with the modules they import from that commit's ``drakedeburr.post`` (the analytic IK and
    the program record lived there then: loaded from git too, in dependency order)."""
    mods = {}
    for name in ("opw", "opw_ik", "program", "cl_reader", "tool_axis", "cl_post"):
        try:
            src = subprocess.run(
                ["git", "-C", str(REPO), "show", f"{BASELINE_COMMIT}:drakedeburr/post/{name}.py"],
                capture_output=True, text=True, check=True).stdout
        except (OSError, subprocess.CalledProcessError):
            return None
        src = re.sub(r"from drakedeburr\.post\.(opw|opw_ik|program|cl_reader|tool_axis) import",
                     r"from baseline_\1 import", src)
        spec = importlib.util.spec_from_loader(f"baseline_{name}", loader=None)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[f"baseline_{name}"] = mod
        exec(compile(src, f"<{BASELINE_COMMIT}:{name}.py>", "exec"), mod.__dict__)
        mods[name] = mod
    return types.SimpleNamespace(read_cl=mods["cl_reader"].read_cl,
                                 program_from_cl=mods["cl_post"].program_from_cl,
                                 solve_tool_axis_path=mods["tool_axis"].solve_tool_axis_path)


def tool(tilt_deg: float, z: float = 0.2) -> np.ndarray:
    """Tool in the flange: tilted about Y (TCP then 50 mm off the axis), ``z`` out [m]."""
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("Y", tilt_deg, degrees=True).as_matrix()
    X[:3, 3] = [0.05 if tilt_deg else 0.0, 0.0, z]
    return X


def timed_post(impl, path: Path, X_FT: np.ndarray, out: Path | None) -> dict[str, float]:
    """Seconds for read, spin + IK + program, write (RAPID) with one implementation."""
    t0, c0 = time.perf_counter(), time.process_time()
    cl = impl.read_cl(path)
    t1 = time.perf_counter()
    res = impl.program_from_cl(cl, "bench", X_WO=pose_from_mm_deg(WOBJ), X_FT=X_FT)
    t2, c2 = time.perf_counter(), time.process_time()
    if out is not None and res.program is not None:
        write_program(res.program, out, "rapid")
    t3 = time.perf_counter()
    assert res.program is not None, "benchmark path must be reachable"
    return {"read": t1 - t0, "post": t2 - t1, "write": t3 - t2, "cpu": c2 - c0,
            "moves": len(res.program.moves)}


def child(mode: str, cl_file: str, out: str) -> None:
    """One job in a fresh process; prints seconds and peak memory as JSON."""
    t = time.perf_counter()
    phases: dict[str, float] = {}

    def progress(done: int, total: int, label: str) -> None:
        if done >= total:
            phases[label] = time.perf_counter() - t

    if mode == "new-post":
        post_cl_file(cl_file, PostOutput(out, "rapid", "big"),
                     PostSettings(X_WO=pose_from_mm_deg(WOBJ)), progress=progress)
    elif mode == "new-read":
        read_cl(cl_file)
    elif mode == "old-read":
        load_baseline().read_cl(cl_file)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"seconds": time.perf_counter() - t, "rss_mb": rss, "phases": phases}))


def run_child(mode: str, cl_file: Path, out: Path) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", mode, str(cl_file), str(out)],
                          capture_output=True, text=True)
    if proc.returncode:
        return {"seconds": float("nan"), "rss_mb": float("nan"), "error": proc.stderr[-300:]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def cam_rows(tmp: Path, quick: bool, base) -> list[tuple[str, str, str, str]]:
    rows = []
    n = 1000 if quick else 7500
    path = make_cam_file(tmp / f"cam_{n}.ncl", n)
    new = types.SimpleNamespace(
        read_cl=read_cl, program_from_cl=lambda cl, name, X_WO, X_FT: program_from_cl(
            cl, name, PostSettings(X_WO=X_WO, X_FT=X_FT)))
    cases = [(f"{n}-target CAM file, tool on the flange axis", tool(0.0), True),
             (f"{n}-target CAM file, tool tilted 30 deg", tool(30.0), False)]
    if not quick:
        path10 = make_cam_file(tmp / "cam_10000.ncl", 10000, seed=1)
        cases.append(("10000-point CAM file, tool on the flange axis", tool(0.0), True))
    for label, X_FT, write in cases:
        p = path10 if label.startswith("10000") else path
        ours = timed_post(new, p, X_FT, tmp / "new.mod" if write else None)
        ours_s = ours["read"] + ours["post"]
        text = (f"{ours_s:.2f} s (read {ours['read']:.2f} + spin/IK/program "
                f"{ours['post']:.2f}; CPU {ours['cpu']:.2f} s)")
        if base is not None:
            old = timed_post(base, p, X_FT, None)
            old_s = old["read"] + old["post"]
            rows.append((f"post {label}", text, f"previous {old_s:.1f} s",
                         f"{old_s / ours_s:.0f}x"))
        else:
            rows.append((f"post {label}", text, "previous: git baseline not available", "-"))
        if write:
            rows.append(("  + RAPID writer (unchanged, not part of this work)",
                         f"{ours['write']:.2f} s -> total {ours_s + ours['write']:.2f} s",
                         "same writer", "-"))
    return rows


def stream_rows(tmp: Path, quick: bool, base) -> list[tuple[str, str, str, str]]:
    n = 100_000 if quick else 1_000_000
    path = make_cam_file(tmp / "big.ncl", n - 8)
    rows = []
    post = run_child("new-post", path, tmp / "big.mod")
    read_new = run_child("new-read", path, tmp / "x")
    read_old = run_child("old-read", path, tmp / "x") if base is not None else None
    rows.append((f"{n:,}-line file: read", f"{read_new['seconds']:.1f} s, peak "
                 f"{read_new['rss_mb']:.0f} MB", "-" if read_old is None else
                 f"previous reader {read_old['seconds']:.1f} s, peak {read_old['rss_mb']:.0f} MB",
                 "-" if read_old is None else f"{read_old['rss_mb'] / read_new['rss_mb']:.1f}x "
                 "memory"))
    ph = post.get("phases", {})
    solved = ph.get("spin + IK", float("nan"))
    rows.append((f"{n:,}-line file: whole post to RAPID parts (CLI path)",
                 f"{post['seconds']:.0f} s (read + spin/IK {solved:.0f} s, writers "
                 f"{post['seconds'] - solved:.0f} s), peak {post['rss_mb']:.0f} MB",
                 "previous: not run (> 170 s and 5.9 GB at 10^6 lines, issue 18)", "-"))
    return rows


def naive_parse(text: str) -> int:
    """Baseline: GOTO x,y,z only, no continuation, no checks."""
    n = 0
    for line in text.splitlines():
        m = GOTO.match(line)
        if m:
            [float(v) for v in m.groups()]
            n += 1
    return n


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def drake_ik_rate(n: int) -> tuple[float, float]:
    """Poses per second and success rate of Drake's numerical IK on the same chain."""
    from pydrake.math import RigidTransform, RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.solvers import Solve

    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(REPO / "tests" / "data" / "irb1600_6_12_reference.urdf"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link"))
    plant.Finalize()
    tool0 = plant.GetFrameByName("tool0")
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    qs = rng.uniform(lo * 0.6, hi * 0.6, size=(n, 6))
    ok = 0
    t0 = time.perf_counter()
    for q in qs:
        X = RigidTransform(fk_opw(IRB1600_10_120, q))
        ik = InverseKinematics(plant)
        ik.AddPositionConstraint(tool0, np.zeros(3), plant.world_frame(), X.translation(),
                                 X.translation())
        ik.AddOrientationConstraint(tool0, RotationMatrix(), plant.world_frame(),
                                    X.rotation(), 1e-6)
        prog = ik.get_mutable_prog()
        prog.SetInitialGuess(ik.q(), q + rng.normal(0, 0.2, 6))
        ok += int(Solve(prog).is_success())
    return n / (time.perf_counter() - t0), ok / n


def micro_rows(ext: Path, quick: bool, base) -> list[tuple[str, str, str, str]]:
    rows = []
    src = (ext / "cl_files" / "MECH491_NX_CLSF__APT_code.txt").read_text()
    body = [ln for ln in src.splitlines() if ln.startswith("GOTO") or ln.startswith("FEDRAT")]
    text = "\n".join(body * (20 if quick else 200) + ["FINI"])
    n_lines = text.count("\n") + 1
    t_ours = best_of(lambda: parse_cl_text(text, units="inch"), 3)
    t_naive = best_of(lambda: naive_parse(text), 3)
    rows.append(("CL parse (streaming reader)", f"{n_lines / t_ours:,.0f} lines/s",
                 f"naive regex GOTO-only {n_lines / t_naive:,.0f} lines/s",
                 f"{t_naive / t_ours:.2f}x"))
    n_pose = 2000 if quick else 20000
    rng = np.random.default_rng(0)
    lo, hi = np.array(ROBOT.limits.lower), np.array(ROBOT.limits.upper)
    X = fk_opw(IRB1600_10_120, rng.uniform(lo, hi, size=(n_pose, 6)))
    t_vec = best_of(lambda: [ik_opw(IRB1600_10_120, X[a:a + 1024])
                             for a in range(0, n_pose, 1024)], 3)
    drake_rate, drake_ok = drake_ik_rate(10 if quick else 50)
    rows.append(("analytic IK, vectorised (1024 poses per call)",
                 f"{n_pose / t_vec:,.0f} poses/s (8 branches each)",
                 f"Drake IK {drake_rate:,.1f} poses/s ({drake_ok:.0%} solved, 1 sol. each)",
                 f"{(n_pose / t_vec) / drake_rate:,.0f}x poses"))
    prog = read_cl(ext / "cl_files" / "MECH491_NX_CLSF__APT_Variable_Axis.txt", units="inch")
    n_pts = 60 if quick else len(prog)
    # the reader applies the file's MSYS (3, 3, 0) inch; placed as before it
    p_W = prog.p_C[:n_pts] - np.array([3.0, 3.0, 0.0]) * 0.0254 + np.array([0.75, 0.0, 0.25])
    axis = prog.axis_C[:n_pts]
    for label, X_FT in (("straight tool", tool(0.0, 0.15)),
                        ("tool tilted 30 deg", tool(30.0, 0.15))):
        res = {}
        for mode in ("min_travel", "greedy", "theta6_zero"):
            t = time.perf_counter()
            out = solve_tool_axis_path(ROBOT, p_W, axis, X_FT, mode)
            res[mode] = (path_travel(ROBOT, out.q)["weighted"], time.perf_counter() - t)
        if base is not None:
            t = time.perf_counter()
            old = base.solve_tool_axis_path(ROBOT, p_W, axis, X_FT, "min_travel")
            res["previous min_travel"] = (path_travel(ROBOT, old.q)["weighted"],
                                          time.perf_counter() - t)
        ta, sa = res["min_travel"]
        for other in [k for k in res if k != "min_travel"]:
            tb, sb = res[other]
            rows.append((f"spin, {label}, {n_pts} pts: min_travel vs {other}",
                         f"travel {ta:.3f} m, {n_pts / sa:,.0f} pts/s",
                         f"{other} {tb:.3f} m, {n_pts / sb:,.0f} pts/s",
                         f"{tb / ta:.3f}x travel"))
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shrink the work")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return 0
    ext = extdata_dir()
    if ext is None:
        print("extdata not found (set DRAKEDEBURR_EXTDATA)")
        return 2
    base = load_baseline()
    if base is None:
        print(f"note: baseline commit {BASELINE_COMMIT} not readable with git: no baseline")
    with tempfile.TemporaryDirectory() as tmp:
        rows = cam_rows(Path(tmp), args.quick, base)
        rows += stream_rows(Path(tmp), args.quick, base)
    rows += micro_rows(ext, args.quick, base)
    head = ("case", "ours", "baseline", "ratio")
    w = [max(len(head[i]), *(len(r[i]) for r in rows)) for i in range(4)]
    print(" | ".join(h.ljust(w[i]) for i, h in enumerate(head)))
    print("-|-".join("-" * x for x in w))
    for r in rows:
        print(" | ".join(c.ljust(w[i]) for i, c in enumerate(r)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
