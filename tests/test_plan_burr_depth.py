"""The burr's depth into the hub along a planned window (plan.burr_depth): on a rounded edge
under a steep flank the recipe's tool points put the burr deeper than the verifier's bound
(the analytic figure: depth sin(beta) + r (1 - cos(beta))); the moved tool points keep it
inside, read again by a dense brute-force reading of the surface (a second implementation),
while the deburring line stays engaged; a flank at the recipe's angle on a square edge moves
nothing."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from drakedeburr.cell.true_surface import burr_cone, cone_signed_distance
from drakedeburr.plan import burr_depth
from drakedeburr.plan.targets import X_HT_from_axis, contact_geometry, tool_point_H


class _Len(SimpleNamespace):
    """Window targets of M CL points (len)."""

    def __len__(self) -> int:
        return len(self.p_HC)


DEPTH = 1.2e-3
BOUND = DEPTH + 0.17e-3  # depth of cut + edge_deviation


def _block(r: float):
    """Material x < 0, z < 0 (mm-scale block along y) with the edge along y rounded by r
    (r = 0: square). The deburring line is the round's face-side tangent line x = -r, z = 0."""
    import manifold3d

    L = 0.04
    if r == 0.0:
        m = manifold3d.Manifold.cube([L, L, L]).translate([-L, -L / 2, -L])
    else:
        a = manifold3d.Manifold.cube([L - r, L, L]).translate([-L, -L / 2, -L])
        b = manifold3d.Manifold.cube([L, L, L - r]).translate([-L, -L / 2, -L])
        cyl = manifold3d.Manifold.cylinder(L, r, r, circular_segments=256)
        cyl = cyl.translate([0, 0, -L / 2]).rotate([90, 0, 0]).translate([-r, 0, -r])
        m = a + b + cyl
    mesh = m.to_mesh()
    V = np.asarray(mesh.vert_properties, float)[:, :3]
    return SimpleNamespace(vertices_H=V, faces=np.asarray(mesh.tri_verts, int),
                           collision_paths=())


def _poses(r: float, lean: float, n: int = 11):
    """Tool poses along the line, the spindle leaning ``lean`` [rad] over the opening."""
    y = np.linspace(-5e-3, 5e-3, n)
    p_HC = np.stack([np.full(n, -r), y, np.zeros(n)], axis=1)
    n_H = np.tile([1.0, 0.0, 0.0], (n, 1))
    retract = np.tile([math.sin(lean), 0.0, math.cos(lean)], (n, 1))
    r_c, _ = contact_geometry()
    p_HQ = tool_point_H(p_HC, n_H, retract, DEPTH, r_c)
    X = X_HT_from_axis(p_HQ, retract, np.tile([0.0, 1.0, 0.0], (n, 1)))
    return X, p_HQ, p_HC


def _dense_depth(hub, X: np.ndarray) -> np.ndarray:
    """Largest depth of the surface in the cone, from 0.05 mm-spaced surface points near the
    edge (the block's faces there are planes and the round: sampled analytically)."""
    cone = burr_cone()
    return np.array([(-cone_signed_distance(cone, (hub.points - Xi[:3, 3]) @ Xi[:3, :3])).max()
                     for Xi in X])


def _surface_points(r: float) -> np.ndarray:
    """Points 0.05 mm apart on the face (z = 0, x <= -r), the round and the wall (x = 0,
    z <= -r), y in [-12, 12] mm."""
    h = 0.05e-3
    y = np.arange(-12e-3, 12e-3 + h, h)
    s = np.arange(0.0, 12e-3, h)
    face = [(-r - t, 0.0) for t in s]
    wall = [(0.0, -r - t) for t in s]
    arc = [(-r + r * math.sin(a), -r + r * math.cos(a))
           for a in np.linspace(0, math.pi / 2, max(2, int(r * math.pi / 2 / h) + 1))]
    xz = np.array(face + wall + arc)
    return np.array([[x, yy, z] for x, z in xz for yy in y[::4]])


@pytest.mark.parametrize("r", [1.4e-3])
def test_a_rounded_edge_under_a_steep_flank_moves_the_tool_points_out(r):
    lean = math.radians(25.0)
    hub = _block(r)
    hub.points = _surface_points(r)
    X, p_HQ, p_HC = _poses(r, lean)
    beta = math.pi / 4 + lean  # the flank's angle to the face
    analytic = DEPTH * math.sin(beta) + r * (1 - math.cos(beta))
    before = _dense_depth(hub, X)
    assert before == pytest.approx(analytic, abs=0.03e-3)
    assert before.min() > BOUND  # the recipe's tool points go too deep
    offsets, worst = burr_depth.relieved_offsets(hub, X, p_HQ, np.zeros_like(p_HQ), BOUND,
                                                 closed=False)
    assert worst == pytest.approx(analytic - (BOUND - burr_depth.MARGIN), abs=0.03e-3)
    moved = X.copy()
    moved[:, :3, 3] += offsets
    after = _dense_depth(hub, moved)
    assert np.all(after <= BOUND - burr_depth.MARGIN + 0.01e-3), after
    # the line is still engaged: its depth inside the cone (normal to the flank) >= 0
    from drakedeburr.verify.cut_geometry import _engagement

    assert np.all(_engagement(moved, p_HC) >= 0.0)
    assert np.all(np.linalg.norm(offsets, axis=1) <= DEPTH)


def test_a_square_edge_at_the_recipes_flank_moves_nothing():
    hub = _block(0.0)
    hub.points = _surface_points(0.0)
    X, p_HQ, _ = _poses(0.0, 0.0)
    assert _dense_depth(hub, X).max() == pytest.approx(DEPTH * math.sin(math.pi / 4),
                                                       abs=0.03e-3)
    offsets, worst = burr_depth.relieved_offsets(hub, X, p_HQ, np.zeros_like(p_HQ), BOUND,
                                                 closed=False)
    assert worst <= 0.0 and not offsets.any()


@pytest.mark.parametrize("mode", ["FULL", "REPORT_ONLY"])
@pytest.mark.parametrize("readings, moved, record", [
    ((-1e-5,), False, False),  # within: nothing moves, no record
    ((0.1e-3, -1e-6), True, False),  # moved once, then within
    ((0.2e-3, 0.15e-3, 0.12e-3, 0.1e-3), True, True),  # still too deep after every round
])
def test_a_window_is_planned_again_with_its_tool_points_moved(monkeypatch, readings, moved,
                                                               record, mode):
    """The window loop (window._plan_window_once): each reading too deep plans the window
    again with the moved tool points; what moved is in the window's stats, and a window still
    deeper than the verifier's bound after the last round gets a failure record (which sends
    it to the recipe relaxation). A report-only pass is relieved the same way: its plan is
    the one a window failing in every recipe keeps and runs."""
    from drakedeburr.plan import window as mut
    from drakedeburr.plan.options import PlanOptions
    from drakedeburr.plan.results import WindowPlan, WindowStatus

    m = 6
    wt = _Len(window_index=3, p_HC=np.zeros((m, 3)), n_H=np.tile([1.0, 0, 0], (m, 1)),
              retract_H=np.tile([0, 0, 1.0], (m, 1)), depth_of_cut=DEPTH, closed=True)
    planned = []

    def fake_at(ctx, wt_, q_from, offset, mode):
        planned.append(offset.copy())
        st = SimpleNamespace(kind="cut", timed=SimpleNamespace(q=np.zeros((4, 6))))
        return WindowPlan(window=3, status=WindowStatus.OK, stretches=[st],
                          stats=SimpleNamespace(), failures=[])

    calls = iter(readings)

    def fake_relief(hub, X, p_HQ, offset, bound, closed):
        worst = next(calls)
        return offset + (np.array([0.0, 0.0, 1e-4]) if worst > 0 else 0.0), worst

    monkeypatch.setattr(mut, "plan_window_pass", fake_at)
    monkeypatch.setattr(burr_depth, "relieved_offsets", fake_relief)
    monkeypatch.setattr(burr_depth, "hub_model_of", lambda d: None)
    monkeypatch.setattr(mut, "replace", lambda obj, **kw: SimpleNamespace(**kw))
    ctx = SimpleNamespace(
        options=PlanOptions(workers=1), cell=SimpleNamespace(hub_sdf=Path("/hub/hub.sdf")),
        kin=SimpleNamespace(X_HT_from_q=lambda q: np.tile(np.eye(4), (len(q), 1, 1))),
        config=SimpleNamespace(tolerances=SimpleNamespace(edge_deviation=0.17e-3)))
    out = mut._plan_window_once(ctx, wt, np.zeros(6), mut.RunMode[mode])
    assert len(planned) == min(len(readings), burr_depth.ROUNDS + 1)
    relief = getattr(out.stats, "chamfer_relief", None)
    assert (relief is not None) == moved
    if moved:
        assert relief["max_mm"] == pytest.approx(0.1 * (len(planned) - 1))
        assert relief["depth_read_mm"] == pytest.approx(
            1e3 * (readings[0] + BOUND - burr_depth.MARGIN))
    recs = [f for f in out.failures if f.kind == "burr_depth"]
    assert bool(recs) == record
    if record:
        assert recs[0].value > recs[0].limit == pytest.approx(BOUND)
        assert out.status is WindowStatus.DEGRADED
