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
from bearing_fmu.hybrid._ritz import km_apply
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
    KA,
    MA,
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
    ka = ws[KA]
    ma = ws[MA]
    cs = ws[COS]
    sn = ws[SIN]
    sq = ws[SCR + 3, 0:4]
    # r_q = (A_q a - b_q)_P,  s_q = 1/2 a.(G2' K_q + G1' M_q) a - G0' F_q.a
    for q in range(2):
        qk, qm = km_apply(ws, X0 if q == 0 else Y0, a, ka, ma)
        sq[q] = 0.5 * (g[G2_T] * qk + g[G1_T] * qm)
        rq = ws[RQ + q]
        for i in range(n):
            rq[i] = (g[G2] * ka[i] + g[G1] * ma[i]) if active[i] else 0.0
    # F_q = Delta sigma (-sin, cos, 2 cos, 2 sin)(theta_i)
    sfa = 0.0
    cfa = 0.0
    for i in range(n):
        sfa += sn[i] * a[i]
        cfa += cs[i] * a[i]
        if active[i]:
            gs = g[G0] * dsig * sn[i]
            gc = g[G0] * dsig * cs[i]
            ws[RQ, i] += gs
            ws[RQ + 1, i] -= gc
            ws[RQ + 2, i] = -2.0 * gc
            ws[RQ + 3, i] = -2.0 * gs
        else:
            ws[RQ + 2, i] = 0.0
            ws[RQ + 3, i] = 0.0
    gd = g[G0_T] * dsig
    sq[0] += gd * sfa
    sq[1] -= gd * cfa
    sq[2] = -2.0 * gd * cfa
    sq[3] = -2.0 * gd * sfa
    substitute4(ws, active, order, runs, nr, RQ, DA)  # A_PP^-1 r_q = -da0
    for q in range(4):
        da = ws[DA + q]
        cda = 0.0
        for i in range(n):
            cda += cv[i] * da[i]
        dtq = -(sq[q] - cda) / jss  # dt_q = -(s_q + c.da0) / J*''
        st.dtdq[q] = dtq
        s1 = 0.0
        s2 = 0.0
        for i in range(n):
            dai = -da[i] - z[i] * dtq  # da_q = da0 - z dt_q
            s1 += dai * cs[i]
            s2 += dai * sn[i]
        col0 = -dsig * (g[G0] * s1 + g[G0_T] * dtq * sc)
        col1 = -dsig * (g[G0] * s2 + g[G0_T] * dtq * ss)
        if q < 2:
            jx[0, q] = col0
            jx[1, q] = col1
        else:
            jx_q = q - 2
            jv[0, jx_q] = col0
            jv[1, jx_q] = col1
