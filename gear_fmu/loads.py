"""External loads on the gear-shaft structure (paper Sec. 3.1 and 4.1, Eq. 10).

* The input torque T acts on the torsion DOF of the pinion shaft's input end (or on the motor
  behind a coupling); the resisting torque is the reaction of the clamped output torsion DOF
  or, with a load at the output (:mod:`gear_fmu.drivetrain`), ``T z2 / z1`` on the load,
  the torque that balances T through the mesh (``T r_b2 / r_b1``).
* Mass unbalance, Eq. (10): a force of magnitude ``M e_mu omega^2`` turning with each shaft,
  applied at its gear node, with M the shaft plus gear mass. The pinion shaft turns about +z
  at omega, the gear shaft about -z at ``omega z1 / z2`` (:mod:`gear_fmu.mesh.geometry`).
* Gravity (optional): ``M g`` on every translational DOF.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from gear_fmu.dofs import DOF_PER_NODE, U, V

__all__ = ["StructureLoads", "constant_loads", "shaft_speeds", "unbalance_amplitudes",
           "unbalance_force", "unbalance_into"]


@dataclass(frozen=True)
class StructureLoads:
    """External loads and kinematics (paper Sec. 3.1 and 4.1).

    Parameters
    ----------
    torque : float
        Input torque T on the pinion shaft [N m] (> 0 drives the pinion about +z).
    input_speed : float
        Pinion speed omega [rad/s] (>= 0); the gear turns at omega z1/z2 about -z.
    unbalance : (float, float)
        e_mu of the pinion shaft and of the gear shaft [m] (Eq. 10), applied at the gear nodes
        with M = shaft + gear mass.
    gravity : (float, float) or None
        Gravity acceleration components (g_s, g_t) [m/s^2]; None = no gravity.
    pinion_angle0 : float
        Rigid-body pinion angle at t = 0 [rad].
    """

    torque: float = 220.0
    input_speed: float = 325.0
    unbalance: tuple[float, float] = (0.0, 0.0)
    gravity: tuple[float, float] | None = None
    pinion_angle0: float = 0.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.torque):
            raise ValueError(f"torque = {self.torque!r} N m is not finite")
        if not (math.isfinite(self.input_speed) and self.input_speed >= 0.0):
            raise ValueError(f"input_speed = {self.input_speed!r} rad/s must be finite and >= 0")
        if len(self.unbalance) != 2 or not all(
            math.isfinite(e) and e >= 0.0 for e in self.unbalance
        ):
            raise ValueError(f"unbalance = {self.unbalance!r} m: two finite values >= 0")


def shaft_speeds(loads: StructureLoads, teeth) -> tuple[float, float]:
    """Speed magnitudes of the pinion and gear shafts [rad/s]: omega and omega z1 / z2."""
    z1, z2 = teeth
    return loads.input_speed, loads.input_speed * z1 / z2


def unbalance_amplitudes(shaft_masses, unbalance, speeds) -> list[float]:
    """``M e_mu omega^2`` of each shaft [N] (Eq. 10)."""
    return [shaft_masses[i] * unbalance[i] * speeds[i] ** 2 for i in range(2)]


def unbalance_force(amplitudes, speeds, t: float) -> np.ndarray:
    """Eq. (10) at time t [s]: ``[F_s, F_t]`` at the pinion node then at the gear node [N].

    The pinion shaft turns about +z (``omega t``), the gear shaft about -z (``-omega_2 t``).
    """
    out = np.empty(4)
    unbalance_into(np.array([*amplitudes, *speeds], dtype=float), t, out)
    return out


@njit(cache=True)
def unbalance_into(coef, t, out):
    """:func:`unbalance_force` into ``out`` (4,), from ``coef`` = [M1 e1 omega^2, M2 e2
    omega_2^2, omega, omega_2] (amplitudes [N], speeds [rad/s]): the compiled step's form."""
    a1 = coef[0]
    a2 = coef[1]
    w1 = coef[2]
    w2 = coef[3]
    out[0] = a1 * math.cos(w1 * t)
    out[1] = a1 * math.sin(w1 * t)
    out[2] = a2 * math.cos(w2 * t)
    out[3] = -a2 * math.sin(w2 * t)


def constant_loads(system, loads: StructureLoads) -> np.ndarray:
    """The time-invariant part of F(t) on the full DOF numbering [N, N m]: the input torque on
    the pinion shaft's input torsion DOF (or the motor), the resisting torque ``T z2 / z1`` on
    the load when the output is not clamped and, if set, gravity ``M g``."""
    f = np.zeros(system.n_dof)
    f[system.torque_dof] += loads.torque
    if system.load_dof is not None:
        # the gear turns about -z: the mesh drives its torsion DOF negative, the load resists
        f[system.load_dof] += loads.torque * system.teeth[1] / system.teeth[0]
    if loads.gravity is not None:
        g = np.zeros(system.n_dof)
        nodes = np.arange(system.n_nodes)  # the drivetrain DOFs are rotations: no weight
        g[DOF_PER_NODE * nodes + U] = loads.gravity[0]
        g[DOF_PER_NODE * nodes + V] = loads.gravity[1]
        f += system.mass @ g
    return f
