"""The Newmark scheme of the structure's step: gamma = 1/2, beta = 1/4 (paper Sec. 3.2, Eq. 12).

With ``c0 = 4/dt^2``, ``c1 = 2/dt``, ``c2 = 4/dt`` (:func:`newmark_coefficients`):

    Xd_{n+1}  = c1 (X_{n+1} - X_n) - Xd_n                       (:func:`newmark_kinematics`)
    Xdd_{n+1} = c0 (X_{n+1} - X_n) - c2 Xd_n - Xdd_n

so that ``M Xdd_{n+1} + C Xd_{n+1} = (c0 M + c1 C) X_{n+1} - M p - C q`` with the history terms
``p = c0 X_n + c2 Xd_n + Xdd_n``, ``q = c1 X_n + Xd_n`` (:func:`newmark_history`). The residual
of Eq. (11) and its Newton-Raphson / contact loop (Eq. 13-16, Fig. 4) are solved on the
condensed DOFs: :mod:`gear_fmu.step.assembly`, :mod:`gear_fmu.step.contact_loop`,
:mod:`gear_fmu.step.kernel`, driven by :meth:`gear_fmu.structure.Structure.step`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "NewmarkConvergenceError",
    "newmark_coefficients",
    "newmark_history",
    "newmark_kinematics",
]

GAMMA = 0.5
BETA = 0.25


class NewmarkConvergenceError(RuntimeError):
    """Newton-Raphson / contact iterations did not converge within a time step."""


@njit(cache=True)
def newmark_coefficients(dt):
    """``(c0, c1, c2) = (4/dt^2, 2/dt, 4/dt)`` of Eq. (12) (gamma = 1/2, beta = 1/4)."""
    return 4.0 / dt**2, 2.0 / dt, 4.0 / dt


@njit(cache=True)
def newmark_kinematics(x1, x0, v0, a0, dt):
    """Velocity and acceleration at t_{n+1} from the displacement (Eq. 12): ``(v1, a1)``."""
    c0, c1, c2 = newmark_coefficients(dt)
    n = x1.size
    v1 = np.empty(n)
    a1 = np.empty(n)
    for i in range(n):
        dx = x1[i] - x0[i]
        v1[i] = c1 * dx - v0[i]
        a1[i] = c0 * dx - c2 * v0[i] - a0[i]
    return v1, a1


@njit(cache=True)
def newmark_history(x0, v0, a0, dt):
    """History terms of Eq. (12) at t_n, stacked: ``[c0 X_n + c2 Xd_n + Xdd_n;
    c1 X_n + Xd_n]`` (2n,), so that ``M Xdd_{n+1} + C Xd_{n+1} = (c0 M + c1 C) X_{n+1} -
    [M C] @ history``."""
    c0, c1, c2 = newmark_coefficients(dt)
    n = x0.size
    out = np.empty(2 * n)
    for i in range(n):
        out[i] = c0 * x0[i] + c2 * v0[i] + a0[i]
        out[n + i] = c1 * x0[i] + v0[i]
    return out
