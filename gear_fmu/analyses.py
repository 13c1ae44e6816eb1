"""Quasi-static analyses of a :class:`gear_fmu.structure.Structure` (no dynamics).

Each analysis runs static solutions under the constant loads (torque, gravity) with given
bearing springs and restores the structure's state afterwards:

* :func:`mean_mesh_stiffness`: the mesh tangent averaged over one mesh period;
* :func:`quasi_static`: transmission error, mesh load and journal positions against the pinion
  angle (the loaded transmission-error sweep);
* :func:`modes`: natural modes with the mean mesh stiffness (``gsb modal``);
* :func:`reference_damping`: the modal damping matrix on the modes of the reference
  configuration (:mod:`gear_fmu.modal`);
* :func:`support_loads`: loads on stiff supports, the master's first guess of X0.
"""

from __future__ import annotations

import math

import numpy as np

from .modal import modal_damping_matrix, natural_modes

__all__ = ["mean_mesh_stiffness", "modes", "quasi_static", "reference_damping", "support_loads"]

#: stiffness of the "stiff supports" of :func:`support_loads` [N/m]
STIFF_SUPPORT = 1e12


def _springs(st, bearing_stiffness):
    """Zero F0 and (4, 2, 2) Kb from an isotropic value [N/m] or a (4, 2, 2) array."""
    kb = np.asarray(bearing_stiffness, dtype=float)
    if kb.ndim == 0:
        kb = np.broadcast_to(kb * np.eye(2), (4, 2, 2)).copy()
    f0, kb, _ = st.check_laws(np.zeros((4, 2)), kb, np.zeros((4, 2, 2)))
    return f0, kb


def mean_mesh_stiffness(st, bearing_stiffness=1e8, n_angles: int = 16) -> np.ndarray:
    """Mesh stiffness (12, 12) averaged over one mesh period of static solutions.

    Static solutions under the constant loads with isotropic or (4, 2, 2) bearing springs at
    ``n_angles`` pinion angles over one base pitch; the state is restored afterwards.
    """
    f0, kb = _springs(st, bearing_stiffness)
    saved = st.get_state()
    acc = np.zeros((12, 12))
    try:
        for i in range(n_angles):
            angle = st.pinion_angle(st.t) + 2.0 * math.pi / st.system.teeth[0] * (
                i / n_angles)
            st.static_at(f0, kb, angle)
            acc += st.mesh_state.stiffness
    finally:
        st.set_state(saved)
    return acc / n_angles


def quasi_static(st, angles, bearing_stiffness=1e8) -> dict:
    """Static solutions under the constant loads at given pinion angles (no dynamics).

    Parameters
    ----------
    st : Structure
    angles : array_like
        Pinion angles [rad].
    bearing_stiffness : float or (4, 2, 2)
        Isotropic [N/m] or per-bearing stiffness of the supports (global frame).

    Returns
    -------
    dict of arrays over the angles: ``transmission_error`` [m] (r_b1 theta1 + r_b2 theta2),
    ``mesh_load`` [N], ``slice_load`` (n, n_slices_total) [N], ``journal`` (n, 4, 2) [m].
    The state is restored afterwards.
    """
    f0, kb = _springs(st, bearing_stiffness)
    saved = st.get_state()
    out = {"transmission_error": [], "mesh_load": [], "slice_load": [], "journal": []}
    try:
        for angle in np.asarray(angles, dtype=float):
            st.static_at(f0, kb, float(angle))
            ms = st.mesh_state
            out["transmission_error"].append(ms.transmission_error)
            out["mesh_load"].append(ms.total_load)
            out["slice_load"].append(np.array(ms.load, copy=True))
            out["journal"].append(st.journal_states()[:, :2].copy())
    finally:
        st.set_state(saved)
    return {k: np.array(v) for k, v in out.items()}


def modes(st, bearing_stiffness=1e8, n_angles: int = 16):
    """Natural modes with the mean mesh stiffness at the static load (for ``gsb modal``): the
    undamped modes of K0 of Eq. (20).

    ``bearing_stiffness``: isotropic [N/m] or (4, 2, 2) (symmetric part used). Returns
    :class:`gear_fmu.modal.Modes`; format with :func:`gear_fmu.modal.mode_table`.
    """
    k_mesh = mean_mesh_stiffness(st, bearing_stiffness, n_angles)
    return natural_modes(st.system, bearing_stiffness, k_mesh)


def reference_damping(st, zeta: float, bearing_stiffness):
    """Modal damping ``C`` (full numbering) on the modes of the reference configuration
    (:mod:`gear_fmu.modal`): shafts, the mean mesh stiffness at the static load with these
    bearings, and the bearing stiffness (isotropic [N/m] or (4, 2, 2), symmetric part).

    Returns ``(C, modes, mean mesh stiffness)``; C is zero (and the others None) for zeta 0.
    """
    system = st.system
    if zeta == 0.0:
        return np.zeros((system.n_dof, system.n_dof)), None, None
    k_mesh = mean_mesh_stiffness(st, bearing_stiffness)
    ref = natural_modes(system, bearing_stiffness, k_mesh)
    return modal_damping_matrix(system, ref, zeta), ref, k_mesh


def support_loads(st) -> np.ndarray:
    """(4, 2) static loads of the structure on stiff bearings (1e12 N/m) [N], global frame."""
    saved = st.get_state()
    kb = np.broadcast_to(STIFF_SUPPORT * np.eye(2), (4, 2, 2)).copy()
    try:
        st.static(np.zeros((4, 2)), kb, None)
        loads = np.einsum("bij,bj->bi", kb, st.journal_states()[:, :2])
    finally:
        st.set_state(saved)
    return loads
