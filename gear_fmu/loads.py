"""External loads on the gear-shaft structure (paper Sec. 3.1 and 4.1, Eq. 10).

* The input torque T acts on the torsion DOF of the input position (or on the motor behind a
  coupling); the resisting torque is the reaction of the clamped output torsion DOF or, with a
  load at the output (:mod:`gear_fmu.drivetrain`), ``T omega_in / omega_out`` on the load, the
  torque that balances T through the meshes (for one stage ``T z2 / z1 = T r_b2 / r_b1``).
* Mass unbalance, Eq. (10): a force of magnitude ``M e_mu omega^2`` turning with its shaft,
  applied at the body's node (:class:`gear_fmu.system.Unbalances`: a gear or disc, M its own
  mass or that of its shaft with all it carries). A shaft turns about +z or -z as the gear graph
  says (:attr:`gear_fmu.layout.Layout.directions`): the input shaft about +z at omega, the gear
  of the paper's pair about -z at ``omega z1 / z2``.
* Gravity (optional): ``M g`` on every translational DOF.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from gear_fmu.dofs import DOF_PER_NODE, U, V

__all__ = ["StructureLoads", "accelerated_unbalance_coefficients", "bearing_ratios",
           "constant_loads", "shaft_speeds", "unbalance_coefficients",
           "unbalance_force", "unbalance_into"]


@dataclass(frozen=True)
class StructureLoads:
    """External loads and kinematics (paper Sec. 3.1 and 4.1).

    Parameters
    ----------
    torque : float
        Input torque T [N m] (> 0 drives the input shaft about +z).
    input_speed : float
        Speed omega of the input shaft [rad/s] (>= 0); the other shafts turn at omega times
        their ratio (:attr:`gear_fmu.layout.Layout.ratios`).
    gravity : (float, float) or None
        Gravity acceleration components (g_s, g_t) [m/s^2]; None = no gravity.
    input_angle0 : float
        Rigid-body angle of the input shaft at t = 0 [rad].
    profile : gear_fmu.speed_profile.SpeedProfile or None
        The input speed against time in a run-up or run-down (its ``omega0`` is
        ``input_speed``, the static solution's, unless it continues from a later time:
        :meth:`gear_fmu.structure.Structure.follow_speed`); None: ``input_speed`` throughout.
    """

    torque: float = 220.0
    input_speed: float = 325.0
    gravity: tuple[float, float] | None = None
    input_angle0: float = 0.0
    profile: object = None

    def __post_init__(self) -> None:
        if not math.isfinite(self.torque):
            raise ValueError(f"torque = {self.torque!r} N m is not finite")
        if not (math.isfinite(self.input_speed) and self.input_speed >= 0.0):
            raise ValueError(f"input_speed = {self.input_speed!r} rad/s must be finite and >= 0")
        if (self.profile is not None and self.profile.times[0] == 0.0
                and self.profile.omega0 != self.input_speed):
            raise ValueError(f"the speed profile starts at {self.profile.omega0!r} rad/s, not at "
                             f"input_speed = {self.input_speed!r} rad/s")


def shaft_speeds(layout, input_speed: float) -> np.ndarray:
    """Signed speed of every shaft about +z [rad/s] at the input speed ``input_speed``
    (:attr:`gear_fmu.layout.Layout.ratios` and ``directions``)."""
    return input_speed * layout.ratios * layout.directions


def bearing_ratios(layout) -> np.ndarray:
    """(nb,) the speed magnitude of each bearing's shaft per unit input speed, in the layout's
    bearing order: what a run-up's bearings turn at, times the input speed."""
    ratios = np.abs(layout.ratios * layout.directions)
    return np.array([ratios[layout.shaft_index[b.shaft]] for b in layout.bearings])


def unbalance_coefficients(unbalances, speeds) -> np.ndarray:
    """(nu, 3) ``[M e_mu omega^2 [N], signed omega [rad/s], phase [rad]]`` of each unbalance
    (:class:`gear_fmu.system.Unbalances`) with the shafts' signed ``speeds`` (Eq. 10): what
    :func:`unbalance_into` turns into forces."""
    w = np.asarray(speeds, dtype=float)[unbalances.shaft]
    return np.ascontiguousarray(np.column_stack([unbalances.me * w * w, w, unbalances.phase]))


def accelerated_unbalance_coefficients(unbalances, ratios, profile, t: float) -> np.ndarray:
    """:func:`unbalance_coefficients` of a run-up at time t [s] (Eq. 10 with the angular
    acceleration, docs/equations.md "Run-ups"): each unbalance ``M e_mu`` at the shaft angle
    ``phi = s Theta(t) + phase`` (``Theta`` the input angle of ``profile``,
    :class:`gear_fmu.speed_profile.SpeedProfile`; ``s`` the shaft's signed ``ratios``) pulls
    its node with ``M e_mu (phi'^2 cos phi + phi'' sin phi, phi'^2 sin phi - phi'' cos phi)``,
    i.e. ``A (cos(phi - delta), sin(phi - delta))`` with ``A = M e_mu sqrt(phi'^4 +
    phi''^2)``, ``delta = atan2(phi'', phi'^2)``: coefficients whose angle ``omega t + c`` is
    ``phi(t) - delta`` at t, turning at ``omega = phi'(t)`` (within a step, its sub-steps
    take that rate: an angle off by ``phi'' h^2 / 2`` at most)."""
    s = np.asarray(ratios, dtype=float)[unbalances.shaft]
    w, acc = s * profile.speed(t), s * profile.acceleration(t)
    phi = s * profile.angle(t) + unbalances.phase
    delta = np.arctan2(acc, w * w)
    amplitude = unbalances.me * np.hypot(w * w, acc)
    return np.ascontiguousarray(np.column_stack([amplitude, w, phi - delta - w * t]))


def unbalance_force(coef, t: float) -> np.ndarray:
    """Eq. (10) at time t [s]: ``[F_s, F_t]`` of each unbalance (nu, 2) [N]
    (:func:`unbalance_coefficients`)."""
    out = np.empty((len(coef), 2))
    unbalance_into(np.asarray(coef, dtype=float), t, out)
    return out


@njit(cache=True)
def unbalance_into(coef, t, out):
    """:func:`unbalance_force` into ``out`` (nu, 2): the force of amplitude ``coef[i, 0]``
    turning at the signed speed ``coef[i, 1]`` from the angle ``coef[i, 2]``,
    ``A (cos(omega t + phase), sin(omega t + phase))``: the compiled step's form."""
    for i in range(coef.shape[0]):
        angle = coef[i, 1] * t + coef[i, 2]
        out[i, 0] = coef[i, 0] * math.cos(angle)
        out[i, 1] = coef[i, 0] * math.sin(angle)


def constant_loads(system, loads: StructureLoads) -> np.ndarray:
    """The time-invariant part of F(t) on the full DOF numbering [N, N m]: the input torque on
    the input torsion DOF (or the motor), the resisting torque on the load when the output is
    not clamped and, if set, gravity ``M g``."""
    f = np.zeros(system.n_dof)
    f[system.torque_dof] += loads.torque
    if system.load_dof is not None:
        # the output shaft turns as its direction says: the meshes drive its torsion DOF that
        # way, the load resists with the torque that balances T through the ratio
        lay = system.layout
        out = lay.shaft_index[lay.drive.output_shaft]
        f[system.load_dof] -= lay.directions[out] * loads.torque / lay.ratios[out]
    if loads.gravity is not None:
        g = np.zeros(system.n_dof)
        nodes = np.arange(system.n_nodes)  # the drivetrain DOFs are rotations: no weight
        g[DOF_PER_NODE * nodes + U] = loads.gravity[0]
        g[DOF_PER_NODE * nodes + V] = loads.gravity[1]
        f += system.mass @ g
    return f
