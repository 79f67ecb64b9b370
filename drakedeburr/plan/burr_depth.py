"""How deep the burr goes into the hub along a planned window, and the tool points moved out where
it would go deeper than the verifier allows.

The CL targets put the flank's cutting circle ``depth_of_cut`` into the material from the
deburring line along the wall's normal (:func:`drakedeburr.plan.targets.tool_point_H`). On a
square edge under a flank at about 45 degrees the line is the deepest point the flank reaches.
Not so where:

* the edge is rounded: the line is the round's face-side tangent line (docs/hub.md) and the
  round below it stands out into the opening, by up to its radius under a steep flank;
* the edge is acute: on a dished face the face falls toward the opening, and a flank about
  parallel to the face lies in it over a band several millimetres wide.

So a planned window is read the way the verifier reads it (the burr head's cone against the
hub's triangle mesh, :func:`drakedeburr.cell.true_surface.true_surface_distances`), on the
executed approach, cut and retract, against the verifier's ``burr_contact`` bound (depth of cut
+ ``edge_deviation``). Where it goes deeper than that bound less :data:`MARGIN`, those CL
targets' tool points move out of the material along the reading's gradient (forward differences
over 0.1 mm) by the excess over the gradient's size, spread to the neighbouring targets, and the
window is planned again (at most :data:`ROUNDS` times). The deburring line stays engaged:
``burr_engagement`` accepts it from just touching (-``edge_deviation``) and a tool point never
moves by more than the depth of cut. The move is a departure from the recipe and recorded as one
(``WindowStats.chamfer_relief``, ``plan.meta["recipe_deviations"]``).

Why: on a deeply dished face (a 62 mm dish: the face normal 38 degrees off the hub axis, 53
degrees of material at the edge) the burr goes 1.39-1.63 mm into the material, over the
verifier's ``burr_contact`` bound of depth of cut + ``edge_deviation`` (1.37 mm), while nothing
else in planning reads it; this module is the planner's reading of it.
"""

from __future__ import annotations

import functools
import logging

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["MARGIN", "ROUNDS", "burr_depth_excess", "relieved_offsets", "hub_model_of"]

log = logging.getLogger(__name__)

#: [m] the planner keeps the burr this far inside the verifier's bound: the verifier reads the
#: program's moves, the planner its dense cut (they differ by the path tolerance's share)
MARGIN = 0.03e-3
#: plans of a window with a relieved chamfer leg, at most
ROUNDS = 3
#: [m] the outward step the reading's rate is measured over
_PROBE = 0.1e-3
#: [m] spacing of the poses read closely along the executed motion (the verifier's: 0.5 mm)
_SPACING = 0.25e-3
#: [m] spacing of the first, coarse reading, and the resolution it is read to
_COARSE = 2e-3
_COARSE_TOLERANCE = 20e-6
#: [m] a coarse pose this close to the bound has its neighbourhood read closely
_NEAR = 0.15e-3


@functools.lru_cache(maxsize=2)
def hub_model_of(hub_dir: str):
    """The :class:`drakedeburr.hub.HubModel` of a cell's hub folder (cached per process)."""
    from drakedeburr.hub import load_hub

    return load_hub(hub_dir)


def burr_depth_excess(hub_model, X_HT: np.ndarray, bound: float, tolerance: float = 2e-6,
                      settle: float = 0.0) -> np.ndarray:
    """(N,) how far the burr head reaches into the hub's material beyond ``bound`` at each
    tool pose in H [m] (<= 0: within; a pose is read only until it is certainly ``settle``
    or more within, to ``tolerance`` otherwise). A pose whose cone in-centre lies in the
    material (or, on an open mesh, in a collision piece) reads at least the in-radius deep."""
    from drakedeburr.cell.true_surface import burr_cone, true_surface_distances

    X_HT = np.asarray(X_HT, float)
    if not len(X_HT):
        return np.zeros(0)
    # a pose whose depth bound falls within ``bound`` is settled there (most of a cut)
    reading = true_surface_distances(hub_model, X_HT, np.arange(len(X_HT)), reach=0.0,
                                     tolerance=tolerance, shallow=bound - settle)
    depth = -reading.value
    depth[reading.engulfed] = np.maximum(depth[reading.engulfed], burr_cone().inradius)
    return depth - bound


def _thin(X: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of the poses where the travel first passes each multiple of ``spacing``, and
    the last one."""
    p = X[:, :3, 3]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    first = np.flatnonzero(np.diff(np.floor(s / spacing), prepend=-1.0) > 0)
    return np.unique(np.concatenate([first, [len(p) - 1]]))


def _read_poses(hub_model, X: np.ndarray, bound: float) -> np.ndarray:
    """The poses worth reading closely: every :data:`_COARSE` of travel first (to
    :data:`_COARSE_TOLERANCE`), then every :data:`_SPACING` within :data:`_COARSE` of a coarse
    pose that comes within :data:`_NEAR` of ``bound``. A square edge under the recipe's flank
    stays some 0.3 mm inside the bound (h5_straight: 1.28-1.41 mm against 1.67 mm) and costs
    the coarse reading only: 0.5 s a window, against 7.5 s for all of it at 0.25 mm."""
    coarse = _thin(X, _COARSE)
    ex = burr_depth_excess(hub_model, X[coarse], bound, tolerance=_COARSE_TOLERANCE,
                           settle=_NEAR)
    close = coarse[ex > -_NEAR]
    if not len(close):
        return X[coarse[ex > 0.0]]
    p = X[:, :3, 3]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    around = np.zeros(len(X), bool)
    for i in close:
        around |= np.abs(s - s[i]) <= _COARSE
    fine = np.flatnonzero(around)
    return X[fine[_thin(X[fine], _SPACING)]]


def relieved_offsets(hub_model, X_HT: np.ndarray, p_HQ: np.ndarray, offset: np.ndarray,
                     bound: float, closed: bool) -> tuple[np.ndarray, float]:
    """New per-CL tool-point offsets where the executed motion goes too deep (module
    docstring).

    Args:
        hub_model: the hub (its mesh and pieces, frame H).
        X_HT: (N, 4, 4) the window's executed approach, cut and retract poses in H.
        p_HQ: (M, 3) the CL targets' cutting-circle centres as planned (offsets included).
        offset: (M, 3) the offsets they were planned with [m] (zero: the recipe's).
        bound: [m] the deepest the burr may reach into the material.
        closed: the CL loop is closed (the relief spreads across its seam).

    Returns:
        ((M, 3) offsets, largest excess read [m]); the offsets are ``offset`` where nothing
        went too deep.
    """
    X = _read_poses(hub_model, np.asarray(X_HT, float), bound - MARGIN)
    excess = burr_depth_excess(hub_model, X, bound - MARGIN)
    over = np.flatnonzero(excess > 0.0)
    worst = float(excess.max()) if len(excess) else 0.0
    offset = np.asarray(offset, float).copy()
    if not len(over):
        return offset, worst
    # the excess' gradient in the tool's position (forward differences): the way out of the
    # material, which a steep flank on a round, or a flank lying along a dished face at an
    # acute edge of a dished face (along the hub axis, not the wall normal), decide
    grad = np.zeros((len(over), 3))
    for k, e in enumerate(np.eye(3)):
        Xs = X[over].copy()
        Xs[:, :3, 3] += _PROBE * e
        grad[:, k] = (burr_depth_excess(hub_model, Xs, bound - MARGIN) - excess[over]) / _PROBE
    rate = np.linalg.norm(grad, axis=1)
    # a rate near zero: moving barely helps (a flat spot of the reading); capped below
    # (a tenth and 2 um beyond the reading's own line: the next reading lands inside)
    step = 1.1 * excess[over] / np.maximum(rate, 0.25) + 2e-6
    move = -grad / np.maximum(rate, 1e-12)[:, None] * step[:, None]
    # each pose too deep belongs to the CL target whose circle centre is nearest its own; a
    # target takes the largest move asked of it
    near = cKDTree(p_HQ).query(X[over, :3, 3])[1]
    m = len(p_HQ)
    need = np.zeros((m, 3))
    size = np.zeros(m)
    for j, v in zip(near, move, strict=True):
        if np.linalg.norm(v) > size[j]:
            need[j], size[j] = v, np.linalg.norm(v)
    # spread to the neighbours: the tool point moves smoothly along the loop
    idx = np.arange(m)
    nb = [(idx + k) % m if closed else np.clip(idx + k, 0, m - 1) for k in (-2, -1, 0, 1, 2)]
    pick = np.array(nb)[np.argmax(np.array([size[j] for j in nb]), axis=0), idx]
    return offset + need[pick], worst
