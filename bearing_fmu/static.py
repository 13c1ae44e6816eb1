"""Static equilibrium of one journal bearing (paper Sec. 2.2.3, Eq. 8).

Sign convention: ``load`` W [N] is the external static force applied to the journal (by the
shaft, e.g. half the tooth force, or ``(0, -m g)``), in the bearing's local frame. The film force
balances it: ``F_b(x0, y0, 0, 0) + W = 0``. The attitude angle is the angle from the load line
to the line of centres O -> O', measured in the direction of rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bearing_fmu.base import (
    BearingError,
    BearingModel,
    BearingResult,
    EccentricityError,
    FilmBearingModel,
    check_omega,
)

__all__ = ["StaticSolution", "newton_equilibrium", "static_equilibrium"]


@dataclass(frozen=True)
class StaticSolution:
    """Static journal position and the film's 8 coefficients there (SI, local frame)."""

    x0: float  # m
    y0: float  # m
    eccentricity: float  # eccentricity ratio e/C [-]
    attitude_deg: float  # deg
    result: BearingResult  # force [N], Kb [N/m], Cb [N s/m] at (x0, y0)
    iterations: int


def _film_ray_guess(model: FilmBearingModel, load_bar: float, direction: float, eps_max: float):
    """Solve |Fbar(eps, 0)| = load_bar (isotropic bearing), rotate onto the load line."""

    def excess(eps: float) -> float:
        return float(np.hypot(*model.dimensionless(eps, 0.0, jacobian=False).force)) - load_bar

    top = excess(eps_max)
    if top < 0.0:
        raise EccentricityError(
            f"the film cannot carry the load: dimensionless load {load_bar:.6g} exceeds the "
            f"force {top + load_bar:.6g} at the eccentricity limit {eps_max}"
        )
    from scipy.optimize import brentq  # here: importing scipy.optimize costs 0.3 s

    eps = brentq(excess, 1e-9, eps_max, xtol=1e-14, rtol=1e-13)
    fx, fy = model.dimensionless(eps, 0.0, jacobian=False).force
    rot = direction + math.pi - math.atan2(fy, fx)  # force must point against the load
    return eps * math.cos(rot), eps * math.sin(rot)


def newton_equilibrium(law, loads, x, radius_limit, *, tol: float, maxit: int,
                       what: str = ""):
    """Newton on ``F(X) + W = 0`` (Eq. 8) with the law's own stiffness ``Kb = -dF/dX``, for
    one journal or several at once (each its own Newton, all evaluated together).

    Parameters
    ----------
    law : callable
        ``law(X) -> (force (nb, 2) [N], Kb (nb, 2, 2) [N/m], anything)`` at the positions X
        (nb, 2) [m], zero velocity; the third item is returned with the solution. A journal
        that has converged keeps its position while the others iterate.
    loads : (nb, 2) array
        External static loads W [N].
    x : (nb, 2) array
        First iterates [m].
    radius_limit : float or (nb,) array
        Every iterate stays inside the circle ``|X| < radius_limit`` [m] (step halving).
    tol : float
        Convergence on ``|F + W|`` relative to ``|W|``, journal by journal.
    maxit : int
        Newton iterations.
    what : str
        Appended to the error message (speed, bearings).

    Returns
    -------
    (X (nb, 2), third item of ``law`` at X, iterations)

    Raises
    ------
    BearingError
        If a journal does not converge (its index, the iterations and residual in the message;
        its 0-based index in ``bearing_index``).
    """
    w = np.array(loads, dtype=float).reshape(-1, 2)
    x = np.array(x, dtype=float).reshape(w.shape)
    limit = np.broadcast_to(np.asarray(radius_limit, dtype=float), len(w))
    scale = np.maximum(np.hypot(w[:, 0], w[:, 1]), 1e-300)
    iterations = 0
    residual = np.full(len(w), np.inf)
    out = None
    while iterations < maxit:
        iterations += 1
        force, kb, out = law(x)
        res = np.asarray(force, dtype=float).reshape(w.shape) + w
        residual = np.hypot(res[:, 0], res[:, 1])
        moving = ~(residual <= tol * scale)
        if not moving.any():
            break
        kb = np.asarray(kb, dtype=float).reshape(-1, 2, 2)
        for b in np.flatnonzero(moving):
            step = np.linalg.solve(kb[b], res[b])  # F(x + dx) ~ F - Kb dx = -W
            alpha = 1.0  # keep the iterate inside the circle
            while math.hypot(*(x[b] + alpha * step)) >= limit[b] and alpha > 1e-6:
                alpha *= 0.5
            x[b] = x[b] + alpha * step
    failed = np.flatnonzero(~(residual <= tol * scale))
    if failed.size:
        b = int(failed[0])
        which = f"journal {b + 1} of {len(w)}: " if len(w) > 1 else ""
        error = BearingError(
            f"static equilibrium did not converge in {maxit} iterations: {which}residual "
            f"{residual[b]:.3e} N for load {float(np.hypot(*w[b])):.6g} N {what}".rstrip()
        )
        error.bearing_index = b  # the caller names the bearing (0-based, the loads' order)
        raise error
    return x, out, iterations


def static_equilibrium(
    model: BearingModel,
    load,
    omega: float,
    *,
    eps_max: float = 0.995,
    tol: float = 1e-11,
    maxit: int = 50,
) -> StaticSolution:
    """Find (x0, y0) with ``F_b(x0, y0, 0, 0) = -W`` (Eq. 8).

    Film models start from the exact solution of the isotropic 1-D problem (Brent on the
    eccentricity, rotated by the attitude angle) and are polished by Newton on (x, y) with the
    model's own stiffness Kb; affine laws converge in one Newton step.

    Parameters
    ----------
    model : BearingModel
    load : (2,) array_like
        External static load on the journal W [N], local frame.
    omega : float
        Shaft speed [rad/s].
    eps_max : float
        Largest admissible eccentricity ratio; a load the film cannot carry below it raises.
    tol : float
        Convergence on the force residual, relative to ``|W|``.

    Raises
    ------
    EccentricityError
        If the load needs an eccentricity ratio >= eps_max.
    BearingError
        If Newton does not converge (iterations and residual in the message).
    """
    omega = check_omega(omega)
    w = np.array(load, dtype=float).reshape(2)
    if not np.all(np.isfinite(w)):
        raise BearingError(f"static load {w!r} N is not finite")
    wnorm = float(np.hypot(*w))
    c = model.bearing.clearance
    if isinstance(model, FilmBearingModel) and wnorm > 0.0:
        load_bar = wnorm / model.bearing.force_scale(omega)
        xb, yb = _film_ray_guess(model, load_bar, math.atan2(w[1], w[0]), eps_max)
        x = np.array([xb * c, yb * c])
    else:
        x = np.zeros(2)

    def law(pos):
        r = model.evaluate(pos[0, 0], pos[0, 1], 0.0, 0.0, omega)
        return r.force, r.stiffness, r

    x, r, iterations = newton_equilibrium(law, w, x, eps_max * c, tol=tol, maxit=maxit,
                                          what=f"at omega = {omega} rad/s")
    x = x[0]
    eps = math.hypot(x[0], x[1]) / c
    if eps >= eps_max:
        raise EccentricityError(f"static eccentricity ratio {eps:.6g} >= limit {eps_max}")
    attitude = math.degrees(math.atan2(x[1], x[0]) - math.atan2(w[1], w[0])) % 360.0
    return StaticSolution(x[0], x[1], eps, attitude, r, iterations)
