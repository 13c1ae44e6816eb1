"""Short-bearing theory (Ocvirk, half-Sommerfeld) with analytic Jacobians (Table 4, case 1).

Dropping the circumferential flow term of Eq. (2), the dimensionless Reynolds equation becomes
``d/dxi (h^3 dp/dxi) = -f`` with ``p(±lambda) = 0``, hence

    p(theta, xi) = f(theta) (lambda^2 - xi^2) / (2 h^3)      where f > 0, else 0,

with ``h = 1 - x cos(theta) - y sin(theta)`` and
``f = (y + 2 xdot) cos(theta) + (2 ydot - x) sin(theta)`` (Eq. 3). Integrating over xi
(``∫ (lambda^2 - xi^2) dxi = 4 lambda^3 / 3``), Eq. (5) gives

    Fbar = -(2 lambda^3 / 3) ∫_{f > 0} f / h^3 (cos(theta), sin(theta)) dtheta.

``f = A cos(theta) + B sin(theta)`` is positive on exactly one half-turn
``(theta_1, theta_1 + pi)``, ``theta_1 = atan2(-A, B)``. Because ``f`` vanishes at both ends,
moving the ends does not change the integral to first order, so the Jacobians are the
integrals of the differentiated integrand:

    dFbar/dx    = -(2 lambda^3/3) ∫ [ -sin(theta)/h^3 + 3 f cos(theta)/h^4 ] e(theta)
    dFbar/dy    = -(2 lambda^3/3) ∫ [  cos(theta)/h^3 + 3 f sin(theta)/h^4 ] e(theta)
    dFbar/dxdot = -(2 lambda^3/3) ∫ 2 cos(theta)/h^3 e(theta),   dFbar/dydot likewise with sin.

The integrals are evaluated in closed form up to round-off with Sommerfeld's substitution
``h = (1 - eps^2)/(1 + eps cos(psi))`` (angles measured from the line of centres): it turns
every integrand above into a trigonometric polynomial of degree <= 3 in ``psi``, which a
40-point Gauss-Legendre rule integrates to machine precision over any interval shorter than 2 pi.
So the model is exact for its own equations at any eccentricity < 1 (no quadrature error grows
as h_min -> 0), and its Jacobians are exact derivatives of its force.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.base import (
    BearingModel,
    FilmBearingModel,
    FilmBearingSet,
    FilmForce,
    check_omega,
)
from bearing_fmu.frames import film_law_global, film_state_local
from bearing_fmu.reynolds import film_thickness, source, source_coefficients

__all__ = ["ShortBearing", "ShortSet", "ocvirk_static_force"]

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(40)


@njit(cache=True)
def _sommerfeld_angle(phi, eps, s):
    """Sommerfeld angle psi, h = (1 - eps^2)/(1 + eps cos psi), of the film angle phi."""
    cphi = math.cos(phi)
    den = 1.0 - eps * cphi
    return math.atan2(s * math.sin(phi) / den, (cphi - eps) / den)


@njit(cache=True, inline="always")
def _quadrature_point(mid, half, gx_q, gw_q, eps, s, cg, sg):
    """Gauss point of Sommerfeld's substitution ``h = (1 - eps^2)/(1 + eps cos psi)``:
    ``(cos(theta), sin(theta), h, dphi)`` at ``psi = mid + half gx_q``, with the film angle
    ``phi = theta - gamma`` (cg, sg: cos and sin of gamma) and ``dphi = sqrt(1 - eps^2) /
    (1 + eps cos psi) dpsi`` times the Gauss weight."""
    psi = mid + half * gx_q
    cpsi = math.cos(psi)
    spsi = math.sin(psi)
    den = 1.0 + eps * cpsi
    cphi = (eps + cpsi) / den
    sphi = s * spsi / den
    h = (1.0 - eps * eps) / den
    dphi = s / den * half * gw_q
    return cphi * cg - sphi * sg, sphi * cg + cphi * sg, h, dphi


@njit(cache=True)
def _degenerate_jacobian(lam, eps, gamma, s, gx, gw, out_dx, out_dv):
    """Jacobians where the source vanishes (f = 0: a centred journal at rest, or the half-speed
    whirl). F is positively homogeneous of degree 1 in the source coefficients (A, B) at fixed
    h, so its one-sided derivatives differ by sign of the source; as the hybrid model does, the
    Jacobian returned is their symmetric part (exact where F is differentiable, e.g. at the
    centre):

        dFbar/dA = -(lambda^3 / 3) int_0^2pi cos(theta) (cos, sin)(theta) / h^3 dtheta,

    dFbar/dB likewise with sin; then ``A = y + 2 xdot``, ``B = 2 ydot - x`` (Eq. 3). The
    integrands become trigonometric polynomials of degree 2 in Sommerfeld's angle, which the
    Gauss rule integrates exactly over the full turn."""
    cg = math.cos(gamma)
    sg = math.sin(gamma)
    half = math.pi
    mid = math.pi
    da = np.zeros(2)
    db = np.zeros(2)
    for q in range(gx.shape[0]):
        c, sn, h, dphi = _quadrature_point(mid, half, gx[q], gw[q], eps, s, cg, sg)
        w = -(lam**3 / 3.0) * dphi / (h * h * h)
        da[0] += w * c * c
        da[1] += w * c * sn
        db[0] += w * sn * c
        db[1] += w * sn * sn
    for r in range(2):
        out_dx[r, 0] = -db[r]
        out_dx[r, 1] = da[r]
        out_dv[r, 0] = 2.0 * da[r]
        out_dv[r, 1] = 2.0 * db[r]


@njit(cache=True)
def _short_bearing_kernel(lam, x, y, xd, yd, gx, gw, out_f, out_dx, out_dv):
    """Eq. (5) with the short-bearing pressure; see the module docstring."""
    a_coef, b_coef = source_coefficients(x, y, xd, yd)  # f = A cos + B sin (Eq. 3)
    for i in range(2):
        out_f[i] = 0.0
        for j in range(2):
            out_dx[i, j] = 0.0
            out_dv[i, j] = 0.0
    eps = math.hypot(x, y)
    gamma = math.atan2(y, x)
    s = math.sqrt(1.0 - eps * eps)
    if a_coef == 0.0 and b_coef == 0.0:
        _degenerate_jacobian(lam, eps, gamma, s, gx, gw, out_dx, out_dv)
        return  # f == 0: no pressure anywhere, F = 0
    theta1 = math.atan2(-a_coef, b_coef)
    # Sommerfeld angle psi of the two ends phi = theta - gamma (monotone map, unwrapped).
    psi_a = _sommerfeld_angle(theta1 - gamma, eps, s)
    psi_b = _sommerfeld_angle(theta1 + math.pi - gamma, eps, s)
    if psi_b <= psi_a:
        psi_b += 2.0 * math.pi
    half = 0.5 * (psi_b - psi_a)
    mid = 0.5 * (psi_b + psi_a)
    cg = math.cos(gamma)
    sg = math.sin(gamma)
    scale = -(2.0 / 3.0) * lam**3
    for q in range(gx.shape[0]):
        c, sn, h, dphi = _quadrature_point(mid, half, gx[q], gw[q], eps, s, cg, sg)
        f = source(a_coef, b_coef, c, sn)
        if f < 0.0:
            f = 0.0  # round-off at the ends only
        ih3 = 1.0 / (h * h * h)
        ih4 = ih3 / h
        w = scale * dphi
        # force
        out_f[0] += w * f * ih3 * c
        out_f[1] += w * f * ih3 * sn
        # d/dx, d/dy of f/h^3
        gx_ = -sn * ih3 + 3.0 * f * c * ih4
        gy_ = c * ih3 + 3.0 * f * sn * ih4
        out_dx[0, 0] += w * gx_ * c
        out_dx[1, 0] += w * gx_ * sn
        out_dx[0, 1] += w * gy_ * c
        out_dx[1, 1] += w * gy_ * sn
        # d/dxdot, d/dydot
        out_dv[0, 0] += w * 2.0 * c * ih3 * c
        out_dv[1, 0] += w * 2.0 * c * ih3 * sn
        out_dv[0, 1] += w * 2.0 * sn * ih3 * c
        out_dv[1, 1] += w * 2.0 * sn * ih3 * sn


#: :func:`short_global` status for an input the kernel is not called with (the caller raises
#: the checks' own errors, :func:`bearing_fmu.base.check_state`)
BAD_STATE = -1


@njit(cache=True)
def short_global(lam, gx, gw, q, s, omega, clearance, fs, out):
    """The short-bearing force and Jacobians (``_short_bearing_kernel``) in SI units and the
    global frame: one call per bearing.

    ``q`` (2, 2) turns global components into local ones
    (:class:`bearing_fmu.frames.LocalFrame`), ``s`` is the global journal state [s, t, sdot,
    tdot] [m, m/s], ``omega`` the speed [rad/s], ``fs`` the force scale of Eq. (5) at omega
    [N]. Writes ``out`` (5, 2): row 0 the film force [N], rows 1-2 Kb = -dF/dX [N/m], rows 3-4
    Cb = -dF/dXdot [N s/m], global.
    The arithmetic of :meth:`bearing_fmu.base.FilmBearingModel.evaluate` and the frame
    conversions, as ``bearing_fmu.hybrid._kernels.hybrid_global``. Returns 0, or
    :data:`BAD_STATE` for a non-finite state or an eccentricity ratio >= 1 (nothing evaluated).
    """
    xb, yb, xdb, ydb, ok = film_state_local(q, s, clearance, omega)
    if not ok:
        return BAD_STATE
    res = np.empty((5, 2))
    _short_bearing_kernel(lam, xb, yb, xdb, ydb, gx, gw, res[0], res[1:3], res[3:5])
    film_law_global(q, res, fs, clearance, omega, out)
    return 0


@njit(cache=True)
def short_set_global(lam, gx, gw, q, omega, clearance, fs, s, out):
    """:func:`short_global` for a set of bearings in one call, in their order (:class:`ShortSet`):
    the set's arrays (nb,) or (nb, 2, 2) first, then the journal states ``s`` (nb, 4) and the
    output ``out`` (nb, 5, 2). Returns ``(-1, 0)``, or the index of the first bearing whose
    status is not 0 and that status (the bearings after it are not evaluated)."""
    for b in range(s.shape[0]):
        status = short_global(lam[b], gx, gw, q[b], s[b], omega[b], clearance[b], fs[b], out[b])
        if status != 0:
            return b, status
    return -1, 0


class ShortBearing(FilmBearingModel):
    """Ocvirk's short-bearing theory with the half-Sommerfeld (pi-film) condition: Eq. (2)
    without its circumferential term, and p = 0 where f < 0 in place of Eq. (4).

    Valid for L/D < 1/8 (paper Sec. 4.2.1); Table 4 case 1 uses it at L/D = 0.72 to show how
    far off it is there.

    Examples
    --------
    >>> from bearing_fmu.base import BearingData
    >>> b = BearingData(diameter=0.07, length=0.005, clearance=1.5e-4, viscosity=0.0288)
    >>> ff = ShortBearing(b).dimensionless(0.5, 0.0)
    >>> fr, ft = ocvirk_static_force(b.lambda_, 0.5)
    >>> bool(np.allclose(ff.force, [fr, ft]))
    True
    """

    name = "short"

    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        f = np.zeros(2)
        dx = np.zeros((2, 2))
        dv = np.zeros((2, 2))
        _short_bearing_kernel(
            self.bearing.lambda_, xbar, ybar, xbar_dot, ybar_dot, _GAUSS_X, _GAUSS_W, f, dx, dv
        )
        if not jacobian:
            return FilmForce(force=f)
        return FilmForce(force=f, d_position=dx, d_velocity=dv)

    def evaluate_global(self, q, state, omega, out):
        """One compiled call (:func:`short_global`): the numbers of
        :meth:`~bearing_fmu.base.FilmBearingModel.evaluate` and the frame conversions of the
        base class."""
        omega = check_omega(omega)
        b = self.bearing
        status = short_global(b.lambda_, _GAUSS_X, _GAUSS_W, q, state, omega, b.clearance,
                              b.force_scale(omega), out)
        if status != 0:
            self.raise_status(status, q, state, omega)

    def raise_status(self, status, q, state, omega):
        """Raise the error of a failed :meth:`evaluate_global` (:func:`short_global`'s status
        ``status`` at the global state ``state`` [m, m/s] of the frame ``q``): the state
        check's error (:data:`BAD_STATE`, the kernel's only failure)."""
        BearingModel.evaluate_global(self, q, state, omega, np.empty((5, 2)))
        raise RuntimeError(f"short bearing: status {status} at a state it accepts")

    def pressure_field(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, n_xi=33):
        """Dimensionless pressure (theta [rad], xi [-], p[theta, xi]) of the short solution."""
        lam = self.bearing.lambda_
        return _short_pressure_field(lam, xbar, ybar, xbar_dot, ybar_dot, n_xi=n_xi)


class ShortSet(FilmBearingSet):
    """Short bearings evaluated in one compiled call (:func:`short_set_global`): the numbers of
    one :meth:`ShortBearing.evaluate_global` per bearing, bit for bit, for a compiled caller
    (:mod:`orchestrator.coupling.step`). The model has no memory: the set holds its
    parameters only (:class:`bearing_fmu.base.FilmBearingSet`, and each bearing's L/D).
    """

    kind = "short bearings"

    def __init__(self, models, q, omegas):
        super().__init__(models, q, omegas)
        self._lam = np.array([m.bearing.lambda_ for m in self.models])

    @staticmethod
    def fits(models) -> bool:
        """Whether the models can share one call: all :class:`ShortBearing`."""
        return len(models) > 0 and all(type(m) is ShortBearing for m in models)

    def evaluate_global(self, states, out) -> None:
        """Film force [N], Kb [N/m], Cb [N s/m] (global frame) of every bearing at its global
        journal state ``states`` (nb, 4) [m, m/s] into ``out`` (nb, 5, 2). A failing bearing
        raises that bearing's error, with its index in ``bearing_index`` (0-based)."""
        b, status = short_set_global(*self.kernel_arguments(), states, out)
        if b >= 0:
            self.raise_status(b, status, states)

    def kernel_arguments(self) -> tuple:
        """The arguments of :func:`short_set_global` before the journal states and the output
        (7): what a compiled caller passes on."""
        return (self._lam, _GAUSS_X, _GAUSS_W, self._q, self._omega, self._clearance, self._fs)


def ocvirk_static_force(lambda_: float, eps: float) -> tuple[float, float]:
    """Closed-form short-bearing force for a static journal at (eps, 0) [dimensionless].

    The classical Ocvirk result in the paper's scaling (``Fbar = F / (6 mu omega R^2 (R/C)^2)``,
    lambda = L/D): with ``f = -eps sin(theta) > 0`` on (pi, 2 pi),

    ``Fbar_x = -(2 lambda^3/3) * 2 eps^2 / (1 - eps^2)^2``,
    ``Fbar_y = +(2 lambda^3/3) * pi eps / (2 (1 - eps^2)^{3/2})``.

    Returns
    -------
    (Fbar_x, Fbar_y) : tuple of float
    """
    if not 0.0 <= eps < 1.0:
        raise ValueError(f"eccentricity ratio {eps!r} must be in [0, 1)")
    k = 2.0 * lambda_**3 / 3.0
    fx = -k * 2.0 * eps**2 / (1.0 - eps**2) ** 2
    fy = k * math.pi * eps / (2.0 * (1.0 - eps**2) ** 1.5)
    return fx, fy


def _short_pressure_field(lambda_, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, n_theta=192, n_xi=33):
    """Short-bearing pressure p(theta, xi) on a grid (dimensionless, for plots)."""
    theta = np.linspace(0.0, 2.0 * np.pi, n_theta + 1)
    xi = np.linspace(-lambda_, lambda_, n_xi)
    c, s = np.cos(theta), np.sin(theta)
    h = film_thickness.py_func(xbar, ybar, c, s)
    f = source.py_func(*source_coefficients.py_func(xbar, ybar, xbar_dot, ybar_dot), c, s)
    p = np.maximum(f, 0.0)[:, None] / (2.0 * h[:, None] ** 3) * (lambda_**2 - xi[None, :] ** 2)
    return theta, xi, p
