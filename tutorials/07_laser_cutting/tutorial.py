"""Tutorial 07: laser cutting with the five-bar Cutting Tool (SPEC.md §S4, source 004).

Steps:
1. the tool: link lengths, working disc, distance to both kinds of singularity;
2. holes cut by the tool alone: shape -> servo IK -> TOPP-RA timing -> accuracy check;
3. TCP-speed output: laser command proportional to the TCP speed through a corner;
4. a larger contour cut by the robot with "Feature" settings;
5. FANUC .ls programs with the analogue output, and a Meshcat animation (static HTML).

Run:  python tutorials/07_laser_cutting/tutorial.py --out /tmp/laser  [--test-mode]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from drakedeburr.laser import (  # noqa: E402
    Circle,
    FeatureSettings,
    FiveBarGeometry,
    Hexagon,
    Keyhole,
    Rectangle,
    ServoLimits,
    Slot,
    check_reach,
    forward_kinematics,
    inverse_kinematics,
    plan_contour,
    plan_hole,
    singularity_measures,
)
from drakedeburr.laser.fanuc_ls import contour_program_ls, hole_program_ls, write_ls  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("laser_out"))
    ap.add_argument("--test-mode", action="store_true", help="fewer holes, coarser sampling")
    args = ap.parse_args()
    out = args.out
    out.mkdir(parents=True, exist_ok=True)

    # 1. The tool --------------------------------------------------------------------------
    g = FiveBarGeometry()
    print(f"Cutting Tool: L0={g.l0 * 1e3:.0f} L1={g.l1 * 1e3:.0f} L2={g.l2 * 1e3:.0f} "
          f"L3={g.l3 * 1e3:.0f} L4={g.l4 * 1e3:.0f} mm, working disc "
          f"{2e3 * g.work_radius:.0f} mm around home {np.round(g.p_CHome * 1e3, 1)} mm")
    xs = np.linspace(0.0, 0.13, 131)
    ys = np.linspace(-0.06, 0.09, 151)
    X, Y = np.meshgrid(xs, ys)
    p = np.stack([X.ravel(), Y.ravel()], axis=1)
    reach = check_reach(g, p, use_disc=False)  # IK + singularity + assembly-mode checks
    q, ok = reach.q, reach.reachable
    cond = np.full(len(p), np.nan)
    if ok.any():
        cond[ok] = singularity_measures(g, q[ok])["condition"]
    fig, ax = plt.subplots(figsize=(6, 6))
    im = ax.pcolormesh(X * 1e3, Y * 1e3, np.log10(cond.reshape(X.shape)), shading="auto",
                       vmin=0, vmax=2)
    fig.colorbar(im, label="log10 Jacobian condition (white: unreachable / near singular)")
    q_home, _ = inverse_kinematics(g, g.p_CHome)
    st = forward_kinematics(g, q_home)
    for a, b in ((g.p_CJ1, st.p_CJ3[0]), (g.p_CJ2, st.p_CJ4[0]), (st.p_CJ3[0], st.p_CJ5[0]),
                 (st.p_CJ4[0], st.p_CJ5[0])):
        ax.plot([a[0] * 1e3, b[0] * 1e3], [a[1] * 1e3, b[1] * 1e3], "k-", lw=3)
    circ = plt.Circle(g.p_CHome * 1e3, g.work_radius * 1e3, fill=False, color="r")
    ax.add_patch(circ)
    ax.set_aspect("equal")
    ax.set_xlabel("x_C [mm]")
    ax.set_ylabel("y_C [mm]")
    ax.set_title("Five-bar Cutting Tool at home; red: working disc")
    fig.savefig(out / "workspace.png", dpi=110)
    plt.close(fig)

    # 2. Holes by the tool alone --------------------------------------------------------------
    limits = ServoLimits()  # 10 rad/s, 300 rad/s^2, feed 10 m/min
    diameters = [1.0, 10.0, 25.0] if args.test_mode else [1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 25.0]
    report = []
    for d_mm in diameters:
        d = d_mm * 1e-3
        prog = plan_hole(Circle(diameter=d, lead_in=min(0.3 * d, 2e-3)),
                         spacing=min(0.2e-3, d / 8), limits=limits)
        t, _q, p_C, _ = prog.sample(1e-4)
        on = t >= prog.t[np.argmax(prog.contour.is_cut)]
        err = np.abs(np.linalg.norm(p_C[on] - g.p_CHome, axis=1) - d / 2).max()
        # key figures, re-read from the forward-kinematics samples: the hole within the
        # source's +-0.1 mm, the TCP never faster than the feed, the servos within their limit
        # (finite differences of the sampled positions and angles, not the timing's own speed)
        dt = np.diff(t)
        v_fd = np.linalg.norm(np.diff(p_C, axis=0), axis=1) / dt
        qd_fd = np.abs(np.diff(_q, axis=0)) / dt[:, None]
        assert err < 0.1e-3, (d_mm, err)
        assert v_fd.max() <= limits.feed * (1 + 1e-6), (d_mm, v_fd.max())
        assert qd_fd.max() <= limits.velocity * (1 + 1e-6), (d_mm, qd_fd.max())
        assert np.isclose(prog.contour.perimeter, np.pi * d, rtol=1e-9)
        report.append({"diameter_mm": d_mm, "points": len(prog.q),
                       "cycle_time_s": round(prog.duration, 4),
                       "max_speed_m_min": round(float(prog.v_tcp.max() * 60), 3),
                       "max_radial_error_mm": float(err * 1e3)})
        print(f"  circle {d_mm:5.1f} mm: {len(prog.q):4d} points, {prog.duration:.3f} s, "
              f"top speed {prog.v_tcp.max() * 60:5.2f} m/min, radial error "
              f"{err * 1e6:.3g} um")
    others = [Rectangle(width=0.016, height=0.010, corner_radius=0.002, lead_in=0.003),
              Slot(length=0.020, width=0.006, lead_in=0.002),
              Keyhole(head_diameter=0.012, slot_width=0.005, slot_length=0.010, lead_in=0.003),
              Hexagon(across_flats=0.017, lead_in=0.004)]
    exact_area = {  # [m^2]: the rectangle's four corners rounded, the hexagon across flats
        "rectangle": 0.016 * 0.010 - (4 - np.pi) * 0.002**2,
        "hexagon": np.sqrt(3) / 2 * 0.017**2,
    }
    for shape in others:
        prog = plan_hole(shape, spacing=0.2e-3, limits=limits)
        c = prog.contour
        cut = c.p_P[c.is_cut]
        shoelace = 0.5 * abs(np.dot(cut[:, 0], np.roll(cut[:, 1], -1))
                             - np.dot(cut[:, 1], np.roll(cut[:, 0], -1)))
        if shape.kind in exact_area:
            # the sampled polygon loses at most one sagitta (spacing^2 / 8 r, r = 2 mm) along
            # the perimeter; the contour's own area is the exact one
            assert abs(shoelace - exact_area[shape.kind]) <= c.perimeter * 0.2e-3**2 / (8 * 2e-3)
            assert np.isclose(c.area, exact_area[shape.kind], rtol=1e-9), shape.kind
        write_ls(out / f"hole_{shape.kind}.ls", hole_program_ls(prog, f"hole_{shape.kind}"))
        print(f"  {shape.kind:10s}: perimeter {prog.contour.perimeter * 1e3:6.2f} mm, area "
              f"{prog.contour.area * 1e6:7.2f} mm^2, cycle {prog.duration:.3f} s")

    # 3. TCP-speed output through the corners of a sharp rectangle -----------------------------
    prog = plan_hole(Rectangle(width=0.016, height=0.010, lead_in=0.003), spacing=0.2e-3)
    t, _, _, power = prog.sample(2e-4)
    fig, ax1 = plt.subplots(figsize=(8, 4))
    ax1.plot(t, power.v_tcp * 60, label="TCP speed [m/min]")
    ax1.plot(t, power.command, label="laser command [V]")
    ax1.set_xlabel("t [s]")
    ax1.legend()
    ax1.set_title("Laser command follows the TCP speed (clamped at 0.5 V in the corners)")
    fig.savefig(out / "tcp_speed_power.png", dpi=110)
    plt.close(fig)
    free = ~power.clamped & (power.v_tcp > 1e-3)
    # the command is proportional to the TCP speed wherever no clamp acts: constant energy/length
    e = power.energy_per_length[free]
    assert free.any() and power.clamped.any() and np.ptp(e) <= 1e-9 * e.max(), (e.min(), e.max())
    print(f"  energy per length, unclamped: {power.energy_per_length[free].min():.3f} .. "
          f"{power.energy_per_length[free].max():.3f} V s/m")
    write_ls(out / "hole_rectangle_sharp.ls", hole_program_ls(prog, "hole_rect_sharp"))

    # 4. A larger contour by the robot ("Feature" settings), in the plate frame (UFRAME) -----
    from drakedeburr.laser.fanuc_ls import job_programs_ls
    from drakedeburr.laser.robot_job import LaserCell, LaserProcess, plan_job

    X_RP = np.eye(4)
    X_RP[:3, 3] = [0.8, 0.0, 0.2]  # the plate 0.8 m in front of the M-10iA, 0.2 m up
    cell = LaserCell(robot="m10ia", X_RP=X_RP)
    feature = FeatureSettings(travel_angle=np.deg2rad(5.0), work_angle=0.0,
                              point_spacing=2e-3, speed=0.10, acceleration=3.0)
    targets = plan_contour(Rectangle(width=0.12, height=0.08, corner_radius=0.01,
                                     lead_in=0.005), None, feature)
    write_ls(out / "contour_rectangle.ls",
             contour_program_ls(targets, "contour_rect", cell, g))
    print(f"  robot contour: {len(targets)} poses, {targets.t[-1]:.2f} s")
    # ... and one job: two holes by the Cutting Tool, then the contour by the robot
    job = plan_job(cell, Rectangle(width=0.12, height=0.08, corner_radius=0.01,
                                   lead_in=0.005),
                   [((0.03, 0.01), Circle(diameter=0.008, lead_in=0.002)),
                    ((-0.03, -0.01), Slot(length=0.015, width=0.005, lead_in=0.002))],
                   g, LaserProcess(settings=feature))
    for name, text in job_programs_ls(job, "part_a").items():
        write_ls(out / f"{name.lower()}.ls", text)
    print(f"  job: {len(job.holes)} holes (CALLed), contour CONFIGs "
          f"{sorted(set(job.contour_motion.config))}")

    # 5. Meshcat animation ------------------------------------------------------------------
    from drakedeburr.laser.display import animate_hole, build_tool_scene
    from drakedeburr.resources import model_path
    from drakedeburr.viz import get_meshcat

    meshcat = get_meshcat(new=True)  # on 127.0.0.1 only (Drake's Meshcat() listens everywhere)
    # the Cutting Tool on the IRB1600's flange (robot_model=None shows the tool alone)
    scene = build_tool_scene(meshcat, g, robot_model=model_path("robots/irb1600_10_120.sdf"))
    prog = plan_hole(Keyhole(head_diameter=0.012, slot_width=0.005, slot_length=0.010,
                             lead_in=0.003), spacing=0.2e-3)
    robot_q = np.array([0.0, 0.3, 0.2, 0.0, -0.5, 0.0])  # robot holds still while the tool cuts
    animate_hole(scene, prog, meshcat, fps=100.0 if args.test_mode else 500.0, robot_q=robot_q)
    (out / "cutting_tool.html").write_text(meshcat.StaticHtml())
    (out / "holes.json").write_text(json.dumps(report, indent=2))
    print(f"outputs in {out}")


if __name__ == "__main__":
    main()
