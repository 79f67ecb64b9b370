"""Meshcat scene of the Cutting Tool: the drawn TCP follows the planned cut."""

import numpy as np

import drakedeburr.laser.display as mut
from drakedeburr.laser import hole, shapes


def test_animation_tcp_follows_hole():
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    scene = mut.build_tool_scene(meshcat)
    prog = hole.plan_hole(shapes.Circle(diameter=0.008), spacing=0.5e-3)
    tcp = mut.animate_hole(scene, prog, meshcat, fps=500.0)
    r = np.linalg.norm(tcp[:, :2] - prog.geometry.p_CHome, axis=1)
    assert np.max(np.abs(r - 0.004)) < 0.1e-3
    assert meshcat.HasPath("/drakedeburr/laser_cut")
