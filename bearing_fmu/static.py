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
    _check_omega,
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


def newton_equilibrium(law, load, x, radius_limit: float, *, tol: float, maxit: int,
                       what: str = ""):
    """Newton on ``F(X) + W = 0`` (Eq. 8) with the law's own stiffness ``Kb = -dF/dX``.

    Parameters
    ----------
    law : callable
        ``law(X) -> (force (2,) [N], Kb (2, 2) [N/m], anything)`` at the position X [m], zero
        velocity; the third item is returned with the solution.
    load : (2,) array
        External static load W [N].
    x : (2,) array
        First iterate [m].
    radius_limit : float
        Every iterate stays inside the circle ``|X| < radius_limit`` [m] (step halving).
    tol : float
        Convergence on ``|F + W|`` relative to ``|W|``.
    maxit : int
        Newton iterations.
    what : str
        Appended to the error message (speed, bearing).

    Returns
    -------
    (X, third item of ``law`` at X, iterations)

    Raises
    ------
    BearingError
        If Newton does not converge (iterations and residual in the message).
    """
    w = np.asarray(load, dtype=float)
    wnorm = float(np.hypot(*w))
    scale = max(wnorm, 1e-300)
    x = np.array(x, dtype=float)
    iterations = 0
    res = np.full(2, np.inf)
    out = None
    while iterations < maxit:
        iterations += 1
        force, kb, out = law(x)
        res = force + w
        if np.hypot(*res) <= tol * scale:
            break
        step = np.linalg.solve(kb, res)  # F(x + dx) ~ F - Kb dx = -W
        # keep the iterate inside the circle
        alpha = 1.0
        while math.hypot(*(x + alpha * step)) >= radius_limit and alpha > 1e-6:
            alpha *= 0.5
        x = x + alpha * step
    if not np.hypot(*res) <= tol * scale:
        raise BearingError(
            f"static equilibrium did not converge in {maxit} iterations: residual "
            f"{np.hypot(*res):.3e} N for load {wnorm:.6g} N {what}".rstrip()
        )
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
    omega = _check_omega(omega)
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
        r = model.evaluate(pos[0], pos[1], 0.0, 0.0, omega)
        return r.force, r.stiffness, r

    x, r, iterations = newton_equilibrium(law, w, x, eps_max * c, tol=tol, maxit=maxit,
                                          what=f"at omega = {omega} rad/s")
    eps = math.hypot(x[0], x[1]) / c
    if eps >= eps_max:
        raise EccentricityError(f"static eccentricity ratio {eps:.6g} >= limit {eps_max}")
    attitude = math.degrees(math.atan2(x[1], x[0]) - math.atan2(w[1], w[0])) % 360.0
    return StaticSolution(x[0], x[1], eps, attitude, r, iterations)
