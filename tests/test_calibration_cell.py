"""Scale compensation as the paper's workflow (source 002) on a simulated cell.

The cell: the project's IRB1600 holds a 240 x 160 mm part over a fixed vertical spindle
(virtual TCP program, source 000; tool radius 4 mm). The controller believes the nominal
OPW model; the real arm's joint zeros and link lengths are off (``_true_arm``). What the
cell makes is simulated independently of the fit: the controller's joints (nominal IK of
the program's targets) through the real arm's forward kinematics give where the spindle
axis runs through the part; the machined edge is that tool-centre path's envelope, R
inside it along its normal. The workflow: cut the part from the nominal model, scan the
edge, fit the map, regenerate the path from ``compensate_path(model)``, cut again.
"""

import dataclasses

import numpy as np
import pytest

from drakedeburr.post.calibration import fit_machined_contour
from drakedeburr.post.cl_post import pose_from_mm_deg
from drakedeburr.post.virtual_tcp import offset_contour
from drakedeburr.post.virtual_tcp_post import virtual_tcp_setup
from drakedeburr.robots import IRB1600_10_120_ROBOT as NOMINAL
from drakedeburr.robots import fk_opw, solve_path

R_TOOL = 0.004
X_BO = pose_from_mm_deg([800, 0, 300, 0, 0, 0])  # spindle tool point, axis up
X_FP = pose_from_mm_deg([0, 0, 100, 0, 0, 0])  # the part's frame on the flange
Q_START = np.array([0, 0, 0, 0, np.pi / 2, 0])
#: link-length [m] and joint-zero [rad] errors of the real arm (a few tenths of a degree and
#: about a millimetre: the order of an uncalibrated industrial arm's)
ERRORS = {"fixed": (np.array([1.5, 2.2, -1.5, 0.7]) * 1e-3,
                    np.radians([0.07, 0.15, -0.12, 0.07, 0.15, 0.0]))}


def _true_arm(links, zeros):
    o = NOMINAL.opw
    return dataclasses.replace(
        o, a1=o.a1 + links[0], c2=o.c2 + links[1], c3=o.c3 + links[2], c4=o.c4 + links[3],
        offsets=tuple(np.asarray(o.offsets) + zeros))


def _rounded_rect(a=0.12, b=0.08, r=0.02, n=24):
    pts = []
    for cx, cy, t0 in ((a - r, b - r, 0), (-a + r, b - r, np.pi / 2), (-a + r, -b + r, np.pi),
                       (a - r, -b + r, 1.5 * np.pi)):
        t = np.linspace(t0, t0 + np.pi / 2, n)
        pts += list(zip(cx + r * np.cos(t), cy + r * np.sin(t), 0 * t, strict=True))
    return np.array(pts)


def _distance_to_polygon(x, poly):
    a, b = poly, np.roll(poly, -1, 0)
    t = np.clip(np.einsum("mnk,nk->mn", x[:, None] - a[None], b - a)
                / np.sum((b - a) ** 2, 1), 0, 1)
    return np.linalg.norm(x[:, None] - (a[None] + t[..., None] * (b - a)[None]), axis=-1).min(1)


class _Cell:
    def __init__(self, arm):
        self.arm = arm
        self.setup = None

    def machine(self, model):
        """The machined edge (scan points, (M, 3) in the part frame) of a path generated from
        ``model`` (the part contour the path is made from)."""
        path = offset_contour(model, R_TOOL, "outward")
        if self.setup is None:  # the program's frames, fixed for the cell
            self.setup = virtual_tcp_setup(NOMINAL, X_BO, X_FP, path, np.array([0, 0, 1.0]))
        X_BV = self.setup.virtual_points(path)
        res = solve_path(NOMINAL, X_BV @ np.linalg.inv(self.setup.X_FT)[None], q_start=Q_START)
        assert res.ok
        X_BP = fk_opw(self.arm, res.q) @ X_FP  # where the real arm holds the part
        X_PB = np.linalg.inv(X_BP)
        c = (X_PB[:, :3, :3] @ X_BO[:3, 3] + X_PB[:, :3, 3])[:, :2]  # tool axis in the part
        t = np.roll(c, -1, 0) - np.roll(c, 1, 0)
        nu = np.column_stack([t[:, 1], -t[:, 0]]) / np.linalg.norm(t, axis=1)[:, None]
        edge = c - R_TOOL * nu  # counter-clockwise path: nu points outward
        return np.column_stack([edge, np.zeros(len(edge))])


def _error(edge, model):
    return float(_distance_to_polygon(edge[:, :2], model[:, :2]).max())


def _cases():
    rng = np.random.default_rng(7)
    cases = dict(ERRORS)
    for i in range(2):
        cases[f"random{i}"] = (rng.normal(0, 1e-3, 4), np.radians(rng.normal(0, 0.1, 6)))
    return cases


@pytest.mark.parametrize("name", list(_cases()))
def test_scale_compensation_on_a_simulated_arm(name):
    """~2 mm off uncompensated -> <= 0.1 mm after one measure-fit-regenerate cycle, the
    residual predicted by the fit within 0.02 mm of the re-cut part; the compensation
    applied the wrong way round makes the error worse."""
    links, zeros = _cases()[name]
    model = _rounded_rect()
    k = 2e-3 / _error(_Cell(_true_arm(links, zeros)).machine(model), model)
    cell = _Cell(_true_arm(k * links, k * zeros))  # errors scaled to a ~2 mm part error
    edge = cell.machine(model)
    before = _error(edge, model)
    assert 1.9e-3 < before < 2.1e-3
    fit = fit_machined_contour(model, edge)  # default: the affine (per-direction) map
    assert fit.error_before == pytest.approx(before, abs=1e-6)
    after = _error(cell.machine(fit.compensate_path(model)), model)
    assert after <= 0.1e-3, after
    assert abs(fit.predicted_residual - after) < 0.02e-3
    wrong = model @ fit.linear.T + fit.offset  # the fitted map applied to the model instead
    assert _error(cell.machine(wrong), model) > before
    # the paper's single scale helps, but an arm with these errors distorts by direction:
    # 0.17, 0.46 and 0.68 mm are left in the three cases (docs/post.md)
    paper = fit_machined_contour(model, edge, model="scale")
    after_paper = _error(cell.machine(paper.compensate_path(model)), model)
    assert after_paper < before
    assert abs(paper.predicted_residual - after_paper) < 0.05e-3
