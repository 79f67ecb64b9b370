"""Through-openings of a hub mesh seen along its axis, and which of them are windows.

Rays are cast along -Z_H on a plan-view grid (open3d ``RaycastingScene``: works on any triangle
soup, closed or not); connected regions of misses (scipy.ndimage) that do not touch the grid's
border are the through-openings. Each is measured (area, width = diameter of the largest
inscribed circle, radius of its centre, roundness) and classified:

* ``centre bore``: it contains the hub axis;
* ``lug hole``: round (area <= 1.35 x its inscribed circle's), <= 35 mm wide, at most half
  the hub's radius from the axis, one of >= 3 openings of that size (+-15 %) on one circle
  (+-3 mm): the bolt pattern;
* ``too narrow``: no burr of the tool library fits it: narrower than the smallest burr's
  need (:func:`burr_need`: head diameter + 2 x clearance; the burrs are tried smallest need
  first, so the small burr is tried before an opening is refused); the reason gives the
  measured width and each burr's need, and says ``vent slot`` when it is long
  (length > 3 x width);
* ``noise``: fewer than 4 grid cells (not reported);
* otherwise a ``window`` (a candidate: the planner and the verifier then judge reach and
  clearance with the real tool).

The burrs come from the caller (the CLI passes the tool library's heads,
``drakedeburr.cell.tools.BURR_HEADS``); the hub stage does not import the cell.

Every opening that is not a window (except noise) is logged at WARNING with its reason and
listed in the result.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["Opening", "OpeningScan", "OpeningSearch", "find_openings", "min_window_width",
           "burr_need", "judged_burrs", "narrow_reason", "DEFAULT_BURR_DIAMETER",
           "DEFAULT_BURR_DIAMETERS", "DEFAULT_CLEARANCE"]

log = logging.getLogger(__name__)

DEFAULT_BURR_DIAMETER = 12e-3  # [m] = drakedeburr.cell.tools.BURR.head_diameter (tested)
#: [m] the head diameters of the tool library, largest first
#: (= drakedeburr.cell.tools.BURR_HEADS, tested)
DEFAULT_BURR_DIAMETERS = (12e-3, 6e-3)
DEFAULT_CLEARANCE = 2e-3  # [m] = drakedeburr.config.Tolerances().min_clearance (tested)


def burr_need(burr_diameter: float = DEFAULT_BURR_DIAMETER,
              clearance: float = DEFAULT_CLEARANCE) -> float:
    """Narrowest opening [m] a burr of ``burr_diameter`` [m] passes with ``clearance`` [m] to
    both walls: ``burr_diameter + 2 clearance`` (12 mm burr, 2 mm: 16 mm; 6 mm burr: 10 mm)."""
    return burr_diameter + 2.0 * clearance


def min_window_width(burr_diameter: float | tuple[float, ...] = DEFAULT_BURR_DIAMETERS,
                     clearance: float = DEFAULT_CLEARANCE) -> float:
    """Narrowest opening [m] that is a window candidate: the smallest :func:`burr_need` of
    the burrs ``burr_diameter`` (one diameter or several) [m]."""
    ds = (burr_diameter,) if np.isscalar(burr_diameter) else tuple(burr_diameter)
    return min(burr_need(float(d), clearance) for d in ds)


@dataclass(frozen=True, eq=False)
class Opening:
    """One through-opening in the plan view of H.

    Attributes:
        label: its label in the grid.
        kind: "window", "centre bore", "lug hole" or "too narrow".
        reason: why it is not a window ("" for a window).
        area: [m^2]; width: inscribed circle's diameter [m]; length: longest extent [m].
        center_xy: (2,) the inscribed circle's centre in H [m]; radius: its distance from the
            axis [m]; roundness: area / inscribed circle's area [-].
        mask: (n, n) bool grid cells of the opening.
    """

    label: int
    kind: str
    reason: str
    area: float
    width: float
    length: float
    center_xy: np.ndarray
    radius: float
    roundness: float
    mask: np.ndarray = field(repr=False)

    def as_dict(self) -> dict:
        """JSON-ready summary in millimetres."""
        return {"kind": self.kind, "reason": self.reason,
                "center_xy_mm": [round(float(v) * 1e3, 2) for v in self.center_xy],
                "radius_mm": round(self.radius * 1e3, 2), "width_mm": round(self.width * 1e3, 2),
                "length_mm": round(self.length * 1e3, 2),
                "area_mm2": round(self.area * 1e6, 1)}


@dataclass(frozen=True, eq=False)
class OpeningScan:
    """The plan-view ray grid and the openings found in it.

    Attributes:
        grid: (n,) cell centre coordinates along X_H and Y_H [m].
        pixel: cell size [m].
        z0: height of the ray origins (above the mesh) in H [m].
        hit: (n, n) bool, a ray hit the mesh.
        openings: every opening, windows and others, by label.
    """

    grid: np.ndarray
    pixel: float
    z0: float
    hit: np.ndarray
    openings: list[Opening]

    @property
    def windows(self) -> list[Opening]:
        return [o for o in self.openings if o.kind == "window"]

    @property
    def not_windows(self) -> list[Opening]:
        return [o for o in self.openings if o.kind != "window"]


def judged_burrs(burr_diameter: float = DEFAULT_BURR_DIAMETER,
                 burr_diameters: tuple[float, ...] | None = None) -> tuple[float, ...]:
    """The burrs [m] an opening is judged by, smallest first: ``burr_diameters`` when given;
    else the tool library's (``DEFAULT_BURR_DIAMETERS``: the small burr is tried before an
    opening is refused) when ``burr_diameter`` is the standard one, else that burr alone."""
    if burr_diameters:
        burrs = burr_diameters
    elif abs(burr_diameter - DEFAULT_BURR_DIAMETER) < 1e-12:
        burrs = DEFAULT_BURR_DIAMETERS
    else:
        burrs = (burr_diameter,)
    return tuple(sorted(float(b) for b in burrs))


def narrow_reason(width: float, burrs: tuple[float, ...], clearance: float,
                  min_width: float, what: str = "opening") -> str:
    """Why an opening ``width`` [m] wide (inscribed circle) is no window: the measured width,
    each burr's need (:func:`burr_need`) and, when the caller asked for a wider bound than
    the smallest need, that bound [m]."""
    needs = [(b, burr_need(b, clearance)) for b in burrs]
    each = ", ".join(f"the {b * 1e3:g} mm burr needs {n * 1e3:.1f} mm" for b, n in needs)
    own = min((n for _, n in needs), default=min_width)
    asked = ("" if abs(own - min_width) < 1e-9
             else f"; the narrowest window asked for is {min_width * 1e3:.1f} mm")
    return (f"{what} {width * 1e3:.1f} mm wide (inscribed circle): no burr fits with the "
            f"{clearance * 1e3:g} mm clearance: {each}{asked}")


@dataclass(frozen=True)
class OpeningSearch:
    """How the through-openings are found and judged (module doc).

    Attributes:
        burrs: the burr head diameters an opening is judged by [m], smallest first
            (:func:`judged_burrs`; the CLI passes the tool library's heads).
        clearance: what each burr needs to both walls [m].
        min_width: narrowest window asked for [m]; None: :func:`min_window_width` of
            ``burrs`` (the smallest burr's need).
        pixel: step of the plan-view ray grid [m].
    """

    burrs: tuple[float, ...] = tuple(sorted(DEFAULT_BURR_DIAMETERS))
    clearance: float = DEFAULT_CLEARANCE
    min_width: float | None = None
    pixel: float = 0.5e-3

    @classmethod
    def of(cls, burr_diameter: float = DEFAULT_BURR_DIAMETER,
           burr_diameters: tuple[float, ...] | None = None,
           clearance: float = DEFAULT_CLEARANCE, min_window_width: float | None = None,
           pixel: float = 0.5e-3) -> OpeningSearch:
        """From the importer's options (:class:`drakedeburr.hub.import_options.ImportOptions`
        fields of the same names): the burrs by :func:`judged_burrs`."""
        return cls(judged_burrs(burr_diameter, burr_diameters), float(clearance),
                   min_window_width, float(pixel))

    @property
    def window_width(self) -> float:
        """Narrowest opening [m] that is a window candidate."""
        return (min_window_width(self.burrs, self.clearance) if self.min_width is None
                else float(self.min_width))


def _measure(mask: np.ndarray, g: np.ndarray, pixel: float) -> dict:
    from scipy import ndimage

    dist = ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    i, j = np.unravel_index(int(np.argmax(dist)), mask.shape)
    width = 2.0 * float(dist[i, j]) * pixel
    area = float(mask.sum()) * pixel**2
    ii, jj = np.nonzero(mask)
    pts = np.column_stack([g[ii], g[jj]])
    c = pts.mean(axis=0)
    # longest extent: along the principal direction of the cells
    u = np.linalg.svd(pts - c, full_matrices=False)[2][0]
    length = float(np.ptp((pts - c) @ u)) + pixel
    centre = np.array([g[i], g[j]])
    return {"area": area, "width": width, "length": length, "center_xy": centre,
            "radius": float(np.linalg.norm(centre)),
            "roundness": area / max(math.pi * (0.5 * width) ** 2, 1e-12)}


def _lug_pattern(cands: list[dict], r_max: float) -> set[int]:
    """Labels of round openings that form a bolt circle (>= 3 of one size on one radius)."""
    round_ = [c for c in cands if c["roundness"] <= 1.35 and c["width"] <= 0.035
              and c["radius"] <= 0.5 * r_max and c["radius"] > 0.5 * c["width"]]
    found: set[int] = set()
    for c in round_:
        group = [d for d in round_ if abs(d["width"] - c["width"]) <= 0.15 * c["width"]
                 and abs(d["radius"] - c["radius"]) <= 3e-3]
        if len(group) >= 3:
            found.update(d["label"] for d in group)
    return found


def find_openings(scene, r_max: float, z_top: float, *,
                  search: OpeningSearch | None = None, source: str = "mesh",
                  quiet: bool = False) -> OpeningScan:
    """Cast the plan-view grid along -Z_H and classify the openings (module doc).

    Args:
        scene: open3d RaycastingScene of the mesh in H [m].
        r_max: largest distance of the mesh from the axis [m].
        z_top: height above the mesh for the ray origins [m].
        search: the grid step, the burrs (the refusal names each one's need), the clearance
            and the narrowest window; default :class:`OpeningSearch` (the tool library's).
        source: name for messages.
        quiet: log the openings that are not windows at DEBUG instead of WARNING.
    """
    import open3d as o3d
    from scipy import ndimage

    search = OpeningSearch() if search is None else search
    burrs = tuple(sorted(float(b) for b in search.burrs)) or (DEFAULT_BURR_DIAMETER,)
    clearance, pixel = search.clearance, search.pixel
    min_width = replace(search, burrs=burrs).window_width
    n_px = int(np.ceil(2 * r_max / pixel)) + 3
    g = (np.arange(n_px) - (n_px - 1) / 2) * pixel
    gx, gy = np.meshgrid(g, g, indexing="ij")
    rays = np.zeros((n_px * n_px, 6), np.float32)
    rays[:, 0], rays[:, 1], rays[:, 2], rays[:, 5] = gx.ravel(), gy.ravel(), z_top, -1.0
    hit = np.isfinite(scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()).reshape(n_px, n_px)
    labels, n_lab = ndimage.label(~hit)
    border = set(np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]]).tolist())
    centre = int(labels[n_px // 2, n_px // 2])
    cands = []
    for lab in range(1, n_lab + 1):
        if lab in border:
            continue
        mask = labels == lab
        if mask.sum() < 4:
            continue  # noise of the grid
        cands.append({"label": lab, "mask": mask, **_measure(mask, g, pixel)})
    lugs = _lug_pattern(cands, r_max)
    openings = [_classify(c, centre, lugs, min_width, burrs, clearance) for c in cands]
    for o in openings:
        if o.kind != "window":
            level = logging.DEBUG if quiet else (
                logging.INFO if o.kind == "centre bore" else logging.WARNING)
            log.log(level, "%s: opening at r = %.0f mm (%.0f deg about +Z_H), %.1f mm wide, "
                    "is not a window: %s", source, o.radius * 1e3,
                        math.degrees(math.atan2(o.center_xy[1], o.center_xy[0])),
                        o.width * 1e3, o.reason)
    return OpeningScan(g, pixel, z_top, hit, openings)


def _classify(c: dict, centre: int, lugs: set[int], min_width: float,
              burrs: tuple[float, ...], clearance: float) -> Opening:
    if c["label"] == centre or c["radius"] < 0.25 * c["width"]:
        kind, reason = "centre bore", "it contains the hub axis (centre bore)"
    elif c["label"] in lugs:
        kind, reason = "lug hole", (f"round {c['width'] * 1e3:.1f} mm hole, one of a bolt "
                                    f"pattern on a {2 * c['radius'] * 1e3:.1f} mm circle")
    elif c["width"] < min_width:
        what = "vent slot" if c["length"] > 3.0 * c["width"] else "opening"
        kind, reason = "too narrow", narrow_reason(c["width"], burrs, clearance, min_width, what)
    else:
        kind, reason = "window", ""
    return Opening(c["label"], kind, reason, c["area"], c["width"], c["length"],
                   c["center_xy"], c["radius"], c["roundness"], c["mask"])
