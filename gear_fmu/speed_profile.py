"""The input shaft's speed as a function of time, and the rigid-body angle it drives.

A run at constant speed turns the input shaft at ``omega t``; a run-up, a run-down or any speed
history turns it at ``Omega(t)``, piecewise linear through points ``(t_k, Omega_k)`` and
constant after the last (the case's ``drive.speed_profile``: a ramp from ``drive.speed``, or a
table of times and speeds, :func:`fmu_src.units.parse_speed_profile`). The angle that drives
the meshes and the unbalances is the integral of the speed (closed form, a sum of trapezoids,
docs/equations.md "Run-ups"); the other shafts follow through their ratios.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

__all__ = ["SpeedProfile"]


@dataclass(frozen=True)
class SpeedProfile:
    """``Omega(t)`` [rad/s] of the input shaft (module docstring): linear between the points
    ``(times[k], speeds[k])``, ``times[0] = 0`` (the static solution's speed; later for one
    that continues another, :meth:`continued`), increasing, and ``speeds[-1]`` after the last.

    Examples
    --------
    >>> p = SpeedProfile.ramp(100.0, 300.0, t_start=1.0, duration=2.0)
    >>> [p.speed(t) for t in (0.5, 2.0, 4.0)], p.acceleration(2.0)
    ([100.0, 200.0, 300.0], 100.0)
    >>> p.angle(3.0)  # 100 rad/s for 1 s, then the ramp's mean 200 rad/s for 2 s
    500.0
    >>> SpeedProfile((0.0, 1.0, 3.0), (300.0, 400.0, 200.0)).angle(3.0)
    950.0
    """

    times: tuple
    speeds: tuple
    #: ``Theta(times[0])`` [rad] of a profile that continues another from ``times[0] > 0``
    #: (:meth:`continued`); None for one that starts at t = 0 (angle 0 there)
    start_angle: float | None = None
    _angles: tuple = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        times = tuple(float(t) for t in self.times)
        speeds = tuple(float(w) for w in self.speeds)
        if not times or len(times) != len(speeds):
            raise ValueError(f"times and speeds: one speed per time, got {len(times)} times "
                             f"and {len(speeds)} speeds")
        if times[0] != 0.0 and self.start_angle is None:
            raise ValueError(f"the first point is at t = {times[0]!r} s: a profile starts at "
                             f"t = 0 s (the static solution's speed)")
        if not (math.isfinite(times[0]) and times[0] >= 0.0):
            raise ValueError(f"the first point is at t = {times[0]!r} s: finite and >= 0")
        for k in range(1, len(times)):
            if not times[k] > times[k - 1]:
                raise ValueError(f"t = {times[k]!r} s after t = {times[k - 1]!r} s: the times "
                                 f"of a profile increase")
        for t, w in zip(times, speeds, strict=True):
            if not (math.isfinite(t) and math.isfinite(w) and w >= 0.0):
                raise ValueError(f"speed {w!r} rad/s at t = {t!r} s: finite and >= 0")
        angles = [0.0 if self.start_angle is None else float(self.start_angle)]  # trapezoids
        for k in range(1, len(times)):
            mean = 0.5 * (speeds[k - 1] + speeds[k])
            angles.append(angles[-1] + mean * (times[k] - times[k - 1]))
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "speeds", speeds)
        object.__setattr__(self, "_angles", tuple(angles))

    @classmethod
    def ramp(cls, omega0: float, omega1: float, t_start: float = 0.0,
             duration: float = 0.0) -> SpeedProfile:
        """``omega0`` [rad/s] until ``t_start`` [s], linear to ``omega1`` over ``duration``
        [s] (> 0 when the speeds differ), then ``omega1``."""
        if omega1 == omega0:
            return cls((0.0,), (omega0,))
        if not duration > 0.0:
            raise ValueError(f"a ramp from {omega0!r} to {omega1!r} rad/s needs a duration > "
                             f"0 s, not {duration!r}")
        if t_start == 0.0:
            return cls((0.0, duration), (omega0, omega1))
        return cls((0.0, t_start, t_start + duration), (omega0, omega0, omega1))

    def continued(self, t0: float, t1: float, speed: float) -> SpeedProfile:
        """This profile until ``t0`` [s], then linear to ``speed`` [rad/s] at ``t1 > t0`` [s]
        and ``speed`` after: as a profile that starts at ``t0`` with this one's speed and
        angle there (two points, whatever this one holds; a host's speed input,
        :class:`orchestrator.coupling.transmission.TransmissionSlave`).

        >>> p = SpeedProfile.ramp(100.0, 300.0, duration=2.0).continued(1.0, 2.0, 100.0)
        >>> p.times, p.speeds, p.angle(1.0), p.angle(2.0)
        ((1.0, 2.0), (200.0, 100.0), 150.0, 300.0)
        """
        if not t1 > t0:
            raise ValueError(f"a speed reached at t = {t1!r} s from t = {t0!r} s: later, "
                             f"please")
        return SpeedProfile((t0, t1), (self.speed(t0), speed), start_angle=self.angle(t0))

    @property
    def omega0(self) -> float:
        """The speed at t = 0 [rad/s]."""
        return self.speeds[0]

    @property
    def omega1(self) -> float:
        """The speed after the last point [rad/s]."""
        return self.speeds[-1]

    @property
    def varies(self) -> bool:
        """Whether the speed changes at all (False: a constant speed ``omega0``)."""
        return any(w != self.speeds[0] for w in self.speeds)

    @property
    def max_speed(self) -> float:
        """The highest speed the profile reaches [rad/s] (the time step's, for the mesh)."""
        return max(self.speeds)

    @property
    def min_speed(self) -> float:
        """The lowest speed the profile reaches [rad/s]."""
        return min(self.speeds)

    @property
    def shortest_change(self) -> float:
        """The shortest interval between two points whose speeds differ [s] (inf: none)."""
        return min((self.times[k] - self.times[k - 1] for k in range(1, len(self.times))
                    if self.speeds[k] != self.speeds[k - 1]), default=math.inf)

    @property
    def max_acceleration(self) -> float:
        """The largest ``|dOmega/dt|`` [rad/s^2]."""
        return max((abs(self.speeds[k] - self.speeds[k - 1]) / (self.times[k] - self.times[k - 1])
                    for k in range(1, len(self.times))), default=0.0)

    def _segment(self, t: float) -> int:
        """k with t in [times[k], times[k + 1]) (-1 before 0, the last index after the end)."""
        return bisect.bisect_right(self.times, t) - 1

    def speed(self, t: float) -> float:
        """``Omega(t)`` [rad/s]."""
        k = self._segment(t)
        if k < 0:
            return self.speeds[0]
        if k >= len(self.times) - 1:
            return self.speeds[-1]
        return self.speeds[k] + self._slope(k) * (t - self.times[k])

    def _slope(self, k: int) -> float:
        return (self.speeds[k + 1] - self.speeds[k]) / (self.times[k + 1] - self.times[k])

    def acceleration(self, t: float) -> float:
        """``dOmega/dt`` at t [rad/s^2]: the slope of the interval ``(t_k, t_k+1]`` holding t,
        0 up to the first point and after the last. At a point, the slope before it: a step's
        loads are those of its end (Newmark's ``F(t_n+1)``), and a step that ends on a ramp's
        last point is in the ramp (a profile continued over each communication step of a
        host, :meth:`continued`, ramps over its steps that way)."""
        k = bisect.bisect_left(self.times, t) - 1
        return self._slope(k) if 0 <= k < len(self.times) - 1 else 0.0

    def angle(self, t: float) -> float:
        """``integral_0^t Omega dt`` [rad]: the input shaft's rigid-body rotation since t = 0
        (for a profile that continues another, ``start_angle`` plus the integral from its
        first point)."""
        k = self._segment(t)
        if k < 0:
            return self._angles[0] + self.speeds[0] * (t - self.times[0])
        tau = t - self.times[k]
        if k >= len(self.times) - 1:
            return self._angles[-1] + self.speeds[-1] * tau
        return self._angles[k] + self.speeds[k] * tau + 0.5 * self._slope(k) * tau * tau

    def describe(self) -> str:
        """The points as text: ``"325 rad/s at 0 s, 400 rad/s at 0.1 s"``."""
        return ", ".join(f"{w:g} rad/s at {t:g} s" for t, w in zip(self.times, self.speeds,
                                                                 strict=True))
