"""Drake Meshcat scenes: a cell at a configuration, edge loops, points, arrows, frames, static HTML.

Everything is drawn under ``/drakedeburr/...`` paths. Geometry is published from a SceneGraph's
model inspector rather than through a ``MeshcatVisualizer`` system: the Cell's diagram is already
built (a visualizer must be wired in before ``Build``), and drawing from the inspector lets one
loaded cell feed any number of viewers, snapshots and animations. Bodies become Meshcat folders
(``<root>/<model>/<body>``) whose transforms follow the robot; geometries sit inside at their fixed
pose in the body, so moving the robot is one ``SetTransform`` per body.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text

__all__ = [
    "ROOT",
    "DEFAULT_HOST",
    "get_meshcat",
    "collect_here",
    "publish_scene_graph",
    "publish_model_file",
    "publish_cell",
    "set_cell_configuration",
    "animate_cell",
    "publish_polyline",
    "publish_edge_loops",
    "publish_points",
    "publish_arrows",
    "publish_frame",
    "write_static_html",
]

log = logging.getLogger(__name__)

ROOT = "/drakedeburr"


#: the interface Meshcat binds unless told otherwise: this machine only (Drake's own default,
#: ``MeshcatParams.host = "*"``, listens on every interface, so anyone on the plant network
#: could open the cell)
DEFAULT_HOST = "127.0.0.1"


def _new_meshcat(host: str | None, port: int | None):
    """A Meshcat on ``host`` (``MeshcatParams.host``: "localhost"/an address binds that
    interface only, "*" every interface; None: :data:`DEFAULT_HOST`) and ``port`` (None: the
    first free one from 7000), logged with the address it actually bound."""
    from pydrake.geometry import Meshcat, MeshcatParams

    params = MeshcatParams()
    params.host = DEFAULT_HOST if host is None else str(host)
    if port is not None:
        params.port = int(port)
    meshcat = Meshcat(params)
    log.info("Meshcat listening on %s port %d: %s", params.host, meshcat.port(),
             meshcat.web_url())
    return meshcat


@functools.cache
def _shared_meshcat(host: str | None = None):
    return _new_meshcat(host, None)


def collect_here() -> None:
    """Run Python's cycle collector now, on the calling thread.

    Drake's ``Meshcat`` must be destroyed on the thread that created it (``meshcat.cc``
    demands ``IsThread(main_thread_id_)`` in its destructor and the process aborts otherwise).
    A diagram with a ``MeshcatVisualizer`` holds its Meshcat in a reference cycle, so once
    dropped it waits for the cycle collector, which may run on any thread that allocates
    (a process pool's manager thread, dask's event loop). Call this after dropping a Meshcat
    you created, and before starting helper threads.
    """
    import gc

    gc.collect()


def get_meshcat(*, new: bool = False, port: int | None = None, host: str | None = None):
    """The process-wide Meshcat (started on first use), or a new one.

    Args:
        new: start a separate Meshcat instead of reusing the shared one.
        port: port for a new Meshcat (None: Drake picks a free one from 7000 on).
        host: interface to listen on (None: :data:`DEFAULT_HOST`, this machine only; "*":
            every interface, reachable from the network).
    """
    if not new and port is None:
        return _shared_meshcat(host)
    return _new_meshcat(host, port)


def _rgba(color: Sequence[float]):
    from pydrake.geometry import Rgba

    c = tuple(float(v) for v in color)
    return Rgba(*c) if len(c) == 4 else Rgba(*c, 1.0)


def _body_path(plant, body, root: str) -> str:
    model = plant.GetModelInstanceName(body.model_instance())
    return f"{root}/{model}/{body.name()}"


def publish_scene_graph(
    meshcat,
    plant,
    scene_graph,
    plant_context,
    *,
    path: str = f"{ROOT}/cell",
    role: str = "illustration",
    default_color: Sequence[float] = (0.8, 0.8, 0.8, 1.0),
) -> None:
    """Publish every geometry of ``role`` registered by ``plant`` at ``plant_context``'s state.

    Args:
        meshcat: a ``pydrake.geometry.Meshcat``.
        plant: finalized MultibodyPlant registered with ``scene_graph``.
        scene_graph: its SceneGraph.
        plant_context: the plant's context (sets the body poses).
        path: Meshcat folder to draw into (replaced).
        role: "illustration" (visuals) or "proximity" (collision geometry, translucent).
    """
    from pydrake.geometry import Role

    roles = {"illustration": Role.kIllustration, "proximity": Role.kProximity}
    if role not in roles:
        raise ValueError(f"role must be one of {sorted(roles)}, got {role!r}")
    inspector = scene_graph.model_inspector()
    meshcat.Delete(path)
    for gid in inspector.GetAllGeometryIds(roles[role]):
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        if body is None:
            continue
        color = default_color
        props = inspector.GetIllustrationProperties(gid)
        if props is not None and props.HasProperty("phong", "diffuse"):
            d = props.GetProperty("phong", "diffuse")
            color = (d.r(), d.g(), d.b(), d.a())
        if role == "proximity":
            color = (0.9, 0.3, 0.2, 0.35)
        gpath = f"{_body_path(plant, body, path)}/{inspector.GetName(gid).replace('::', '_')}"
        meshcat.SetObject(gpath, inspector.GetShape(gid), _rgba(color))
        meshcat.SetTransform(gpath, inspector.GetPoseInFrame(gid))
    _set_body_transforms(meshcat, plant, plant_context, path)


def _set_body_transforms(meshcat, plant, plant_context, path: str, time: float | None = None,
                         animation=None) -> None:
    from pydrake.multibody.tree import BodyIndex

    for index in range(1, plant.num_bodies()):  # 0 is the world body
        body = plant.get_body(BodyIndex(index))
        X_WB = plant.EvalBodyPoseInWorld(plant_context, body)
        bpath = _body_path(plant, body, path)
        if animation is not None:
            animation.SetTransform(animation.frame(time), bpath, X_WB)
        else:
            meshcat.SetTransform(bpath, X_WB)


def publish_model_file(meshcat, model_file: str | Path, *, path: str = f"{ROOT}/model",
                       role: str = "illustration") -> None:
    """Publish a model file (SDF/URDF, e.g. a hub) on its own, its first body welded at W."""
    from pydrake.geometry import SceneGraph
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    from drakedeburr.resources import add_package_to

    plant = MultibodyPlant(0.0)
    scene_graph = SceneGraph()
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    parser = Parser(plant)
    add_package_to(parser.package_map())
    for model in parser.AddModels(str(model_file)):
        bodies = plant.GetBodyIndices(model)
        if bodies:
            plant.WeldFrames(plant.world_frame(), plant.get_body(bodies[0]).body_frame())
    plant.Finalize()
    publish_scene_graph(meshcat, plant, scene_graph, plant.CreateDefaultContext(), path=path,
                        role=role)


def publish_cell(meshcat, cell, q: np.ndarray | None = None, *, path: str = f"{ROOT}/cell",
                 role: str = "illustration") -> None:
    """Publish a :class:`drakedeburr.cell.Cell` with the robot at ``q`` (default ``q_home``)."""
    context = cell.create_context(q)
    publish_scene_graph(meshcat, cell.plant, cell.scene_graph,
                        cell.plant.GetMyContextFromRoot(context), path=path, role=role)


def set_cell_configuration(meshcat, cell, q: np.ndarray, *,
                           path: str = f"{ROOT}/cell") -> None:
    """Move an already published cell to joints ``q`` [rad] (one transform per body)."""
    context = cell.create_context(q)
    _set_body_transforms(meshcat, cell.plant, cell.plant.GetMyContextFromRoot(context), path)


def animate_cell(meshcat, cell, times: np.ndarray, qs: np.ndarray, *,
                 path: str = f"{ROOT}/cell", frames_per_second: float = 30.0) -> None:
    """Play a joint trajectory in Meshcat (and in its static HTML).

    Args:
        times: (K,) sample times [s], increasing.
        qs: (K, 6) joints [rad] at those times.
    """
    from pydrake.geometry import MeshcatAnimation

    times = np.asarray(times, float)
    qs = np.asarray(qs, float)
    if qs.shape != (len(times), cell.num_joints):
        raise ValueError(f"qs must have shape ({len(times)}, {cell.num_joints}), got {qs.shape}")
    animation = MeshcatAnimation(frames_per_second)
    context = cell.create_context()
    plant_context = cell.plant.GetMyMutableContextFromRoot(context)
    for t, q in zip(times, qs, strict=True):
        cell.plant.SetPositions(plant_context, q)
        _set_body_transforms(meshcat, cell.plant, plant_context, path, float(t), animation)
    meshcat.SetAnimation(animation)


def _as_points(p: np.ndarray, name: str) -> np.ndarray:
    p = np.asarray(p, float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {p.shape}")
    return p


def _transform(X, p: np.ndarray) -> np.ndarray:
    if X is None:
        return p
    return X.multiply(p.T).T


def publish_polyline(meshcat, path: str, p_W: np.ndarray, *, closed: bool = True,
                     color: Sequence[float] = (0.1, 0.8, 0.2, 1.0), line_width: float = 3.0,
                     X_WP=None) -> None:
    """A polyline through ``p_W`` (N, 3) [m] (closed by default). ``X_WP`` maps points given
    in a frame P (e.g. the hub frame) to world."""
    p = _transform(X_WP, _as_points(p_W, "p_W"))
    if closed:
        p = np.vstack([p, p[:1]])
    meshcat.SetLine(path, p.T, line_width, _rgba(color))


def publish_edge_loops(meshcat, loops: Iterable[np.ndarray], X_WH=None, *,
                       path: str = f"{ROOT}/edges",
                       colors: Sequence[Sequence[float]] | None = None,
                       line_width: float = 4.0) -> None:
    """Window edge loops, each (N_i, 3) in the hub frame H [m], drawn closed at ``X_WH``.

    ``loops`` may also hold objects with a ``p_HE`` attribute (``WindowEdge``).
    """
    meshcat.Delete(path)
    palette = colors or [(0.1, 0.8, 0.2, 1.0), (0.95, 0.55, 0.05, 1.0), (0.2, 0.5, 1.0, 1.0),
                         (0.85, 0.15, 0.6, 1.0)]
    for i, loop in enumerate(loops):
        p_HE = getattr(loop, "p_HE", loop)
        publish_polyline(meshcat, f"{path}/window_{i:02d}", p_HE, closed=True,
                         color=palette[i % len(palette)], line_width=line_width, X_WP=X_WH)


def publish_points(meshcat, path: str, p_W: np.ndarray, *,
                   color: Sequence[float] = (1.0, 0.2, 0.2, 1.0), point_size: float = 0.004,
                   X_WP=None) -> None:
    """Points (N, 3) [m] as a point cloud of ``point_size`` [m]."""
    from pydrake.perception import BaseField, Fields, PointCloud

    p = _transform(X_WP, _as_points(p_W, "p_W"))
    cloud = PointCloud(len(p), Fields(BaseField.kXYZs))
    cloud.mutable_xyzs()[:] = p.T
    meshcat.SetObject(path, cloud, point_size, _rgba(color))


def publish_arrows(meshcat, path: str, p_W: np.ndarray, v_W: np.ndarray, *,
                   length: float | None = 0.02, color: Sequence[float] = (0.2, 0.4, 1.0, 1.0),
                   line_width: float = 2.0, X_WP=None) -> None:
    """Line segments from ``p_W`` (N, 3) along ``v_W`` (N, 3); unit-scaled to ``length`` [m]
    unless ``length`` is None (then drawn as given)."""
    p = _as_points(p_W, "p_W")
    v = _as_points(v_W, "v_W")
    if len(v) != len(p):
        raise ValueError(f"p_W and v_W differ in length: {len(p)} vs {len(v)}")
    if length is not None:
        v = length * v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-300)
    start = _transform(X_WP, p)
    end = _transform(X_WP, p + v)
    meshcat.SetLineSegments(path, start.T, end.T, line_width, _rgba(color))


def publish_frame(meshcat, path: str, X_WF, *, length: float = 0.05,
                  line_width: float = 4.0) -> None:
    """A frame triad (x red, y green, z blue) at pose ``X_WF`` (a RigidTransform)."""
    R = X_WF.rotation().matrix()
    origin = X_WF.translation()
    for axis, color in zip("xyz", ((1, 0, 0, 1), (0, 0.8, 0, 1), (0, 0, 1, 1)), strict=True):
        i = "xyz".index(axis)
        meshcat.SetLine(f"{path}/{axis}", np.column_stack([origin, origin + length * R[:, i]]),
                        line_width, _rgba(color))


def write_static_html(meshcat, path: str | Path) -> Path:
    """Write Meshcat's current scene as one self-contained HTML file (atomically)."""
    return atomic_write_text(path, meshcat.StaticHtml())
