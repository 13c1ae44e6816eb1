"""The Newton-Raphson / normal-contact loop of one structural solve (paper Sec. 3.2, Fig. 4).

On the condensed DOFs (:mod:`gear_fmu.step.condensation`) the residual of Eq. (11) is
``G_c = S X_c - z0 - F_mesh(X_c)`` with S the condensed tangent of the linear part and the
bearing laws. The mesh force is piecewise linear in X (fixed active set), so Newton (Eq. 13-15)
converges in one solve once the contact set is right; the loop ends when the contact set used by
the last solve equals the one at the iterate and the relative residual
``||G_c|| / max(f_scale, ||F_mesh||)`` is below the limit l, or below the round-off floor of
its evaluation when that is larger: ``64 eps (||z0|| + ||F_mesh||)`` over the same scale (at
the solution ``S X_c`` balances ``z0 + F_mesh``, so these are the sizes of the terms that
cancel). At small time steps the inertia terms in S and z0 (``4/dt^2 M``) are many
orders above the external loads, and a limit such as 1e-10 of the loads lies below what
double precision can resolve; the floor only accepts where the limit could never be met, so
it changes no step that converged before.

Mesh element API consumed: ``mesh.evaluate(pinion_angle, q12) -> state`` with ``state.force``
(12,) the generalised mesh force on the gear-node DOFs, ``state.stiffness`` (12, 12) its tangent
``-dforce/dq`` for the current active set, ``state.active`` the contact set.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from gear_fmu.step.condensation import N_GEAR, gauss_solve
from gear_fmu.step.newmark import NewmarkConvergenceError

__all__ = ["ROUNDOFF", "StepInfo", "solve_condensed"]

#: the round-off floor of the residual, in units of machine epsilon times the norms of its terms
ROUNDOFF = 64.0 * np.finfo(float).eps


@dataclass
class StepInfo:
    """Outcome of one step or static solve."""

    t: float
    iterations: int  # linear solves of the Newton/contact loop
    residual: float
    residuals: list = field(default_factory=list)


@njit(cache=True)
def _residual_norm(s_lin, z0, xc, mesh_force):
    """2-norm of the condensed residual G_c = S X_c - z0 - F_mesh (mesh rows first)."""
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
    """Solve (S + K_mesh) X_c = z0 + F_mesh + K_mesh X_c (fixed active set), Eq. (13)."""
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
def _same_set(a, b):
    """Equality of two boolean contact sets (False if the sizes differ)."""
    if a.shape != b.shape:
        return False
    for i in range(a.size):
        if a.flat[i] != b.flat[i]:
            return False
    return True


def same_contact_set(a, b) -> bool:
    """Contact sets equal (numba for boolean arrays, numpy otherwise)."""
    if (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == np.bool_
            and b.dtype == np.bool_):
        return _same_set(a, b)
    return np.array_equal(a, b)


def solve_condensed(mesh, s_lin, z0, xc, angle, active_used, f_scale, t, what, tol, max_iter,
                    timing=None):
    """Newton/contact loop on the condensed block; returns (X_c, mesh state, StepInfo).

    Parameters
    ----------
    mesh : mesh element (module docstring)
    s_lin, z0 : (nc, nc), (nc,) arrays
        Condensed tangent without the mesh and right-hand side.
    xc : (nc,) array
        First iterate.
    angle : float
        Rigid-body pinion angle of the solve [rad].
    active_used : array or None
        Contact set the first iterate is consistent with (None: none, iterate at least once).
    f_scale : float
        Force scale of the relative residual [N] (largest external load or bearing force).
    t : float
        Time of the solve [s] (messages).
    what : str
        "static solution" or "Newmark step N" (messages).
    tol, max_iter
        Limit l on the relative residual; Newton/contact iterations allowed.
    timing : dict, optional
        Accumulates seconds under "mesh" and "solve" when given (benchmarks).

    Raises
    ------
    NewmarkConvergenceError
        With the time, the residual history and the contact count.
    """
    residuals = []
    z_norm = -1.0  # ||z0||, computed when first needed
    for k in range(max_iter + 1):
        t0 = time.perf_counter() if timing is not None else 0.0
        ms = mesh.evaluate(angle, xc[:N_GEAR])
        if timing is not None:
            t1_ = time.perf_counter()
            timing["mesh"] += t1_ - t0
            t0 = t1_
        force = ms.force
        scale = max(f_scale, math.sqrt(float(force @ force)))
        scale = scale if scale > 0.0 else 1.0
        r = _residual_norm(s_lin, z0, xc, force) / scale
        residuals.append(r)
        limit = tol
        if r > tol:  # the round-off floor at this iterate (module docstring)
            if z_norm < 0.0:
                z_norm = math.sqrt(float(z0 @ z0))
            limit = max(tol, ROUNDOFF * (z_norm + math.sqrt(float(force @ force))) / scale)
        if r <= limit and active_used is not None and same_contact_set(ms.active, active_used):
            if timing is not None:
                timing["solve"] += time.perf_counter() - t0
            return xc, ms, StepInfo(t, k, r, residuals)
        if k == max_iter:
            break
        xc, ok = _newton_solve(s_lin, z0, xc, force, ms.stiffness)
        if not ok:
            raise NewmarkConvergenceError(
                f"{what} at t = {t:.9g} s: singular tangent at iteration {k} "
                f"({int(np.count_nonzero(ms.active))} mesh slices in contact; with no tooth "
                "contact the pinion is free in torsion - check the torque sign)"
            )
        active_used = ms.active
        if timing is not None:
            timing["solve"] += time.perf_counter() - t0
    raise NewmarkConvergenceError(
        f"{what} at t = {t:.9g} s did not converge: relative residual {residuals[-1]:.3e} "
        f"(tol {tol:.1e}) after {max_iter} iterations; last residuals "
        f"{', '.join(f'{v:.2e}' for v in residuals[-5:])}"
    )
