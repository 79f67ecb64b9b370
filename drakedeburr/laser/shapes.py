"""Shape generator of the laser cell (source 004 §3.2): parameterised hole contours.

Each shape is a frozen dataclass of its size plus a common placement (centre, rotation,
lead-in, direction). :func:`build_contour` turns it into exact line/arc primitives in the
part plane P (metres, x-y of the user frame) and samples them at a chosen point spacing.

Start points (before rotation): circle, keyhole, slot: the right-most point; rectangle,
hexagon: the middle of the right side; semicircle: the middle of the flat side; polyline: the
middle of its first edge. The lead-in is a straight line of length ``lead_in`` from a pierce
point inside the hole (scrap side) to the start point, along the inward normal.

Area and perimeter of the cut contour are computed exactly from the primitives (Green's
theorem on lines and arcs). Written by hand: 2-D line/arc sampling is a few lines and the
mesh/CAD libraries we depend on do not offer parameterised hole shapes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drakedeburr.errors import InputError

__all__ = [
    "ShapeBase",
    "Circle",
    "Semicircle",
    "Rectangle",
    "Slot",
    "Keyhole",
    "Hexagon",
    "Polyline",
    "Contour",
    "SHAPE_KINDS",
    "build_contour",
]


@dataclass(frozen=True, kw_only=True)
class ShapeBase:
    """Placement common to all shapes.

    Attributes:
        center: (x, y) of the shape origin in the part plane P [m].
        rotation: rotation about the plane normal [rad], counter-clockwise.
        lead_in: length of the straight lead-in from the pierce point [m]; 0 = none.
        clockwise: cut direction (default counter-clockwise, seen from +z of P).
    """

    center: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0
    lead_in: float = 0.0
    clockwise: bool = False

    kind = "shape"

    def _validate(self) -> None:
        for name, value in self._sizes():
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"{self.kind}: {name} must be > 0, got {value!r}")
        if not (np.isfinite(self.lead_in) and self.lead_in >= 0):
            raise InputError(f"{self.kind}: lead_in must be >= 0, got {self.lead_in!r}")

    def _sizes(self) -> list[tuple[str, float]]:
        return []

    def primitives(self) -> list[tuple]:
        """Primitives in the shape's own frame, counter-clockwise (see module doc)."""
        raise NotImplementedError


def _line(p0, p1) -> tuple:
    return ("line", np.asarray(p0, float), np.asarray(p1, float))


def _arc(c, r: float, a0: float, sweep: float) -> tuple:
    return ("arc", np.asarray(c, float), float(r), float(a0), float(sweep))


@dataclass(frozen=True, kw_only=True)
class Circle(ShapeBase):
    """Round hole of ``diameter`` [m]."""

    diameter: float
    kind = "circle"

    def _sizes(self):
        return [("diameter", self.diameter)]

    def primitives(self):
        return [_arc((0, 0), self.diameter / 2, 0.0, 2 * math.pi)]


@dataclass(frozen=True, kw_only=True)
class Semicircle(ShapeBase):
    """Half disc of ``diameter`` [m]; the flat side on the x axis, the arc towards +y."""

    diameter: float
    kind = "semicircle"

    def _sizes(self):
        return [("diameter", self.diameter)]

    def primitives(self):
        r = self.diameter / 2
        return [_line((0, 0), (r, 0)), _arc((0, 0), r, 0.0, math.pi), _line((-r, 0), (0, 0))]


@dataclass(frozen=True, kw_only=True)
class Rectangle(ShapeBase):
    """``width`` (x) x ``height`` (y) rectangle [m] with ``corner_radius`` [m] (0 = sharp)."""

    width: float
    height: float
    corner_radius: float = 0.0
    kind = "rectangle"

    def _sizes(self):
        return [("width", self.width), ("height", self.height)]

    def _validate(self):
        super()._validate()
        if not (0 <= self.corner_radius <= 0.5 * min(self.width, self.height)):
            raise InputError(f"rectangle: corner_radius must be in [0, min(width, height)/2 = "
                             f"{0.5 * min(self.width, self.height)!r}], got "
                             f"{self.corner_radius!r}")

    def primitives(self):
        w, h, r = self.width / 2, self.height / 2, self.corner_radius
        prims = [_line((w, 0), (w, h - r))]
        corners = [((w - r, h - r), 0.0), ((-w + r, h - r), 0.5 * math.pi),
                   ((-w + r, -h + r), math.pi), ((w - r, -h + r), 1.5 * math.pi)]
        ends = [(-w + r, h), (-w, -h + r), (w - r, -h), (w, 0)]
        for (c, a0), end in zip(corners, ends, strict=True):
            if r > 0:
                prims.append(_arc(c, r, a0, 0.5 * math.pi))
            start = np.asarray(c) + r * np.array([math.cos(a0 + 0.5 * math.pi),
                                                  math.sin(a0 + 0.5 * math.pi)])
            prims.append(_line(start, end))
        return [p for p in prims if p[0] == "arc" or np.linalg.norm(p[2] - p[1]) > 0]


@dataclass(frozen=True, kw_only=True)
class Slot(ShapeBase):
    """Obround slot: overall ``length`` (x) and ``width`` (y) [m], round ends."""

    length: float
    width: float
    kind = "slot"

    def _sizes(self):
        return [("length", self.length), ("width", self.width)]

    def _validate(self):
        super()._validate()
        if self.length < self.width:
            raise InputError(f"slot: length {self.length!r} must be >= width {self.width!r}")

    def primitives(self):
        r, a = self.width / 2, (self.length - self.width) / 2
        prims = [_arc((a, 0), r, 0.0, 0.5 * math.pi), _line((a, r), (-a, r)),
                 _arc((-a, 0), r, 0.5 * math.pi, math.pi), _line((-a, -r), (a, -r)),
                 _arc((a, 0), r, 1.5 * math.pi, 0.5 * math.pi)]
        return [p for p in prims if p[0] == "arc" or np.linalg.norm(p[2] - p[1]) > 0]


@dataclass(frozen=True, kw_only=True)
class Keyhole(ShapeBase):
    """Round head of ``head_diameter`` centred at the origin with a slot of ``slot_width``
    running towards -y; the centre of the slot's round end is ``slot_length`` below the head
    centre. All [m]."""

    head_diameter: float
    slot_width: float
    slot_length: float
    kind = "keyhole"

    def _sizes(self):
        return [("head_diameter", self.head_diameter), ("slot_width", self.slot_width),
                ("slot_length", self.slot_length)]

    def _validate(self):
        super()._validate()
        R, w = self.head_diameter / 2, self.slot_width / 2
        if w >= R:
            raise InputError(f"keyhole: slot_width {self.slot_width!r} must be < head_diameter "
                             f"{self.head_diameter!r}")
        if self.slot_length <= math.sqrt(R * R - w * w):
            raise InputError(f"keyhole: slot_length {self.slot_length!r} must reach outside the "
                             f"head (> {math.sqrt(R * R - w * w)!r})")

    def primitives(self):
        R, w, ell = self.head_diameter / 2, self.slot_width / 2, self.slot_length
        alpha = math.asin(w / R)  # half the angle the slot cuts out of the head
        a_end = 1.5 * math.pi - alpha
        d = math.sqrt(R * R - w * w)
        return [_arc((0, 0), R, 0.0, a_end), _line((-w, -d), (-w, -ell)),
                _arc((0, -ell), w, math.pi, math.pi), _line((w, -ell), (w, -d)),
                _arc((0, 0), R, -0.5 * math.pi + alpha, 0.5 * math.pi - alpha)]


@dataclass(frozen=True, kw_only=True)
class Hexagon(ShapeBase):
    """Regular hexagon of ``across_flats`` [m]; two flats parallel to the y axis."""

    across_flats: float
    kind = "hexagon"

    def _sizes(self):
        return [("across_flats", self.across_flats)]

    def primitives(self):
        a = self.across_flats / math.sqrt(3)  # side = circumradius
        v = [(a * math.cos(math.radians(-30 + 60 * k)), a * math.sin(math.radians(-30 + 60 * k)))
             for k in range(6)]
        m = (self.across_flats / 2, 0.0)
        prims = [_line(m, v[1])]
        prims += [_line(v[k], v[(k + 1) % 6]) for k in range(1, 6)]
        prims.append(_line(v[0], m))
        return prims


@dataclass(frozen=True, kw_only=True)
class Polyline(ShapeBase):
    """Custom closed polygon through ``points`` ((x, y) pairs [m], >= 3, not repeated)."""

    points: tuple[tuple[float, float], ...] = field(default=())
    kind = "polyline"

    def _validate(self):
        super()._validate()
        p = np.asarray(self.points, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3 or not np.all(np.isfinite(p)):
            raise InputError(f"polyline: need >= 3 finite (x, y) points, got shape {p.shape}")
        seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
        if np.any(seg <= 0):
            raise InputError(f"polyline: point {int(np.argmin(seg))} repeats the next point")

    def primitives(self):
        p = np.asarray(self.points, dtype=float)
        if _green_area_polygon(p) < 0:  # primitives run counter-clockwise; see ``clockwise``
            p = p[::-1]
        m = 0.5 * (p[0] + p[1])
        prims = [_line(m, p[1])]
        prims += [_line(p[k], p[(k + 1) % len(p)]) for k in range(1, len(p))]
        prims.append(_line(p[0], m))
        return prims


SHAPE_KINDS: dict[str, type[ShapeBase]] = {
    cls.kind: cls for cls in (Circle, Semicircle, Rectangle, Slot, Keyhole, Hexagon, Polyline)
}


def _green_area_polygon(p: np.ndarray) -> float:
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _prim_length(pr) -> float:
    if pr[0] == "line":
        return float(np.linalg.norm(pr[2] - pr[1]))
    return abs(pr[2] * pr[4])


def _prim_area(pr) -> float:
    """Green's theorem term 1/2 * integral(x dy - y dx) of one primitive."""
    if pr[0] == "line":
        (x0, y0), (x1, y1) = pr[1], pr[2]
        return 0.5 * (x0 * y1 - x1 * y0)
    _, (cx, cy), r, a0, sw = pr
    a1 = a0 + sw
    return 0.5 * (r * r * sw + r * cx * (math.sin(a1) - math.sin(a0))
                  - r * cy * (math.cos(a1) - math.cos(a0)))


def _prim_eval(pr, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (K, 2) and unit tangents (K, 2) at fractions u (K,) of the primitive."""
    if pr[0] == "line":
        d = pr[2] - pr[1]
        return pr[1] + u[:, None] * d, np.tile(d / np.linalg.norm(d), (len(u), 1))
    _, c, r, a0, sw = pr
    a = a0 + u * sw
    p = c + r * np.stack([np.cos(a), np.sin(a)], axis=1)
    t = math.copysign(1.0, sw) * np.stack([-np.sin(a), np.cos(a)], axis=1)
    return p, t


def _reverse(pr) -> tuple:
    if pr[0] == "line":
        return _line(pr[2], pr[1])
    _, c, r, a0, sw = pr
    return _arc(c, r, a0 + sw, -sw)


def _transform(pr, R: np.ndarray, p0: np.ndarray, rot: float) -> tuple:
    if pr[0] == "line":
        return _line(p0 + R @ pr[1], p0 + R @ pr[2])
    _, c, r, a0, sw = pr
    return _arc(p0 + R @ c, r, a0 + rot, sw)


@dataclass(frozen=True, eq=False)
class Contour:
    """A sampled cut contour in the part plane P.

    Attributes:
        name: shape kind ("circle", ...).
        shape: the shape that made it.
        p_P: (N, 2) points in P [m]: lead-in points (if any), then the closed contour; the
            last point repeats the contour start.
        t_P: (N, 2) unit tangents (cut direction) at the points.
        s: (N,) arc length from the pierce point [m].
        is_cut: (N,) False on the lead-in (before the contour start), True on the contour.
        corner: (N,) True where the tangent jumps (the tool must stop there).
        area: enclosed area of the contour (exact, from the primitives) [m^2].
        perimeter: contour length without the lead-in [m].
        spacing: requested point spacing [m].
    """

    name: str
    shape: ShapeBase
    p_P: np.ndarray
    t_P: np.ndarray
    s: np.ndarray
    is_cut: np.ndarray
    corner: np.ndarray
    area: float
    perimeter: float
    spacing: float

    def __len__(self) -> int:
        return len(self.s)


def build_contour(shape: ShapeBase, spacing: float, corner_angle: float = 1e-3) -> Contour:
    """Sample ``shape`` at arc-length ``spacing`` [m] (every primitive end is kept).

    Args:
        shape: a shape dataclass (Circle, ..., Polyline).
        spacing: maximum distance between consecutive points along the contour [m].
        corner_angle: a tangent jump above this [rad] marks a corner.

    Returns:
        Contour in the part plane P.

    Raises:
        InputError: bad sizes, or a lead-in that leaves the hole.
    """
    shape._validate()
    if not (np.isfinite(spacing) and spacing > 0):
        raise InputError(f"{shape.kind}: point spacing must be > 0, got {spacing!r}")
    rot = float(shape.rotation)
    R = np.array([[math.cos(rot), -math.sin(rot)], [math.sin(rot), math.cos(rot)]])
    p0 = np.asarray(shape.center, dtype=float)
    prims = [_transform(pr, R, p0, rot) for pr in shape.primitives()]
    area = sum(_prim_area(pr) for pr in prims)
    if shape.clockwise:
        prims = [_reverse(pr) for pr in reversed(prims)]
    perimeter = sum(_prim_length(pr) for pr in prims)

    pts, tans, cut, corner = [], [], [], []
    for k, pr in enumerate(prims):
        n = max(2, math.ceil(_prim_length(pr) / spacing - 1e-9))  # >= 3 points per piece
        last = k == len(prims) - 1
        u = np.linspace(0.0, 1.0, n + 1) if last else np.linspace(0.0, 1.0, n + 1)[:-1]
        p, t = _prim_eval(pr, u)
        pts.append(p)
        tans.append(t)
        cut.append(np.ones(len(u), bool))
        c = np.zeros(len(u), bool)
        prev = prims[k - 1]
        t_prev = _prim_eval(prev, np.array([1.0]))[1][0]
        c[0] = math.acos(np.clip(np.dot(t_prev, t[0]), -1, 1)) > corner_angle
        corner.append(c)
    p_P, t_P = np.concatenate(pts), np.concatenate(tans)
    is_cut, corners = np.concatenate(cut), np.concatenate(corner)
    corners[-1] = corners[0]

    if shape.lead_in > 0:
        sign = -1.0 if shape.clockwise else 1.0  # interior is left of a CCW contour
        t0 = t_P[0]
        n_in = sign * np.array([-t0[1], t0[0]])
        pierce = p_P[0] + shape.lead_in * n_in
        from matplotlib.path import Path as MplPath  # point-in-polygon of the sampled contour

        if not MplPath(p_P).contains_point(pierce):
            raise InputError(f"{shape.kind}: lead_in {shape.lead_in!r} m puts the pierce point "
                             f"{pierce.tolist()} outside the hole; shorten it")
        n = max(2, math.ceil(shape.lead_in / spacing - 1e-9))
        u = np.linspace(0.0, 1.0, n + 1)[:-1]
        lead = pierce + u[:, None] * (p_P[0] - pierce)
        p_P = np.concatenate([lead, p_P])
        t_P = np.concatenate([np.tile(-n_in, (n, 1)), t_P])
        is_cut = np.concatenate([np.zeros(n, bool), is_cut])
        corners = np.concatenate([np.zeros(n, bool), corners])
        corners[n] = True  # lead-in meets the contour at a right angle
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p_P, axis=0), axis=1))])
    return Contour(name=shape.kind, shape=shape, p_P=p_P, t_P=t_P, s=s, is_cut=is_cut,
                   corner=corners, area=abs(area), perimeter=perimeter, spacing=float(spacing))
