"""Tutorial 09: calibrating a cell and compensating its systematic error (source 002).

Steps, on a simulated cell (the arm's forward kinematics stands in for the real robot):
1. touch points: the calibration tip held on one point in six orientations (pivot) and on
   eight known features of the work table; the table is 2.5 mm / 0.8 deg and the tip 1.5 mm
   off their design values; ``drakedeburr calibrate`` fits the TCP and the table frame,
   writes a calibrated scenario and a check program;
2. scale compensation as the paper's workflow: an arm whose joint zeros and link lengths are
   off cuts a 240 x 160 mm part ~2 mm wrong; the machined edge is scanned, the map fitted
   (the paper's single scale, a similarity, a scale per direction), the path regenerated
   from ``compensate_path(model)`` and the part cut again. Scaling the model by the fitted
   scale instead (the old tutorial's way) doubles the error.

Run:  python tutorials/09_cell_calibration/tutorial.py --out /tmp/cal  [--test-mode]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from drakedeburr.cli import main as drakedeburr
from drakedeburr.post import fit_machined_contour, offset_contour, pose_from_mm_deg
from drakedeburr.post.virtual_tcp_post import virtual_tcp_setup
from drakedeburr.robots import IRB1600_10_120_ROBOT as ARM
from drakedeburr.robots import fk_opw, ik_opw, solve_path

TOOL_SET = [0.0, 0, 200, 0, 0, 0]  # the tool set on the controller (mm, deg)
TIP_TRUE = np.array([0.8, -0.6, 201.5]) * 1e-3  # where the tip really is in the flange [m]
TABLE_TRUE = pose_from_mm_deg([752.5, -1.8, -458.8, 0.3, -0.2, 0.8])  # design: 750, 0, -460


def _report_pose(p_B, R, rng):
    """What the controller shows when the real tip touches p_B (0.02 mm touch noise)."""
    X_BF = np.eye(4)
    X_BF[:3, :3] = R
    X_BF[:3, 3] = p_B + rng.normal(0, 0.02e-3, 3) - R @ TIP_TRUE
    sol = ik_opw(ARM.opw, X_BF[None])
    q = sol.q[0, np.flatnonzero(sol.valid[0] & ARM.limits.contains(sol.q[0]))[0]]
    X = fk_opw(ARM.opw, q) @ pose_from_mm_deg(TOOL_SET)
    rz, ry, rx = Rotation.from_matrix(X[:3, :3]).as_euler("ZYX", degrees=True)
    return [round(float(v), 4) for v in (*(X[:3, 3] * 1e3), rx, ry, rz)]


def _down(tilt, about):
    return (Rotation.from_euler("z", about, degrees=True) * Rotation.from_euler("y", tilt,
            degrees=True) * Rotation.from_euler("x", 180, degrees=True)).as_matrix()


def step1_calibrate(out: Path) -> dict:
    print("\n1. drakedeburr calibrate on touched points")
    rng = np.random.default_rng(0)
    tcp = [_report_pose(np.array([0.7, 0.2, -0.2]), _down(t, a), rng)
           for t, a in ((0, 0), (25, 0), (25, 90), (25, 180), (25, 270), (35, 45))]
    features = [[-100, -140, 0], [100, -140, 0], [100, 140, 0], [-100, 140, 0], [0, 0, 0],
                [60, -40, 30], [-60, 70, 30], [0, 150, 0]]
    points = [{"feature": f, "pose": _report_pose(
        TABLE_TRUE[:3, :3] @ (np.array(f) * 1e-3) + TABLE_TRUE[:3, 3], _down(8, 45 * i), rng)}
        for i, f in enumerate(features)]
    touches = out / "touches.yaml"
    touches.write_text(yaml.safe_dump({
        "robot": "irb1600", "tool": TOOL_SET, "tcp": tcp,
        "table": {"points": points, "part": [[-90, -130, 0], [90, 130, 0], [400, 0, 0]]}}))
    rc = drakedeburr(["calibrate", str(touches), "--report", str(out / "calibration.yaml"),
                      "--scenario", "tool_in_hand", "--scenario-out", str(out / "cell.yaml"),
                      "--program", str(out / "check.mod")])
    rep = yaml.safe_load((out / "calibration.yaml").read_text())
    assert rc == 0 and (out / "cell.yaml").is_file() and (out / "check.mod").is_file(), rc
    print(f"   exit {rc}; TCP {rep['tcp']['tool_mm_deg'][:3]} mm (true 0.8, -0.6, 201.5); "
          f"table {rep['table']['frame_mm_deg']} (true 752.5, -1.8, -458.8, 0.3, -0.2, 0.8)")
    print(f"   residual RMS {rep['table']['rms_mm']} mm; a part point 300 mm outside the "
          f"touches: predicted error {rep['table']['part_predicted_error_mm']} mm (warned)")
    return rep


def _rounded_rect(a=0.12, b=0.08, r=0.02, n=24):
    pts = []
    for cx, cy, t0 in ((a - r, b - r, 0), (-a + r, b - r, np.pi / 2), (-a + r, -b + r, np.pi),
                       (a - r, -b + r, 1.5 * np.pi)):
        t = np.linspace(t0, t0 + np.pi / 2, n)
        pts += list(zip(cx + r * np.cos(t), cy + r * np.sin(t), 0 * t, strict=True))
    return np.array(pts)


class SimulatedCell:
    """The arm holds the part over a fixed vertical spindle (virtual TCP program); the
    controller believes the nominal model, the real arm's zeros and links are off."""

    R_TOOL = 0.004
    X_BO = pose_from_mm_deg([800, 0, 300, 0, 0, 0])
    X_FP = pose_from_mm_deg([0, 0, 100, 0, 0, 0])

    def __init__(self, links, zeros):
        o = ARM.opw
        self.real = dataclasses.replace(
            o, a1=o.a1 + links[0], c2=o.c2 + links[1], c3=o.c3 + links[2], c4=o.c4 + links[3],
            offsets=tuple(np.asarray(o.offsets) + zeros))
        self.setup = None

    def machine(self, model: np.ndarray) -> np.ndarray:
        """Cut along a path generated from ``model``; returns the scanned machined edge."""
        path = offset_contour(model, self.R_TOOL, "outward")
        if self.setup is None:
            self.setup = virtual_tcp_setup(ARM, self.X_BO, self.X_FP, path, np.eye(3)[2])
        X_BF = self.setup.virtual_points(path) @ np.linalg.inv(self.setup.X_FT)[None]
        q = solve_path(ARM, X_BF, q_start=np.array([0, 0, 0, 0, np.pi / 2, 0])).q
        X_PB = np.linalg.inv(fk_opw(self.real, q) @ self.X_FP)
        c = (X_PB[:, :3, :3] @ self.X_BO[:3, 3] + X_PB[:, :3, 3])[:, :2]
        t = np.roll(c, -1, 0) - np.roll(c, 1, 0)
        nu = np.column_stack([t[:, 1], -t[:, 0]]) / np.linalg.norm(t, axis=1)[:, None]
        edge = c - self.R_TOOL * nu
        return np.column_stack([edge, np.zeros(len(edge))])


def _error(edge, model):
    a, b = model[:, :2], np.roll(model[:, :2], -1, 0)
    x = edge[:, :2]
    t = np.clip(np.einsum("mnk,nk->mn", x[:, None] - a[None], b - a)
                / np.sum((b - a) ** 2, 1), 0, 1)
    d = np.linalg.norm(x[:, None] - (a[None] + t[..., None] * (b - a)[None]), axis=-1)
    return float(d.min(1).max())


def step2_scale_compensation() -> dict:
    print("\n2. Scale compensation: measure the part -> fit -> regenerate -> cut again")
    cell = SimulatedCell(np.array([1.5, 2.2, -1.5, 0.7]) * 1e-3,
                         np.radians([0.07, 0.15, -0.12, 0.07, 0.15, 0.0]))
    model = _rounded_rect()
    edge = cell.machine(model)
    report = {"before_mm": _error(edge, model) * 1e3}
    print(f"   uncompensated: the part is off by up to {report['before_mm']:.2f} mm")
    for kind in ("scale", "similarity", "affine"):
        fit = fit_machined_contour(model, edge, model=kind)
        after = _error(cell.machine(fit.compensate_path(model)), model) * 1e3
        report[kind] = {"scale": fit.scale, "predicted_mm": fit.predicted_residual * 1e3,
                        "after_mm": after}
        print(f"   {kind:10s}: s = {fit.scale:.5f}, predicted {fit.predicted_residual * 1e3:.3f}"
              f" mm, re-cut part off by {after:.3f} mm")
    fit = fit_machined_contour(model, edge, model="scale")
    wrong = cell.machine(fit.center + (model - fit.center) * fit.scale)
    report["wrong_way_mm"] = _error(wrong, model) * 1e3
    print(f"   the model scaled by s instead of compensated: {report['wrong_way_mm']:.2f} mm")
    return report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/09_cell_calibration"))
    ap.add_argument("--test-mode", action="store_true", help="(the tutorial is small already)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    summary = {"calibration": step1_calibrate(args.out),
               "scale_compensation": step2_scale_compensation()}
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2, sort_keys=True))
    check(summary)
    print(f"\noutputs in {args.out}")


def check(summary: dict) -> None:
    """What the tutorial shows, held against the simulated truth: the fitted TCP and table
    within the touch noise's reach (0.02 mm a touch), the files written, each compensation
    better than none and the richer maps better, scaling the model the wrong way worse."""
    cal, comp = summary["calibration"], summary["scale_compensation"]
    assert cal["ok"], cal["failures"]
    tcp_err = np.linalg.norm(np.array(cal["tcp"]["tool_mm_deg"][:3]) - TIP_TRUE * 1e3)
    assert tcp_err < 0.1, f"TCP {tcp_err:.3f} mm from the true tip"
    frame = pose_from_mm_deg(cal["table"]["frame_mm_deg"])
    pos_err = np.linalg.norm(frame[:3, 3] - TABLE_TRUE[:3, 3]) * 1e3
    turn = np.degrees(Rotation.from_matrix(frame[:3, :3].T @ TABLE_TRUE[:3, :3]).magnitude())
    assert pos_err < 0.1 and turn < 0.02, f"table {pos_err:.3f} mm / {turn:.4f} deg off"
    assert cal["table"]["rms_mm"] < 0.05  # the touch noise, not a misfit
    after = [comp[k]["after_mm"] for k in ("scale", "similarity", "affine")]
    assert comp["before_mm"] > 1.0 and after[0] < 0.25 * comp["before_mm"], comp
    assert after[0] > after[1] > after[2], after
    for k in ("scale", "similarity", "affine"):  # the fit predicts what the re-cut gives
        assert abs(comp[k]["predicted_mm"] - comp[k]["after_mm"]) < 0.01, (k, comp[k])
    assert comp["wrong_way_mm"] > comp["before_mm"], comp


if __name__ == "__main__":
    main()
