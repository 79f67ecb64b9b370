"""Tutorial 06: post-processing and cell set-up (SPEC.md S0, S1, S2).

Steps:
1. read real CAM cutter-location files (Creo mm with CIRCLE, NX CLSF inch, 5-axis);
2. the analytic OPW IK: all 8 solutions of one pose and their vendor configuration data;
3. CL file -> robot program: work object, tool, free spin about the tool axis resolved by
   minimum joint travel (compared with the paper's theta6 = 0), ABB RAPID / KUKA KRL /
   FANUC LS written and read back;
4. workpiece in hand: virtual TCP points for a contour (translation and rotation modes);
5. calibration of the worktable from touched points, with scale compensation.

Run:  python tutorials/06_post_processing/tutorial.py --out /tmp/post  [--test-mode]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from drakedeburr.errors import InputError  # noqa: E402
from drakedeburr.post import (  # noqa: E402
    PostSettings,
    contour_frames,
    fit_touch_points,
    offset_contour,
    part_contour_at_virtual,
    path_travel,
    pose_from_mm_deg,
    program_from_cl,
    read_cl,
    solve_tool_axis_path,
    virtual_tcp_poses,
)
from drakedeburr.programs import compare_programs, read_program, write_program  # noqa: E402
from drakedeburr.resources import extdata_dir  # noqa: E402
from drakedeburr.robots import (  # noqa: E402
    IRB1600_10_120_ROBOT,
    abb_confdata,
    fanuc_config,
    fk_opw,
    ik_opw,
    joints_from_configuration,
    kuka_status_turn,
)

ROBOT = IRB1600_10_120_ROBOT


def step1_read(cl_dir: Path) -> dict:
    print("\n1. CL files")
    creo = read_cl(cl_dir / "CreoPost__profilfraesen_2.ncl.2")  # UNITS / MM in the file
    nx = read_cl(cl_dir / "MECH491_NX_CLSF__APT_Variable_Axis.txt", units="inch")  # no UNITS
    for prog in (creo, nx):
        n_circle = sum(m.from_circle for m in prog.moves)
        print(f"   {Path(prog.source).name}: {len(prog.moves)} moves ({n_circle} from CIRCLE), "
              f"{int(prog.rapid.sum())} rapid, units {prog.units}, "
              f"{len(prog.warnings)} warnings, end at line {prog.end_line}")
    return {"creo": creo, "nx": nx}


def step2_ik() -> None:
    print("\n2. Analytic IK of one pose: all solutions and their configuration data")
    q_true = np.array([0.3, 0.4, -0.5, 0.6, 1.1, -0.4])
    X_BF = fk_opw(ROBOT.opw, q_true)
    sols = ik_opw(ROBOT.opw, X_BF)
    print("   branch (shoulder, elbow, wrist) | joints [deg] | ABB confdata | KUKA S,T | FANUC")
    for q, ok, br in zip(sols.q[0], sols.valid[0], sols.branch, strict=True):
        if not ok:
            print(f"   {tuple(int(b) for b in br)} out of reach")
            continue
        inside = "" if ROBOT.limits.contains(q) else "  (outside joint limits)"
        print(f"   {tuple(int(b) for b in br)} {np.round(np.degrees(q), 1)} "
              f"{abb_confdata(ROBOT, q)} {kuka_status_turn(ROBOT, q)} "
              f"'{fanuc_config(ROBOT, q)}'{inside}")
        err = np.abs(fk_opw(ROBOT.opw, q) - X_BF).max()
        assert err < 1e-9, err
    # pose + configuration -> joints (what a controller does with a robtarget)
    q_back = joints_from_configuration(ROBOT, X_BF, "abb", abb_confdata(ROBOT, q_true))
    print(f"   robtarget pose + confdata -> joints: error {np.abs(q_back - q_true).max():.1e} rad")


def step3_programs(cl: dict, out: Path, test_mode: bool) -> dict:
    print("\n3. CL -> robot programs")
    # the Creo part is clamped 700 mm in front of the robot, 300 mm up, turned 30 deg
    X_WO = pose_from_mm_deg([700, 0, 300, 0, 0, 30])
    X_FT = pose_from_mm_deg([0, 0, 200, 0, 0, 0])  # burr 200 mm out along the flange axis
    result = program_from_cl(cl["creo"], "creo_profile", PostSettings(X_WO=X_WO, X_FT=X_FT))
    print(f"   {len(result.program.moves)} moves, unreachable CL lines: "
          f"{result.unreachable_lines or 'none'}")
    # the program is written in the arm's own language (RAPID for the ABB) and read back
    (path,) = write_program(result.program, out / "creo_profile.mod")
    back = read_program(path)
    differences = compare_programs(result.program, back)
    print(f"   wrote {path.name}: {len(back.moves)} moves read back, {len(differences)} "
          "differences to the program")
    assert not differences
    try:  # KRL is a KUKA language: refused for the ABB arm
        write_program(result.program, out / "creo_profile.src", "krl")
    except InputError as exc:
        print(f"   KRL refused: {exc}")
    # without the work object the CL coordinates are robot base coordinates: unreachable
    base = program_from_cl(cl["creo"], "creo_base", PostSettings(X_FT=X_FT))
    print(f"   same file in the robot base frame: {len(base.unreachable_lines)} unreachable "
          f"lines (first {base.unreachable_lines[:3]}), no program unless forced")

    # 5-axis: the spin about the tool axis is free; compare the two rules
    nx = cl["nx"]
    n = 40 if test_mode else len(nx.moves)
    p_W = nx.p_C[:n] + np.array([0.75, 0.0, 0.25])
    X_tilt = np.eye(4)
    X_tilt[:3, :3] = Rotation.from_euler("Y", 30, degrees=True).as_matrix()
    X_tilt[:3, 3] = [0.05, 0.0, 0.15]
    travel = {}
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for mode in ("min_travel", "theta6_zero"):
        res = solve_tool_axis_path(ROBOT, p_W, nx.axis_C[:n], X_tilt, mode=mode)
        travel[mode] = path_travel(ROBOT, res.q)
        ax.plot(np.degrees(res.q[:, 3]), label=f"J4, {mode}")
        ax.plot(np.degrees(res.q[:, 5]), "--", label=f"J6, {mode}")
    ax.set_xlabel("CL point")
    ax.set_ylabel("joint [deg]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "spin_rules.png", dpi=100)
    plt.close(fig)
    ratio = travel["theta6_zero"]["weighted"] / travel["min_travel"]["weighted"]
    print(f"   NX 5-axis file, tool tilted 30 deg, {n} points: weighted joint travel "
          f"{travel['min_travel']['weighted']:.3f} m (min travel) vs "
          f"{travel['theta6_zero']['weighted']:.3f} m (theta6 = 0): x{ratio:.2f}")
    return {"spin_travel": travel, "files": [path.name]}


def _rounded_rect(a=0.06, b=0.04, r=0.01, n=16):
    pts = []
    for cx, cy, t0 in ((a - r, b - r, 0), (-a + r, b - r, np.pi / 2), (-a + r, -b + r, np.pi),
                       (a - r, -b + r, 1.5 * np.pi)):
        t = np.linspace(t0, t0 + np.pi / 2, n, endpoint=False)
        pts += list(zip(cx + r * np.cos(t), cy + r * np.sin(t), 0 * t, strict=True))
    return np.array(pts)


def step4_virtual_tcp(out: Path) -> dict:
    print("\n4. Workpiece in hand: virtual TCP")
    X_RO = pose_from_mm_deg([900, -200, 400, 0, 0, 40])  # fixed spindle, burr radius 4 mm
    X_RP = pose_from_mm_deg([880, -190, 400, 0, 0, 55])  # part at the reference pose
    p_PA = offset_contour(_rounded_rect(), 0.004, "outward")
    X_RA = X_RP[None] @ contour_frames(p_PA)
    report = {}
    fig, ax = plt.subplots(figsize=(5, 4))
    for mode in ("translation", "rotation"):
        X_RV = virtual_tcp_poses(X_RO, X_RA, mode)
        X_OA = part_contour_at_virtual(X_RO, X_RV, X_RA)
        err = float(np.abs(X_OA[:, :3, 3]).max())
        report[mode] = err
        turn = Rotation.from_matrix(X_RV[0, :3, :3]).inv() * Rotation.from_matrix(X_RV[:, :3, :3])
        print(f"   {mode}: contour point on the tool centre to {err:.1e} m; the TCP turns "
              f"up to {np.degrees(turn.magnitude()).max():.1f} deg from the first point")
        ax.plot(X_RV[:, 0, 3] * 1e3, X_RV[:, 1, 3] * 1e3, label=f"virtual points, {mode}")
    ax.plot(X_RA[:, 0, 3] * 1e3, X_RA[:, 1, 3] * 1e3, "k:", label="contour (+R) at reference")
    ax.plot(X_RO[0, 3] * 1e3, X_RO[1, 3] * 1e3, "r*", label="tool (virtual TCP)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7)
    fig.savefig(out / "virtual_tcp.png", dpi=100)
    plt.close(fig)
    return report


def step5_calibration() -> dict:
    print("\n5. Worktable calibration from touched points")
    rng = np.random.default_rng(0)
    X_true = pose_from_mm_deg([850, -120, 310, 0.5, -1.0, 63])
    p_T = np.column_stack([rng.uniform(-0.2, 0.2, 8), rng.uniform(-0.15, 0.15, 8),
                           rng.choice([0.0, 0.05], 8)])
    s_true = 1.005  # systematic error ~1 mm at 200 mm (robot zero offset + geometry)
    p_W = s_true * p_T @ X_true[:3, :3].T + X_true[:3, 3] + rng.normal(0, 0.03e-3, p_T.shape)
    fit = fit_touch_points(p_T, p_W, estimate_scale=True)
    print(f"   rigid fit RMS {fit.rms_rigid * 1e3:.3f} mm -> with scale {fit.scale:.5f}: "
          f"RMS {fit.rms_scaled * 1e3:.3f} mm")
    # the robot's coordinates of a table point are s times T's: paths in T are compensated
    # by the typed compensation (its direction is fixed by what was measured)
    refit = fit_touch_points(fit.scale_compensation().compensate_path(p_T), p_W)
    print(f"   paths in T compensated (scale {fit.scale_compensation().scale:.5f} made), rigid "
          f"refit RMS {refit.rms_rigid * 1e3:.3f} mm (machined parts: tutorial 09)")
    return {"rms_rigid_mm": fit.rms_rigid * 1e3, "rms_scaled_mm": fit.rms_scaled * 1e3,
            "scale": fit.scale}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/06_post_processing"))
    ap.add_argument("--test-mode", action="store_true", help="less work (CI)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    ext = extdata_dir()
    if ext is None:
        raise SystemExit("extdata (../shared/extdata) not found: set DRAKEDEBURR_EXTDATA")
    cl = step1_read(ext / "cl_files")
    step2_ik()
    summary = step3_programs(cl, args.out, args.test_mode)
    summary["virtual_tcp_error_m"] = step4_virtual_tcp(args.out)
    summary["calibration"] = step5_calibration()
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2, sort_keys=True))
    print(f"\noutputs in {args.out}")


if __name__ == "__main__":
    main()
