"""The Newton-Raphson / normal-contact loop of one structural solve (paper Sec. 3.2, Fig. 4),
for any number of meshes.

On the condensed DOFs (:mod:`gear_fmu.step.condensation`; the gear-node DOFs first) the
residual of Eq. (11) is ``G_c = S X_c - z0 - F_mesh(X_c)`` with S the condensed tangent of the
linear part and the bearing laws, ``F_mesh`` the sum of every mesh element's force on its two
gear nodes (:func:`evaluate_train`). The mesh force is piecewise linear in X (fixed contact
sets), so Newton (Eq. 13-15) converges in one solve once the contact sets are right; the loop
ends when the contact set each mesh used in the last solve equals the one at the iterate and
the relative residual ``||G_c|| / max(f_scale, ||F_mesh||)`` is below the limit l, or below
the round-off floor of its evaluation when that is larger: ``64 eps (||z0|| + ||F_mesh||)``
over the same scale (at the solution ``S X_c`` balances ``z0 + F_mesh``, so these are the
sizes of the terms that cancel). At small time steps the inertia terms in S and z0
(``4/dt^2 M``) are many orders above the external loads, and a limit such as 1e-10 of the
loads lies below what double precision can resolve; the floor only accepts where the limit
could never be met.

A mesh's workspace (:class:`MeshWork`) is one tuple of arrays, the same types for every mesh,
so that a train's meshes are one homogeneous tuple the compiled loop indexes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from gear_fmu.mesh.element import MeshState, _mesh_kernel
from gear_fmu.step.condensation import gauss_solve

__all__ = ["CONVERGED", "NOT_CONVERGED", "ROUNDOFF", "SINGULAR", "MeshWork", "StepInfo",
           "contact_newton", "evaluate_train", "use_sets"]

#: the round-off floor of the residual, in units of machine epsilon times the norms of its terms
ROUNDOFF = 64.0 * np.finfo(float).eps
#: outcomes of :func:`contact_newton`
CONVERGED, NOT_CONVERGED, SINGULAR = 0, 1, 2
#: entries of a mesh's workspace tuple (:meth:`MeshWork.arrays`): the kernel's arrays
#: (:meth:`gear_fmu.mesh.element.MeshElement.kernel_arrays`, 12), then
_IDX, _TE = 12, 13  # its 12 DOFs in the condensed vector, its transmission-error vector
#: the last evaluation: force, stiffness, contact set, inside, approach, load, abscissa, z
_OUT, _STIFF, _ACTIVE, _INSIDE, _DELTA, _LOAD, _XI, _Z = 14, 15, 16, 17, 18, 19, 20, 21
_USED = 22  # the contact set the current iterate is consistent with
#: the evaluation the last accepted step ended on, as the last evaluation's entries
_KEPT, _KEPT_ACTIVE = 23, 25


@dataclass
class StepInfo:
    """Outcome of one step or static solve."""

    t: float
    iterations: int  # linear solves of the Newton/contact loop
    residual: float
    residuals: list = field(default_factory=list)


def kept_views(floats: np.ndarray, bools: np.ndarray) -> tuple:
    """A mesh evaluation's buffers (force (12,), stiffness (12, 12), contact set, inside,
    approach, load, abscissa, z (n,)) as contiguous views of a float block (156 + 4 n,)
    and a bool block (2 n,) of a mesh of n slices."""
    n = bools.size // 2
    if floats.size != 156 + 4 * n:
        raise ValueError(f"mesh evaluation block of {floats.size} floats for {n} slices "
                         f"(expected 156 + 4 n = {156 + 4 * n})")
    d = [floats[156 + i * n:156 + (i + 1) * n] for i in range(4)]
    return (floats[:12], floats[12:156].reshape(12, 12), bools[:n], bools[n:], *d)


class MeshWork:
    """A mesh element in a structure: its kernel's arrays, where its 12 DOFs sit in the
    condensed vector (``idx``) and the buffers its evaluations fill (module docstring).

    Parameters
    ----------
    mesh : gear_fmu.mesh.element.MeshElement
    idx : (12,) int
        Condensed indices of the driver's then the driven gear node's six DOFs.
    """

    def __init__(self, mesh, idx):
        self.mesh = mesh
        self.idx = np.ascontiguousarray(idx, dtype=np.int64)
        n = self.n
        self.out = kept_views(np.zeros(156 + 4 * n), np.zeros(2 * n, dtype=np.bool_))
        self.used = np.zeros(n, dtype=np.bool_)
        # the state's evaluation as views of two blocks: a master saves and restores it at
        # every step, two copies per mesh
        self.kept_f, self.kept_b = np.zeros(156 + 4 * n), np.zeros(2 * n, dtype=np.bool_)
        self.kept = kept_views(self.kept_f, self.kept_b)

    @property
    def n(self) -> int:
        """Slices of all contact lines."""
        return self.mesh.n_lines * self.mesh.n_slices

    def arrays(self) -> tuple:
        """The workspace tuple of the compiled loop (module docstring)."""
        return (*self.mesh.kernel_arrays(), self.idx, self.mesh._te, *self.out, self.used,
                *self.kept)

    def state(self, buffers, total: float, length: float, q) -> MeshState:
        """A :class:`~gear_fmu.mesh.element.MeshState` (copies) of the evaluation in
        ``buffers`` (``out`` or ``kept``) at the gear-node DOFs ``q`` (12,)."""
        force, stiff, active, inside, delta, load, xi, z = (b.copy() for b in buffers)
        return MeshState(force, stiff, active, delta, load, inside, xi, z, float(total),
                         self.mesh.transmission_error(q), {"contact_length": float(length)})


@njit(cache=True, _nrt=False)
def evaluate_train(meshes, xc, angles, errs, has_err, fc, kc, totals, lengths, q):
    """The mesh forces of Eq. (9): every mesh of ``meshes`` (workspace tuples) at its pinion
    angle ``angles[m]`` [rad] and the condensed DOFs ``xc`` (plus ``errs[m]``, the error
    displacement, when ``has_err``): each mesh's evaluation into its workspace, their forces
    summed into ``fc`` (ng,) and their tangents into ``kc`` (ng, ng) on the condensed
    gear-node DOFs, each mesh's total load [N] and contact length [m] into ``totals[m]``,
    ``lengths[m]``; ``q`` (12,) a buffer. Compiled without reference counting: the meshes'
    tuples are read, never kept (a count per array of each tuple read cost more than the
    sums)."""
    ng = fc.size
    for i in range(ng):
        fc[i] = 0.0
        for j in range(ng):
            kc[i, j] = 0.0
    for m in range(len(meshes)):
        w = meshes[m]
        idx = w[_IDX]
        for i in range(12):
            q[i] = xc[idx[i]] + errs[m, i] if has_err else xc[idx[i]]
        totals[m], lengths[m] = _mesh_kernel(
            angles[m], q, w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8], w[9], w[10],
            w[11], w[_OUT], w[_STIFF], w[_ACTIVE], w[_INSIDE], w[_DELTA], w[_LOAD], w[_XI],
            w[_Z])
        force, stiff = w[_OUT], w[_STIFF]
        for i in range(12):
            fc[idx[i]] += force[i]
            for j in range(12):
                kc[idx[i], idx[j]] += stiff[i, j]


@njit(cache=True, _nrt=False)
def _same_sets(meshes):
    """Every mesh's contact set equals the one its iterate is consistent with."""
    for m in range(len(meshes)):
        a, b = meshes[m][_ACTIVE], meshes[m][_USED]
        for i in range(a.size):
            if a[i] != b[i]:
                return False
    return True


@njit(cache=True, _nrt=False)
def use_sets(meshes, kept):
    """Each mesh's next iterate is consistent with its last evaluation's contact set, or with
    its ``kept`` one (the state's)."""
    for m in range(len(meshes)):
        w = meshes[m]
        src = w[_KEPT_ACTIVE] if kept else w[_ACTIVE]
        used = w[_USED]
        for i in range(used.size):
            used[i] = src[i]


@njit(cache=True)
def _dot(u, w):
    """``u . w`` summed in index order (not BLAS's, whose order depends on the CPU)."""
    acc = 0.0
    for i in range(u.size):
        acc += u[i] * w[i]
    return acc


@njit(cache=True)
def _residual_norm(s_lin, z0, xc, mesh_force):
    """2-norm of the condensed residual G_c = S X_c - z0 - F_mesh (gear-node rows first)."""
    nc = z0.size
    ng = mesh_force.size
    acc = 0.0
    for i in range(nc):
        g = -z0[i]
        for j in range(nc):
            g += s_lin[i, j] * xc[j]
        if i < ng:
            g -= mesh_force[i]
        acc += g * g
    return np.sqrt(acc)


@njit(cache=True)
def _newton_solve(s_lin, z0, xc, mesh_force, mesh_stiffness):
    """Solve (S + K_mesh) X_c = z0 + F_mesh + K_mesh X_c (fixed contact sets), Eq. (13)."""
    ng = mesh_force.size
    s = s_lin.copy()
    rhs = z0.copy()
    for i in range(ng):
        acc = mesh_force[i]
        for j in range(ng):
            s[i, j] += mesh_stiffness[i, j]
            acc += mesh_stiffness[i, j] * xc[j]
        rhs[i] += acc
    return gauss_solve(s, rhs)


@njit(cache=True)
def contact_newton(s_lin, z0, xc, angles, errs, has_err, meshes, fc, kc, totals, lengths,
                   has_used, f_scale, tol, max_iter, residuals):
    """The Newton/contact loop (module docstring) from the iterate ``xc`` (nc,), each mesh's
    first iterate consistent with its ``used`` set when ``has_used``; ``f_scale`` [N] the
    largest external load, ``residuals`` (max_iter + 1,) receives each pass's relative
    residual, ``fc``, ``kc``, ``totals``, ``lengths`` the last evaluation
    (:func:`evaluate_train`).

    Returns ``(status, passes, X_c)``: :data:`CONVERGED`, :data:`NOT_CONVERGED` after
    ``max_iter`` solves or :data:`SINGULAR` (a zero pivot: no contact in a mesh leaves a shaft
    free in torsion).
    """
    z_norm = -1.0
    q = np.empty(12)
    for k in range(max_iter + 1):
        evaluate_train(meshes, xc, angles, errs, has_err, fc, kc, totals, lengths, q)
        ff = _dot(fc, fc)
        scale = max(f_scale, math.sqrt(ff))
        scale = scale if scale > 0.0 else 1.0
        r = _residual_norm(s_lin, z0, xc, fc) / scale
        residuals[k] = r
        limit = tol
        if r > tol:  # the round-off floor at this iterate (module docstring)
            if z_norm < 0.0:
                z_norm = math.sqrt(_dot(z0, z0))
            limit = max(tol, ROUNDOFF * (z_norm + math.sqrt(ff)) / scale)
        if r <= limit and has_used and _same_sets(meshes):
            return CONVERGED, k, xc
        if k == max_iter:
            break
        xc, ok = _newton_solve(s_lin, z0, xc, fc, kc)
        if not ok:
            return SINGULAR, k, xc
        use_sets(meshes, np.bool_(False))  # (a plain bool: use_sets compiled once)
        has_used = True
    return NOT_CONVERGED, max_iter, xc
