"""Numba kernels of the hybrid method (:mod:`bearing_fmu.hybrid.model`; docs/hybrid-method.md).

One call of :func:`hybrid_kernel` does the whole per-state computation: element integrals
(:mod:`bearing_fmu.hybrid._ritz`), the tridiagonal LCP (:mod:`bearing_fmu.hybrid._lcp`), Newton
on t = (k lambda)^2 (:func:`solve_t`), the force of Eq. (5) and the analytic Jacobians
(:mod:`bearing_fmu.hybrid._jacobian`). The memory it works in is laid out in
:mod:`bearing_fmu.hybrid._workspace`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from bearing_fmu.frames import film_law_global, film_state_local
from bearing_fmu.hybrid._jacobian import film_jacobian
from bearing_fmu.hybrid._lcp import solve_lcp, substitute, substitute3
from bearing_fmu.hybrid._ritz import assemble, element_integrals, km_node
from bearing_fmu.hybrid._workspace import (
    COS,
    CV,
    FB,
    G0,
    G0_T,
    G0_TT,
    G1_T,
    G1_TT,
    G2_T,
    G2_TT,
    KE,
    NEW,
    SCR,
    SIN,
    A,
    Z,
    kernel,
)
from bearing_fmu.hybrid.axial import T_LOW, T_MAX, axial_integrals
from bearing_fmu.reynolds import nodal_force, source, source_coefficients

#: bound of the corrector's relative force error per squared relative step on t: a last Newton
#: step dt is taken as a - z dt without a new solve when CORRECTOR_ERROR (dt / (1 + |t|))^2
#: <= tol (measured: at most 0.010, over 1,279 warm calls whose last step was 1e-5-1e-3,
#: L/D 0.25-1; margin 2). The Jacobians' error is O(dt): at most 0.15 |dt| / (1 + |t|)
CORRECTOR_ERROR = 0.02


@kernel
def _stationarity(ws, active, g):
    """a.K a, a.M a, a.F and c = (A_t a - b_t)_P into ws[CV] (section 5), in one sweep."""
    n = active.shape[0]
    a = ws[A]
    fb = ws[FB]
    cv = ws[CV]
    ke = ws[KE]
    m11 = ws[KE + 1]
    m12 = ws[KE + 2]
    m22 = ws[KE + 3]
    g2t = g[G2_T]
    g1t = g[G1_T]
    g0t = g[G0_T]
    qk = 0.0
    qm = 0.0
    af = 0.0
    for i in range(n):
        if not active[i]:  # a_i = 0 off P: the sums' terms there are exact zeros
            cv[i] = 0.0
            continue
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        kai, mai = km_node(ke, m11, m12, m22, a, im, i, ip)
        qk += a[i] * kai
        qm += a[i] * mai
        af += a[i] * fb[i]
        cv[i] = g2t * kai + g1t * mai - g0t * fb[i]
    return qk, qm, af


@kernel
def solve_t(ws, active, order, runs, g, coef, lam, t, tol, maxit, pinned, adjoint):
    """LCP (section 4) and Newton on J*(t) (section 5) for the source in ws[FB].

    Leaves a (ws[A]), the factors of A_PP, c, z at the converged t; with ``adjoint``, also
    the Jacobian's adjoint vectors w (ws[W]; :func:`bearing_fmu.hybrid._jacobian.film_jacobian`),
    solved at each pass with z (:func:`bearing_fmu.hybrid._lcp.substitute3`): the pass that
    converges needs them, and the others (0.2 per call) waste less than a separate solve
    costs. Returns ``(t, Newton passes, active-set passes, status, J*'', last step)``.

    Safeguarded (docs/hybrid-method.md, section 5): the sign of J*' at each iterate narrows
    the bracket ``(lo, hi)`` of the root; a Newton step that leaves it, or a pass where
    J*'' <= 0, is replaced by the bisection of the bracket once both of its ends are found,
    and before that by a step of max(2, |t|/2) downhill. Where the plain Newton stays in
    the bracket with J*'' > 0, which is every pass near the root, the steps are its steps.
    """
    n = active.shape[0]
    a = ws[A]
    cv = ws[CV]
    z = ws[Z]
    corrector = math.sqrt(tol / CORRECTOR_ERROR)  # largest relative step taken as a corrector
    lcp_total = 0
    status = 2
    jss = 1.0
    nr = 0
    dt = 0.0
    nt = 0
    lo = -T_LOW  # the bracket of the root of J*': J*' < 0 at lo, > 0 at hi once found
    hi = T_MAX
    found_lo = False
    found_hi = False
    for _ in range(maxit):
        nt += 1
        axial_integrals(t, lam, coef, g)
        if assemble(g, ws) >= 0.0:
            status = 3
            break
        passes, nr, ok = solve_lcp(ws, active, order, runs, pinned, 8 * n + 20)
        lcp_total += passes
        if not ok:
            status = 1
            break
        qk, qm, af = _stationarity(ws, active, g)
        js = 0.5 * (g[G2_T] * qk + g[G1_T] * qm) - g[G0_T] * af
        jss = 0.5 * (g[G2_TT] * qk + g[G1_TT] * qm) - g[G0_TT] * af
        if adjoint:
            substitute3(ws, active, order, runs, nr)
        else:
            substitute(ws, active, order, runs, nr, cv, z)
        for i in range(n):
            jss -= cv[i] * z[i]
        if js > 0.0:
            hi = min(hi, t)
            found_hi = True
        else:
            lo = max(lo, t)
            found_lo = True
        lim = max(2.0, 0.5 * abs(t))
        newton = jss > 0.0
        if newton:
            dt = -js / jss
            newton = lo < t + dt < hi or abs(dt) <= tol * (1.0 + abs(t))
        if not newton:
            if found_lo and found_hi:
                dt = 0.5 * (lo + hi) - t
            else:
                dt = -lim if js > 0.0 else lim
        if abs(dt) <= tol * (1.0 + abs(t)):
            status = 0  # (a, t) converged; c, z and J*'' belong to them
            break
        if newton and abs(dt) <= corrector * (1.0 + abs(t)):
            # last Newton step without a new solve: a(t + dt) = a - z dt + O(dt^2), kept only
            # if it leaves P unchanged (force error below tol, Jacobian error O(dt))
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
        dt = min(max(dt, -lim), lim)
        t = min(max(t + dt, -T_LOW), T_MAX)
    return t, nt, lcp_total, status, jss, dt


@kernel
def _cold_set(ws, active, pinned):
    """The pressurised set of a cold start: the nodes where the source f is positive."""
    for i in range(active.shape[0]):
        active[i] = ws[FB, i] > 0.0
    if pinned:
        active[0] = False


@kernel
def _turn_set(active, ws, dpsi, delta):
    """The warm start's pressurised set turned by the nodes nearest to dpsi [rad], the turn of
    the source f = A cos + B sin (Eq. 3, direction atan2(B, A)) since the call the set comes
    from: the film follows its source, mostly driven by the journal's velocity. It saves
    active-set passes (1.81 -> 1.50 per call over the paper's case), not bits: the LCP's
    solution is unique (A is a Stieltjes matrix), and every Newton pass on t ends on it
    whatever the set it starts from."""
    n = active.shape[0]
    shift = round(dpsi / delta) % n  # a turn of 2 pi is n nodes: the modulo wraps dpsi
    if shift == 0:
        return
    old = ws[NEW]  # free until the active-set method fills it
    for i in range(n):
        old[i] = 1.0 if active[i] else 0.0
    for i in range(shift):
        active[i] = old[n - shift + i] > 0.5
    for i in range(shift, n):
        active[i] = old[i - shift] > 0.5


@kernel
def _degenerate(st, active, ws, iws, coef, g, dsig, lam, tol, maxit, pinned, jx, jv):
    """f = 0 identically (e.g. centred journal at rest, or the half-speed whirl x = 2 ydot,
    y = -2 xdot): p = 0, F = 0. The force is positively homogeneous in the source f, so its
    one-sided derivatives are the forces for the sources +-cos, +-sin (each a full solve, same
    h); the Jacobian returned is their symmetric part (exact where F is differentiable)."""
    n = active.shape[0]
    order = iws[0]
    runs = iws[1]
    fpm = ws[SCR, 4:12]  # F of source s (cos, sin), sign (+, -): components at 4 s + 2 sign
    tot_nt = 0
    tot_lcp = 0
    status = 0
    for s in range(2):
        for sg in range(2):
            sign = 1.0 if sg == 0 else -1.0
            for i in range(n):
                ws[FB, i] = sign * dsig * (ws[COS, i] if s == 0 else ws[SIN, i])
            _cold_set(ws, active, pinned)
            # np.bool_(False): a plain bool, not numba's literal (solve_t compiled once)
            _, nt, nlcp, stat, _, _ = solve_t(ws, active, order, runs, g, coef, lam, 1.0,
                                              tol, maxit, pinned, np.bool_(False))
            tot_nt += nt
            tot_lcp += nlcp
            if stat != 0:
                status = stat
            f = 4 * s + 2 * sg
            nodal_force(ws[A], ws[COS], ws[SIN], g[G0] * dsig, fpm[f:f + 2])
    for r in range(2):
        dcos = 0.5 * (fpm[r] - fpm[2 + r])  # dF/d(source amplitude of cos)
        dsin = 0.5 * (fpm[4 + r] - fpm[6 + r])
        # f = (y + 2 xdot) cos + (2 ydot - x) sin
        jx[r, 0] = -dsin
        jx[r, 1] = dcos
        jv[r, 0] = 2.0 * dcos
        jv[r, 1] = 2.0 * dsin
    st.t_iterations = tot_nt
    st.lcp_iterations = tot_lcp
    st.status = status
    st.predict = False
    st.cold = True  # the next call starts cold
    for i in range(n):
        ws[A, i] = 0.0


@kernel
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


@kernel
def hybrid_kernel(state, x0, y0, xd0, yd0, want_jac, active, ws, iws, trig, coef, res):
    """Force and Jacobians of the hybrid method at the dimensionless state (x0, y0, xd0, yd0).

    ``state`` is the one-element record array of :data:`bearing_fmu.hybrid._workspace.STATE`
    (settings, warm start, diagnostics). Results go to ``res`` (5, 2): row 0 Fbar, rows 1-2
    dFbar/d(x, y), rows 3-4 dFbar/d(xdot, ydot) (row = force component). Returns the status
    (0 ok; see the ``status`` field).
    """
    st = state[0]
    n = active.shape[0]
    delta = 2.0 * math.pi / n
    dsig = delta * (math.sin(0.5 * delta) / (0.5 * delta)) ** 2  # Delta sinc^2(Delta/2)
    lam = st.lam
    tol = st.tol
    maxit = st.maxit
    pinned = st.pinned
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
    st.theta0 = math.atan2(sa, ca) if pinned else 0.0
    x = ca * x0 + sa * y0
    y = -sa * x0 + ca * y0
    xd = ca * xd0 + sa * yd0
    yd = -sa * xd0 + ca * yd0
    element_integrals(x, y, trig, ws, delta, want_jac)
    srcc, srcs = source_coefficients(x, y, xd, yd)  # f = srcc cos + srcs sin (Eq. 3)
    for i in range(n):
        ws[COS, i] = trig[6, i]
        ws[SIN, i] = trig[7, i]
        ws[FB, i] = dsig * source(srcc, srcs, trig[6, i], trig[7, i])  # F_i = int f l_i
    jx = ws[SCR:SCR + 2, 0:2]
    jv = ws[SCR:SCR + 2, 2:4]
    g = ws[SCR + 2, 0:9]
    fr = ws[SCR + 2, 9:11]
    for r in range(2):
        fr[r] = 0.0
        for c in range(2):
            jx[r, c] = 0.0
            jv[r, c] = 0.0
    if math.hypot(srcc, srcs) <= 1e-14:
        if want_jac:
            _degenerate(st, active, ws, iws, coef, g, dsig, lam, tol, maxit, pinned, jx, jv)
        else:
            st.t_iterations = 0
            st.lcp_iterations = 0
            st.status = 0
            for i in range(n):
                ws[A, i] = 0.0
    else:
        if st.cold:
            _cold_set(ws, active, pinned)
            st.t = 1.0
            st.predict = False
            st.cold = False
        t = st.t
        if st.predict:  # first-order predictor with the exact dt/dq of the last call
            dq = st.dtdq
            qp = st.q_prev
            t += (dq[0] * (x0 - qp[0]) + dq[1] * (y0 - qp[1]) + dq[2] * (xd0 - qp[2])
                  + dq[3] * (yd0 - qp[3]))
            t = min(max(t, -T_LOW), T_MAX)
            pc, ps = source_coefficients(qp[0], qp[1], qp[2], qp[3])
            _turn_set(active, ws, math.atan2(srcs, srcc) - math.atan2(ps, pc), delta)
        st.predict = False
        order = iws[0]
        runs = iws[1]
        t, nt, nlcp, status, jss, dt = solve_t(ws, active, order, runs, g, coef, lam, t,
                                               tol, maxit, pinned, want_jac)
        st.t = t
        st.t_iterations = nt
        st.lcp_iterations = nlcp
        st.status = status
        st.last_dt = dt
        if status != 0:
            st.cold = True
            return status
        sc, ss = nodal_force(ws[A], ws[COS], ws[SIN], g[G0] * dsig, fr)  # Eq. (5)
        if want_jac:
            film_jacobian(ws, active, g, jss, dsig, sc, ss, jx, jv, st)
            if not pinned:
                qp = st.q_prev
                qp[0] = x0
                qp[1] = y0
                qp[2] = xd0
                qp[3] = yd0
                st.predict = True
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
    return st.status


#: :func:`hybrid_global` statuses for an input the kernel is not called with (the caller
#: raises the checks' own errors, :func:`bearing_fmu.base.check_state`)
BAD_STATE = -1


@kernel
def hybrid_global(state, active, ws, iws, trig, coef, q, s, omega, clearance, fs, res, out):
    """:func:`hybrid_kernel` in SI units and the global frame: one call per bearing.

    ``q`` (2, 2) turns global components into local ones (:class:`bearing_fmu.frames.
    LocalFrame`), ``s`` is the global journal state [s, t, sdot, tdot] [m, m/s], ``omega`` the
    speed [rad/s], ``fs`` the force scale of Eq. (5) at omega [N]. Writes ``out`` (5, 2): row 0
    the film force [N], rows 1-2 Kb = -dF/dX [N/m], rows 3-4 Cb = -dF/dXdot [N s/m], global
    (F = Q^T F_loc, K = Q^T K_loc Q); ``res`` (5, 2) is scratch (the dimensionless law, then
    the local one in SI units). The arithmetic is that of
    :meth:`bearing_fmu.base.FilmBearingModel.evaluate` and the frame conversions, in the same
    order. Returns the kernel's status, or :data:`BAD_STATE` for a non-finite state or an
    eccentricity ratio >= 1 (nothing evaluated).
    """
    xb, yb, xdb, ydb, ok = film_state_local(q, s, clearance, omega)
    if not ok:
        return BAD_STATE
    # np.bool_(True): a plain bool, not numba's literal (hybrid_kernel compiled once)
    status = hybrid_kernel(state, xb, yb, xdb, ydb, np.bool_(True), active, ws, iws, trig, coef,
                           res)
    if status != 0:
        return status
    film_law_global(q, res, fs, clearance, omega, out)
    return 0


@kernel
def hybrid_set_global(states, active, ws, iws, trig, coef, q, omega, clearance, fs, res, s,
                      out):
    """:func:`hybrid_global` for a set of bearings in one call, in their order, with their
    workspaces stacked along the first axis (:class:`bearing_fmu.hybrid.model.HybridSet`):
    the same arithmetic as one call per bearing; the set's arrays first, then the journal
    states ``s`` (nb, 4) and the output ``out`` (nb, 5, 2). Returns ``(-1, 0)``, or the index
    of the first bearing whose status is not 0 and that status (the bearings after it are not
    evaluated)."""
    for b in range(states.shape[0]):
        status = hybrid_global(states[b:b + 1], active[b], ws[b], iws[b], trig[b], coef, q[b],
                               s[b], omega[b], clearance[b], fs[b], res[b], out[b])
        if status != 0:
            return b, status
    return -1, 0


@njit(cache=True, parallel=True)
def hybrid_set_threads(states, active, ws, iws, trig, coef, q, omega, clearance, fs, res,
                       status, s, out):
    """:func:`hybrid_set_global` with the bearings shared among the threads of numba's
    threading layer, as many as ``numba.set_num_threads`` gave the calling thread
    (:meth:`bearing_fmu.hybrid.model.HybridSet.use_threads`; set in Python: the call inside
    would make this kernel and its callers uncachable). Each bearing is the same
    :func:`hybrid_global` call on its own memory as in the serial loop, so the bits do not
    depend on the thread count. Every bearing is evaluated, also after a failing one;
    ``status`` (nb,) int64 receives their statuses. Returns ``(-1, 0)``, or the index of the
    first bearing whose status is not 0 and that status."""
    for b in prange(states.shape[0]):
        status[b] = hybrid_global(states[b:b + 1], active[b], ws[b], iws[b], trig[b], coef,
                                  q[b], s[b], omega[b], clearance[b], fs[b], res[b], out[b])
    for b in range(states.shape[0]):
        if status[b] != 0:
            return b, status[b]
    return -1, 0
