"""Drivetrain boundary conditions in torsion: the motor at the input end, the load at the output.

The paper leaves the drivetrain unstated; its defaults here (:class:`Drivetrain` ``()``) are the
conditions the reproduction used from the start: the input end of the pinion shaft free, with
the input torque T on its torsion DOF and no motor inertia; the output end of the gear shaft
clamped in torsion (a load of infinite inertia, the resisting torque being the reaction).

Input end
---------
``motor_inertia`` J_m [kg m^2] > 0 adds a motor:

* rigidly (``motor_coupling_stiffness`` 0): J_m on the input torsion DOF theta_in;
* behind a coupling of stiffness k_m [N m/rad] and damping c_m [N m s/rad]: a DOF theta_m
  with inertia J_m, joined to theta_in by ``k_m (theta_m - theta_in)`` and
  ``c_m (theta_m_dot - theta_in_dot)``; the input torque T then acts on theta_m.

Output end
----------
``output_end = "clamped"`` (default) or ``"load"``: a load inertia J_L [kg m^2] on the output
torsion DOF theta_out, rigidly (``load_coupling_stiffness`` 0) or through a coupling (k_L, c_L)
to a DOF theta_L. The resisting torque ``T z2 / z1`` (the torque that balances T through the
mesh, T r_b2 / r_b1) acts on the load (theta_L, or theta_out for a rigid load). The torsional
rigid-body rotation of the whole train is then free: its mean is the imposed rigid rotation
(pinion angle ``omega t``) and the theta DOFs are the elastic rotations on top of it, as with a
clamped output. The static solution fixes that rotation by a spring on the load DOF, which
carries no load because T and the resisting torque balance exactly
(``GearShaftSystem.static_ground``, :mod:`gear_fmu.system`).

The extra DOFs (theta_m, theta_L) are appended after the node DOFs of
:class:`gear_fmu.system.GearShaftSystem` (torsion DOFs without a node).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["OUTPUT_ENDS", "Drivetrain"]

OUTPUT_ENDS = ("clamped", "load")


@dataclass(frozen=True)
class Drivetrain:
    """Motor and load in torsion (module docstring). Inertias [kg m^2], coupling stiffnesses
    [N m/rad] (0: rigid attachment), coupling dampings [N m s/rad]."""

    motor_inertia: float = 0.0
    motor_coupling_stiffness: float = 0.0
    motor_coupling_damping: float = 0.0
    output_end: str = "clamped"
    load_inertia: float = 0.0
    load_coupling_stiffness: float = 0.0
    load_coupling_damping: float = 0.0

    def __post_init__(self) -> None:
        for name in ("motor_inertia", "motor_coupling_stiffness", "motor_coupling_damping",
                     "load_inertia", "load_coupling_stiffness", "load_coupling_damping"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"drivetrain.{name} = {v!r} must be finite and >= 0")
        if self.output_end not in OUTPUT_ENDS:
            raise ValueError(f"drivetrain.output_end = {self.output_end!r}: one of "
                             f"{', '.join(OUTPUT_ENDS)}")
        if self.output_end == "clamped" and (self.load_inertia or self.load_coupling_stiffness
                                             or self.load_coupling_damping):
            raise ValueError("drivetrain.load_* is set but drivetrain.output_end = 'clamped' "
                             "(set output_end = 'load')")
        for end in ("motor", "load"):  # a coupling needs its inertia, a damper its coupling
            inertia, stiffness, damping = (getattr(self, f"{end}_{k}") for k in (
                "inertia", "coupling_stiffness", "coupling_damping"))
            if stiffness > 0.0 and inertia == 0.0:
                raise ValueError(f"drivetrain.{end}_coupling_stiffness = {stiffness!r} "
                                 f"N.m/rad needs a {end}: drivetrain.{end}_inertia must be > 0")
            if damping > 0.0 and stiffness == 0.0:
                raise ValueError(f"drivetrain.{end}_coupling_damping = {damping!r} N.m.s/rad "
                                 f"needs a coupling: drivetrain.{end}_coupling_stiffness must "
                                 "be > 0")

    @property
    def motor_dof(self) -> bool:
        """A separate motor DOF theta_m (motor behind a coupling)."""
        return self.motor_coupling_stiffness > 0.0

    @property
    def load_dof(self) -> bool:
        """A separate load DOF theta_L (load behind a coupling)."""
        return self.output_end == "load" and self.load_coupling_stiffness > 0.0

    @property
    def clamped(self) -> bool:
        """The output torsion DOF is clamped."""
        return self.output_end == "clamped"

    @property
    def n_extra(self) -> int:
        """DOFs added after the node DOFs."""
        return int(self.motor_dof) + int(self.load_dof)
