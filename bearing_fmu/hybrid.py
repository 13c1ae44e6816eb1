"""Hybrid method for finite journal bearings (paper Sec. 2.2.2, Eq. 6-7; Table 4 cases 0, 2, 3).

Separated pressure ``p(theta, xi) = [cosh(k lambda) - cosh(k xi)] a(theta)`` (Eq. 6), ``a``
piecewise linear on n periodic nodes (Eq. 7). For fixed ``t = (k lambda)^2`` the Ritz
minimisation of the Reynolds functional over ``a >= 0`` is a symmetric cyclic tridiagonal
linear complementarity problem, solved exactly by a primal-dual active set (the Swift-Stieber
condition, Eq. 4, holds at the discrete free boundaries by construction); ``t`` is then moved by
Newton on the reduced functional ``J*(t)`` (3-5 iterations cold, 1-2 warm). Forces and their
derivatives with respect to (x, y, xdot, ydot) come from the same factorisations with the
active set frozen, differentiated through ``t`` (no numerical differentiation).

The derivation, with the axial integrals and the Jacobian formulas, is in
``docs/hybrid-method.md``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.base import FilmBearingModel, FilmForce

_NT = 40  # terms of the axial power series in t = (k lambda)^2


def _axial_coefficients(nt=_NT):
    """Power-series coefficients in t of E = (cosh k - 1)/t and of P0, P1, P2 with
    I0 = P0/E, I1 = P1/E^2, I2 = P2/E^2 (docs/hybrid-method.md, section 3).

    With ``H(u; t) = (cosh kappa - cosh kappa u)/t = sum_m t^(m-1) (1 - u^(2m))/(2m)!``
    (kappa^2 = t) the normalised axial shape is ``g = H/E`` and
    ``P0 = int H du``, ``P1 = int H_u^2 du``, ``P2 = int H^2 du`` over u in [-1, 1]; every
    coefficient is a finite sum of exact moments, so the series have no cancellation for
    t >= 0 and converge for all t (entire functions).
    """
    fact = [math.factorial(k) for k in range(4 * nt + 8)]
    e = np.array([1.0 / fact[2 * k + 2] for k in range(nt)])
    p0 = np.array([(2.0 - 2.0 / (2 * k + 3)) / fact[2 * k + 2] for k in range(nt)])
    p1 = np.zeros(nt)
    p2 = np.zeros(nt)
    for k in range(nt):
        for m in range(1, k + 2):
            n = k + 2 - m
            p1[k] += 2.0 / (2 * k + 3) / (fact[2 * m - 1] * fact[2 * n - 1])
            p2[k] += (2.0 - 2.0 / (2 * m + 1) - 2.0 / (2 * n + 1) + 2.0 / (2 * m + 2 * n + 1)) / (
                fact[2 * m] * fact[2 * n])
    return e, p0, p1, p2


_E, _P0, _P1, _P2 = _axial_coefficients()


@njit(cache=True)
def _series(c, t):
    """Value, first and second derivative of sum c_k t^k (Horner), terms as |t| needs."""
    at = abs(t)
    nt = 16 if at <= 6.0 else (26 if at <= 20.0 else c.shape[0])
    v = 0.0
    d1 = 0.0
    d2 = 0.0
    for k in range(nt - 1, -1, -1):
        d2 = d2 * t + 2.0 * d1
        d1 = d1 * t + v
        v = v * t + c[k]
    return v, d1, d2


@njit(cache=True)
def axial_integrals(t, lam, e, p0, p1, p2, out):
    """out[0:3] = G0, G1, G2; out[3:6] = d/dt; out[6:9] = d2/dt2 (G0 = lam I0, G1 = I1/lam,
    G2 = lam I2; I0 = P0/E, I1 = P1/E^2, I2 = P2/E^2)."""
    E, E1, E2 = _series(e, t)
    a0, a1, a2 = _series(p0, t)
    b0, b1, b2 = _series(p1, t)
    c0, c1, c2 = _series(p2, t)
    # I0 = P0 / E
    i0 = a0 / E
    i0t = (a1 - i0 * E1) / E
    i0tt = (a2 - 2.0 * i0t * E1 - i0 * E2) / E
    # Q = E^2
    Q = E * E
    Q1 = 2.0 * E * E1
    Q2 = 2.0 * (E1 * E1 + E * E2)
    i1 = b0 / Q
    i1t = (b1 - i1 * Q1) / Q
    i1tt = (b2 - 2.0 * i1t * Q1 - i1 * Q2) / Q
    i2 = c0 / Q
    i2t = (c1 - i2 * Q1) / Q
    i2tt = (c2 - 2.0 * i2t * Q1 - i2 * Q2) / Q
    out[0] = lam * i0
    out[1] = i1 / lam
    out[2] = lam * i2
    out[3] = lam * i0t
    out[4] = i1t / lam
    out[5] = lam * i2t
    out[6] = lam * i0tt
    out[7] = i1tt / lam
    out[8] = lam * i2tt


_GT = np.array([0.5 - math.sqrt(15.0) / 10.0, 0.5, 0.5 + math.sqrt(15.0) / 10.0])
_GW = np.array([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0])


@njit(cache=True)
def _solve_segments(d, lo, active, rhs, out, inact0):
    """Solve A_PP out_P = rhs_P, out = 0 off P (A: cyclic tridiagonal with diag d, coupling
    lo[i] between i and i+1), by Thomas sweeps over the runs of active nodes; the ring is
    walked once starting after the inactive node inact0."""
    n = d.shape[0]
    cp = np.empty(n)
    dp = np.empty(n)
    order = np.empty(n, dtype=np.int64)
    idx = inact0
    for k in range(n):
        idx += 1
        if idx == n:
            idx = 0
        order[k] = idx
        out[idx] = 0.0
    k = 0
    while k < n:
        if not active[order[k]]:
            k += 1
            continue
        start = k
        prev = -1
        while k < n and active[order[k]]:
            i = order[k]
            if prev < 0:
                cp[k] = lo[i] / d[i]
                dp[k] = rhs[i] / d[i]
            else:
                den = d[i] - lo[prev] * cp[k - 1]
                cp[k] = lo[i] / den
                dp[k] = (rhs[i] - lo[prev] * dp[k - 1]) / den
            prev = i
            k += 1
        out[order[k - 1]] = dp[k - 1]
        for j in range(k - 2, start - 1, -1):
            out[order[j]] = dp[j] - cp[j] * out[order[j + 1]]


@njit(cache=True)
def _matvec(d, lo, a, out):
    n = d.shape[0]
    out[0] = d[0] * a[0] + lo[0] * a[1] + lo[n - 1] * a[n - 1]
    for i in range(1, n - 1):
        out[i] = d[i] * a[i] + lo[i] * a[i + 1] + lo[i - 1] * a[i - 1]
    out[n - 1] = d[n - 1] * a[n - 1] + lo[n - 1] * a[0] + lo[n - 2] * a[n - 2]


@njit(cache=True)
def _hybrid_kernel(lam, x, y, xd, yd, theta0, pinned, t_init, active, e, p0, p1, p2,
                   gt, gw, trig_q, trig_n, tol, maxit, want_jac, force, dfx, dfv, info):
    n = active.shape[0]
    c0 = math.cos(theta0)
    s0 = math.sin(theta0)
    delta = 2.0 * math.pi / n
    sig = (math.sin(0.5 * delta) / (0.5 * delta)) ** 2
    # element integrals: k_e (stiffness), m11, m12, m22 (mass) for w = h^3, w_x, w_y
    ke = np.empty((3, n))
    m11 = np.empty((3, n))
    m12 = np.empty((3, n))
    m22 = np.empty((3, n))
    for i in range(n):
        for r in range(3):
            ke[r, i] = 0.0
            m11[r, i] = 0.0
            m12[r, i] = 0.0
            m22[r, i] = 0.0
        for q in range(3):
            cq = trig_q[0, i, q]
            sq_ = trig_q[1, i, q]
            c = c0 * cq - s0 * sq_
            s = s0 * cq + c0 * sq_
            h = 1.0 - x * c - y * s
            ws = (h * h * h, -3.0 * h * h * c, -3.0 * h * h * s)
            tau = gt[q]
            for r in range(3):
                w = gw[q] * ws[r]
                ke[r, i] += w / delta
                m11[r, i] += delta * w * (1.0 - tau) * (1.0 - tau)
                m12[r, i] += delta * w * tau * (1.0 - tau)
                m22[r, i] += delta * w * tau * tau
    # nodal loads (exact): F = D sig f(theta_i), derivatives in x, y, xd, yd
    cth = np.empty(n)
    sth = np.empty(n)
    fb = np.empty(n)
    for i in range(n):
        cth[i] = c0 * trig_n[0, i] - s0 * trig_n[1, i]
        sth[i] = s0 * trig_n[0, i] + c0 * trig_n[1, i]
        fb[i] = delta * sig * ((y + 2.0 * xd) * cth[i] + (2.0 * yd - x) * sth[i])
    if pinned:
        active[0] = False
    # diagonals of K and M (r = 0: the operator itself)
    kd = np.empty((3, n))
    kl = np.empty((3, n))
    md = np.empty((3, n))
    ml = np.empty((3, n))
    for r in range(3):
        for i in range(n):
            im = i - 1 if i > 0 else n - 1
            kd[r, i] = ke[r, im] + ke[r, i]
            kl[r, i] = -ke[r, i]
            md[r, i] = m22[r, im] + m11[r, i]
            ml[r, i] = m12[r, i]
    g = np.empty(9)
    d = np.empty(n)
    lo = np.empty(n)
    a = np.zeros(n)
    w = np.empty(n)
    b = np.empty(n)
    cvec = np.empty(n)
    z = np.empty(n)
    tmp = np.empty(n)
    t = t_init
    lcp_total = 0
    jss = 0.0
    n_t_iter = 0
    for _ in range(maxit):
        n_t_iter += 1
        axial_integrals(t, lam, e, p0, p1, p2, g)
        for i in range(n):
            d[i] = g[2] * kd[0, i] + g[1] * md[0, i]
            lo[i] = g[2] * kl[0, i] + g[1] * ml[0, i]
            b[i] = g[0] * fb[i]
        # primal-dual active set on the LCP a >= 0, Aa - b >= 0, a (Aa - b) = 0
        for _ in range(4 * n):
            lcp_total += 1
            inact0 = -1
            for i in range(n):
                if not active[i]:
                    inact0 = i
                    break
            if inact0 < 0:  # the whole ring pressurised cannot be a solution: drop min b
                inact0 = 0
                for i in range(n):
                    if b[i] < b[inact0]:
                        inact0 = i
                active[inact0] = False
            _solve_segments(d, lo, active, b, a, inact0)
            _matvec(d, lo, a, w)
            changed = False
            for i in range(n):
                if active[i]:
                    if a[i] <= 0.0:
                        active[i] = False
                        changed = True
                elif w[i] - b[i] < 0.0 and not (pinned and i == 0):
                    active[i] = True
                    changed = True
            if not changed:
                break
        for i in range(n):
            if not active[i]:
                a[i] = 0.0
        # t-Newton: J*' = 1/2 a A_t a - b_t a ; J*'' = 1/2 a A_tt a - b_tt a - c.z
        for i in range(n):
            d[i] = g[5] * kd[0, i] + g[4] * md[0, i]
            lo[i] = g[5] * kl[0, i] + g[4] * ml[0, i]
        _matvec(d, lo, a, tmp)
        js = 0.0
        for i in range(n):
            cvec[i] = (tmp[i] - g[3] * fb[i]) if active[i] else 0.0
            js += 0.5 * a[i] * tmp[i] - g[3] * fb[i] * a[i]
        for i in range(n):
            d[i] = g[8] * kd[0, i] + g[7] * md[0, i]
            lo[i] = g[8] * kl[0, i] + g[7] * ml[0, i]
        _matvec(d, lo, a, tmp)
        jss = 0.0
        for i in range(n):
            jss += 0.5 * a[i] * tmp[i] - g[6] * fb[i] * a[i]
        for i in range(n):
            d[i] = g[2] * kd[0, i] + g[1] * md[0, i]
            lo[i] = g[2] * kl[0, i] + g[1] * ml[0, i]
        inact0 = 0
        for i in range(n):
            if not active[i]:
                inact0 = i
                break
        _solve_segments(d, lo, active, cvec, z, inact0)
        for i in range(n):
            jss -= cvec[i] * z[i]
        if jss > 0.0:
            dt = -js / jss
        else:
            dt = -2.0 if js > 0.0 else 2.0
        lim = max(2.0, 0.5 * abs(t))
        if dt > lim:
            dt = lim
        elif dt < -lim:
            dt = -lim
        t_new = min(max(t + dt, -9.0), 60.0)
        converged = abs(t_new - t) <= tol * (1.0 + abs(t))
        t = t_new
        if converged:
            break
    # final solve at the converged t (same active set, Newton step was tiny)
    axial_integrals(t, lam, e, p0, p1, p2, g)
    for i in range(n):
        d[i] = g[2] * kd[0, i] + g[1] * md[0, i]
        lo[i] = g[2] * kl[0, i] + g[1] * ml[0, i]
        b[i] = g[0] * fb[i]
    inact0 = 0
    for i in range(n):
        if not active[i]:
            inact0 = i
            break
    _solve_segments(d, lo, active, b, a, inact0)
    sa_c = 0.0
    sa_s = 0.0
    for i in range(n):
        sa_c += a[i] * cth[i]
        sa_s += a[i] * sth[i]
    force[0] = -g[0] * delta * sig * sa_c
    force[1] = -g[0] * delta * sig * sa_s
    info[0] = t
    info[1] = n_t_iter
    info[2] = lcp_total
    if not want_jac:
        return
    # c, z, J*'' at the final point
    for i in range(n):
        d[i] = g[5] * kd[0, i] + g[4] * md[0, i]
        lo[i] = g[5] * kl[0, i] + g[4] * ml[0, i]
    _matvec(d, lo, a, tmp)
    for i in range(n):
        cvec[i] = (tmp[i] - g[3] * fb[i]) if active[i] else 0.0
    for i in range(n):
        d[i] = g[8] * kd[0, i] + g[7] * md[0, i]
        lo[i] = g[8] * kl[0, i] + g[7] * ml[0, i]
    _matvec(d, lo, a, tmp)
    jss = 0.0
    for i in range(n):
        jss += 0.5 * a[i] * tmp[i] - g[6] * fb[i] * a[i]
    for i in range(n):
        d[i] = g[2] * kd[0, i] + g[1] * md[0, i]
        lo[i] = g[2] * kl[0, i] + g[1] * ml[0, i]
    _solve_segments(d, lo, active, cvec, z, inact0)
    for i in range(n):
        jss -= cvec[i] * z[i]
    r = np.empty(n)
    da = np.empty(n)
    fq = np.empty(n)
    dq_d = np.empty(n)
    dq_l = np.empty(n)
    for q in range(4):
        # load derivative F_q and operator derivative A_q (position only)
        for i in range(n):
            if q == 0:
                fq[i] = -delta * sig * sth[i]
            elif q == 1:
                fq[i] = delta * sig * cth[i]
            elif q == 2:
                fq[i] = 2.0 * delta * sig * cth[i]
            else:
                fq[i] = 2.0 * delta * sig * sth[i]
        sq = 0.0
        if q < 2:
            rr = q + 1
            for i in range(n):
                dq_d[i] = g[2] * kd[rr, i] + g[1] * md[rr, i]
                dq_l[i] = g[2] * kl[rr, i] + g[1] * ml[rr, i]
            _matvec(dq_d, dq_l, a, tmp)
            for i in range(n):
                r[i] = (tmp[i] - g[0] * fq[i]) if active[i] else 0.0
            for i in range(n):
                dq_d[i] = g[5] * kd[rr, i] + g[4] * md[rr, i]
                dq_l[i] = g[5] * kl[rr, i] + g[4] * ml[rr, i]
            _matvec(dq_d, dq_l, a, tmp)
            for i in range(n):
                sq += 0.5 * a[i] * tmp[i] - g[3] * fq[i] * a[i]
        else:
            for i in range(n):
                r[i] = -g[0] * fq[i] if active[i] else 0.0
                sq -= g[3] * fq[i] * a[i]
        _solve_segments(d, lo, active, r, da, inact0)
        cda = 0.0
        for i in range(n):
            da[i] = -da[i]
            cda += cvec[i] * da[i]
        dtq = -(sq + cda) / jss
        sc = 0.0
        ss = 0.0
        for i in range(n):
            dai = da[i] - z[i] * dtq
            sc += dai * cth[i]
            ss += dai * sth[i]
        col0 = -delta * sig * (g[0] * sc + g[3] * dtq * sa_c)
        col1 = -delta * sig * (g[0] * ss + g[3] * dtq * sa_s)
        if q < 2:
            dfx[0, q] = col0
            dfx[1, q] = col1
        else:
            dfv[0, q - 2] = col0
            dfv[1, q - 2] = col1


class HybridBearing(FilmBearingModel):
    """Hybrid (separated Ritz) Reynolds solver with analytic Jacobians.

    Parameters
    ----------
    bearing : BearingData
    n : int
        Circumferential nodes of a(theta) (paper: 192, Table 4 case 3: 384).
    pinned_start : bool
        Impose p = 0 on the line of maximum film thickness (the convention of Raimondi &
        Boyd's design tables). The paper's formulation (default) leaves the film start free.
    tol : float
        Convergence of t = (k lambda)^2, relative.
    maxit : int
        Newton iterations on t.

    Examples
    --------
    >>> from bearing_fmu.base import BearingData
    >>> hb = HybridBearing(BearingData(1.0, 1.0, 1e-3, 1.0), pinned_start=True)
    >>> f = hb.dimensionless(0.6, 0.0).force
    >>> round(float(1.0 / (3 * np.pi * np.hypot(*f))), 3)  # Sommerfeld number; R&B: 0.121
    0.121
    """

    name = "hybrid"

    def __init__(self, bearing, n=192, pinned_start=False, tol=1e-10, maxit=30):
        super().__init__(bearing)
        if n < 16:
            raise ValueError(f"n = {n} circumferential nodes: need at least 16")
        self.n = int(n)
        self.pinned_start = bool(pinned_start)
        self.tol = tol
        self.maxit = maxit
        self._t = 1.0
        self._active = None
        self.last_info = None
        delta = 2 * math.pi / self.n
        thq = (np.arange(self.n)[:, None] + _GT[None, :]) * delta
        self._trig_q = np.stack([np.cos(thq), np.sin(thq)])
        thn = np.arange(self.n) * delta
        self._trig_n = np.stack([np.cos(thn), np.sin(thn)])

    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        """Dimensionless force (Eq. 5) and its analytic derivatives; warm-started."""
        n = self.n
        if self.pinned_start:
            theta0 = math.atan2(ybar, xbar) + math.pi  # h_max
            active = np.ones(n, dtype=np.bool_)
        else:
            theta0 = 0.0
            if self._active is None:
                th = np.arange(n) * 2 * math.pi / n
                f = (ybar + 2 * xbar_dot) * np.cos(th) + (2 * ybar_dot - xbar) * np.sin(th)
                self._active = f > 0
            active = self._active
        force = np.zeros(2)
        dfx = np.zeros((2, 2))
        dfv = np.zeros((2, 2))
        info = np.zeros(3)
        _hybrid_kernel(self.bearing.lambda_, xbar, ybar, xbar_dot, ybar_dot, theta0,
                       self.pinned_start, self._t, active, _E, _P0, _P1, _P2, _GT, _GW,
                       self._trig_q, self._trig_n, self.tol, self.maxit, jacobian, force, dfx,
                       dfv, info)
        self._t = info[0]
        self.last_info = dict(t=info[0], k=math.sqrt(abs(info[0])) / self.bearing.lambda_,
                              t_iterations=int(info[1]), lcp_iterations=int(info[2]))
        if not jacobian:
            return FilmForce(force)
        return FilmForce(force, dfx, dfv)
