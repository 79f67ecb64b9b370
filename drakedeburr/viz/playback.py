"""Meshcat playback of a Plan: animated replay and a self-contained static HTML recording.

The cell is rebuilt from the plan's scenario and hub (``drakedeburr.cell.load_cell``) and its
``RobotDiagram`` put in a diagram with a ``MeshcatVisualizer`` on its ``scene_graph_query``
port. The replay is a Meshcat recording (an animation the browser plays with its own controls);
``Meshcat.StaticHtml()`` turns it into one HTML file (a few MB) that needs no server.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.viz.scene import collect_here, get_meshcat

__all__ = ["plan_replay", "save_plan_html", "draw_tool_path"]

log = logging.getLogger(__name__)


def _unique_cell(plan, cell):
    if cell is not None:
        return cell
    from drakedeburr.cell.station import load_plan_cell

    return load_plan_cell(plan)


def draw_tool_path(meshcat, plan, path: str = "/plan/tool_path") -> None:
    """Draw the commanded tool-point path of each window (relative to the hub, shown at the
    hub's planning pose ``plan.X_WH``) as red polylines."""
    from pydrake.geometry import Rgba
    from pydrake.math import RigidTransform

    for seg in plan.segments:
        if seg.kind != "cut":
            continue
        p_H = np.array([plan.targets[i].X_HT[:3, 3] for i in range(*seg.target_range)])
        if len(p_H) < 2:
            continue
        p_W = (plan.X_WH[:3, :3] @ p_H.T).T + plan.X_WH[:3, 3]
        meshcat.SetLine(f"{path}/window_{seg.window_index}", p_W.T, 2.0, Rgba(0.9, 0.1, 0.1, 1))
    if plan.mode == "workpiece":
        # the hub moves: draw the path in the hub's frame as it sits at home
        meshcat.SetTransform(path, RigidTransform())


def plan_replay(plan, *, cell=None, meshcat=None, dt: float = 0.04, show_path: bool = True):
    """Record an animated replay of ``plan.trajectory`` in Meshcat.

    Args:
        plan: the Plan.
        cell: the loaded cell (default: rebuilt from ``plan.scenario``/``plan.hub``).
        meshcat: a ``pydrake.geometry.Meshcat`` (default: a new one on a free port of
            127.0.0.1, :func:`drakedeburr.viz.scene.get_meshcat`).
        dt: frame spacing of the recording [s].
        show_path: draw the commanded tool paths.

    Returns:
        The Meshcat instance (its recording is published; open ``meshcat.web_url()``).
    """
    from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams, Role
    from pydrake.systems.framework import DiagramBuilder

    cell = _unique_cell(plan, cell)
    meshcat = meshcat or get_meshcat(new=True)
    builder = DiagramBuilder()
    robot_diagram = builder.AddSystem(cell.diagram)
    params = MeshcatVisualizerParams()
    params.role = Role.kIllustration
    viz = MeshcatVisualizer.AddToBuilder(
        builder, robot_diagram.GetOutputPort("scene_graph_query"), meshcat, params)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = cell.plant.GetMyMutableContextFromRoot(context)
    viz_context = viz.GetMyContextFromRoot(context)
    tr = plan.trajectory
    if len(tr.t) < 2:  # nothing could be planned: the plan stands at home
        times, q = np.asarray(tr.t, float)[:1], np.array([plan.targets[0].q])
    else:
        times = np.append(np.arange(tr.t[0], tr.t[-1], dt), tr.t[-1])
        q = tr.value(times)
    recording = viz.StartRecording(set_transforms_while_recording=False)
    for ti, qi in zip(times, q, strict=True):
        context.SetTime(float(ti))
        cell.plant.SetPositions(plant_context, qi)
        viz.ForcedPublish(viz_context)
    viz.StopRecording()
    viz.PublishRecording()
    if show_path:
        draw_tool_path(meshcat, plan)
    log.info("replay of %.1f s recorded with %d frames", tr.duration, len(times))
    del recording
    return meshcat


def save_plan_html(plan, path: str | Path, *, cell=None, dt: float = 0.05) -> Path:
    """Write a self-contained HTML replay of a plan (``Meshcat.StaticHtml()``).

    Returns:
        The written path.
    """
    meshcat = plan_replay(plan, cell=cell, dt=dt)
    try:
        return atomic_write_text(path, meshcat.StaticHtml())
    finally:
        del meshcat
        collect_here()  # free the replay's Meshcat on this thread (see collect_here)
