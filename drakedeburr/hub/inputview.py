"""Window edge loops, hub axis and front side in the *input mesh's* coordinates and unit (what
``hub info --json`` and ``cl --json`` report, so a user can check them against their CAD)."""

from __future__ import annotations

import numpy as np

__all__ = ["input_view", "input_view_of_hub"]


def input_view(windows, X_MH: np.ndarray, unit: str, *, front: dict | None = None,
               not_windows: list | None = None, source: str = "",
               decimals: int = 4) -> dict:
    """JSON-ready description of the hub in the file's frame M and unit.

    Args:
        windows: WindowEdge per window (``p_HE`` in H [m]).
        X_MH: (4, 4) pose of H in M [m].
        unit: "m" or "mm": the file's unit (points are written in it).
        front: the front decision (``FrontDecision.as_dict``), or None.
        not_windows: openings that are not windows (with reasons), or None.
        source: the mesh file (or a description).
        decimals: rounding of the coordinates (in the file's unit).

    Returns:
        {"source", "unit", "frame", "hub_axis": {"point", "direction"}, "front",
        "not_windows", "edges": [{"index", "kind", "points": [[x, y, z], ...]}]}.
    """
    scale = 1e3 if unit == "mm" else 1.0
    R, o = X_MH[:3, :3], X_MH[:3, 3]
    edges = []
    for w in windows:
        p_M = (w.p_HE @ R.T + o) * scale
        edges.append({"index": int(w.index), "kind": w.kind,
                      "points": np.round(p_M, decimals).tolist()})
    return {"source": source, "unit": unit,
            "frame": "the input mesh's own coordinates, in its unit",
            "hub_axis": {"point": np.round(o * scale, decimals).tolist(),
                         "direction": np.round(R[:, 2], 6).tolist(),
                         "meaning": "the axle; the direction points out of the front face "
                                    "(the side the tool works on)"},
            "front": front, "not_windows": not_windows or [], "edges": edges}


def input_view_of_hub(hub) -> dict:
    """:func:`input_view` of a hub model folder: an imported hub in the file it came from,
    a generated one in its own hub.obj (frame H, metres)."""
    imp = hub.summary.get("import")
    if imp is None:
        return input_view(hub.windows, np.eye(4), "m", source=str(hub.mesh_path),
                          front={"decided_by": "generator", "evidence": [
                              "generated hub: +Z_H is the front by construction"]})
    return input_view(hub.windows, np.asarray(imp["X_MH"], float), imp.get("unit", "m"),
                      front=imp.get("front"), not_windows=imp.get("not_windows"),
                      source=imp.get("source", ""))
