"""hub.edgeline's band filter (``_smoothed_edge``) on an analytic face: profiles around a round
opening that read the face start a facet apart (0.3 / 0.6 mm alternating) give a loop at the
mean band, on the face; where the filtered point's ray finds no face it keeps its raw point."""

from __future__ import annotations

import numpy as np

from drakedeburr.hub import edgeline as mut


def _plate_scene(hole=None):
    """A flat face z = 0 over [-0.1, 0.1]^2 m as rectangles, without the rectangle ``hole``
    ((x0, x1), (y0, y1)) if given."""
    import open3d as o3d

    rects = [((-0.1, 0.1), (-0.1, 0.1))]
    if hole is not None:
        (x0, x1), (y0, y1) = hole
        rects = [((-0.1, x0), (-0.1, 0.1)), ((x1, 0.1), (-0.1, 0.1)),
                 ((x0, x1), (-0.1, y0)), ((x0, x1), (y1, 0.1))]
    V, F = [], []
    for (a, b), (c, d) in rects:
        k = len(V)
        V += [[a, c, 0.0], [b, c, 0.0], [b, d, 0.0], [a, d, 0.0]]
        F += [[k, k + 1, k + 2], [k, k + 2, k + 3]]
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.array(V, np.float32)),
                        o3d.core.Tensor(np.array(F, np.uint32)))
    return scene


def _circle_profiles(radius=0.02, spacing=0.5e-3):
    n = 2 * int(round(np.pi * radius / spacing))  # even: the alternation closes
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    out = np.c_[np.cos(a), np.sin(a)]
    band = np.where(np.arange(n) % 2 == 0, 0.3e-3, 0.6e-3)
    p = np.c_[radius * out + band[:, None] * out, np.zeros(n)]
    return radius * out, out, band, p


def test_the_band_filter_takes_out_a_facet_zig_zag_and_stays_on_the_face():
    outline, out, band, p = _circle_profiles()
    q = mut._smoothed_edge(_plate_scene(), p, outline, out, band, 0.01, 0.1e-3)
    b = np.linalg.norm(q[:, :2], axis=1) - 0.02
    np.testing.assert_allclose(b, 0.45e-3, atol=0.03e-3)  # raw: 0.3 / 0.6 mm
    assert np.abs(q[:, 2]).max() < 1e-6  # read again on the face
    # the filtered points lie on their own profiles (outline + b * out)
    np.testing.assert_allclose(q[:, :2], outline + b[:, None] * out, atol=1e-9)


def test_a_filtered_point_without_a_face_under_it_keeps_its_raw_position():
    outline, out, band, p = _circle_profiles()
    hole = ((0.02035, 0.02055), (-0.002, 0.002))  # under the filtered band near angle 0
    q = mut._smoothed_edge(_plate_scene(hole), p, outline, out, band, 0.01, 0.1e-3)
    xy = outline + 0.45e-3 * out
    in_hole = ((xy[:, 0] > 0.02035 + 0.05e-3) & (xy[:, 0] < 0.02055 - 0.05e-3)
               & (np.abs(xy[:, 1]) < 0.002 - 0.05e-3))
    assert in_hole.sum() >= 3
    np.testing.assert_array_equal(q[in_hole], p[in_hole])
    moved = np.linalg.norm(q - p, axis=1) > 1e-6
    assert moved[~in_hole].mean() > 0.9
