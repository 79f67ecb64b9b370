"""drakedeburr.viz: Drake Meshcat scenes (cells, edge loops, points, frames) and static HTML."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "scene": (
        "ROOT", "animate_cell", "get_meshcat", "publish_arrows", "publish_cell",
        "publish_edge_loops", "publish_frame", "publish_model_file", "publish_points",
        "publish_polyline", "publish_scene_graph", "set_cell_configuration", "write_static_html",
    ),
})
