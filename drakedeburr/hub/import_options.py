"""The settings of a hub import (mesh or CAD) and the version of what it writes: one home that
:mod:`drakedeburr.hub.import_mesh`, :mod:`drakedeburr.hub.import_cad`,
:mod:`drakedeburr.hub.import_common` and :mod:`drakedeburr.hub.import_output` all read (no
import circle between them)."""

from __future__ import annotations

from dataclasses import dataclass

from drakedeburr.hub.openings import DEFAULT_BURR_DIAMETER, DEFAULT_CLEARANCE

__all__ = ["ImportOptions", "IMPORT_VERSION"]

# 14: the edge band turns toward the front, the face start steps past a round's last facets
# (hub.edgeline FACE_ANGLE); 13: an open mesh's shell behind its surface where the front view
# gives the side; 12: drafted flanks are walls, 30 mm profiles; 11: into-the-opening from the
# outline on steep stretches; 5-10: 3-D loops, burrs (issue 42); 4: front_band; 3: band filter
IMPORT_VERSION = 14


@dataclass(frozen=True)
class ImportOptions:
    """Settings of :func:`import_mesh` (all part of the cache key).

    Attributes:
        unit: "m" or "mm" to force the file's unit; None detects it from the size.
        axis_M: (3,) hub axis (+Z_H, out of the visible face) in the file's frame, or None to
            estimate it.
        front: "auto" (decided from the mesh, see :mod:`drakedeburr.hub.front`) or the file
            axis the front face looks along: "+x", "-x", "+y", "-y", "+z", "-z".
        burr_diameter, clearance: the burr and the clearance it needs [m].
        burr_diameters: every burr of the tool library [m] (None: see
            :func:`drakedeburr.hub.extract.extract_window_edges`): an opening no burr fits
            with the clearance (:func:`drakedeburr.hub.openings.burr_need`) is not a window.
        min_window_width: [m] overrides that bound when given.
        expected_windows: fail unless this many windows are found (None: any number >= 1).
        edge_spacing: arc-length spacing of the stored edge points [m].
        simplify_tolerance: the solid is simplified within this distance before decomposition
            [m] (CoACD's time grows with the triangle count).
        threshold: CoACD concavity threshold (relative to the part's size). Deliberately
            coarse: CoACD's time grows steeply with a finer threshold (0.05 with the search
            below took 70 s on a 17 in hub, 0.1 takes 4 s) and a fine threshold still bridges
            window corners; the targeted refinement does the rest.
        max_convex_hull: CoACD's piece limit of the first pass (-1: none).
        resolution: CoACD surface sampling resolution.
        mcts_iterations, mcts_nodes, mcts_max_depth: CoACD's tree search effort.
        seed: CoACD random seed (deterministic output for a given mesh).
        window_reach: a piece may reach at most this far into a window opening [m]. The
            generator holds 0.5 mm (which ``Tolerances.collision_model_excess`` assumes); at
            1 mm the full-hub verification of h5_straight's mesh failed ``burr_contact`` by
            0.03 mm and the planner lost 7 IK targets of window 4, at 0.5 mm it passed like the
            bundled hub but took 1108 pieces, 53 s, and did not converge within
            ``max_refine_rounds`` on the same mesh in another pose (known weakness).
        probe_depth: the opening probes span this depth below the edge [m].
        max_refine_rounds: refinement rounds for pieces that reach into an opening.
        front_reach: within ``front_band`` of a window's wall line, a piece may stand at most
            this far proud of the surface seen from the front (+Z_H) [m]: the generator's own
            bound near a window (``hub.collision.COLL_FRONT_REACH_MM``). At 3 mm a CoACD hull
            bridged a concave part of an unseen hub's front 2.5 mm proud beside a window where
            the burr's shank needs 2.05 mm above the face, and the window could not be planned
            (benchmarks/RESULTS.md, r3141_001). Probes on a plan-view grid of
            ``front_probe_spacing`` [m].
        front_reach_far: the same further out [m].
        front_band: plan-view distance from a window's wall line within which
            ``front_reach`` holds [m]. Where the tool is low over the face: the burr's head
            (12 mm) and the lowest line of its shank, which at the recipes' tilts (<= 0.44 rad
            from the normal) rises at least ~2 mm per mm away from the edge, stay within
            ~10 mm of the edge below 3 mm above it. Not the generator's 30 mm: on an imported
            mesh that band also takes in a rim's step beside the windows, where an open mesh's
            shell cannot hold 1 mm (review, session 19).
        refine: how such a piece's part is split: "cut" or "coacd" (see import_collision).
        shell_max_edge, shell_thickness, shell_cell, shell_min_cell: the surface shell of an
            open mesh: triangles subdivided to this edge length, hull thickness, first and
            smallest quadtree cell [m].
        shell_behind: an open mesh's shell lies behind its surface (``shell_thickness`` deep)
            on each connected part whose side the front view tells
            (:func:`drakedeburr.hub.import_collision.front_sides`), instead of half either
            side: the pieces then stand no higher than the surface the tool sees (with the
            half shell the burr shank read 0.49 mm closer than the true mesh on the audibot
            rim, where it passes ~2.1 mm over the face against the IK's 2.05 mm).
        density: material density for the inertia in hub.sdf [kg/m^3] (aluminium).
    """

    unit: str | None = None
    axis_M: tuple[float, float, float] | None = None
    front: str = "auto"
    burr_diameter: float = DEFAULT_BURR_DIAMETER
    burr_diameters: tuple[float, ...] | None = None
    clearance: float = DEFAULT_CLEARANCE
    min_window_width: float | None = None
    expected_windows: int | None = None
    edge_spacing: float = 0.5e-3
    simplify_tolerance: float = 0.5e-3
    threshold: float = 0.1
    max_convex_hull: int = -1
    resolution: int = 500
    mcts_iterations: int = 20
    mcts_nodes: int = 20
    mcts_max_depth: int = 1
    seed: int = 0
    window_reach: float = 1.0e-3
    probe_depth: float = 20e-3
    max_refine_rounds: int = 40
    front_reach: float = 1.0e-3
    front_reach_far: float = 3.0e-3
    front_band: float = 15e-3
    front_probe_spacing: float = 4.0e-3
    refine: str = "cut"
    shell_max_edge: float = 8e-3
    shell_thickness: float = 1e-3
    shell_cell: float = 0.04
    shell_min_cell: float = 2.5e-3
    shell_behind: bool = True
    density: float = 2700.0
