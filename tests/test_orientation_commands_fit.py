"""orientation.commands: the ``orient`` command's CL points lie on the pipeline's edge fit
(path.window_fit, issue 42 item 3): a faceted low-poly loop gets the smoothing fit (the row's
fit record says so, and the CL points stay within the facets' sagitta of the designed circle),
a bundled hub's loops keep the interpolating fit point for point."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.config import ProcessParameters
from drakedeburr.frames.local_frames import angles_from_zT_H
from drakedeburr.hub.extract import resample_loop
from drakedeburr.hub.types import WindowEdge
from drakedeburr.orientation.commands import OrientRun, cl_points_planned, run_orient

Z = np.array([0.0, 0.0, 1.0])


def _faceted_window(n_facets=24, R=0.05):
    """A round window of radius R cut into N facets (a low-poly mesh's edge), sampled every
    0.5 mm as ``hub import`` stores it; vertical walls, inner normal Z x t of each facet."""
    a = 2 * np.pi * np.arange(n_facets) / n_facets + 0.2
    p = resample_loop(np.c_[R * np.cos(a), R * np.sin(a), np.zeros(n_facets)], 0.5e-3)
    t = np.roll(p, -1, axis=0) - p
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return WindowEdge(index=0, kind="large", p_HE=p, t_H=t, n_wall_H=np.cross(Z, t)), R


def test_orient_on_a_faceted_loop_uses_the_faceted_fit():
    edge, R = _faceted_window()
    hub = SimpleNamespace(windows=[edge], process=ProcessParameters())
    (row,) = run_orient(hub, OrientRun(normals="truth"))
    fit = row["edge_fit"]
    assert fit["fit"] == "faceted" and fit["facets"] == 24
    tp = row["_tool_path"]
    # independent: the CL points on the smoothing fit stay within the facets' sagitta of the
    # designed circle (the interpolating fit's corner wiggles are not followed) ...
    sagitta = R * (1 - np.cos(np.pi / 24))
    r = np.linalg.norm(tp.p_HC[:, :2], axis=1)
    assert np.abs(r - R).max() <= sagitta + 2e-6
    # ... their tangents turn one way round (CCW) at every step, no back-and-forth at corners
    t = tp.cl_path.t_H
    turn_z = np.cross(t, np.roll(t, -1, axis=0))[:, 2]
    assert (turn_z > 0).all()
    # and every tool axis, read back to angles, is inside the process box
    a, b = angles_from_zT_H(tp.R_HL, tp.zT_H)
    box = tp.bounds
    assert tp.success
    assert (a >= box.theta_min - 1e-9).all() and (a <= box.theta_max + 1e-9).all()
    assert (b >= box.theta_min - 1e-9).all() and (b <= box.theta_max + 1e-9).all()


@pytest.mark.parametrize("name", ["h5_straight", "h6_curved"])
def test_bundled_hubs_keep_the_interpolating_fit_point_for_point(name):
    from drakedeburr.hub.model import load_hub
    from drakedeburr.path import fit_edge_curve, plan_cl

    hub = load_hub(name)
    for edge in hub.windows[:2]:
        cl, idx = cl_points_planned(edge, "proposed")
        assert cl.metrics["edge_fit"]["fit"] == "interpolating"
        ref = plan_cl(fit_edge_curve(edge.p_HE), "proposed", window_index=edge.index,
                      kind=edge.kind)
        assert np.array_equal(cl.p_HC, ref.p_HC) and np.array_equal(cl.t_H, ref.t_H)
