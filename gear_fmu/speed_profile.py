"""The input shaft's speed as a function of time, and the rigid-body angle it drives.

A run at constant speed turns the input shaft at ``omega t``; a run-up (or run-down) turns it
at ``Omega(t)``: ``omega0`` until ``t_start``, then linear to ``omega1`` over ``duration``, then
``omega1`` (the case's ``drive.speed_profile``, :func:`fmu_src.units.parse_speed_profile`).
The angle that drives the meshes and the unbalances is the integral of the speed (closed
form, docs/equations.md "Run-ups"); the other shafts follow through their ratios.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SpeedProfile"]


@dataclass(frozen=True)
class SpeedProfile:
    """``Omega(t)`` [rad/s] of the input shaft (module docstring).

    Parameters
    ----------
    omega0 : float
        Speed [rad/s] from t = 0 to ``t_start``, the speed of the static solution.
    omega1 : float
        Speed [rad/s] from ``t_start + duration`` on.
    t_start : float
        Start of the ramp [s].
    duration : float
        Length of the ramp [s] (> 0 when the speeds differ).

    Examples
    --------
    >>> p = SpeedProfile(100.0, 300.0, t_start=1.0, duration=2.0)
    >>> [p.speed(t) for t in (0.5, 2.0, 4.0)], p.acceleration(2.0)
    ([100.0, 200.0, 300.0], 100.0)
    >>> p.angle(3.0)  # 100 rad/s for 1 s, then the ramp's mean 200 rad/s for 2 s
    500.0
    """

    omega0: float
    omega1: float
    t_start: float = 0.0
    duration: float = 0.0

    def __post_init__(self) -> None:
        for name in ("omega0", "omega1", "t_start", "duration"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{name} = {value!r} must be finite and >= 0")
        if self.omega1 != self.omega0 and self.duration <= 0.0:
            raise ValueError(f"a ramp from {self.omega0!r} to {self.omega1!r} rad/s needs a "
                             f"duration > 0 s, not {self.duration!r}")

    @property
    def varies(self) -> bool:
        """Whether the speed changes at all (False: a constant speed ``omega0``)."""
        return self.omega1 != self.omega0

    @property
    def t_end(self) -> float:
        """End of the ramp [s]."""
        return self.t_start + self.duration

    @property
    def ramp_acceleration(self) -> float:
        """Angular acceleration during the ramp [rad/s^2] (0 without one)."""
        return (self.omega1 - self.omega0) / self.duration if self.varies else 0.0

    @property
    def max_speed(self) -> float:
        """The highest speed the profile reaches [rad/s] (the time step's, for the mesh)."""
        return max(self.omega0, self.omega1)

    def speed(self, t: float) -> float:
        """``Omega(t)`` [rad/s]."""
        if not self.varies or t <= self.t_start:
            return self.omega0
        if t >= self.t_end:
            return self.omega1
        return self.omega0 + self.ramp_acceleration * (t - self.t_start)

    def acceleration(self, t: float) -> float:
        """``dOmega/dt`` at t [rad/s^2]: the ramp's on ``[t_start, t_end)``, else 0."""
        return self.ramp_acceleration if self.t_start <= t < self.t_end else 0.0

    def angle(self, t: float) -> float:
        """``integral_0^t Omega dt`` [rad]: the input shaft's rigid-body rotation since t = 0."""
        w0, ts = self.omega0, self.t_start
        if not self.varies or t <= ts:
            return w0 * t
        if t <= self.t_end:
            tau = t - ts
            return w0 * t + 0.5 * self.ramp_acceleration * tau * tau
        return w0 * ts + 0.5 * (w0 + self.omega1) * self.duration + self.omega1 * (t - self.t_end)
