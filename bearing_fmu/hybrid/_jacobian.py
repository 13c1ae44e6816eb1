"""Analytic Jacobians of the hybrid method: dFbar/d(x, y, xdot, ydot) (docs/hybrid-method.md,
section 6).

With the active set P frozen, the converged pair (a, t) is differentiated through the
stationarity conditions of the Ritz functional: ``A_PP da = -(A_q a - b_q)_P - (A_t a - b_t) dt``
and ``J*'' dt = -(s_q + c.da0)``, reusing the Thomas factors of the LCP (four solves at once).
The force derivative then follows from Eq. (5) on the nodes (:func:`bearing_fmu.reynolds.
nodal_force`): ``dFbar = -Delta sigma (G0 sum da_i (cos, sin)_i + G0' dt sum a_i (cos, sin)_i)``.
"""

from __future__ import annotations

from numba import njit

from bearing_fmu.hybrid._lcp import substitute4
from bearing_fmu.hybrid._ritz import km_node
from bearing_fmu.hybrid._workspace import (
    COS,
    CV,
    DA,
    G0,
    G0_T,
    G1,
    G1_T,
    G2,
    G2_T,
    RQ,
    SCR,
    SIN,
    X0,
    Y0,
    A,
    Z,
)


@njit(cache=True)
def film_jacobian(ws, active, order, runs, nr, g, jss, dsig, sc, ss, jx, jv, st):
    """dFbar/d(x, y, xdot, ydot) into jx, jv (row = force component) with P frozen, through
    t (section 6); dt/dq into the state record ``st`` (the predictor of the next call)."""
    n = active.shape[0]
    a = ws[A]
    cv = ws[CV]
    z = ws[Z]
    cs = ws[COS]
    sn = ws[SIN]
    sq = ws[SCR + 3, 0:4]
    # r_q = (A_q a - b_q)_P,  s_q = 1/2 a.(G2' K_q + G1' M_q) a - G0' F_q.a, with
    # F_q = Delta sigma (-sin, cos, 2 cos, 2 sin)(theta_i): one sweep for q = x, y
    kx, x11, x12, x22 = ws[X0], ws[X0 + 1], ws[X0 + 2], ws[X0 + 3]
    ky, y11, y12, y22 = ws[Y0], ws[Y0 + 1], ws[Y0 + 2], ws[Y0 + 3]
    g0, g1, g2 = g[G0], g[G1], g[G2]
    qkx = 0.0
    qmx = 0.0
    qky = 0.0
    qmy = 0.0
    sfa = 0.0
    cfa = 0.0
    # off P, a_i = 0 (the LCP's solution), so the sums skip those nodes: the terms they would
    # add are exact zeros
    for i in range(n):
        if not active[i]:
            ws[RQ, i] = 0.0
            ws[RQ + 1, i] = 0.0
            ws[RQ + 2, i] = 0.0
            ws[RQ + 3, i] = 0.0
            continue
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        ai = a[i]
        kax, max_ = km_node(kx, x11, x12, x22, a, im, i, ip)
        kay, may = km_node(ky, y11, y12, y22, a, im, i, ip)
        qkx += ai * kax
        qmx += ai * max_
        qky += ai * kay
        qmy += ai * may
        sfa += sn[i] * ai
        cfa += cs[i] * ai
        gs = g0 * dsig * sn[i]
        gc = g0 * dsig * cs[i]
        ws[RQ, i] = (g2 * kax + g1 * max_) + gs
        ws[RQ + 1, i] = (g2 * kay + g1 * may) - gc
        ws[RQ + 2, i] = -2.0 * gc
        ws[RQ + 3, i] = -2.0 * gs
    sq[0] = 0.5 * (g[G2_T] * qkx + g[G1_T] * qmx)
    sq[1] = 0.5 * (g[G2_T] * qky + g[G1_T] * qmy)
    gd = g[G0_T] * dsig
    sq[0] += gd * sfa
    sq[1] -= gd * cfa
    sq[2] = -2.0 * gd * cfa
    sq[3] = -2.0 * gd * sfa
    substitute4(ws, active, order, runs, nr, RQ, DA)  # A_PP^-1 r_q = -da0
    cda = ws[SCR + 3, 4:8]  # c.da0 for the four q
    for q in range(4):
        cda[q] = 0.0
    for i in range(n):
        if active[i]:  # c and da0 vanish off P
            for q in range(4):
                cda[q] += cv[i] * ws[DA + q, i]
    dts = ws[SCR + 3, 8:12]
    for q in range(4):
        dts[q] = -(sq[q] - cda[q]) / jss  # dt_q = -(s_q + c.da0) / J*''
        st.dtdq[q] = dts[q]
    s1 = ws[SCR + 1, 4:8]  # (row SCR + 1, columns 0-3: jx, jv of the caller)
    s2 = ws[SCR + 1, 8:12]
    for q in range(4):
        s1[q] = 0.0
        s2[q] = 0.0
    for i in range(n):
        if active[i]:  # da_q vanishes off P
            for q in range(4):
                dai = -ws[DA + q, i] - z[i] * dts[q]  # da_q = da0 - z dt_q
                s1[q] += dai * cs[i]
                s2[q] += dai * sn[i]
    for q in range(4):
        col0 = -dsig * (g[G0] * s1[q] + g[G0_T] * dts[q] * sc)
        col1 = -dsig * (g[G0] * s2[q] + g[G0_T] * dts[q] * ss)
        if q < 2:
            jx[0, q] = col0
            jx[1, q] = col1
        else:
            jv[0, q - 2] = col0
            jv[1, q - 2] = col1
