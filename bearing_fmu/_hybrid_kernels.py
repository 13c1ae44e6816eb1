"""Numba kernels of the hybrid method (``bearing_fmu.hybrid``; docs/hybrid-method.md).

One call of :func:`hybrid_kernel` does the whole per-state computation: element integrals,
tridiagonal LCP (primal-dual active set with flux extrapolation), Newton on t = (k lambda)^2,
forces and the analytic Jacobians. All arrays are allocated once per model instance:

* ``io`` (float, :data:`IO_SIZE`): inputs, warm-start memory and outputs (indices below);
* ``active`` (bool, n): the pressurised set P, kept between calls (warm start);
* ``ws`` (float, (:data:`WS_ROWS`, n)) and ``iws`` (int, (2, 2n)): work space;
* ``res`` (float, (5, 2)): the results (a new array per call);
* ``trig`` (float, (8, n)): cos/sin at the 3 Gauss points of each element and at the nodes;
* ``coef``: :data:`bearing_fmu.axial.AXIAL_COEF`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.axial import T_MAX, axial_integrals

# --- io layout -------------------------------------------------------------------------------
IO_T = 0  # t = (k lambda)^2: warm start in, converged value out
IO_NT = 1  # Newton passes on t (out)
IO_NLCP = 2  # active-set passes, summed over the Newton passes (out)
IO_STATUS = 3  # 0 ok, 1 LCP not converged, 2 t not converged, 3 A not an M-matrix (out)
IO_DTDQ = 4  # 4: dt/d(x, y, xdot, ydot) of the last Jacobian call (predictor)
IO_QPREV = 8  # 4: the state of that call
IO_PRED = 12  # 1 if the predictor data are valid
IO_LAM = 23  # lambda = L/D
IO_STATE = 24  # 4: x, y, xdot, ydot (in)
IO_TOL = 28
IO_MAXIT = 29
IO_PINNED = 30
IO_JAC = 31  # 1: compute the Jacobians
IO_COLD = 32  # 1: initialise P from f > 0 (set by the caller; cleared by the kernel)
IO_THETA0 = 33  # angle of node 0 (out; nonzero only for the pinned variant)
IO_DTLAST = 34  # last Newton step on t (out)
IO_SIZE = 36

# --- work-space rows -------------------------------------------------------------------------
_KE, _M11, _M12, _M22 = 0, 1, 2, 3  # element integrals, weight h^3
_X0 = 4  # rows 4-7: the same for -3 h^2 cos(theta) (d/dx)
_Y0 = 8  # rows 8-11: the same for -3 h^2 sin(theta) (d/dy)
_KD, _KL, _MD, _ML = 12, 13, 14, 15  # nodal K and M: diagonal and (i, i+1) entries
_FB = 16  # F_i = int f l_i
_D, _LO, _B = 17, 18, 19  # A = G2 K + G1 M (diagonal, (i, i+1)), b = G0 F
_A = 20  # the nodal amplitudes a_i
_CV, _Z = 21, 22  # c = (A_t a - b_t)_P, z = A_PP^-1 c
_KA, _MA = 23, 24  # K_r a, M_r a
_CP, _PIV = 25, 26  # Thomas factors
_COS, _SIN = 27, 28  # cos, sin at the nodes (solution frame)
_NEW = 29  # next active set (0/1) during a PDAS pass
_RQ = 30  # rows 30-33: Jacobian right-hand sides r_q
_DA = 34  # rows 34-37: A_PP^-1 r_q
_SCR = 38  # rows 38-41: small scratch arrays (views, no allocation in the hot path)
WS_ROWS = 42

# Gauss rule on an element (3 points, exact to degree 5)
_GT0 = 0.5 - math.sqrt(15.0) / 10.0
_GT2 = 0.5 + math.sqrt(15.0) / 10.0
_GW0 = 5.0 / 18.0
_GW1 = 8.0 / 18.0

#: a last Newton step on t below _CORRECTOR * tol (1 + |t|) is taken without a new solve
_CORRECTOR = 1000.0
#: extrapolating active-set passes before falling back to the plain primal-dual active set
_EXTRAP_PASSES = 12


def make_trig(n: int) -> np.ndarray:
    """cos (rows 0-2) and sin (rows 3-5) at the Gauss points of element i = [theta_i,
    theta_i+1], cos and sin (rows 6-7) at the nodes theta_i = i 2 pi / n."""
    delta = 2.0 * math.pi / n
    gt = np.array([_GT0, 0.5, _GT2])
    thq = (np.arange(n)[None, :] + gt[:, None]) * delta
    thn = np.arange(n) * delta
    return np.vstack([np.cos(thq), np.sin(thq), np.cos(thn)[None], np.sin(thn)[None]])


@njit(cache=True, fastmath=True)
def _elements(x, y, trig, ws, delta, jac):
    """Element stiffness k_e = int w l'^2 and mass moments int w l_a l_b, 3-point Gauss, for
    w = h^3 and (with ``jac``) w = dh^3/dx = -3h^2 cos, dh^3/dy = -3h^2 sin; then the nodal
    diagonals and couplings of K and M for w = h^3 (docs/hybrid-method.md, section 3)."""
    n = ws.shape[1]
    gw0 = _GW0
    gw1 = _GW1
    wa0 = gw0 * (1.0 - _GT0) ** 2 * delta
    wa1 = gw1 * 0.25 * delta
    wa2 = gw0 * (1.0 - _GT2) ** 2 * delta
    wb0 = gw0 * _GT0 * (1.0 - _GT0) * delta
    wb1 = gw1 * 0.25 * delta
    wc0 = wa2  # tau^2 at tau_0 = (1 - tau_2)^2
    wc2 = wa0
    gk0 = gw0 / delta
    gk1 = gw1 / delta
    ke = ws[_KE]
    m11 = ws[_M11]
    m12 = ws[_M12]
    m22 = ws[_M22]
    c0 = trig[0]
    c1 = trig[1]
    c2 = trig[2]
    s0 = trig[3]
    s1 = trig[4]
    s2 = trig[5]
    for i in range(n):
        h0 = 1.0 - x * c0[i] - y * s0[i]
        h1 = 1.0 - x * c1[i] - y * s1[i]
        h2 = 1.0 - x * c2[i] - y * s2[i]
        w0 = h0 * h0 * h0
        w1 = h1 * h1 * h1
        w2 = h2 * h2 * h2
        ke[i] = gk0 * (w0 + w2) + gk1 * w1
        m11[i] = wa0 * w0 + wa1 * w1 + wa2 * w2
        m12[i] = wb0 * (w0 + w2) + wb1 * w1
        m22[i] = wc0 * w0 + wa1 * w1 + wc2 * w2
    if jac:
        for r in range(2):
            rke = ws[_X0 + 4 * r]
            rm11 = ws[_X0 + 4 * r + 1]
            rm12 = ws[_X0 + 4 * r + 2]
            rm22 = ws[_X0 + 4 * r + 3]
            e0 = trig[3 * r]
            e1 = trig[3 * r + 1]
            e2 = trig[3 * r + 2]
            for i in range(n):
                h0 = 1.0 - x * c0[i] - y * s0[i]
                h1 = 1.0 - x * c1[i] - y * s1[i]
                h2 = 1.0 - x * c2[i] - y * s2[i]
                u0 = -3.0 * h0 * h0 * e0[i]
                u1 = -3.0 * h1 * h1 * e1[i]
                u2 = -3.0 * h2 * h2 * e2[i]
                rke[i] = gk0 * (u0 + u2) + gk1 * u1
                rm11[i] = wa0 * u0 + wa1 * u1 + wa2 * u2
                rm12[i] = wb0 * (u0 + u2) + wb1 * u1
                rm22[i] = wc0 * u0 + wa1 * u1 + wc2 * u2
    im = n - 1
    for i in range(n):
        ws[_KD, i] = ke[im] + ke[i]
        ws[_KL, i] = -ke[i]
        ws[_MD, i] = m22[im] + m11[i]
        ws[_ML, i] = m12[i]
        im = i


@njit(cache=True, fastmath=True)
def _km_apply(ws, r0, a, ka, ma):
    """ka = K_r a, ma = M_r a for the element rows r0..r0+3; returns (a.K_r a, a.M_r a)."""
    n = a.shape[0]
    ke = ws[r0]
    m11 = ws[r0 + 1]
    m12 = ws[r0 + 2]
    m22 = ws[r0 + 3]
    qk = 0.0
    qm = 0.0
    im = n - 1
    for i in range(n):
        ip = i + 1 if i < n - 1 else 0
        ka[i] = (ke[im] + ke[i]) * a[i] - ke[i] * a[ip] - ke[im] * a[im]
        ma[i] = (m22[im] + m11[i]) * a[i] + m12[i] * a[ip] + m12[im] * a[im]
        qk += a[i] * ka[i]
        qm += a[i] * ma[i]
        im = i
    return qk, qm


@njit(cache=True)
def _factor(ws, active, order, runs):
    """Thomas factors (inverse pivots) of A_PP over the runs of consecutive active nodes, the
    ring walked from the node after an inactive one (so no run wraps: no cyclic coupling left).
    Returns the number of runs; run r covers positions runs[r] <= k < runs[n + r] of
    ``order``."""
    n = active.shape[0]
    d = ws[_D]
    lo = ws[_LO]
    cp = ws[_CP]
    piv = ws[_PIV]
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
        piv[k] = 1.0 / d[i]
        cp[k] = lo[i] * piv[k]
        k += 1
        while k < n and active[order[k]]:
            i = order[k]
            piv[k] = 1.0 / (d[i] - lo[order[k - 1]] * cp[k - 1])
            cp[k] = lo[i] * piv[k]
            k += 1
        runs[nr] = start
        runs[n + nr] = k
        nr += 1
    return nr


@njit(cache=True)
def _substitute(ws, active, order, runs, nr, rhs, out):
    """Solve A_PP out_P = rhs_P with the factors of :func:`_factor`; out = 0 off P."""
    n = out.shape[0]
    lo = ws[_LO]
    cp = ws[_CP]
    piv = ws[_PIV]
    for i in range(n):
        if not active[i]:
            out[i] = 0.0
    for r in range(nr):
        k0 = runs[r]
        k1 = runs[n + r]
        i = order[k0]
        prev = rhs[i] * piv[k0]
        out[i] = prev
        for k in range(k0 + 1, k1):
            i = order[k]
            prev = (rhs[i] - lo[order[k - 1]] * prev) * piv[k]
            out[i] = prev
        nxt = prev
        for k in range(k1 - 2, k0 - 1, -1):
            i = order[k]
            nxt = out[i] - cp[k] * nxt
            out[i] = nxt


@njit(cache=True, fastmath=True)
def _substitute4(ws, active, order, runs, nr, r0, o0):
    """Four solves at once (rows r0..r0+3 -> rows o0..o0+3), as :func:`_substitute`."""
    n = active.shape[0]
    lo = ws[_LO]
    cp = ws[_CP]
    piv = ws[_PIV]
    for i in range(n):
        if not active[i]:
            for q in range(4):
                ws[o0 + q, i] = 0.0
    for r in range(nr):
        k0 = runs[r]
        k1 = runs[n + r]
        i = order[k0]
        p0 = ws[r0, i] * piv[k0]
        p1 = ws[r0 + 1, i] * piv[k0]
        p2 = ws[r0 + 2, i] * piv[k0]
        p3 = ws[r0 + 3, i] * piv[k0]
        ws[o0, i] = p0
        ws[o0 + 1, i] = p1
        ws[o0 + 2, i] = p2
        ws[o0 + 3, i] = p3
        for k in range(k0 + 1, k1):
            l = lo[order[k - 1]]
            pv = piv[k]
            i = order[k]
            p0 = (ws[r0, i] - l * p0) * pv
            p1 = (ws[r0 + 1, i] - l * p1) * pv
            p2 = (ws[r0 + 2, i] - l * p2) * pv
            p3 = (ws[r0 + 3, i] - l * p3) * pv
            ws[o0, i] = p0
            ws[o0 + 1, i] = p1
            ws[o0 + 2, i] = p2
            ws[o0 + 3, i] = p3
        for k in range(k1 - 2, k0 - 1, -1):
            i = order[k]
            c = cp[k]
            p0 = ws[o0, i] - c * p0
            p1 = ws[o0 + 1, i] - c * p1
            p2 = ws[o0 + 2, i] - c * p2
            p3 = ws[o0 + 3, i] - c * p3
            ws[o0, i] = p0
            ws[o0 + 1, i] = p1
            ws[o0 + 2, i] = p2
            ws[o0 + 3, i] = p3


@njit(cache=True)
def _lcp(ws, active, order, runs, pinned, maxpass):
    """Primal-dual active set for a >= 0, w = A a - b >= 0, a.w = 0 (section 4).

    Each pass solves A_PP a_P = b_P and sets P <- {a_i > 0 in P} U {w_i < 0 off P}; during the
    first passes an inactive node next to a film end that enters P also brings in the
    following inactive nodes while their summed deficit sum(-b) stays below the end flux
    -A_ej a_e (flux extrapolation: the film end moves by many nodes per pass). Stops when P
    repeats; the solution is then the exact LCP solution. Returns (passes, runs, converged).
    """
    n = active.shape[0]
    a = ws[_A]
    b = ws[_B]
    lo = ws[_LO]
    new = ws[_NEW]
    nr = 0
    for it in range(maxpass):
        any_inactive = False
        for i in range(n):
            if not active[i]:
                any_inactive = True
                break
        if not any_inactive:  # the whole ring pressurised is never the solution (sum b = 0)
            imin = 0
            for i in range(n):
                if b[i] < b[imin]:
                    imin = i
            active[imin] = False
        nr = _factor(ws, active, order, runs)
        _substitute(ws, active, order, runs, nr, b, a)
        extrap = it < _EXTRAP_PASSES
        for i in range(n):
            new[i] = 1.0 if active[i] else 0.0
        changed = False
        im = n - 1
        for i in range(n):
            ip = i + 1 if i < n - 1 else 0
            if active[i]:
                if a[i] <= 0.0:
                    new[i] = 0.0
                    changed = True
            elif not (pinned and i == 0):
                w = lo[im] * a[im] + lo[i] * a[ip] - b[i]
                if w < 0.0:
                    new[i] = 1.0
                    changed = True
                    if extrap and active[im] != active[ip]:
                        if active[im]:
                            step = 1
                            flux = -lo[im] * a[im]
                        else:
                            step = -1
                            flux = -lo[i] * a[ip]
                        deficit = -b[i]
                        j = i
                        for _ in range(n):
                            j += step
                            if j == n:
                                j = 0
                            elif j < 0:
                                j = n - 1
                            if active[j] or (pinned and j == 0):
                                break
                            deficit -= b[j]
                            if deficit > flux:
                                break
                            new[j] = 1.0
            im = i
        if not changed:
            return it + 1, nr, True
        for i in range(n):
            active[i] = new[i] > 0.5
    return maxpass, nr, False


@njit(cache=True)
def _build(g, ws):
    """A = G2 K + G1 M (diagonal and couplings), b = G0 F; returns max of the couplings
    (A is a Stieltjes matrix, as the active-set method needs, when it is < 0)."""
    n = ws.shape[1]
    d = ws[_D]
    lo = ws[_LO]
    b = ws[_B]
    kd = ws[_KD]
    kl = ws[_KL]
    md = ws[_MD]
    ml = ws[_ML]
    fb = ws[_FB]
    g0 = g[0]
    g1 = g[1]
    g2 = g[2]
    lmax = -1e300
    for i in range(n):
        d[i] = g2 * kd[i] + g1 * md[i]
        lo[i] = g2 * kl[i] + g1 * ml[i]
        b[i] = g0 * fb[i]
        if lo[i] > lmax:
            lmax = lo[i]
    return lmax


@njit(cache=True)
def _solve(ws, active, order, runs, g, coef, lam, t, tol, maxit, pinned, stat):
    """LCP (section 4) and Newton on J*(t) (section 5) for the source in ws[_FB].

    Leaves a (ws[_A]), the factors of A_PP, c, z at the converged t. ``stat`` receives
    (Newton passes, active-set passes, status, J*'', runs, last step). Returns t.
    """
    n = active.shape[0]
    a = ws[_A]
    fb = ws[_FB]
    cv = ws[_CV]
    z = ws[_Z]
    ka = ws[_KA]
    ma = ws[_MA]
    lcp_total = 0
    status = 2
    jss = 1.0
    nr = 0
    dt = 0.0
    nt = 0
    for _ in range(maxit):
        nt += 1
        axial_integrals(t, lam, coef, g)
        if _build(g, ws) >= 0.0:
            status = 3
            break
        passes, nr, ok = _lcp(ws, active, order, runs, pinned, 8 * n + 20)
        lcp_total += passes
        if not ok:
            status = 1
            break
        qk, qm = _km_apply(ws, _KE, a, ka, ma)
        af = 0.0
        for i in range(n):
            af += a[i] * fb[i]
            cv[i] = (g[5] * ka[i] + g[4] * ma[i] - g[3] * fb[i]) if active[i] else 0.0
        js = 0.5 * (g[5] * qk + g[4] * qm) - g[3] * af
        jss = 0.5 * (g[8] * qk + g[7] * qm) - g[6] * af
        _substitute(ws, active, order, runs, nr, cv, z)
        for i in range(n):
            jss -= cv[i] * z[i]
        if jss > 0.0:
            dt = -js / jss
        else:
            dt = -2.0 if js > 0.0 else 2.0
        if abs(dt) <= tol * (1.0 + abs(t)):
            status = 0  # (a, t) converged; c, z and J*'' belong to them
            break
        if abs(dt) <= _CORRECTOR * tol * (1.0 + abs(t)):
            # last Newton step without a new solve: a(t + dt) = a - z dt + O(dt^2), kept only
            # if it leaves P unchanged (force error O(dt^2), Jacobian error O(dt))
            ok = True
            for i in range(n):
                if active[i] and a[i] - z[i] * dt <= 0.0:
                    ok = False
                    break
            if ok:
                for i in range(n):
                    a[i] -= z[i] * dt
                t += dt
                axial_integrals(t, lam, coef, g)
                status = 0
                break
        lim = max(2.0, 0.5 * abs(t))
        dt = min(max(dt, -lim), lim)
        t = min(max(t + dt, -9.0), T_MAX)
    stat[0] = nt
    stat[1] = lcp_total
    stat[2] = status
    stat[3] = jss
    stat[4] = nr
    stat[5] = dt
    return t


@njit(cache=True)
def _nodal_force(ws, g, dsig, out):
    """Fbar = -G0 Delta sigma sum a_i (cos, sin)(theta_i) (Eq. 5 with Eq. 6-7, exact)."""
    a = ws[_A]
    sc = 0.0
    ss = 0.0
    for i in range(a.shape[0]):
        sc += a[i] * ws[_COS, i]
        ss += a[i] * ws[_SIN, i]
    out[0] = -g[0] * dsig * sc
    out[1] = -g[0] * dsig * ss
    return sc, ss


@njit(cache=True)
def _cold_set(ws, active, pinned):
    for i in range(active.shape[0]):
        active[i] = ws[_FB, i] > 0.0
    if pinned:
        active[0] = False


@njit(cache=True)
def _degenerate(io, active, ws, iws, coef, g, stat, dsig, lam, tol, maxit, pinned, jx, jv):
    """f = 0 identically (e.g. centred journal at rest, or the half-speed whirl x = 2 ydot,
    y = -2 xdot): p = 0, F = 0. The force is positively homogeneous in the source f, so its
    one-sided derivatives are the forces for the sources +-cos, +-sin (each a full solve, same
    h); the Jacobian returned is their symmetric part (exact where F is differentiable)."""
    n = active.shape[0]
    order = iws[0]
    runs = iws[1]
    fpm = np.empty((2, 2, 2))  # [source cos/sin, sign +/-, component]
    tot_nt = 0
    tot_lcp = 0
    status = 0
    for s in range(2):
        for sg in range(2):
            sign = 1.0 if sg == 0 else -1.0
            for i in range(n):
                ws[_FB, i] = sign * dsig * (ws[_COS, i] if s == 0 else ws[_SIN, i])
            _cold_set(ws, active, pinned)
            _solve(ws, active, order, runs, g, coef, lam, 1.0, tol, maxit, pinned, stat)
            tot_nt += int(stat[0])
            tot_lcp += int(stat[1])
            if stat[2] != 0:
                status = int(stat[2])
            _nodal_force(ws, g, dsig, fpm[s, sg])
    for r in range(2):
        dcos = 0.5 * (fpm[0, 0, r] - fpm[0, 1, r])  # dF/d(source amplitude of cos)
        dsin = 0.5 * (fpm[1, 0, r] - fpm[1, 1, r])
        # f = (y + 2 xdot) cos + (2 ydot - x) sin
        jx[r, 0] = -dsin
        jx[r, 1] = dcos
        jv[r, 0] = 2.0 * dcos
        jv[r, 1] = 2.0 * dsin
    io[IO_NT] = tot_nt
    io[IO_NLCP] = tot_lcp
    io[IO_STATUS] = status
    io[IO_PRED] = 0.0
    io[IO_COLD] = 1.0  # the next call starts cold
    for i in range(n):
        ws[_A, i] = 0.0


@njit(cache=True)
def hybrid_kernel(io, active, ws, iws, trig, coef, res):
    """Force and Jacobians of the hybrid method at the state io[IO_STATE:IO_STATE+4].

    See the module docstring for the arguments and docs/hybrid-method.md for the method.
    Results go to ``res`` (5, 2): row 0 Fbar, rows 1-2 dFbar/d(x, y), rows 3-4
    dFbar/d(xdot, ydot) (row = force component).
    """
    n = active.shape[0]
    delta = 2.0 * math.pi / n
    dsig = delta * (math.sin(0.5 * delta) / (0.5 * delta)) ** 2  # Delta sinc^2(Delta/2)
    lam = io[IO_LAM]
    x0 = io[IO_STATE]
    y0 = io[IO_STATE + 1]
    xd0 = io[IO_STATE + 2]
    yd0 = io[IO_STATE + 3]
    tol = io[IO_TOL]
    maxit = int(io[IO_MAXIT])
    pinned = io[IO_PINNED] > 0.5
    want_jac = io[IO_JAC] > 0.5
    # solution frame: the bearing frame, or (pinned) the frame turned by alpha so that node 0
    # lies on the line of maximum film thickness, where p = 0 is imposed
    ca = 1.0
    sa = 0.0
    eps = math.hypot(x0, y0)
    if pinned:
        if eps > 0.0:
            ca = -x0 / eps
            sa = -y0 / eps
        else:
            ca = -1.0
    io[IO_THETA0] = math.atan2(sa, ca) if pinned else 0.0
    x = ca * x0 + sa * y0
    y = -sa * x0 + ca * y0
    xd = ca * xd0 + sa * yd0
    yd = -sa * xd0 + ca * yd0
    _elements(x, y, trig, ws, delta, want_jac)
    srcc = y + 2.0 * xd  # f = srcc cos + srcs sin (Eq. 3)
    srcs = 2.0 * yd - x
    for i in range(n):
        ws[_COS, i] = trig[6, i]
        ws[_SIN, i] = trig[7, i]
        ws[_FB, i] = dsig * (srcc * trig[6, i] + srcs * trig[7, i])  # F_i = int f l_i (exact)
    jx = ws[_SCR:_SCR + 2, 0:2]
    jv = ws[_SCR:_SCR + 2, 2:4]
    g = ws[_SCR + 2, 0:9]
    stat = ws[_SCR + 2, 9:15]
    fr = ws[_SCR + 2, 15:17]
    for r in range(2):
        fr[r] = 0.0
        for c in range(2):
            jx[r, c] = 0.0
            jv[r, c] = 0.0
    if math.hypot(srcc, srcs) <= 1e-14:
        if want_jac:
            _degenerate(io, active, ws, iws, coef, g, stat, dsig, lam, tol, maxit, pinned, jx,
                        jv)
        else:
            io[IO_NT] = 0
            io[IO_NLCP] = 0
            io[IO_STATUS] = 0
            for i in range(n):
                ws[_A, i] = 0.0
    else:
        if io[IO_COLD] > 0.5:
            _cold_set(ws, active, pinned)
            io[IO_T] = 1.0
            io[IO_PRED] = 0.0
            io[IO_COLD] = 0.0
        t = io[IO_T]
        if io[IO_PRED] > 0.5:  # first-order predictor with the exact dt/dq of the last call
            t += (io[IO_DTDQ] * (x0 - io[IO_QPREV]) + io[IO_DTDQ + 1] * (y0 - io[IO_QPREV + 1])
                  + io[IO_DTDQ + 2] * (xd0 - io[IO_QPREV + 2])
                  + io[IO_DTDQ + 3] * (yd0 - io[IO_QPREV + 3]))
            t = min(max(t, -9.0), T_MAX)
        io[IO_PRED] = 0.0
        order = iws[0]
        runs = iws[1]
        t = _solve(ws, active, order, runs, g, coef, lam, t, tol, maxit, pinned, stat)
        io[IO_T] = t
        io[IO_NT] = stat[0]
        io[IO_NLCP] = stat[1]
        io[IO_STATUS] = stat[2]
        io[IO_DTLAST] = stat[5]
        if stat[2] != 0:
            io[IO_COLD] = 1.0
            return
        sc, ss = _nodal_force(ws, g, dsig, fr)
        if want_jac:
            _jacobian(ws, active, order, runs, int(stat[4]), g, stat[3], dsig, sc, ss, jx, jv,
                      io)
            if not pinned:
                io[IO_QPREV] = x0
                io[IO_QPREV + 1] = y0
                io[IO_QPREV + 2] = xd0
                io[IO_QPREV + 3] = yd0
                io[IO_PRED] = 1.0
    if pinned:  # back to the bearing frame: F = R F', D = R D' R^T
        f0 = fr[0]
        fr[0] = ca * f0 - sa * fr[1]
        fr[1] = sa * f0 + ca * fr[1]
        if want_jac:
            _rotate(jx, ca, sa)
            _rotate(jv, ca, sa)
            if eps > 0.0:
                # the pinned line turns with the journal, so the tangential column is not the
                # frozen-line one: from F(R X, R V) = R F(X, V) (exact on the turning grid),
                # dF/dX e_t = (J F - dF/dV J V) / eps, J = rotation by +90 deg
                er0 = x0 / eps
                er1 = y0 / eps
                tan0 = (-fr[1] - (jv[0, 0] * -yd0 + jv[0, 1] * xd0)) / eps
                tan1 = (fr[0] - (jv[1, 0] * -yd0 + jv[1, 1] * xd0)) / eps
                rad0 = jx[0, 0] * er0 + jx[0, 1] * er1
                rad1 = jx[1, 0] * er0 + jx[1, 1] * er1
                jx[0, 0] = rad0 * er0 - tan0 * er1
                jx[0, 1] = rad0 * er1 + tan0 * er0
                jx[1, 0] = rad1 * er0 - tan1 * er1
                jx[1, 1] = rad1 * er1 + tan1 * er0
    res[0, 0] = fr[0]
    res[0, 1] = fr[1]
    if want_jac:
        for r in range(2):
            for c in range(2):
                res[1 + r, c] = jx[r, c]
                res[3 + r, c] = jv[r, c]

@njit(cache=True)
def _rotate(m, ca, sa):
    """m <- R m R^T, R = [[ca, -sa], [sa, ca]]."""
    a00 = m[0, 0]
    a01 = m[0, 1]
    a10 = m[1, 0]
    a11 = m[1, 1]
    # R m
    b00 = ca * a00 - sa * a10
    b01 = ca * a01 - sa * a11
    b10 = sa * a00 + ca * a10
    b11 = sa * a01 + ca * a11
    # (R m) R^T
    m[0, 0] = b00 * ca - b01 * sa
    m[0, 1] = b00 * sa + b01 * ca
    m[1, 0] = b10 * ca - b11 * sa
    m[1, 1] = b10 * sa + b11 * ca


@njit(cache=True, fastmath=True)
def _jacobian(ws, active, order, runs, nr, g, jss, dsig, sc, ss, jx, jv, io):
    """dFbar/d(x, y, xdot, ydot) with P frozen, through t (section 6); dt/dq into io."""
    n = active.shape[0]
    a = ws[_A]
    cv = ws[_CV]
    z = ws[_Z]
    ka = ws[_KA]
    ma = ws[_MA]
    cs = ws[_COS]
    sn = ws[_SIN]
    sq = ws[_SCR + 3, 0:4]
    # r_q = (A_q a - b_q)_P,  s_q = 1/2 a.(G2' K_q + G1' M_q) a - G0' F_q.a
    for q in range(2):
        qk, qm = _km_apply(ws, _X0 if q == 0 else _Y0, a, ka, ma)
        sq[q] = 0.5 * (g[5] * qk + g[4] * qm)
        rq = ws[_RQ + q]
        for i in range(n):
            rq[i] = (g[2] * ka[i] + g[1] * ma[i]) if active[i] else 0.0
    # F_q = Delta sigma (-sin, cos, 2 cos, 2 sin)(theta_i)
    sfa = 0.0
    cfa = 0.0
    for i in range(n):
        sfa += sn[i] * a[i]
        cfa += cs[i] * a[i]
        if active[i]:
            gs = g[0] * dsig * sn[i]
            gc = g[0] * dsig * cs[i]
            ws[_RQ, i] += gs
            ws[_RQ + 1, i] -= gc
            ws[_RQ + 2, i] = -2.0 * gc
            ws[_RQ + 3, i] = -2.0 * gs
        else:
            ws[_RQ + 2, i] = 0.0
            ws[_RQ + 3, i] = 0.0
    gd = g[3] * dsig
    sq[0] += gd * sfa
    sq[1] -= gd * cfa
    sq[2] = -2.0 * gd * cfa
    sq[3] = -2.0 * gd * sfa
    _substitute4(ws, active, order, runs, nr, _RQ, _DA)  # A_PP^-1 r_q = -da0
    for q in range(4):
        da = ws[_DA + q]
        cda = 0.0
        for i in range(n):
            cda += cv[i] * da[i]
        dtq = -(sq[q] - cda) / jss  # dt_q = -(s_q + c.da0) / J*''
        io[IO_DTDQ + q] = dtq
        s1 = 0.0
        s2 = 0.0
        for i in range(n):
            dai = -da[i] - z[i] * dtq  # da_q = da0 - z dt_q
            s1 += dai * cs[i]
            s2 += dai * sn[i]
        col0 = -dsig * (g[0] * s1 + g[3] * dtq * sc)
        col1 = -dsig * (g[0] * s2 + g[3] * dtq * ss)
        if q < 2:
            jx[0, q] = col0
            jx[1, q] = col1
        else:
            jv[0, q - 2] = col0
            jv[1, q - 2] = col1
