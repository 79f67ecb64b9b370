"""TCP-speed output (source 004 §3.3): laser power command proportional to the TCP speed.

The laser runs in external-control mode and takes its power from an analogue input. The
command is ``gain * v`` with ``gain = nominal_command / nominal_speed``, clamped to
[min_command, max_command]; while unclamped the energy per unit length P / v is constant, so
the kerf does not over-burn where the tool slows down (corners, accelerations).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["PowerMap", "PowerProfile", "power_profile"]


@dataclass(frozen=True)
class PowerMap:
    """Speed -> analogue command map.

    Attributes:
        nominal_speed: TCP speed at which the command equals ``nominal_command`` [m/s]
            (default 10 m/min, the Cutting Tool's top speed in the source).
        nominal_command: command at the nominal speed [V].
        min_command: lower clamp [V] (keeps the beam cutting while the tool stops to turn a
            corner or pierces; 0 would switch the beam off).
        max_command: upper clamp [V] (full scale of the laser's analogue input).
        counts_per_volt: FANUC AO counts per volt (12-bit 0-10 V board: 409.5).
        channel: AO port number used in the .ls program.
    """

    nominal_speed: float = 10.0 / 60.0
    nominal_command: float = 10.0
    min_command: float = 0.5
    max_command: float = 10.0
    counts_per_volt: float = 409.5
    channel: int = 1

    def __post_init__(self) -> None:
        if not (self.nominal_speed > 0 and self.nominal_command > 0):
            raise InputError(f"PowerMap: nominal_speed and nominal_command must be > 0, got "
                             f"{self.nominal_speed!r}, {self.nominal_command!r}")
        if not (0 <= self.min_command < self.max_command):
            raise InputError(f"PowerMap: need 0 <= min_command < max_command, got "
                             f"{self.min_command!r}, {self.max_command!r}")

    @property
    def gain(self) -> float:
        """Command per TCP speed [V / (m/s)]."""
        return self.nominal_command / self.nominal_speed

    def command(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Command [V] for TCP speeds v [m/s] and a mask of the clamped samples."""
        raw = self.gain * np.asarray(v, dtype=float)
        out = np.clip(raw, self.min_command, self.max_command)
        return out, out != raw

    def counts(self, command: np.ndarray) -> np.ndarray:
        """Integer AO counts of commands [V]."""
        return np.rint(np.asarray(command, dtype=float) * self.counts_per_volt).astype(int)


@dataclass(frozen=True, eq=False)
class PowerProfile:
    """TCP speed and laser command sampled in time.

    Attributes:
        t: (M,) time [s].
        v_tcp: (M,) TCP speed [m/s].
        command: (M,) analogue command [V].
        clamped: (M,) True where min/max clamps act.
    """

    t: np.ndarray
    v_tcp: np.ndarray
    command: np.ndarray
    clamped: np.ndarray

    @property
    def energy_per_length(self) -> np.ndarray:
        """(M,) command / speed [V s / m]; constant (= gain) where unclamped."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.command / self.v_tcp


def power_profile(t: np.ndarray, v_tcp: np.ndarray, power: PowerMap) -> PowerProfile:
    """Analogue command for a sampled TCP speed profile v_tcp(t) [m/s]."""
    command, clamped = power.command(v_tcp)
    return PowerProfile(t=np.asarray(t, float), v_tcp=np.asarray(v_tcp, float),
                        command=command, clamped=clamped)
