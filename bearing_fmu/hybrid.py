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


@njit(cache=True, error_model="numpy", fastmath=True)
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


@njit(cache=True, error_model="numpy", fastmath=True)
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


@njit(cache=True, error_model="numpy", fastmath=True)
def _factor(d, lo, active, order, cp, piv, runs):
    """Thomas factorisation of A_PP over the runs of active nodes (walked from the node after
    the first inactive one, so no run wraps). Returns the number of runs; run r covers
    positions runs[r, 0] <= k < runs[r, 1] of ``order``."""
    n = d.shape[0]
    inact0 = 0
    for i in range(n):
        if not active[i]:
            inact0 = i
            break
    idx = inact0
    for k in range(n):
        idx += 1
        if idx == n:
            idx = 0
        order[k] = idx
    nr = 0
    k = 0
    while k < n:
        if not active[order[k]]:
            k += 1
            continue
        start = k
        i = order[k]
        piv[k] = d[i]
        cp[k] = lo[i] / piv[k]
        k += 1
        while k < n and active[order[k]]:
            i = order[k]
            piv[k] = d[i] - lo[order[k - 1]] * cp[k - 1]
            cp[k] = lo[i] / piv[k]
            k += 1
        runs[nr, 0] = start
        runs[nr, 1] = k
        nr += 1
    return nr


@njit(cache=True, error_model="numpy", fastmath=True)
def _substitute(lo, active, order, cp, piv, runs, nr, rhs, out):
    """Solve A_PP out_P = rhs_P with the factors of :func:`_factor`; out = 0 off P."""
    for i in range(out.shape[0]):
        if not active[i]:
            out[i] = 0.0
    for r in range(nr):
        k0 = runs[r, 0]
        k1 = runs[r, 1]
        i = order[k0]
        prev = out[i] = rhs[i] / piv[k0]
        for k in range(k0 + 1, k1):
            i = order[k]
            prev = out[i] = (rhs[i] - lo[order[k - 1]] * prev) / piv[k]
        nxt = prev
        for k in range(k1 - 2, k0 - 1, -1):
            i = order[k]
            nxt = out[i] = out[i] - cp[k] * nxt


@njit(cache=True, error_model="numpy", fastmath=True)
def _elements(x, y, c0, s0, trig_q, gt, gw, delta, jac, ke, m11, m12, m22):
    """Element stiffness k_e and mass moments, 3-point Gauss (docs/hybrid-method.md sec. 3),
    for the weight h^3 (row 0) and, with ``jac``, for -3 h^2 cos and -3 h^2 sin (rows 1, 2)."""
    n = ke.shape[1]
    wa0 = gw[0] * (1.0 - gt[0]) ** 2
    wa1 = gw[1] * (1.0 - gt[1]) ** 2
    wa2 = gw[2] * (1.0 - gt[2]) ** 2
    wb0 = gw[0] * gt[0] * (1.0 - gt[0])
    wb1 = gw[1] * gt[1] * (1.0 - gt[1])
    wb2 = gw[2] * gt[2] * (1.0 - gt[2])
    wc0 = gw[0] * gt[0] ** 2
    wc1 = gw[1] * gt[1] ** 2
    wc2 = gw[2] * gt[2] ** 2
    inv = 1.0 / delta
    for i in range(n):
        c_0 = c0 * trig_q[0, i, 0] - s0 * trig_q[1, i, 0]
        c_1 = c0 * trig_q[0, i, 1] - s0 * trig_q[1, i, 1]
        c_2 = c0 * trig_q[0, i, 2] - s0 * trig_q[1, i, 2]
        s_0 = s0 * trig_q[0, i, 0] + c0 * trig_q[1, i, 0]
        s_1 = s0 * trig_q[0, i, 1] + c0 * trig_q[1, i, 1]
        s_2 = s0 * trig_q[0, i, 2] + c0 * trig_q[1, i, 2]
        h0 = 1.0 - x * c_0 - y * s_0
        h1 = 1.0 - x * c_1 - y * s_1
        h2 = 1.0 - x * c_2 - y * s_2
        for r in range(3 if jac else 1):
            if r == 0:
                w0 = h0 * h0 * h0
                w1 = h1 * h1 * h1
                w2 = h2 * h2 * h2
            elif r == 1:
                w0 = -3.0 * h0 * h0 * c_0
                w1 = -3.0 * h1 * h1 * c_1
                w2 = -3.0 * h2 * h2 * c_2
            else:
                w0 = -3.0 * h0 * h0 * s_0
                w1 = -3.0 * h1 * h1 * s_1
                w2 = -3.0 * h2 * h2 * s_2
            ke[r, i] = (gw[0] * w0 + gw[1] * w1 + gw[2] * w2) * inv
            m11[r, i] = (wa0 * w0 + wa1 * w1 + wa2 * w2) * delta
            m12[r, i] = (wb0 * w0 + wb1 * w1 + wb2 * w2) * delta
            m22[r, i] = (wc0 * w0 + wc1 * w1 + wc2 * w2) * delta


@njit(cache=True, error_model="numpy", fastmath=True)
def _km_apply(r, ke, m11, m12, m22, a, ka, ma):
    """ka = K_r a, ma = M_r a; returns (a.K_r a, a.M_r a)."""
    n = a.shape[0]
    qk = 0.0
    qm = 0.0
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        ka[i] = (ke[r, im] + ke[r, i]) * a[i] - ke[r, i] * a[ip] - ke[r, im] * a[im]
        ma[i] = (m22[r, im] + m11[r, i]) * a[i] + m12[r, i] * a[ip] + m12[r, im] * a[im]
        qk += a[i] * ka[i]
        qm += a[i] * ma[i]
    return qk, qm


@njit(cache=True, error_model="numpy", fastmath=True)
def _hybrid_kernel(lam, x, y, xd, yd, theta0, pinned, t_init, active, e, p0, p1, p2,
                   gt, gw, trig_q, trig_n, tol, maxit, want_jac, force, dfx, dfv, info):
    n = active.shape[0]
    delta = 2.0 * math.pi / n
    dsig = delta * (math.sin(0.5 * delta) / (0.5 * delta)) ** 2  # Delta * sinc^2(Delta/2)
    c0 = math.cos(theta0)
    s0 = math.sin(theta0)
    ke = np.empty((3, n))
    m11 = np.empty((3, n))
    m12 = np.empty((3, n))
    m22 = np.empty((3, n))
    _elements(x, y, c0, s0, trig_q, gt, gw, delta, want_jac, ke, m11, m12, m22)
    cth = np.empty(n)
    sth = np.empty(n)
    fb = np.empty(n)
    kd = np.empty(n)
    kl = np.empty(n)
    md = np.empty(n)
    for i in range(n):
        cth[i] = c0 * trig_n[0, i] - s0 * trig_n[1, i]
        sth[i] = s0 * trig_n[0, i] + c0 * trig_n[1, i]
        fb[i] = dsig * ((y + 2.0 * xd) * cth[i] + (2.0 * yd - x) * sth[i])  # F_i, exact
        im = i - 1 if i > 0 else n - 1
        kd[i] = ke[0, im] + ke[0, i]
        kl[i] = -ke[0, i]
        md[i] = m22[0, im] + m11[0, i]
    if pinned:
        active[0] = False
    g = np.empty(9)
    d = np.empty(n)
    lo = np.empty(n)
    a = np.zeros(n)
    b = np.empty(n)
    cvec = np.empty(n)
    z = np.empty(n)
    ka = np.empty(n)
    ma = np.empty(n)
    order = np.empty(n, dtype=np.int64)
    cp = np.empty(n)
    piv = np.empty(n)
    runs = np.empty((n, 2), dtype=np.int64)
    nr = 0
    t = t_init
    if info[11] > 0.0:  # first-order predictor with the exact dt/dq of the previous call
        t += (info[3] * (x - info[7]) + info[4] * (y - info[8]) + info[5] * (xd - info[9])
              + info[6] * (yd - info[10]))
    info[11] = 0.0
    lcp_total = 0
    n_t_iter = 0
    jss = 1.0
    for _ in range(maxit):
        n_t_iter += 1
        axial_integrals(t, lam, e, p0, p1, p2, g)
        for i in range(n):
            d[i] = g[2] * kd[i] + g[1] * md[i]
            lo[i] = g[2] * kl[i] + g[1] * m12[0, i]
            b[i] = g[0] * fb[i]
        # primal-dual active set: a >= 0, w = A a - b >= 0, a w = 0 (section 4)
        for _ in range(4 * n):
            lcp_total += 1
            any_inactive = False
            for i in range(n):
                if not active[i]:
                    any_inactive = True
                    break
            if not any_inactive:  # the whole ring pressurised cannot be the solution
                imin = 0
                for i in range(n):
                    if b[i] < b[imin]:
                        imin = i
                active[imin] = False
            nr = _factor(d, lo, active, order, cp, piv, runs)
            _substitute(lo, active, order, cp, piv, runs, nr, b, a)
            changed = False
            for i in range(n):
                im = i - 1 if i > 0 else n - 1
                ip = i + 1 if i < n - 1 else 0
                if active[i]:
                    if a[i] <= 0.0:
                        active[i] = False
                        changed = True
                elif not (pinned and i == 0):
                    w = d[i] * a[i] + lo[i] * a[ip] + lo[im] * a[im] - b[i]
                    if w < 0.0:
                        active[i] = True
                        changed = True
            if not changed:
                break
        # Newton on J*(t) (section 5)
        qk, qm = _km_apply(0, ke, m11, m12, m22, a, ka, ma)
        af = 0.0
        for i in range(n):
            af += a[i] * fb[i]
            cvec[i] = (g[5] * ka[i] + g[4] * ma[i] - g[3] * fb[i]) if active[i] else 0.0
        js = 0.5 * (g[5] * qk + g[4] * qm) - g[3] * af
        jss = 0.5 * (g[8] * qk + g[7] * qm) - g[6] * af
        _substitute(lo, active, order, cp, piv, runs, nr, cvec, z)
        for i in range(n):
            jss -= cvec[i] * z[i]
        if jss > 0.0:
            dt = -js / jss
        else:
            dt = -2.0 if js > 0.0 else 2.0
        if abs(dt) <= tol * (1.0 + abs(t)):
            break  # (a, t) is the converged pair; c, z, J*'' belong to it
        if abs(dt) <= math.sqrt(tol) * (1.0 + abs(t)):
            # one Newton corrector without a new solve: a(t + dt) = a - z dt + O(dt^2)
            ok = True
            for i in range(n):
                if active[i] and a[i] - z[i] * dt <= 0.0:
                    ok = False
                    break
            if ok:
                for i in range(n):
                    a[i] -= z[i] * dt
                t += dt
                axial_integrals(t, lam, e, p0, p1, p2, g)
                break
        lim = max(2.0, 0.5 * abs(t))
        dt = min(max(dt, -lim), lim)
        t = min(max(t + dt, -9.0), 60.0)
    sa_c = 0.0
    sa_s = 0.0
    for i in range(n):
        sa_c += a[i] * cth[i]
        sa_s += a[i] * sth[i]
    force[0] = -g[0] * dsig * sa_c
    force[1] = -g[0] * dsig * sa_s
    info[0] = t
    info[1] = n_t_iter
    info[2] = lcp_total
    if not want_jac:
        return
    info[7] = x
    info[8] = y
    info[9] = xd
    info[10] = yd
    info[11] = 1.0
    # Jacobians with the active set frozen, through t (section 6)
    rq = np.empty(n)
    da = np.empty(n)
    for q in range(4):
        sq = 0.0
        if q < 2:
            qk, qm = _km_apply(q + 1, ke, m11, m12, m22, a, ka, ma)
            for i in range(n):
                fq = -dsig * sth[i] if q == 0 else dsig * cth[i]
                rq[i] = (g[2] * ka[i] + g[1] * ma[i] - g[0] * fq) if active[i] else 0.0
                sq -= g[3] * fq * a[i]
            sq += 0.5 * (g[5] * qk + g[4] * qm)
        else:
            for i in range(n):
                fq = 2.0 * dsig * (cth[i] if q == 2 else sth[i])
                rq[i] = -g[0] * fq if active[i] else 0.0
                sq -= g[3] * fq * a[i]
        _substitute(lo, active, order, cp, piv, runs, nr, rq, da)
        cda = 0.0
        for i in range(n):
            cda -= cvec[i] * da[i]
        dtq = -(sq + cda) / jss
        info[3 + q] = dtq  # dt/dq: the next call predicts t from it
        sc = 0.0
        ss = 0.0
        for i in range(n):
            dai = -da[i] - z[i] * dtq
            sc += dai * cth[i]
            ss += dai * sth[i]
        col0 = -dsig * (g[0] * sc + g[3] * dtq * sa_c)
        col1 = -dsig * (g[0] * ss + g[3] * dtq * sa_s)
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

    def __init__(self, bearing, n=192, pinned_start=False, tol=1e-9, maxit=30):
        super().__init__(bearing)
        if n < 16:
            raise ValueError(f"n = {n} circumferential nodes: need at least 16")
        self.n = int(n)
        self.pinned_start = bool(pinned_start)
        self.tol = tol
        self.maxit = maxit
        self._t = 1.0
        self._active = None
        # t, Newton passes, active-set passes, dt/dq (4), state of the last Jacobian call (4),
        # predictor valid flag
        self._info = np.zeros(12)
        delta = 2 * math.pi / self.n
        thq = (np.arange(self.n)[:, None] + _GT[None, :]) * delta
        self._trig_q = np.stack([np.cos(thq), np.sin(thq)])
        thn = np.arange(self.n) * delta
        self._trig_n = np.stack([np.cos(thn), np.sin(thn)])

    @property
    def last_info(self) -> dict:
        """Diagnostics of the last call: t = (k lambda)^2, k, Newton and active-set passes."""
        t = float(self._info[0])
        return dict(t=t, k=math.sqrt(abs(t)) / self.bearing.lambda_,
                    t_iterations=int(self._info[1]), lcp_iterations=int(self._info[2]))

    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        """Dimensionless force (Eq. 5) and its analytic derivatives; warm-started.

        Convergence: Newton on t stops when the step is below ``tol (1 + |t|)``, or, when it
        is below ``sqrt(tol) (1 + |t|)``, after one corrector ``a - z dt`` without a new solve
        (force error O(dt^2), Jacobian error O(dt)).
        """
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
        force = np.empty(2)
        dfx = np.empty((2, 2))
        dfv = np.empty((2, 2))
        info = self._info
        _hybrid_kernel(self.bearing.lambda_, xbar, ybar, xbar_dot, ybar_dot, theta0,
                       self.pinned_start, self._t, active, _E, _P0, _P1, _P2, _GT, _GW,
                       self._trig_q, self._trig_n, self.tol, self.maxit, jacobian, force, dfx,
                       dfv, info)
        self._t = info[0]
        if not jacobian:
            return FilmForce(force)
        return FilmForce(force, dfx, dfv)
