"""Natural modes of the gear-shaft system and the modal damping matrix (paper Sec. 4).

Reference configuration for the damping (choice, documented)
-------------------------------------------------------------
The paper uses one modal damping factor (0.03) for all modes without saying on which modes. Here
``C = M Phi diag(2 zeta omega_i) Phi^T M`` (Phi mass-normalised, so that ``Phi^T C Phi =
diag(2 zeta omega_i)``) is built on the modes of

    K_ref = K_shaft + K_mesh,mean + sum_j B_j^T sym(Kb_ref_j) B_j

with ``K_mesh,mean`` the mesh stiffness matrix averaged over one mesh period at the static load
(:func:`gear_fmu.modal.analyses.mean_mesh_stiffness`) and ``Kb_ref`` a reference bearing
stiffness supplied by the caller (the symmetric part of the bearings' static stiffness when it is
known, otherwise an isotropic spring). C is constant during a run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.system import GearShaftSystem

__all__ = [
    "Modes",
    "bearing_block_matrix",
    "bearing_stiffness_matrix",
    "mesh_dofs",
    "mesh_stiffness_matrix",
    "modal_damping_matrix",
    "mode_table",
    "natural_modes",
]

KINDS = ("bending", "torsion", "axial")


def bearing_block_matrix(system: GearShaftSystem, blocks, name: str = "bearing stiffness"
                         ) -> np.ndarray:
    """Full (n_dof, n_dof) matrix of one 2x2 block per bearing on its (u, v) DOFs, as given
    (not symmetrised).

    Parameters
    ----------
    system : GearShaftSystem
    blocks : float or array_like (nb, 2, 2)
        Isotropic value for every bearing, or one 2x2 block per bearing (global s, t; the
        layout's order): Kb [N/m] or Cb [N s/m].
    name : str
        For error messages.
    """
    nb = len(system.bearing_dofs)
    b = np.asarray(blocks, dtype=float)
    if b.ndim == 0:
        b = np.broadcast_to(b * np.eye(2), (nb, 2, 2))
    if b.shape != (nb, 2, 2):
        raise ValueError(f"{name} shape {b.shape} must be () or ({nb}, 2, 2) for {nb} bearings")
    if not np.all(np.isfinite(b)):
        raise ValueError(f"{name} has non-finite entries")
    out = np.zeros((system.n_dof, system.n_dof))
    for j in range(nb):
        idx = system.bearing_dofs[j]
        out[np.ix_(idx, idx)] += b[j]
    return out


def bearing_stiffness_matrix(system: GearShaftSystem, kb) -> np.ndarray:
    """Full (n_dof, n_dof) matrix of the bearing springs, the symmetric part of each 2x2 Kb
    (:func:`bearing_block_matrix` symmetrised).

    Parameters
    ----------
    system : GearShaftSystem
    kb : float or array_like (nb, 2, 2)
        Isotropic stiffness [N/m] for every bearing, or one 2x2 Kb per bearing (global s, t).
    """
    b = bearing_block_matrix(system, kb)
    return 0.5 * (b + b.T)


def mesh_dofs(system: GearShaftSystem, m: int) -> np.ndarray:
    """The 12 full DOFs of mesh m: the driver's node's six, then the driven gear's node's."""
    return np.concatenate([np.arange(6 * n, 6 * n + 6) for n in system.mesh_nodes[m]])


def mesh_stiffness_matrix(system: GearShaftSystem, k_meshes) -> np.ndarray:
    """Full (n_dof, n_dof) matrix of the meshes' stiffnesses, one (12, 12) per mesh on its
    gear nodes' DOFs (:func:`mesh_dofs`; the structure's frame), symmetric parts summed.
    ``k_meshes``: (n_meshes, 12, 12), or (12, 12) for a train of one mesh."""
    k = np.asarray(k_meshes, dtype=float)
    n_meshes = len(system.mesh_nodes)
    if k.ndim == 2:
        k = k[None]
    if k.shape != (n_meshes, 12, 12):
        raise ValueError(f"mesh stiffness shape {np.shape(k_meshes)} must be "
                         f"({n_meshes}, 12, 12) for {n_meshes} mesh(es)")
    out = np.zeros((system.n_dof, system.n_dof))
    for m in range(n_meshes):
        idx = mesh_dofs(system, m)
        out[np.ix_(idx, idx)] += 0.5 * (k[m] + k[m].T)
    return out


@dataclass
class Modes:
    """Natural modes, ascending.

    Attributes
    ----------
    omega : (n,) angular frequencies [rad/s] (negative round-off eigenvalues clipped to 0)
    shapes : (n_dof, n) full mode shapes, mass-normalised (zero on the clamped DOF)
    kinetic_fraction : (n, 3) share of the modal kinetic energy in bending / torsion / axial DOFs
        (exact partition: M has no coupling between DOF kinds)
    mesh_energy_fraction : (n,) share of the strain energy stored in the mesh
    kinds : list of str, type of each mode (see :func:`classify`)
    """

    omega: np.ndarray
    shapes: np.ndarray
    kinetic_fraction: np.ndarray
    mesh_energy_fraction: np.ndarray
    kinds: list

    @property
    def frequency_hz(self) -> np.ndarray:
        return self.omega / (2.0 * np.pi)


def classify(fractions: np.ndarray, dominant: float = 0.75) -> str:
    """Name a mode by its kinetic energy fractions (bending, torsion, axial).

    A single kind when its share is >= ``dominant``, else the two largest joined by '-'
    (largest first), e.g. ``'torsion-bending'`` for a coupled mesh mode.
    """
    order = np.argsort(fractions)[::-1]
    if fractions[order[0]] >= dominant:
        return KINDS[order[0]]
    return f"{KINDS[order[0]]}-{KINDS[order[1]]}"


@one_blas_thread
def natural_modes(
    system: GearShaftSystem, bearing_stiffness, mesh_stiffness=None, stiffness_extra=None
) -> Modes:
    """Undamped natural modes of ``K_shaft + K_mesh + K_bearings`` with mass M: the stiffness
    K0 of Eq. (20) when the bearings' Kb(X0) and the mean mesh stiffness are given.

    Parameters
    ----------
    system : GearShaftSystem
    bearing_stiffness : float or (nb, 2, 2)
        See :func:`bearing_stiffness_matrix` (symmetric part used).
    mesh_stiffness : (n_meshes, 12, 12) array, optional
        Each mesh's stiffness on its gear nodes' DOFs (e.g. the mean mesh stiffness,
        :func:`mesh_stiffness_matrix`); symmetric parts used.
    stiffness_extra : (n_dof, n_dof) array, optional
        Any further stiffness (full DOF numbering).
    """
    kfull = system.stiffness + bearing_stiffness_matrix(system, bearing_stiffness)
    kmesh = np.zeros_like(kfull)
    if mesh_stiffness is not None:
        kmesh = mesh_stiffness_matrix(system, mesh_stiffness)
    kfull = kfull + kmesh
    if stiffness_extra is not None:
        kfull = kfull + np.asarray(stiffness_extra, dtype=float)
    mr = system.reduce(system.mass)
    kr = system.reduce(kfull)
    lam, phi_r = scipy.linalg.eigh(kr, mr)
    omega = np.sqrt(np.clip(lam, 0.0, None))
    shapes = np.zeros((system.n_dof, lam.size))
    shapes[system.free] = phi_r
    kind = system.dof_kind()
    kin = np.empty((lam.size, 3))
    mphi = system.mass @ shapes
    for c in range(3):
        sel = kind == c
        kin[:, c] = np.einsum("ij,ij->j", shapes[sel], mphi[sel])
    kin /= kin.sum(axis=1, keepdims=True)
    strain = np.einsum("ij,ij->j", shapes, kfull @ shapes)
    smesh = np.einsum("ij,ij->j", shapes, kmesh @ shapes)
    with np.errstate(invalid="ignore", divide="ignore"):
        mesh_frac = np.where(strain > 0.0, smesh / strain, 0.0)
    kinds = [classify(f) for f in kin]
    return Modes(omega, shapes, kin, mesh_frac, kinds)


@one_blas_thread
def modal_damping_matrix(system: GearShaftSystem, modes: Modes, zeta: float) -> np.ndarray:
    """Modal damping ``C = M Phi diag(2 zeta omega_i) Phi^T M`` (full numbering) [N s/m]: the C
    of Eq. (9).

    Parameters
    ----------
    system : GearShaftSystem
    modes : Modes
        Modes of the reference configuration (module docstring), all of them.
    zeta : float
        Modal damping factor [-] (paper: 0.03), in [0, 1).
    """
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"modal damping factor zeta = {zeta!r} must lie in [0, 1)")
    mphi = system.mass @ modes.shapes
    c = (mphi * (2.0 * zeta * modes.omega)) @ mphi.T
    return 0.5 * (c + c.T)


def mode_table(modes: Modes, n_modes: int | None = None) -> str:
    """Text table of the modes: index, frequency [Hz], type, energy shares (for ``gsb modal``)."""
    n = modes.omega.size if n_modes is None else min(n_modes, modes.omega.size)
    lines = [f"{'mode':>4}  {'f [Hz]':>11}  {'type':<17} {'bend':>5} {'tors':>5} {'axial':>5} "
             f"{'mesh':>5}"]
    for i in range(n):
        b, t, a = modes.kinetic_fraction[i]
        lines.append(
            f"{i + 1:>4}  {modes.frequency_hz[i]:>11.2f}  {modes.kinds[i]:<17} {b:>5.2f} {t:>5.2f} "
            f"{a:>5.2f} {modes.mesh_energy_fraction[i]:>5.2f}"
        )
    return "\n".join(lines)
