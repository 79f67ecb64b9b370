"""The bundled hubs: their specs are defined here and written to ``models/hubs/<name>/hub.yaml``.

Sizes are those of 17-inch passenger-car wheels (barrel 432 mm, flange 470 mm, PCD 114.3 mm).
"""

from __future__ import annotations

from drakedeburr.hub.spec import HubSpec
from drakedeburr.units import m_from_mm, rad_from_deg

__all__ = ["BUNDLED", "DEFAULT_HUB", "bundled_spec"]

DEFAULT_HUB = "h5_straight"




def mm(x: float) -> float:
    """Millimetres -> metres (a division, so that YAML values in mm round-trip exactly)."""
    return m_from_mm(x)


BUNDLED: dict[str, HubSpec] = {
    spec.name: spec
    for spec in (
        HubSpec(
            name="h5_straight",
            description="17 in, 5 straight tapered spokes, 5 large windows; the demo's default",
            spoke_count=5, spoke_style="straight",
            dish_depth=mm(30), dish_inner_radius=mm(85), dish_outer_radius=mm(200),
            window_inner_radius=mm(88), window_outer_radius=mm(175),
            spoke_width=mm(42), spoke_width_outer=mm(85),
            fillet_radius=mm(10),
        ),
        HubSpec(
            name="h5_split",
            description="17 in, 5 split (Y) spokes: 5 large and 5 small windows alternating "
                        "(the source's hub 1)",
            spoke_count=5, spoke_style="split",
            dish_depth=mm(28), dish_inner_radius=mm(85), dish_outer_radius=mm(200),
            window_inner_radius=mm(88), window_outer_radius=mm(184),
            spoke_width=mm(36), spoke_width_outer=mm(20),
            split_radius=mm(118), split_angle=rad_from_deg(12.0),
            fillet_radius=mm(8), fillet_radius_small=mm(4),
        ),
        HubSpec(
            name="h6_curved",
            description="17 in, 6 curved spokes (30 deg sweep), 6 large windows",
            spoke_count=6, spoke_style="curved",
            dish_depth=mm(25), dish_inner_radius=mm(85), dish_outer_radius=mm(200),
            window_inner_radius=mm(88), window_outer_radius=mm(182),
            spoke_width=mm(30), spoke_width_outer=mm(40), spoke_sweep=rad_from_deg(30.0),
            fillet_radius=mm(9),
        ),
        HubSpec(
            name="h5_deepdish",
            description="17 in, 5 straight spokes on a deep dish (70 mm): strongly 3-D edges",
            spoke_count=5, spoke_style="straight",
            rim_width=mm(215),
            dish_depth=mm(70), dish_inner_radius=mm(85), dish_outer_radius=mm(195),
            window_inner_radius=mm(90), window_outer_radius=mm(182),
            spoke_width=mm(38), spoke_width_outer=mm(50),
            fillet_radius=mm(12),
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
