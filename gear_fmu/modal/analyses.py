"""Quasi-static analyses of a :class:`gear_fmu.structure.Structure` (no dynamics).

Each analysis runs static solutions under the constant loads (torque, gravity) with given
bearing springs and restores the structure's state afterwards:

* :func:`mean_mesh_stiffness`: each mesh's tangent averaged over one of its periods at equally
  spaced angles (the modal damping reference);
* :func:`exact_mean_mesh_stiffness`: the same mean integrated piecewise between the contact
  events (Gauss-Legendre), and :func:`line_of_action_stiffness`, its scalar value;
* :func:`quasi_static`: transmission errors, mesh loads and journal positions against the
  input angle (the loaded transmission-error sweep);
* :func:`modes`: natural modes with the exact mean mesh stiffness (``gsb modal``);
* :func:`damped`: damped modes of the linearised system, Eq. (20) with C0 = C + Cb(X0);
* :func:`reference_damping`: the modal damping matrix on the modes of the reference
  configuration (:mod:`gear_fmu.modal.modes`);
* :func:`support_loads`: loads on stiff supports, the master's first guess of X0.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from bearing_fmu.blas_threads import one_blas_thread
from gear_fmu.modal.damped_modes import damped_modes
from gear_fmu.modal.modes import natural_modes

__all__ = ["damped", "exact_mean_mesh_stiffness", "line_of_action_stiffness",
           "mean_mesh_stiffness", "modes", "quasi_static", "reference_damping", "support_loads"]

#: stiffness of the "stiff supports" of :func:`support_loads` [N/m]
STIFF_SUPPORT = 1e12


def _springs(st, bearing_stiffness):
    """Zero F0 and (nb, 2, 2) Kb from an isotropic value [N/m] or an (nb, 2, 2) array."""
    kb = np.asarray(bearing_stiffness, dtype=float)
    if kb.ndim == 0:
        kb = np.broadcast_to(kb * np.eye(2), (st.nb, 2, 2)).copy()
    f0, kb, _ = st.check_laws(np.zeros((st.nb, 2)), kb, np.zeros((st.nb, 2, 2)))
    return f0, kb


def _mesh_turn(st, m: int) -> tuple[float, float]:
    """``(input angle at t [rad], input angle per pinion angle of mesh m [-])``: one period of
    mesh m is ``2 pi / z_driver`` of its pinion, that over its ratio of the input shaft."""
    return st.input_angle(st.t), 1.0 / float(st.mesh_angles(1.0)[m])


@one_blas_thread
def mean_mesh_stiffness(st, bearing_stiffness=1e8, n_angles: int = 16) -> np.ndarray:
    """Each mesh's stiffness (n_meshes, 12, 12) averaged over one of its periods of static
    solutions.

    For mesh m, static solutions under the constant loads with isotropic or (nb, 2, 2)
    bearing springs at ``n_angles`` pinion angles of m over one of its base pitches (the
    other meshes turning with the train); the state is restored afterwards.
    """
    f0, kb = _springs(st, bearing_stiffness)
    saved = st.get_state()
    acc = np.zeros((len(st.meshes), 12, 12))
    try:
        for m, mesh in enumerate(st.meshes):
            a0, per = _mesh_turn(st, m)
            for i in range(n_angles):
                st.static_at(f0, kb, a0 + per * 2.0 * math.pi / mesh.pair.teeth[0] * (
                    i / n_angles))
                acc[m] += st.mesh_states[m].stiffness
    finally:
        st.set_state(saved)
    return acc / n_angles


@one_blas_thread
def quasi_static(st, input_angles, bearing_stiffness=1e8) -> dict:
    """Static solutions under the constant loads at given input-shaft angles (no dynamics).

    Parameters
    ----------
    st : Structure
    input_angles : array_like
        Rigid-body angles of the input shaft [rad] (the pinion's, for the paper's pair).
    bearing_stiffness : float or (nb, 2, 2)
        Isotropic [N/m] or per-bearing stiffness of the supports (global frame).

    Returns
    -------
    dict of arrays over the angles: ``transmission_error`` (n, n_meshes) [m] (r_b1 theta1 +
    r_b2 theta2 of each mesh), ``mesh_load`` (n, n_meshes) [N], ``slice_load`` (a list per
    mesh of (n, slices) arrays) [N], ``journal`` (n, nb, 2) [m]. The state is restored
    afterwards.
    """
    f0, kb = _springs(st, bearing_stiffness)
    saved = st.get_state()
    out = {"transmission_error": [], "mesh_load": [], "slice_load": [], "journal": []}
    try:
        for angle in np.asarray(input_angles, dtype=float):
            st.static_at(f0, kb, float(angle))
            states = st.mesh_states
            out["transmission_error"].append([ms.transmission_error for ms in states])
            out["mesh_load"].append([ms.total_load for ms in states])
            out["slice_load"].append([np.array(ms.load, copy=True) for ms in states])
            out["journal"].append(st.journal_states()[:, :2].copy())
    finally:
        st.set_state(saved)
    slices = [np.array([row[m] for row in out["slice_load"]]) for m in range(len(st.meshes))]
    return {"transmission_error": np.array(out["transmission_error"]),
            "mesh_load": np.array(out["mesh_load"]), "slice_load": slices,
            "journal": np.array(out["journal"])}


@one_blas_thread
def exact_mean_mesh_stiffness(st, bearing_stiffness=1e8, n_gauss: int = 8) -> np.ndarray:
    """Each mesh's stiffness (n_meshes, 12, 12) averaged over one of its periods, integrated
    between its contact events.

    One period of mesh m, ``[a0, a0 + 2 pi / z1]`` of its pinion angle from the present one, is
    split at its kinematic contact events (``mesh.event_angles``: a slice entering or leaving
    the path of contact, where the quasi-static stiffness jumps). On each event-free
    sub-interval the stiffness of m's static solution under the constant loads (as in
    :func:`mean_mesh_stiffness`, the other meshes turning with the train) is integrated by
    ``n_gauss``-point Gauss-Legendre, whose nodes lie strictly inside the sub-interval; the
    state is restored afterwards.

    Accuracy: without tooth deviations every slice on the path is in contact and the stiffness
    is smooth between events except for the kinks of the linearly interpolated tooth stiffness
    table (:class:`gear_fmu.mesh.element.MeshElement`); on the spur case of the paper 8 and 32
    points agree to 1.5e-6 (relative), where 16 equally spaced angles are 1.4 % off. A contact
    lost inside a sub-interval (tip relief at a light load), or an event of another mesh, is
    not a split point.

    Parameters
    ----------
    st : Structure
    bearing_stiffness : float or (nb, 2, 2)
        Isotropic [N/m] or per-bearing stiffness of the supports (global frame).
    n_gauss : int
        Gauss-Legendre points per event-free sub-interval, >= 1.

    Returns
    -------
    (n_meshes, 12, 12) array
        Mean of each mesh's K_gear over its period [N/m, N, N m] (its gear nodes' DOFs,
        driver first, the structure's frame).
    """
    if int(n_gauss) != n_gauss or n_gauss < 1:
        raise ValueError(f"n_gauss = {n_gauss!r}: need an integer >= 1")
    f0, kb = _springs(st, bearing_stiffness)
    x, w = np.polynomial.legendre.leggauss(int(n_gauss))
    saved = st.get_state()
    acc = np.zeros((len(st.meshes), 12, 12))
    try:
        for m, mesh in enumerate(st.meshes):
            start, per = _mesh_turn(st, m)
            a0 = start / per
            period = mesh.event_period
            edges = np.unique(np.concatenate([[a0], mesh.event_angles(a0, a0 + period),
                                              [a0 + period]]))
            edges = edges[np.concatenate([[True], np.diff(edges) > 1e-12 * period])]
            edges[-1] = a0 + period
            for lo, hi in itertools.pairwise(edges):
                half, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
                for xi, wi in zip(x, w, strict=True):
                    st.static_at(f0, kb, float((mid + half * xi) * per))
                    acc[m] += (wi * half) * st.mesh_states[m].stiffness
            acc[m] /= period
    finally:
        st.set_state(saved)
    return acc


def line_of_action_stiffness(st, mesh_stiffness, mesh: int = 0) -> float:
    """Scalar stiffness of mesh ``mesh`` along its line of action (normal to the flanks)
    [N/m].

    ``K[theta1, theta1] / (r_b1 cos(beta_b))^2`` of its (12, 12) stiffness: for every contact
    point the structure vector of Eq. (12) has ``V[theta1] = r_b1 cos(beta_b)`` in the pair's
    frame (the line of action is tangent to the base circle; the structure's frame changes at
    most its sign), so this is exactly ``sum k dl``, the sum of the slice springs. Divide by
    ``pair.contact_width`` for the stiffness per unit face width (1 N/(mm um) = 1e9 N/m^2).
    ``mesh_stiffness``: (12, 12), or (n_meshes, 12, 12) of which mesh ``mesh`` is taken.
    """
    k = np.asarray(mesh_stiffness, dtype=float)
    if k.ndim == 3:
        k = k[mesh]
    if k.shape != (12, 12):
        raise ValueError(f"mesh stiffness shape {k.shape} must be (12, 12)")
    pair = st.meshes[mesh].pair
    lever = pair.base_radius[0] * math.cos(pair.base_helix_angle)
    return float(k[5, 5] / lever**2)


@one_blas_thread
def modes(st, bearing_stiffness=1e8, n_gauss: int = 8, mesh_stiffness=None):
    """Natural modes with the mean mesh stiffnesses at the static load (for ``gsb modal``):
    the undamped modes of K0 of Eq. (20).

    ``bearing_stiffness``: isotropic [N/m] or (nb, 2, 2) (symmetric part used);
    ``mesh_stiffness``: (n_meshes, 12, 12) mean mesh stiffnesses already computed, else
    :func:`exact_mean_mesh_stiffness` with these bearings and ``n_gauss``. Returns
    :class:`gear_fmu.modal.modes.Modes`; format with :func:`gear_fmu.modal.modes.mode_table`.
    """
    if mesh_stiffness is None:
        mesh_stiffness = exact_mean_mesh_stiffness(st, bearing_stiffness, n_gauss)
    return natural_modes(st.system, bearing_stiffness, mesh_stiffness)


@one_blas_thread
def damped(st, kb, cb, mesh_stiffness=None, n_gauss: int = 8):
    """Damped modes of the linearised system about X0, Eq. (20) with C0 = C + Cb(X0).

    M, the structure's damping ``st.damping_full`` (whatever built it) and gyroscopic matrix
    ``st.gyroscopic_full`` (zero without), K_shaft, the mean mesh
    stiffnesses and the bearings' full 2x2 ``kb`` [N/m] and ``cb`` [N s/m] (nb, 2, 2) in the
    global frame (:func:`gear_fmu.modal.damped_modes.damped_modes`). ``mesh_stiffness``:
    (n_meshes, 12, 12) means already computed, else :func:`exact_mean_mesh_stiffness` with the
    symmetric part of ``kb`` (as the modal damping reference). Returns
    :class:`gear_fmu.modal.damped_modes.DampedModes`.
    """
    kb = np.asarray(kb, dtype=float)
    if mesh_stiffness is None:
        sym = kb if kb.ndim == 0 else 0.5 * (kb + np.swapaxes(kb, -1, -2))
        mesh_stiffness = exact_mean_mesh_stiffness(st, sym, n_gauss)
    return damped_modes(st.system, st.damping_full, mesh_stiffness, kb, cb,
                        st.gyroscopic_full)


@one_blas_thread
def reference_damping(st, model, bearing_stiffness):
    """The damping matrix ``C`` (full numbering) of a damping model
    (:mod:`gear_fmu.modal.damping`) on the reference configuration: shafts, the mean mesh
    stiffnesses at the static load with these bearings, and the bearing stiffness (isotropic
    [N/m] or (nb, 2, 2), symmetric part).

    ``model``: a :class:`gear_fmu.modal.damping.DampingModel`, or a float zeta (modal damping on
    the ``"bearings"`` basis). Returns ``(C, modes, mean mesh stiffnesses)``; the modes are
    those of the modal damping (None otherwise), the mean mesh stiffnesses None when nothing
    needs them.
    """
    from gear_fmu.modal.damping import DampingModel, damping_matrix

    if not isinstance(model, DampingModel):
        model = DampingModel(ratio=float(model))
    system = st.system
    if model.is_zero:
        return np.array(system.coupling_damping, copy=True), None, None
    k_mesh = mean_mesh_stiffness(st, bearing_stiffness)
    radii = np.array([m.pair.base_radius for m in st.meshes]) if (
        model.mesh_ratio or model.mesh_coefficient) else None
    c, ref = damping_matrix(system, model, k_mesh, bearing_stiffness, radii)
    return c, ref, k_mesh


@one_blas_thread
def support_loads(st) -> np.ndarray:
    """(nb, 2) static loads of the structure on stiff bearings (1e12 N/m) [N], global frame."""
    saved = st.get_state()
    kb = np.broadcast_to(STIFF_SUPPORT * np.eye(2), (st.nb, 2, 2)).copy()
    try:
        st.static(np.zeros((st.nb, 2)), kb, None)
        loads = np.einsum("bij,bj->bi", kb, st.journal_states()[:, :2])
    finally:
        st.set_state(saved)
    return loads
