"""The bundled hubs: their specs are defined here and written to ``models/hubs/<name>/hub.yaml``.

Sizes are those of 17-inch passenger-car wheels (barrel 432 mm, flange 470 mm, PCD 114.3 mm).
"""

from __future__ import annotations

import math

from drakedeburr.hub.spec import HubSpec

__all__ = ["BUNDLED", "DEFAULT_HUB", "bundled_spec"]

DEFAULT_HUB = "h5_straight"

_mm = 1e-3

BUNDLED: dict[str, HubSpec] = {
    spec.name: spec
    for spec in (
        HubSpec(
            name="h5_straight",
            description="17 in, 5 straight tapered spokes, 5 large windows; the demo's default",
            spoke_count=5, spoke_style="straight",
            dish_depth=30 * _mm, dish_inner_radius=85 * _mm, dish_outer_radius=200 * _mm,
            window_inner_radius=88 * _mm, window_outer_radius=175 * _mm,
            spoke_width=42 * _mm, spoke_width_outer=85 * _mm,
            fillet_radius=10 * _mm,
        ),
        HubSpec(
            name="h5_split",
            description="17 in, 5 split (Y) spokes: 5 large and 5 small windows alternating "
                        "(the source's hub 1)",
            spoke_count=5, spoke_style="split",
            dish_depth=28 * _mm, dish_inner_radius=85 * _mm, dish_outer_radius=200 * _mm,
            window_inner_radius=88 * _mm, window_outer_radius=184 * _mm,
            spoke_width=36 * _mm, spoke_width_outer=20 * _mm,
            split_radius=118 * _mm, split_angle=math.radians(12.0),
            fillet_radius=8 * _mm, fillet_radius_small=4 * _mm,
        ),
        HubSpec(
            name="h6_curved",
            description="17 in, 6 curved spokes (30 deg sweep), 6 large windows",
            spoke_count=6, spoke_style="curved",
            dish_depth=25 * _mm, dish_inner_radius=85 * _mm, dish_outer_radius=200 * _mm,
            window_inner_radius=88 * _mm, window_outer_radius=182 * _mm,
            spoke_width=30 * _mm, spoke_width_outer=40 * _mm, spoke_sweep=math.radians(30.0),
            fillet_radius=9 * _mm,
        ),
        HubSpec(
            name="h5_deepdish",
            description="17 in, 5 straight spokes on a deep dish (70 mm): strongly 3-D edges",
            spoke_count=5, spoke_style="straight",
            rim_width=0.215,
            dish_depth=70 * _mm, dish_inner_radius=85 * _mm, dish_outer_radius=195 * _mm,
            window_inner_radius=90 * _mm, window_outer_radius=182 * _mm,
            spoke_width=38 * _mm, spoke_width_outer=50 * _mm,
            fillet_radius=12 * _mm,
        ),
    )
}


def bundled_spec(name: str) -> HubSpec:
    """The catalogue spec of a bundled hub (KeyError-free: FileNotFoundError names the list)."""
    try:
        return BUNDLED[name]
    except KeyError:
        raise FileNotFoundError(
            f"no bundled hub spec {name!r}; bundled: {', '.join(sorted(BUNDLED))}") from None
