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
    assert len(moves) == len(prog.segments.q)
    ao = [int(m) for m in re.findall(r"AO\[1\]=(\d+) ;", text)]
    assert max(ao) <= 4095 and ao[-1] == 0
    # positions: degrees of the servo angles at the segment ends, in order
    j = np.array(re.findall(r"J1 =\t(-?[\d.]+)\tdeg,\tJ2 =\t(-?[\d.]+)\tdeg", text), float)
    assert np.allclose(np.deg2rad(j), prog.segments.q, atol=1e-7)
    # whole msec per move, summing to the cycle time
    ms = np.array(re.findall(r" (\d+)msec ", text), int)
    assert ms.sum() / 1000.0 == pytest.approx(prog.duration, abs=1e-9)
    assert "sec " not in text.replace("msec ", "")
    with pytest.raises(InputError, match="FANUC program name"):
        fanuc_ls.hole_program_ls(prog, "9bad name")


def _read_hole_ls(text):
    """(AO counts before each timed move, msec of each move, FINE flags, J1/J2 [deg] of every
    P[]) read from the /MN and /POS text with plain regexes."""
    mn = text.split("/MN\n")[1].split("/POS")[0]
    pairs = re.findall(r"AO\[1\]=(\d+) ;\n\t\d+:J P\[(\d+)\] (\d+)msec (FINE|CNT100) ;", mn)
    pos = np.array(re.findall(r"J1 =\t(-?[\d.]+)\tdeg,\tJ2 =\t(-?[\d.]+)\tdeg", text), float)
    assert [int(p[1]) for p in pairs] == list(range(2, len(pos) + 1))
    counts = np.array([int(p[0]) for p in pairs])
    ms = np.array([int(p[2]) for p in pairs])
    return counts, ms, np.array([p[3] == "FINE" for p in pairs]), pos


@pytest.mark.parametrize("period_ms", [8, 16])
@pytest.mark.parametrize("diameter_mm", [1.0, 2.0, 3.5, 5.0, 8.0, 12.0, 16.0, 20.0, 25.0])
def test_hole_program_runs_in_whole_periods_at_the_planned_energy(diameter_mm, period_ms):
    """Issue 44 item 6, over every hole size the tool cuts (1-25 mm, its 30 mm disc): read
    from the written .ls alone, every move lasts a whole number of interpolation periods,
    and every segment's energy per length (AO volts x time / chord length of the FK of the
    written servo angles) is the plan's: the speed-proportional gain where the command is
    not clamped, within 5 %. A controller running the old 0.001 sec lines at 8 ms per point
    put ~6.7 x this energy into the kerf."""
    from drakedeburr.laser.itp import ControllerTiming

    d = diameter_mm * 1e-3
    prog = mut.plan_hole(shapes.Circle(diameter=d, lead_in=min(0.3 * d, 2e-3)),
                         spacing=min(0.2e-3, d / 8),
                         timing=ControllerTiming(period=period_ms * 1e-3))
    counts, ms, fine, pos = _read_hole_ls(fanuc_ls.hole_program_ls(prog, "h"))
    assert np.all(ms % period_ms == 0) and np.all(ms >= period_ms)
    g = prog.geometry
    q = np.deg2rad(pos)
    p = forward_kinematics_circles(g, q)  # circle-intersection FK, not eq. 9
    L = np.linalg.norm(np.diff(p, axis=0), axis=1)
    dt = ms / 1000.0
    volts = counts / prog.power.counts_per_volt
    e_per_m = volts * dt / L
    gain = prog.power.nominal_command / prog.power.nominal_speed  # the plan: V per (m/s)
    v = L / dt
    # a segment that starts or ends at a stop passes through the clamp (v -> 0)
    at_stop = fine | np.r_[True, fine[:-1]]
    free = ~at_stop & (v * gain > 1.2 * prog.power.min_command) & (
        v * gain < prog.power.max_command)
    assert free.sum() > 0.7 * len(free)
    assert np.max(np.abs(e_per_m[free] / gain - 1)) < 0.05
    # the stop segments: the plan's clamped energy (min command while slow), never less
    # than the gain, and the written value is the planned one
    plan = prog.segments.energy / prog.segments.length
    assert np.max(np.abs(e_per_m / plan - 1)) < 0.05
    assert np.all(e_per_m >= 0.95 * np.minimum(gain, prog.power.max_command / v))
    # the controller's path (servo angles linear in time within a move) stays on the hole
    tt = np.concatenate([[0.0], np.cumsum(dt)])
    t = np.linspace(0.0, tt[-1], 20 * len(tt))
    q_lin = np.stack([np.interp(t, tt, q[:, k]) for k in range(2)], axis=1)
    r = np.linalg.norm(forward_kinematics_circles(g, q_lin) - g.p_CHome, axis=1)
    start = np.argmax(prog.contour.is_cut)
    t_cut = tt[np.searchsorted(np.cumsum(np.r_[0.0, L]), prog.contour.s[start] - 1e-9)]
    assert np.max(np.abs(r[t >= t_cut + 1e-9] - d / 2)) <= 0.05e-3
    # the servo speed limits hold on the written segments, and the feed is never exceeded
    assert np.max(np.abs(np.diff(q, axis=0)) / dt[:, None]) <= prog.limits.velocity * 1.02
    assert v.max() <= prog.feed_requested * 1.001
    assert fine[-1] and fine.sum() >= 2


@pytest.mark.parametrize("shape", [
    shapes.Rectangle(width=0.016, height=0.010, lead_in=0.003),  # four sharp corners: stops
    shapes.Keyhole(head_diameter=0.012, slot_width=0.005, slot_length=0.010, lead_in=0.003),
    shapes.Hexagon(across_flats=0.025, lead_in=0.004)], ids=lambda s: s.kind)
def test_corner_shapes_run_in_whole_periods_at_the_planned_energy(shape):
    """Shapes with corners (the tool stops at each, the command clamps at its floor): the
    same read-back check as for circles, segment by segment."""
    prog = mut.plan_hole(shape, spacing=0.2e-3)
    counts, ms, fine, pos = _read_hole_ls(fanuc_ls.hole_program_ls(prog, "h"))
    assert np.all(ms % 8 == 0) and np.all(ms >= 8)
    p = forward_kinematics_circles(prog.geometry, np.deg2rad(pos))
    L = np.linalg.norm(np.diff(p, axis=0), axis=1)
    e_per_m = counts / prog.power.counts_per_volt * ms / 1000.0 / L
    gain = prog.power.nominal_command / prog.power.nominal_speed
    at_stop = fine | np.r_[True, fine[:-1]]
    v = L / (ms / 1000.0)
    free = ~at_stop & (v * gain > 1.2 * prog.power.min_command)
    assert free.sum() > 0.5 * len(free) and fine.sum() >= 4
    assert np.max(np.abs(e_per_m[free] / gain - 1)) < 0.05
    plan = prog.segments.energy / prog.segments.length
    assert np.max(np.abs(e_per_m / plan - 1)) < 0.05
