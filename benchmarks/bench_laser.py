"""Laser cell benchmark: shapes per second, and the top contour speed the Cutting Tool reaches.

    python benchmarks/bench_laser.py [--quick]

1. Shape generation rate (build_contour at 0.2 mm spacing) per kind, and the full tool
   pipeline (shape -> IK -> TOPP-RA -> power) per second; baseline: circle generation.
2. Top TCP speed on circles of 1-25 mm diameter, feed cap lifted to 100 m/min, under the
   assumed servo limits (speed / acceleration at the servo output), vs the source's 10 m/min
   claim; baseline: the robot alone cutting the same circle under a 3 m/s^2 TCP acceleration
   limit (same run, same timing code).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from drakedeburr.laser import FeatureSettings, plan_contour, plan_hole  # noqa: E402
from drakedeburr.laser import shapes as S  # noqa: E402
from drakedeburr.laser.hole import ServoLimits  # noqa: E402

# run_all.py: the reference run and a fast one (benchmarks/README.md)
FULL_ARGS = ()
QUICK_ARGS = ("--quick",)


def _rate(fn, min_time: float) -> float:
    fn()  # warm-up: lazy imports, cached TOPP-RA plant
    n, t0 = 0, time.perf_counter()
    while True:
        fn()
        n += 1
        dt = time.perf_counter() - t0
        if dt >= min_time:
            return n / dt


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    min_time = 0.3 if args.quick else 1.5
    spacing = 0.2e-3
    shapes = {
        "circle": S.Circle(diameter=0.010, lead_in=0.002),
        "semicircle": S.Semicircle(diameter=0.012, lead_in=0.002),
        "rectangle": S.Rectangle(width=0.016, height=0.010, corner_radius=0.002, lead_in=0.003),
        "slot": S.Slot(length=0.020, width=0.006, lead_in=0.002),
        "keyhole": S.Keyhole(head_diameter=0.012, slot_width=0.005, slot_length=0.010,
                             lead_in=0.003),
        "hexagon": S.Hexagon(across_flats=0.017, lead_in=0.004),
        "polyline": S.Polyline(points=((-0.005, -0.005), (0.006, -0.004), (0.0, 0.007)),
                               lead_in=0.002),
    }
    print("## 1. shapes per second (0.2 mm spacing)")
    base = None
    print(f"{'shape':12s} {'points':>7s} {'shapes/s':>10s} {'vs circle':>10s} "
          f"{'full plan/s':>12s} {'vs circle':>10s}")
    for name, shape in shapes.items():
        n = len(S.build_contour(shape, spacing))
        r = _rate(lambda shape=shape: S.build_contour(shape, spacing), min_time)
        rp = _rate(lambda shape=shape: plan_hole(shape, spacing), min_time)
        base = base or r  # baseline: the circle row, measured first
        print(f"{name:12s} {n:7d} {r:10.0f} {r / base:10.2f} {rp:12.1f} {rp / base:10.4f}")

    print("\n## 2. top TCP speed on circles [m/min] (feed cap 100 m/min)")
    limit_sets = [ServoLimits(velocity=5.0, acceleration=150.0),
                  ServoLimits(velocity=10.0, acceleration=300.0),
                  ServoLimits(velocity=20.0, acceleration=1000.0)]
    diameters = [1, 5, 25] if args.quick else [1, 2, 3, 5, 10, 15, 20, 25]
    head = " ".join(f"{f'tool {lim.velocity:g}r/s,{lim.acceleration:g}r/s2':>22s}"
                    for lim in limit_sets)
    print(f"{'diam mm':>7s} {'robot 3m/s2 (base)':>19s} {head} {'ratio mid/base':>15s}")
    for d_mm in diameters:
        d = d_mm * 1e-3
        shape = S.Circle(diameter=d)
        robot = plan_contour(shape, settings=FeatureSettings(point_spacing=min(2e-4, d / 8),
                                                             speed=100 / 60, acceleration=3.0))
        v_robot = robot.speed.max() * 60
        tops = []
        for lim in limit_sets:
            lim = ServoLimits(velocity=lim.velocity, acceleration=lim.acceleration,
                              feed=100 / 60, feed_acceleration=1e3)
            prog = plan_hole(shape, min(0.2e-3, d / 8), limits=lim)
            tops.append(prog.v_tcp.max() * 60)
        cells = " ".join(f"{v:22.2f}" for v in tops)
        print(f"{d_mm:7g} {v_robot:19.2f} {cells} {tops[1] / v_robot:15.2f}")
    print("\nsource claim: 10 m/min top speed; holes 1-25 mm; +-0.1 mm")


if __name__ == "__main__":
    main()
