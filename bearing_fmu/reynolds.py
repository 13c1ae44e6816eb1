"""The dimensionless Reynolds problem shared by every film model (paper Sec. 2.2.1, Eq. 2-5).

One home for the quantities the hybrid, short-bearing and finite-difference models all use:

* Eq. (3), film thickness ``h = 1 - x cos(theta) - y sin(theta)`` and source term
  ``f = (y + 2 xdot) cos(theta) + (2 ydot - x) sin(theta) = A cos(theta) + B sin(theta)``
  (:func:`film_thickness`, :func:`source_coefficients`, :func:`source`), in the dimensionless
  state ``x = x/C``, ``xdot = xdot/(C omega)`` of the journal centre;
* Eq. (2) with Eq. (4): ``d/dtheta (h^3 dp/dtheta) + d/dxi (h^3 dp/dxi) = -f`` on
  ``theta`` periodic, ``xi = z/R`` in ``[-lambda, lambda]``, ``lambda = L/D``, ``p = 0`` at the
  bearing edges and ``p >= 0`` with the Swift-Stieber condition at the film end (each model's
  module says how it discretises this);
* Eq. (5), the film force on the journal ``Fbar = -integral of p (cos(theta), sin(theta))`` over
  the film (:func:`nodal_force`: the sum over theta nodes of the axially integrated pressure,
  used by the hybrid and finite-difference models; the short-bearing model integrates Eq. (5)
  in closed form along xi);
* the scales of the Nomenclature: ``F = Fbar 6 mu omega R^2 (R/C)^2`` (:func:`force_scale`),
  ``p = pbar 6 mu omega (R/C)^2`` (:func:`pressure_scale`).

The scalar functions are numba-compiled and inlined into the kernels (``inline="always"``: the
caller's compilation flags apply, so a kernel computes exactly what it computed with the formula
written in place). From Python their ``py_func`` works on numpy arrays as well.

>>> round(film_thickness(0.5, 0.0, -1.0, 0.0), 12)  # largest thickness, opposite the journal
1.5
>>> source_coefficients(0.5, 0.0, 0.0, 0.0)  # static journal on +x: f = -0.5 sin(theta)
(0.0, -0.5)
"""

from __future__ import annotations

from numba import njit

__all__ = [
    "film_thickness",
    "force_scale",
    "nodal_force",
    "pressure_scale",
    "source",
    "source_coefficients",
]


@njit(cache=True, inline="always")
def film_thickness(x, y, cos_theta, sin_theta):
    """Eq. (3): dimensionless film thickness ``h = 1 - x cos(theta) - y sin(theta)``."""
    return 1.0 - x * cos_theta - y * sin_theta


@njit(cache=True, inline="always")
def source_coefficients(x, y, x_dot, y_dot):
    """Eq. (3): ``(A, B)`` with ``f = A cos(theta) + B sin(theta)``, ``A = y + 2 xdot``,
    ``B = 2 ydot - x`` (wedge and squeeze terms of the dimensionless state)."""
    return y + 2.0 * x_dot, 2.0 * y_dot - x


@njit(cache=True, inline="always")
def source(a, b, cos_theta, sin_theta):
    """Eq. (3): the source term ``f = A cos(theta) + B sin(theta)`` of Eq. (2)."""
    return a * cos_theta + b * sin_theta


@njit(cache=True)
def nodal_force(line_pressure, cos_theta, sin_theta, weight, out):
    """Eq. (5) on theta nodes: ``Fbar = -weight sum_i P_i (cos(theta_i), sin(theta_i))``.

    Parameters
    ----------
    line_pressure : (n,) array
        ``P_i``, the pressure of node i integrated along xi (up to the factor in ``weight``).
    cos_theta, sin_theta : (n,) arrays
        cos and sin of the node angles.
    weight : float
        Quadrature weight of a node (and any common factor of ``P_i``).
    out : (2,) array
        Receives ``(Fbar_x, Fbar_y)``.

    Returns
    -------
    (sum_i P_i cos(theta_i), sum_i P_i sin(theta_i))
        The unweighted sums (the hybrid Jacobians reuse them).
    """
    sc = 0.0
    ss = 0.0
    for i in range(line_pressure.shape[0]):
        sc += line_pressure[i] * cos_theta[i]
        ss += line_pressure[i] * sin_theta[i]
    out[0] = -weight * sc
    out[1] = -weight * ss
    return sc, ss


def force_scale(viscosity: float, omega: float, radius: float, clearance: float) -> float:
    """Force scale of Eq. (5): ``6 mu omega R^2 (R/C)^2`` [N] (paper Nomenclature).

    Parameters are SI: mu [Pa s], omega [rad/s], R and C [m].
    """
    return 6.0 * viscosity * omega * radius * radius * (radius / clearance) ** 2


def pressure_scale(viscosity: float, omega: float, radius: float, clearance: float) -> float:
    """Pressure scale of Eq. (2): ``6 mu omega (R/C)^2`` [Pa] (paper Nomenclature)."""
    return 6.0 * viscosity * omega * (radius / clearance) ** 2
