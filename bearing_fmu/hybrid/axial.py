"""Axial integrals of the separated pressure of the hybrid method (paper Eq. 6).

With ``u = xi / lambda``, ``kappa = k lambda`` and ``t = kappa^2``, the axial shape of Eq. (6)
normalised to 1 at mid-length is

    g(u; t) = (cosh kappa - cosh kappa u) / (cosh kappa - 1)            (g(+-1) = 0, g(0) = 1)

and the Ritz functional needs (docs/hybrid-method.md, section 2)

    I0 = int g du,   I1 = int g_u^2 du,   I2 = int g^2 du        (u in [-1, 1]),
    G0 = lambda I0,  G1 = I1 / lambda,    G2 = lambda I2         (integrals over xi).

Closed forms (c = cosh kappa, s = sinh kappa, D = c - 1):
``I0 = (2c - 2s/kappa)/D``, ``I1 = kappa (s c - kappa)/D^2``, ``I2 = (2c^2 - 3cs/kappa + 1)/D^2``
— 0/0 at t -> 0 and imaginary for t < 0. They are therefore evaluated as quotients of power
series in t, exact for every t (the functions are entire): with
``H(u; t) = (cosh kappa - cosh kappa u)/t = sum_{m>=1} t^(m-1) (1 - u^(2m)) / (2m)!`` and
``E(t) = (cosh kappa - 1)/t = sum_{m>=1} t^(m-1) / (2m)!`` one has g = H/E and

    I0 = P0 / E,  I1 = P1 / E^2,  I2 = P2 / E^2,   P0 = int H,  P1 = int H_u^2,  P2 = int H^2,

whose Taylor coefficients are finite sums of exact moments (:func:`axial_coefficients`). For
t >= 0 all terms are positive (no cancellation); for -9 <= t < 0 the alternating sums lose at
most ~1e-13. t -> 0 gives (4/3, 8/3, 16/15), the short-bearing parabola 1 - u^2.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_fmu.hybrid._workspace import kernel

__all__ = ["AXIAL_COEF", "axial_coefficients", "axial_integrals", "axial_shape"]

#: number of Taylor terms kept (enough for ``|t| <= T_MAX`` to round-off)
N_TERMS = 60
#: largest ``t`` the kernels use
T_MAX = 150.0
#: largest ``-t`` the kernels use (t < 0: k imaginary, the axial shape a cosine)
T_LOW = 9.0
#: ``|t|`` limits below which 16, 26 and 40 terms reach round-off (the term-count switches)
T_SWITCH = (6.0, 20.0, 60.0)


def axial_coefficients(nt: int = N_TERMS) -> np.ndarray:
    """Taylor coefficients in t of E, P0, P1, P2 (rows 0-3), shape (4, nt).

    ``E_k = 1/(2k+2)!``, ``P0_k = (2 - 2/(2k+3))/(2k+2)!``,
    ``P1_k = sum_{m+n=k+2} 2/((2k+3) (2m-1)! (2n-1)!)``,
    ``P2_k = sum_{m+n=k+2} [2 - 2/(2m+1) - 2/(2n+1) + 2/(2m+2n+1)] / ((2m)! (2n)!)``
    (m, n >= 1), from the term-by-term products of the series of H and H_u.
    """
    fact = [math.factorial(k) for k in range(4 * nt + 8)]
    c = np.zeros((4, nt))
    for k in range(nt):
        c[0, k] = 1.0 / fact[2 * k + 2]
        c[1, k] = (2.0 - 2.0 / (2 * k + 3)) / fact[2 * k + 2]
        for m in range(1, k + 2):
            n = k + 2 - m
            c[2, k] += 2.0 / (2 * k + 3) / (fact[2 * m - 1] * fact[2 * n - 1])
            c[3, k] += (2.0 - 2.0 / (2 * m + 1) - 2.0 / (2 * n + 1)
                        + 2.0 / (2 * m + 2 * n + 1)) / (fact[2 * m] * fact[2 * n])
    return c


#: the coefficient table passed to the kernels
AXIAL_COEF = axial_coefficients()


@kernel(error_model="numpy")
def _series(c, row, t):
    """Value, first and second t-derivative of sum_k c[row, k] t^k (Horner)."""
    at = abs(t)
    nt = 16 if at <= 6.0 else (26 if at <= 20.0 else (40 if at <= 60.0 else c.shape[1]))
    v = 0.0
    d1 = 0.0
    d2 = 0.0
    for k in range(nt - 1, -1, -1):
        d2 = d2 * t + 2.0 * d1
        d1 = d1 * t + v
        v = v * t + c[row, k]
    return v, d1, d2


@kernel(error_model="numpy")
def axial_integrals(t, lam, coef, out):
    """G0, G1, G2 and their first and second t-derivatives.

    Parameters
    ----------
    t : float
        ``(k lambda)^2``, -9 <= t <= 150 (t < 0: imaginary k).
    lam : float
        lambda = L/D.
    coef : ndarray (4, nt)
        :data:`AXIAL_COEF`.
    out : ndarray (9,)
        Filled with ``G0, G1, G2, G0', G1', G2', G0'', G1'', G2''`` (' = d/dt).
    """
    # np.int64(k): plain rows, not numba's literals (one compilation of _series for the four)
    e0, e1, e2 = _series(coef, np.int64(0), t)
    a0, a1, a2 = _series(coef, np.int64(1), t)
    b0, b1, b2 = _series(coef, np.int64(2), t)
    c0, c1, c2 = _series(coef, np.int64(3), t)
    # I0 = P0 / E (quotient rule twice)
    i0 = a0 / e0
    i0t = (a1 - i0 * e1) / e0
    i0tt = (a2 - 2.0 * i0t * e1 - i0 * e2) / e0
    # I1 = P1 / Q, I2 = P2 / Q with Q = E^2
    q0 = e0 * e0
    q1 = 2.0 * e0 * e1
    q2 = 2.0 * (e1 * e1 + e0 * e2)
    i1 = b0 / q0
    i1t = (b1 - i1 * q1) / q0
    i1tt = (b2 - 2.0 * i1t * q1 - i1 * q2) / q0
    i2 = c0 / q0
    i2t = (c1 - i2 * q1) / q0
    i2tt = (c2 - 2.0 * i2t * q1 - i2 * q2) / q0
    out[0] = lam * i0
    out[1] = i1 / lam
    out[2] = lam * i2
    out[3] = lam * i0t
    out[4] = i1t / lam
    out[5] = lam * i2t
    out[6] = lam * i0tt
    out[7] = i1tt / lam
    out[8] = lam * i2tt


def _shc(x: np.ndarray, t: float) -> np.ndarray:
    """sinh(x)/x for t >= 0, sin(x)/x for t < 0 (x = kappa-scaled argument), 1 at x = 0."""
    if t >= 0.0:
        return np.where(x == 0.0, 1.0, np.sinh(x) / np.where(x == 0.0, 1.0, x))
    return np.where(x == 0.0, 1.0, np.sin(x) / np.where(x == 0.0, 1.0, x))


def axial_shape(u, t: float) -> np.ndarray:
    """The normalised axial shape g(u; t) of Eq. (6), u = xi/lambda in [-1, 1].

    Cancellation-free: ``g = (1 - u^2) shc(kappa (1+u)/2) shc(kappa (1-u)/2) / shc(kappa/2)^2``
    with ``shc(x) = sinh(x)/x`` (``sin(x)/x`` and kappa = sqrt(-t) for t < 0), from
    ``cosh A - cosh B = 2 sinh((A+B)/2) sinh((A-B)/2)``.
    """
    u = np.asarray(u, dtype=float)
    kap = math.sqrt(abs(t))
    return ((1.0 - u) * (1.0 + u) * _shc(0.5 * kap * (1.0 + u), t) * _shc(0.5 * kap * (1.0 - u), t)
            / _shc(np.array(0.5 * kap), t) ** 2)
