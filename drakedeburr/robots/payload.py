"""What an arm carries against what it is rated for: mass, wrist moments, wrist inertias.

The load is everything bolted to the flange and held by it (tool or gripper, and the part in
hand): its mass ``m``, its centre of gravity in the flange frame F and its inertia. The
vendors rate the wrist by the static load moment and the load inertia about axes 4, 5, 6
(FANUC "allowable load moment / inertia at wrist", ABB "maximum load and moment of inertia",
Ja5 = m ((Z + d)^2 + L^2) + max(J0x, J0y), Ja6 = m L^2 + J0z, d = axis 5 to the flange). All
three axes pass through the wrist centre W, ``c4`` behind the flange on its axis. With
``r`` = the centre of gravity seen from W and ``I_W`` the load's inertia about W (flange axes):

* J6 turns about the flange axis z: moment ``m g |r_xy|``, inertia ``I_W[z, z]``;
* J5 turns about an axis through W normal to z (its direction in F set by J6): the worst J6
  gives moment ``m g |r|`` and inertia = the largest eigenvalue of the x-y block of ``I_W``
  (ABB's Ja5 formula is this with the cross term dropped);
* J4 turns about the forearm, any direction through W as J5 moves: moment ``m g |r|``, inertia
  = the largest eigenvalue of ``I_W``.

These are the worst over every posture (gravity in any direction), so a load within them is
within the rating wherever the arm goes. A figure is checked where the arm file gives the
vendor's rating (``wrist_moment_Nm``, ``wrist_inertia_kgm2``); the mass always.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.robots.spec import RobotSpec

__all__ = ["G", "CarriedLoad", "PayloadFigure", "carried_load", "payload_figures",
           "within_rating"]

#: standard gravity [m/s^2]
G = 9.80665


@dataclass(frozen=True, eq=False)
class CarriedLoad:
    """Everything on the flange, combined.

    Attributes:
        mass: [kg]. cog_F: (3,) centre of gravity in the flange frame F [m].
        inertia_cog_F: (3, 3) rotational inertia about the centre of gravity, F axes [kg m^2].
        parts: names of the models it sums (gripper, hub, spindle, ...).
    """

    mass: float
    cog_F: np.ndarray
    inertia_cog_F: np.ndarray
    parts: tuple[str, ...] = ()


def carried_load(parts) -> CarriedLoad:
    """Combine ``(name, mass [kg], cog_F (3,) [m], inertia about its own cog, F axes (3, 3))``
    parts into one load (parallel-axis theorem)."""
    m = sum(float(p[1]) for p in parts)
    if not m > 0:
        raise ValueError("nothing with mass on the flange")
    c = sum(float(p[1]) * np.asarray(p[2], float) for p in parts) / m
    inertia = np.zeros((3, 3))
    for _, mi, pi, Ii in parts:
        d = np.asarray(pi, float) - c
        inertia += np.asarray(Ii, float) + float(mi) * (d @ d * np.eye(3) - np.outer(d, d))
    return CarriedLoad(mass=m, cog_F=c, inertia_cog_F=inertia,
                       parts=tuple(str(p[0]) for p in parts))


@dataclass(frozen=True)
class PayloadFigure:
    """One rated figure: ``value`` must not exceed ``limit`` (units: kg, N m, kg m^2)."""

    name: str
    value: float
    limit: float
    unit: str

    @property
    def ok(self) -> bool:
        return self.value <= self.limit

    @property
    def ratio(self) -> float:
        return self.value / self.limit

    def __str__(self) -> str:
        return f"{self.name} {self.value:.3f} {self.unit} (rated {self.limit:g})"


def payload_figures(spec: RobotSpec, load: CarriedLoad) -> list[PayloadFigure]:
    """The load's figures against ``spec``'s ratings (module docstring): mass always, wrist
    moments and inertias where the arm file gives them."""
    out = [PayloadFigure("mass", load.mass, spec.payload_kg, "kg")]
    r = np.asarray(load.cog_F, float) + np.array([0.0, 0.0, spec.opw.c4])  # seen from W
    I_W = load.inertia_cog_F + load.mass * (r @ r * np.eye(3) - np.outer(r, r))
    if spec.wrist_moment_Nm is not None:
        full, axial = load.mass * G * np.linalg.norm(r), load.mass * G * np.hypot(r[0], r[1])
        out += [PayloadFigure(f"J{i + 4} moment", v, lim, "N m") for i, (v, lim) in
                enumerate(zip((full, full, axial), spec.wrist_moment_Nm, strict=True))]
    if spec.wrist_inertia_kgm2 is not None:
        j4 = float(np.linalg.eigvalsh(I_W)[-1])
        j5 = float(np.linalg.eigvalsh(I_W[:2, :2])[-1])
        out += [PayloadFigure(f"J{i + 4} inertia", v, lim, "kg m^2") for i, (v, lim) in
                enumerate(zip((j4, j5, float(I_W[2, 2])), spec.wrist_inertia_kgm2,
                              strict=True))]
    return out


def within_rating(spec: RobotSpec, load: CarriedLoad) -> bool:
    """Every figure of ``load`` within ``spec``'s ratings."""
    return all(f.ok for f in payload_figures(spec, load))
