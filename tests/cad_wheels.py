"""Parametric CAD test wheels (build123d / OpenCASCADE), independent of the project's hub
generator (``drakedeburr.hub.generate``): the window outlines are 2-D sketch regions cut
through a revolved rim + disc with a draft, the window's front edge is rounded by the CAD
kernel's fillet (an exact blend face), and the windows open into the rim's lip (the cut runs
into the conical lip, so the loop climbs out of the disc face: a 3-D loop). Pockets are cut
blind into the back of the spokes; the centre bore and the lug holes are through-holes that
are not windows.

Kinds (:data:`KINDS`): ``"straight"`` (5 spokes), ``"y"`` (5 Y-spokes: a large window
between spokes and a small one between the arms of each Y), ``"twin"`` (5 twin spokes: a
large window between pairs and a slot between the two bars of a pair).

``make_wheel(kind, out_dir)`` writes ``<kind>.step`` (mm), ``<kind>.iges``, and
``<kind>_coarse.stl`` / ``<kind>_fine.stl`` (tessellated at the chordal tolerances in
:data:`STL_TOLERANCES`) and returns a :class:`CadWheel` with the number of windows the
model has by construction. Run as a script to write all kinds into a folder.

Dimensions [mm] (a 17 in class wheel, 430 mm over the flange): barrel 188-194 mm radius,
flange to 215 mm; disc face at z = -12, the centre recessed to -18, back at -40; lip cone from
(r 176, z -12) to (r 200, z 0), the disc face running into it through a 20 mm round
(``LIP_BLEND``); windows from r 82 to 184 with 7 mm plan corners (``CORNER``; half that where
the kernel cannot round the window edges of 7, see ``CadWheel.corner_mm``).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

KINDS = ("straight", "y", "twin")
#: chordal tolerance [mm] (angular tolerance [rad]) of the STL exports
STL_TOLERANCES = {"coarse": (0.5, 0.5), "fine": (0.05, 0.1)}
N_SPOKES = 5
R_IN, R_OUT = 82.0, 184.0  # window radial extent [mm]
DRAFT_DEG = 3.0  # window wall draft (the opening narrows towards the back)
EDGE_ROUND = 1.0  # [mm] fillet on the window's front edge
CORNER = 7.0  # [mm] plan-view corner radius of a window
LIP_BLEND = 20.0  # [mm] round between the disc face and the lip cone (profile)
Z_FACE, Z_BACK = -12.0, -40.0
Z_CUT_TOP = 2.0  # the window cuts start (full size) this far above z = 0
SPOKE_WIDTH = 34.0  # straight spokes, at the top of the cut [mm]
TWIN_BAR, TWIN_SLOT = 13.0, 18.0  # twin spokes: bar width, slot between the bars [mm]
PHASE_DEG = 9.0  # spoke k along 9 + 72 k deg (off the circles' seam at +-X: a kernel taper
#                  failure there)


@dataclass(frozen=True)
class CadWheel:
    kind: str
    step: Path
    iges: Path
    stl: dict
    windows: int  # windows by construction
    edge_round_mm: float
    corner_mm: float  # plan-view corner radius of the windows (0: sharp)


def _body():
    """The revolved rim and disc; the disc face runs into the lip cone through a round of
    LIP_BLEND (a tangent-continuous front surface, as a cast wheel's)."""
    from build123d import Axis, Plane, Polyline, fillet, make_face, revolve

    prof = Polyline((0, -18), (70, -18), (80, Z_FACE), (176, Z_FACE), (200, 0), (215, 0),
                    (215, -10), (194, -16), (194, -200), (203, -205), (203, -212), (188, -212),
                    (188, Z_BACK), (0, Z_BACK), close=True)
    face = make_face(prof)
    crease = min(face.vertices(), key=lambda v: math.hypot(v.X - 176, v.Y - Z_FACE))
    face = fillet([crease], LIP_BLEND)
    return revolve(Plane.XZ * face, Axis.Z)


def _band(width, r0, r1, angle, lateral=0.0):
    """A bar of ``width`` from radius r0 to r1 along the direction ``angle`` [deg], shifted
    ``lateral`` sideways."""
    from build123d import Align, Axis, Pos, Rectangle

    bar = Pos(r0, lateral) * Rectangle(r1 - r0, width, align=(Align.MIN, Align.CENTER))
    return bar.rotate(Axis.Z, angle)


def _arm(a, s):
    """One arm of a Y spoke: a bar from the fork (r 112 on the spoke axis) outwards,
    diverging from the axis by 16 deg."""
    from build123d import Align, Pos, Rectangle, Rot

    fork = Pos(112 * math.cos(math.radians(a)), 112 * math.sin(math.radians(a)))
    return fork * Rot(0, 0, a + s * 16.0) * Rectangle(95, 18.0, align=(Align.MIN, Align.CENTER))


def _window_regions(kind, slot=TWIN_SLOT):
    """2-D faces of every window (plan view, mm) and the bands under which pockets go;
    ``slot``: the twin spokes' slot width at the top of the cut [mm]."""
    from build123d import Circle

    region = Circle(R_OUT) - Circle(R_IN)
    pockets = []
    for k in range(N_SPOKES):
        a = PHASE_DEG + 360.0 * k / N_SPOKES
        if kind == "straight":
            region -= _band(SPOKE_WIDTH, 0, 200, a)
            pockets.append(_band(16.0, 95, 165, a))
        elif kind == "y":
            region -= _band(30.0, 0, 140, a)  # the trunk ends inside the arms (no step)
            region -= _arm(a, -1)
            region -= _arm(a, 1)
            pockets.append(_band(14.0, 95, 120, a))
        else:  # twin: two parallel bars with a ``slot`` between them
            for s in (-1, 1):
                region -= _band(TWIN_BAR, 0, 200, a, lateral=s * 0.5 * (slot + TWIN_BAR))
                pockets.append(_band(8.0, 100, 160, a, lateral=s * 0.5 * (slot + TWIN_BAR)))
    return region.faces(), pockets


def _round_corners(face, radius):
    """Plan-view corner radii: ``radius``, smaller where the kernel cannot fit it. (build123d's
    ``fillet`` of one face of a sketch returns every face of the sketch, the others unrounded:
    the rounded face is the one with the original's centre.)"""
    from build123d import fillet

    for r in (radius, 0.5 * radius, 0.25 * radius):
        try:
            faces = fillet(face.vertices(), r).faces()
        except ValueError:
            continue
        c = face.center()
        return min(faces, key=lambda f: (f.center() - c).length)
    return face


def build(kind: str, corner: float | None = None, slot: float = TWIN_SLOT):
    """(the wheel solid (build123d Part, mm), its window count, the plan-view corner radius
    [mm] its windows were cut with). The corner radius is ``corner``, else :data:`CORNER` or,
    where the kernel cannot round the window edges of that (the Y wheel's narrow windows
    between the arms), half of it, else sharp corners. ``slot``: the twin spokes' slot [mm]."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    tries = (corner,) if corner is not None else (CORNER, 0.5 * CORNER, 0.0)
    for i, r in enumerate(tries):
        try:
            wheel, n = _build(kind, r, slot)
        except ValueError:
            if i == len(tries) - 1:
                raise
            continue
        return wheel, n, r
    raise AssertionError("unreachable")


def _build(kind: str, corner: float, slot: float = TWIN_SLOT):
    from build123d import Cylinder, Plane, Pos, extrude

    wheel = _body()
    regions, pockets = _window_regions(kind, slot)
    depth = Z_BACK - Z_CUT_TOP
    taper = DRAFT_DEG
    cuts = []
    for f in regions:
        if corner > 0:
            f = _round_corners(f, corner)
        cuts.append(extrude(Plane.XY.offset(Z_CUT_TOP) * f, amount=Z_CUT_TOP - depth,
                            dir=(0, 0, -1),
                            taper=taper))
    for c in cuts:
        wheel -= c
    for p in pockets:  # blind pockets into the back of the spokes, 12 mm deep
        p = _round_corners(p, 2.0)
        wheel -= extrude(Plane.XY.offset(Z_BACK) * p, amount=12.0, dir=(0, 0, 1), taper=2)
    wheel -= Cylinder(31.0, 100.0)  # centre bore
    for k in range(5):  # lug holes, PCD 112
        a = 2 * math.pi * (k + 0.5) / 5
        wheel -= Pos(56 * math.cos(a), 56 * math.sin(a), 0) * Cylinder(7.0, 100.0)
    wheel = _round_window_edges(wheel)
    return wheel, len(regions)


def _round_window_edges(wheel):
    """Fillet (EDGE_ROUND) every edge where a window wall meets a front surface (the disc
    face z = Z_FACE or the lip cone) inside the window's radial band."""
    from build123d import GeomType

    front = [f for f in wheel.faces()
             if (f.geom_type == GeomType.PLANE and abs(f.center().Z - Z_FACE) < 1e-6)
             or f.geom_type in (GeomType.CONE, GeomType.TORUS)]
    edges, seen = [], {}
    for f in front:
        for e in f.edges():
            seen[e] = seen.get(e, 0) + 1
    for e, n in seen.items():
        c = e.center()
        # n == 2: the crease where the disc face meets the lip cone (over a spoke), no
        # window edge
        if n == 1 and R_IN - 1 < math.hypot(c.X, c.Y) < R_OUT + 2 and e.length > 0.5:
            edges.append(e)
    return wheel.fillet(EDGE_ROUND, edges)


def make_wheel(kind: str, out_dir: str | Path, formats=("step", "iges", "stl"),
               slot: float = TWIN_SLOT) -> CadWheel:
    """Write the wheel ``kind`` (module doc); ``slot``: the twin spokes' slot width [mm] at
    the top of the cut (a slot the 12 mm burr does not fit and the 6 mm one does: 12)."""
    from build123d import export_step, export_stl

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    wheel, n, corner = build(kind, slot=slot)
    step = out / f"{kind}.step"
    export_step(wheel, str(step))
    iges = out / f"{kind}.iges"
    if "iges" in formats:
        _export_iges(wheel, iges)
    stl = {}
    for name, (tol, ang) in STL_TOLERANCES.items() if "stl" in formats else ():
        stl[name] = out / f"{kind}_{name}.stl"
        export_stl(wheel, str(stl[name]), tolerance=tol, angular_tolerance=ang)
    return CadWheel(kind, step, iges, stl, n, EDGE_ROUND, corner)


def _export_iges(wheel, path: Path) -> None:
    from OCP.IGESControl import IGESControl_Writer
    from OCP.Interface import Interface_Static

    Interface_Static.SetIVal_s("write.iges.brep.mode", 1)  # faces and edges (MSBO)
    w = IGESControl_Writer("MM", 1)
    w.AddShape(wheel.wrapped)
    w.ComputeModel()
    if not w.Write(str(path)):
        raise OSError(f"could not write {path}")


if __name__ == "__main__":
    for k in KINDS:
        print(make_wheel(k, sys.argv[1] if len(sys.argv) > 1 else "."))
