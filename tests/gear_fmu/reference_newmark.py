"""A generic Newmark step on the full system: the tests' independent reference (no tests here).

The structure (:mod:`gear_fmu.structure`) solves its steps condensed onto the gear and bearing
DOFs, with the mesh element inside a compiled Newton/contact loop. This is the textbook form of
the same scheme on any (M, C, K) with the nonlinear forces as callbacks, written apart from that
code path, against which ``tests/gear_fmu/test_structure.py`` and
``tests/orchestrator/run/test_run.py`` hold the structure and the master (monolithic Newton).

Residual at t_{n+1} (Eq. 11): ``G(X) = M Xdd + C Xd + K X - F(t_{n+1}) - F_nl(X, Xd)`` with the
Newmark kinematics of Eq. (12) (gamma 1/2, beta 1/4,
:func:`gear_fmu.step.newmark.newmark_kinematics`);
Newton-Raphson (Eq. 13-16): ``J dX = -G`` with ``J = 4/dt^2 M + 2/dt C + K - dF_nl/dX -
2/dt dF_nl/dXd``. Contact loop (Fig. 4): the callback returns the active set of the iterate it
is evaluated at and its tangent for that set; the step is converged when the relative residual
is below ``tol`` and the active set at the iterate equals the one the last Newton solve used.
Relative residual: ``||G||_2`` over the largest 2-norm of the terms of Eq. (11) at the iterate
(1 if all vanish).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gear_fmu.step.newmark import NewmarkConvergenceError, newmark_coefficients, newmark_kinematics


@dataclass
class NonlinearForce:
    """Value of a nonlinear force callback at (X, Xd).

    Attributes
    ----------
    force : (n,) array
        F_nl [N].
    d_x, d_xdot : (n, n) arrays or None
        dF_nl/dX and dF_nl/dXd (None = zero).
    active : array or None
        Contact status at (X, Xd) (compared between iterates; None = no contact).
    """

    force: np.ndarray
    d_x: np.ndarray | None = None
    d_xdot: np.ndarray | None = None
    active: np.ndarray | None = None


@dataclass
class NewtonInfo:
    """Convergence record of one step."""

    iterations: int
    residual: float
    residuals: list = field(default_factory=list)
    active: np.ndarray | None = None


def relative_residual(g, terms) -> float:
    """``||g||_2 / max(||term||_2)`` over the terms of the residual (1 if all vanish)."""
    scale = max((float(np.linalg.norm(t)) for t in terms), default=0.0)
    return float(np.linalg.norm(g)) / (scale if scale > 0.0 else 1.0)


def _same_active(a, b) -> bool:
    if a is None and b is None:
        return True
    if a is None or b is None:
        return False
    return np.array_equal(a, b)


def newmark_step(
    mass: np.ndarray,
    damping: np.ndarray,
    stiffness: np.ndarray,
    dt: float,
    t1: float,
    x0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    force: Callable[[float], np.ndarray] | np.ndarray | None = None,
    nonlinear: Callable[[np.ndarray, np.ndarray], NonlinearForce] | None = None,
    active0=None,
    tol: float = 1e-5,
    max_iter: int = 50,
    step_index: int | None = None,
    x_start: np.ndarray | None = None,
):
    """One Newmark step (gamma 1/2, beta 1/4) solved by Newton-Raphson with contact.

    Parameters
    ----------
    mass, damping, stiffness : (n, n) arrays
        M, C, K (constant) [SI].
    dt : float
        Time step [s] > 0.
    t1 : float
        t_{n+1} [s].
    x0, v0, a0 : (n,) arrays
        State at t_n.
    force : callable t -> (n,) or (n,) array or None
        External load F(t_{n+1}) [N].
    nonlinear : callable (X, Xd) -> NonlinearForce, optional
        Nonlinear force and its derivatives.
    active0 : array, optional
        Active set at the end of the previous step (for the first convergence test).
    tol : float
        Relative residual limit l (module docstring).
    max_iter : int
        Newton iterations allowed.
    step_index : int, optional
        For the error message.
    x_start : (n,) array, optional
        First iterate (default X_n).

    Returns
    -------
    x1, v1, a1 : (n,) arrays
    info : NewtonInfo

    Raises
    ------
    NewmarkConvergenceError
        With the step, the time and the last residual.
    """
    if not (dt > 0.0 and np.isfinite(dt)):
        raise ValueError(f"time step dt = {dt!r} s must be finite and > 0")
    f_ext = force(t1) if callable(force) else (np.zeros_like(x0) if force is None else force)
    c0, c1, _ = newmark_coefficients(dt)
    j_lin = c0 * mass + c1 * damping + stiffness
    x = x0.copy() if x_start is None else np.array(x_start, dtype=float)
    used = active0
    residuals = []
    for k in range(max_iter + 1):
        v, a = newmark_kinematics(x, x0, v0, a0, dt)
        ma, cv, kx = mass @ a, damping @ v, stiffness @ x
        g = ma + cv + kx - f_ext
        terms = [ma, cv, kx, f_ext]
        nl = None
        if nonlinear is not None:
            nl = nonlinear(x, v)
            g = g - nl.force
            terms.append(nl.force)
        r = relative_residual(g, terms)
        residuals.append(r)
        active = None if nl is None else nl.active
        if r <= tol and _same_active(active, used):
            return x, v, a, NewtonInfo(k, r, residuals, active)
        if k == max_iter:
            break
        jac = j_lin
        if nl is not None:
            if nl.d_x is not None:
                jac = jac - nl.d_x
            if nl.d_xdot is not None:
                jac = jac - c1 * nl.d_xdot  # Eq. (16)
        x = x + np.linalg.solve(jac, -g)  # Eq. (13), (15)
        used = active
    where = f"step {step_index}" if step_index is not None else "step"
    raise NewmarkConvergenceError(
        f"Newmark/Newton did not converge at {where}, t = {t1:.9g} s: relative residual "
        f"{residuals[-1]:.3e} > tol {tol:.1e} after {max_iter} iterations "
        f"(history {', '.join(f'{v:.2e}' for v in residuals[-5:])})"
    )
