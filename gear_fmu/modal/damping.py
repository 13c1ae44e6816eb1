"""The damping matrix C of Eq. (9): structural damping, mesh damping, drivetrain couplings.

``C = C_s + C_m + C_d`` (full DOF numbering, constant during a run), with

Structural damping C_s (``DampingModel.kind``)
    * ``"modal"`` (paper: one factor zeta = 0.03 for all modes):
      ``C_s = M Phi diag(2 zeta omega_i) Phi^T M`` (Phi mass-normalised, so that
      ``Phi^T C_s Phi = diag(2 zeta omega_i)``) on the modes of a reference stiffness, the
      ``basis``:

      - ``"bearings"`` (default): ``K_shaft + K_mesh,mean + sum_j B_j^T sym(Kb_j) B_j`` with the
        bearings' static film stiffness at X0 (the master passes it at the end of the static
        phase);
      - ``"structure"``: ``K_shaft + K_mesh,mean``, the shafts and the mesh alone (modes with
        zero frequency, such as the journals' rigid motions, get no damping).

    * ``"rayleigh"``: ``C_s = alpha M + beta (K_shaft + K_mesh,mean)``, with alpha [1/s] and
      beta [s] given, or from two frequencies f1 < f2 [Hz] and the ratio zeta:
      ``alpha = 2 zeta w1 w2 / (w1 + w2)``, ``beta = 2 zeta / (w1 + w2)`` (``w = 2 pi f``), so
      that a mode of K_shaft + K_mesh,mean at w has the ratio ``alpha / (2 w) + beta w / 2``,
      zeta at w1 and w2 and less in between.

Mesh damping C_m
    For each mesh, a viscous damper along the contact lines with the geometry of its mean
    stiffness: ``C_m = (c_m / k_m) K_mesh,mean`` (12 x 12 on its gear nodes' DOFs), with
    ``k_m = K_mesh,mean[theta1, theta1] / r_b1^2`` the mesh stiffness seen along the transverse
    line of action [N/m] and ``c_m`` [N s/m] given (``mesh_coefficient``) or from a ratio of
    the two-inertia mesh mode (``mesh_ratio``): ``c_m = 2 zeta_m sqrt(k_m m_e)``,
    ``m_e = 1 / (r_b1^2 / J1 + r_b2^2 / J2)`` with J the gear bodies' polar inertias.

Drivetrain couplings C_d
    The coupling dampers of the motor and the load (:mod:`gear_fmu.drivetrain`).

K_mesh,mean is a mesh's tangent averaged over one of its periods at the static load
(:func:`gear_fmu.modal.analyses.mean_mesh_stiffness`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.dofs import THETA
from gear_fmu.modal.modes import Modes, mesh_stiffness_matrix, modal_damping_matrix, natural_modes
from gear_fmu.system import gear_inertias

__all__ = ["BASES", "DAMPING_KINDS", "DampingModel", "damping_matrix", "mesh_damping_coefficient",
           "rayleigh_coefficients", "transverse_mesh_stiffness"]

DAMPING_KINDS = ("modal", "rayleigh")
BASES = ("bearings", "structure")


@dataclass(frozen=True)
class DampingModel:
    """The choice of damping (module docstring).

    Parameters
    ----------
    kind : str
        ``"modal"`` or ``"rayleigh"``.
    ratio : float
        zeta [-] of the modal damping, or of the Rayleigh damping at ``rayleigh_frequencies``.
    basis : str
        Modal damping reference: ``"bearings"`` or ``"structure"``.
    rayleigh_frequencies : (float, float)
        f1 < f2 [Hz] (both 0: use ``rayleigh_alpha``, ``rayleigh_beta``).
    rayleigh_alpha, rayleigh_beta : float
        Mass [1/s] and stiffness [s] coefficients.
    mesh_ratio : float
        zeta_m [-] of the two-inertia mesh mode (0: none).
    mesh_coefficient : float
        c_m [N s/m] (0: none; exclusive with ``mesh_ratio``).
    """

    kind: str = "modal"
    ratio: float = 0.03
    basis: str = "bearings"
    rayleigh_frequencies: tuple[float, float] = (0.0, 0.0)
    rayleigh_alpha: float = 0.0
    rayleigh_beta: float = 0.0
    mesh_ratio: float = 0.0
    mesh_coefficient: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in DAMPING_KINDS:
            raise ValueError(f"damping model {self.kind!r}: one of {', '.join(DAMPING_KINDS)}")
        if self.basis not in BASES:
            raise ValueError(f"damping basis {self.basis!r}: one of {', '.join(BASES)}")
        if not 0.0 <= self.ratio < 1.0:
            raise ValueError(f"damping ratio zeta = {self.ratio!r} must lie in [0, 1)")
        if not 0.0 <= self.mesh_ratio < 1.0:
            raise ValueError(f"mesh damping ratio = {self.mesh_ratio!r} must lie in [0, 1)")
        for name in ("rayleigh_alpha", "rayleigh_beta", "mesh_coefficient"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"{name} = {v!r} must be finite and >= 0")
        if self.mesh_ratio > 0.0 and self.mesh_coefficient > 0.0:
            raise ValueError(f"mesh damping: give a ratio ({self.mesh_ratio!r}) or a "
                             f"coefficient ({self.mesh_coefficient!r} N.s/m), not both")
        f1, f2 = self.rayleigh_frequencies
        if self.kind == "rayleigh":
            given = self.rayleigh_alpha > 0.0 or self.rayleigh_beta > 0.0
            if (f1, f2) != (0.0, 0.0):
                if given:
                    raise ValueError("Rayleigh damping: give rayleigh_frequencies (with the "
                                     "ratio) or rayleigh_alpha / rayleigh_beta, not both")
                if not 0.0 < f1 < f2:
                    raise ValueError(f"rayleigh_frequencies = [{f1!r}, {f2!r}] Hz: need "
                                     "0 < f1 < f2")
            elif not given:
                raise ValueError("Rayleigh damping needs rayleigh_frequencies [f1, f2] Hz or "
                                 "rayleigh_alpha / rayleigh_beta")

    @property
    def is_zero(self) -> bool:
        """No structural and no mesh damping."""
        structural = (self.ratio == 0.0 if self.kind == "modal"
                      else rayleigh_coefficients(self) == (0.0, 0.0))
        return structural and self.mesh_ratio == 0.0 and self.mesh_coefficient == 0.0


def rayleigh_coefficients(model: DampingModel) -> tuple[float, float]:
    """``(alpha [1/s], beta [s])`` of a Rayleigh model (module docstring)."""
    f1, f2 = model.rayleigh_frequencies
    if (f1, f2) == (0.0, 0.0):
        return model.rayleigh_alpha, model.rayleigh_beta
    w1, w2 = 2.0 * math.pi * f1, 2.0 * math.pi * f2
    return 2.0 * model.ratio * w1 * w2 / (w1 + w2), 2.0 * model.ratio / (w1 + w2)


def transverse_mesh_stiffness(k_mesh12, rb1: float) -> float:
    """``k_m = K_mesh[theta1, theta1] / r_b1^2`` [N/m]: the mesh stiffness seen along the
    transverse line of action (module docstring)."""
    return float(k_mesh12[THETA, THETA]) / rb1**2


def mesh_damping_coefficient(model: DampingModel, k_mesh12, base_radii, polar_inertias) -> float:
    """``c_m`` [N s/m] (module docstring) for one mesh's mean stiffness (12, 12)."""
    if model.mesh_coefficient > 0.0:
        return model.mesh_coefficient
    if model.mesh_ratio == 0.0:
        return 0.0
    rb1, rb2 = base_radii
    k_m = transverse_mesh_stiffness(k_mesh12, rb1)
    m_e = 1.0 / (rb1**2 / polar_inertias[0] + rb2**2 / polar_inertias[1])
    return 2.0 * model.mesh_ratio * math.sqrt(k_m * m_e)


def _mesh_polar_inertias(system) -> list[tuple[float, float]]:
    """The driver's and the driven gear's polar inertia of each mesh [kg m^2]."""
    lay = system.layout
    out = []
    for driver, driven in lay.drivers:
        pair = []
        for name in (driver, driven):
            g = lay.gear(name)
            pair.append(gear_inertias(g, lay.shaft(g.shaft).density)[1])
        out.append(tuple(pair))
    return out


@one_blas_thread
def damping_matrix(system, model: DampingModel, k_meshes, bearing_stiffness, base_radii
                   ) -> tuple[np.ndarray, Modes | None]:
    """``C = C_s + C_m + C_d`` [SI] (full numbering) and the modes C_s was built on (None for
    Rayleigh damping).

    Parameters
    ----------
    system : GearShaftSystem
    model : DampingModel
    k_meshes : (n_meshes, 12, 12) array or None
        Each mesh's mean stiffness (None only when no term needs it).
    bearing_stiffness : float or (nb, 2, 2)
        Kb of the ``"bearings"`` basis [N/m] (symmetric part used).
    base_radii : (n_meshes, 2) array or None
        r_b1, r_b2 of each mesh (driver first) [m] (None without mesh damping).
    """
    c = np.array(system.coupling_damping, copy=True)
    ref = None
    k_struct = system.stiffness
    if k_meshes is not None:
        k_meshes = np.asarray(k_meshes, dtype=float).reshape(-1, 12, 12)
        k_struct = k_struct + mesh_stiffness_matrix(system, k_meshes)
    if model.kind == "modal" and model.ratio > 0.0:
        kb = bearing_stiffness if model.basis == "bearings" else 0.0
        ref = natural_modes(system, kb, k_meshes)
        c += modal_damping_matrix(system, ref, model.ratio)
    elif model.kind == "rayleigh":
        alpha, beta = rayleigh_coefficients(model)
        c += alpha * system.mass + beta * k_struct
    if model.mesh_ratio or model.mesh_coefficient:
        inertias = _mesh_polar_inertias(system)
        for m, (k12, radii) in enumerate(zip(k_meshes, base_radii, strict=True)):
            cm = mesh_damping_coefficient(model, k12, radii, inertias[m])
            if cm > 0.0:
                k_m = transverse_mesh_stiffness(k12, radii[0])
                one = np.zeros_like(k_meshes)
                one[m] = k12
                c += (cm / k_m) * mesh_stiffness_matrix(system, one)
    return 0.5 * (c + c.T), ref
