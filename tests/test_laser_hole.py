"""Holes by the Cutting Tool: timed servo trajectory accuracy, TCP-speed power, .ls output."""

import re

import numpy as np
import pytest

import drakedeburr.laser.hole as mut
from drakedeburr.errors import InputError
from drakedeburr.laser import fanuc_ls, shapes
from drakedeburr.laser.kinematics import FiveBarGeometry, forward_kinematics_circles


@pytest.mark.parametrize("diameter_mm", [1.0, 2.0, 3.5, 5.0, 8.0, 12.0, 16.0, 20.0, 25.0])
def test_circle_within_0p1_mm_from_timed_joint_trajectory(diameter_mm):
    d = diameter_mm * 1e-3
    prog = mut.plan_hole(shapes.Circle(diameter=d, lead_in=min(0.3 * d, 2e-3)),
                         spacing=min(0.2e-3, d / 8))
    assert prog.timed.success
    t, q, p, power = prog.sample(dt=1e-4)
    # independent FK (circle intersection), radial error on the cut part
    p2 = forward_kinematics_circles(prog.geometry, q)
    assert np.allclose(p, p2, atol=1e-12)
    cut = t >= prog.t[np.argmax(prog.contour.is_cut)] - 1e-12
    r = np.linalg.norm(p2[cut] - prog.geometry.p_CHome, axis=1)
    assert np.max(np.abs(r - d / 2)) <= 0.1e-3
    # the program's own points, servo angles interpolated linearly in time (joint moves)
    q_lin = np.stack([np.interp(t, prog.t, prog.q[:, k]) for k in range(2)], axis=1)
    p_lin = forward_kinematics_circles(prog.geometry, q_lin)
    r_lin = np.linalg.norm(p_lin[cut] - prog.geometry.p_CHome, axis=1)
    assert np.max(np.abs(r_lin - d / 2)) <= 0.1e-3
    # and the whole circle is swept: angles cover 2 pi
    ang = np.unwrap(np.arctan2(*(p2[cut] - prog.geometry.p_CHome).T[::-1]))
    step = prog.limits.feed * 1e-4 / (d / 2)  # angle travelled in one sample at most
    assert 2 * np.pi - step <= abs(ang[-1] - ang[0]) <= 2 * np.pi + 1e-9
    # servo limits respected (small slack for spline sampling)
    qd = np.gradient(q, t, axis=0)
    assert np.max(np.abs(qd)) <= prog.limits.velocity * 1.02
    v_fd = np.linalg.norm(np.gradient(p2, t, axis=0), axis=1)
    assert np.max(v_fd) <= prog.limits.feed * 1.02


def test_power_proportional_to_speed_where_unclamped():
    shape = shapes.Rectangle(width=0.016, height=0.010, corner_radius=0.0, lead_in=0.003)
    prog = mut.plan_hole(shape, spacing=0.2e-3)
    t, q, p, power = prog.sample(dt=2e-4)
    # speed by finite differences of FK positions, independent of the Jacobian
    v_fd = np.linalg.norm(np.gradient(p, t, axis=0), axis=1)
    interior = np.ones(len(t), bool)
    interior[[0, -1]] = False
    free = ~power.clamped & interior & (v_fd > 0.05 * prog.limits.feed)
    assert free.sum() > 50
    ratio = power.command[free] / v_fd[free]
    assert np.max(np.abs(ratio / prog.power.gain - 1)) < 0.01
    # the corners slow the tool down: the command follows and clamps at the minimum
    assert power.v_tcp.min() < 0.1 * prog.limits.feed
    assert power.clamped.any() and np.all(power.command >= prog.power.min_command)
    assert np.all(power.command <= prog.power.max_command)
    # an acceleration phase exists (speed between 20 % and 90 % of feed, unclamped)
    accel = free & (v_fd > 0.2 * prog.limits.feed) & (v_fd < 0.9 * prog.limits.feed)
    assert accel.sum() > 5


def test_unreachable_shape_rejected_with_name_and_point():
    with pytest.raises(InputError, match=r"slot: point 0 of \d+ at .* unreachable "
                                         r"\(outside working disc"):
        mut.plan_hole(shapes.Slot(length=0.040, width=0.010), spacing=0.5e-3)
    g = FiveBarGeometry(work_radius=1.0)  # disc check off: the linkage itself fails
    with pytest.raises(InputError,
                       match=r"circle: point \d+ .* \((out of reach|serial singularity)"):
        mut.plan_hole(shapes.Circle(diameter=0.2), spacing=2e-3, geometry=g)


def test_hole_ls_program(tmp_path):
    prog = mut.plan_hole(shapes.Hexagon(across_flats=0.010, lead_in=0.002), spacing=0.5e-3)
    text = fanuc_ls.hole_program_ls(prog, "hex10")
    path = fanuc_ls.write_ls(tmp_path / "hex10.ls", text)
    text = path.read_text()
    assert text.startswith("/PROG HEX10\n") and text.rstrip().endswith("/END")
    assert "DEFAULT_GROUP\t= *,1,*,*,*;" in text
    mn = text.split("/MN\n")[1].split("/POS")[0].splitlines()
    assert int(re.search(r"LINE_COUNT\t\t= (\d+);", text).group(1)) == len(mn)
    moves = [ln for ln in mn if re.match(r"\t\d+:J P\[\d+\] ", ln)]
    assert len(moves) == len(prog.q)
    ao = [int(m) for m in re.findall(r"AO\[1\]=(\d+) ;", text)]
    assert max(ao) <= 4095 and ao[-1] == 0
    # positions: degrees of the planned servo angles, in order
    j = np.array(re.findall(r"J1 =\t(-?[\d.]+)\tdeg,\tJ2 =\t(-?[\d.]+)\tdeg", text), float)
    assert np.allclose(np.deg2rad(j), prog.q, atol=1e-7)
    # time per move sums to the cycle time (3 decimals per line)
    secs = np.array(re.findall(r" ([\d.]+)sec ", text), float)
    assert secs.sum() == pytest.approx(prog.duration, abs=len(secs) * 0.0006)
    with pytest.raises(InputError, match="FANUC program name"):
        fanuc_ls.hole_program_ls(prog, "9bad name")
