"""Analytic Jacobians of the hybrid method: dFbar/d(x, y, xdot, ydot) (docs/hybrid-method.md,
section 6).

With the active set P frozen, the converged pair (a, t) is differentiated through the
stationarity conditions of the Ritz functional: ``A_PP da0 = -r_q`` with ``r_q = (A_q a -
b_q)_P``, ``J*'' dt_q = -(s_q + c.da0)`` and ``da_q = da0 - z dt_q``. The force of Eq. (5)
needs da_q only through ``e.da0`` for e = cos, sin (at the nodes of P) and c, and A_PP is
symmetric: ``e.da0 = -(A_PP^-1 e).r_q``, ``c.da0 = -z.r_q``. So two solves with the Thomas
factors of the LCP (the adjoint vectors ``w = A_PP^-1 (cos, sin)_P``) serve the four
derivatives, and ``z = A_PP^-1 c`` is the Newton on t's own; the three are solved together
(:func:`bearing_fmu.hybrid._lcp.substitute3`). The force derivative then follows
from Eq. (5) on the nodes (:func:`bearing_fmu.reynolds.nodal_force`): ``dFbar = -Delta sigma
(G0 sum da_i (cos, sin)_i + G0' dt sum a_i (cos, sin)_i)``.
"""

from __future__ import annotations

from bearing_fmu.hybrid._ritz import km_node
from bearing_fmu.hybrid._workspace import (
    COS,
    G0,
    G0_T,
    G1,
    G1_T,
    G2,
    G2_T,
    SCR,
    SIN,
    X0,
    Y0,
    A,
    W,
    Z,
    kernel,
)


@kernel
def film_jacobian(ws, active, g, jss, dsig, sc, ss, jx, jv, st):
    """dFbar/d(x, y, xdot, ydot) into jx, jv (row = force component) with P frozen, through
    t (section 6); dt/dq into the state record ``st`` (the predictor of the next call). The
    adjoint vectors w (ws[W]) and z (ws[Z]) come solved with the last pass's factors
    (:func:`bearing_fmu.hybrid._kernels.solve_t`)."""
    n = active.shape[0]
    a = ws[A]
    z = ws[Z]
    cs = ws[COS]
    sn = ws[SIN]
    wc = ws[W]
    wsn = ws[W + 1]
    # r_q = (A_q a - b_q)_P,  s_q = 1/2 a.(G2' K_q + G1' M_q) a - G0' F_q.a, with
    # F_q = Delta sigma (-sin, cos, 2 cos, 2 sin)(theta_i): r_x = u_x + G0 Delta sigma sin,
    # r_y = u_y - G0 Delta sigma cos, r_xdot = -2 G0 Delta sigma cos, r_ydot = -2 G0 Delta
    # sigma sin, with u_q = (G2 K_q + G1 M_q) a. One sweep gathers the dot products of u_x,
    # u_y, cos and sin with w_cos, w_sin and z.
    kx, x11, x12, x22 = ws[X0], ws[X0 + 1], ws[X0 + 2], ws[X0 + 3]
    ky, y11, y12, y22 = ws[Y0], ws[Y0 + 1], ws[Y0 + 2], ws[Y0 + 3]
    g1, g2 = g[G1], g[G2]
    qkx = 0.0
    qmx = 0.0
    qky = 0.0
    qmy = 0.0
    sfa = 0.0
    cfa = 0.0
    xwc = 0.0  # u_x.w_cos
    ywc = 0.0
    cwc = 0.0
    swc = 0.0
    xws = 0.0  # u_x.w_sin
    yws = 0.0
    cws = 0.0
    sws = 0.0
    xz = 0.0  # u_x.z
    yz = 0.0
    cz = 0.0
    sz = 0.0
    # off P, a_i = 0 (the LCP's solution) and w, z vanish, so the sums skip those nodes: the
    # terms they would add are exact zeros
    for i in range(n):
        if not active[i]:
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
        ci = cs[i]
        si = sn[i]
        sfa += si * ai
        cfa += ci * ai
        ux = g2 * kax + g1 * max_
        uy = g2 * kay + g1 * may
        wci = wc[i]
        wsi = wsn[i]
        zi = z[i]
        xwc += ux * wci
        ywc += uy * wci
        cwc += ci * wci
        swc += si * wci
        xws += ux * wsi
        yws += uy * wsi
        cws += ci * wsi
        sws += si * wsi
        xz += ux * zi
        yz += uy * zi
        cz += ci * zi
        sz += si * zi
    sq = ws[SCR + 3, 0:4]
    sq[0] = 0.5 * (g[G2_T] * qkx + g[G1_T] * qmx)
    sq[1] = 0.5 * (g[G2_T] * qky + g[G1_T] * qmy)
    gd = g[G0_T] * dsig
    sq[0] += gd * sfa
    sq[1] -= gd * cfa
    sq[2] = -2.0 * gd * cfa
    sq[3] = -2.0 * gd * sfa
    gb = g[G0] * dsig
    rwc = ws[SCR + 3, 4:8]  # r_q.w_cos = -cos.da0
    rws = ws[SCR + 3, 8:12]  # r_q.w_sin = -sin.da0
    rz = ws[SCR + 1, 4:8]  # r_q.z = -c.da0
    dts = ws[SCR + 1, 8:12]  # (row SCR + 1, columns 0-3: jx, jv of the caller)
    for w_x, w_y, w_c, w_s, out in ((xwc, ywc, cwc, swc, rwc), (xws, yws, cws, sws, rws),
                                    (xz, yz, cz, sz, rz)):
        out[0] = w_x + gb * w_s
        out[1] = w_y - gb * w_c
        out[2] = -2.0 * gb * w_c
        out[3] = -2.0 * gb * w_s
    for q in range(4):
        dts[q] = -(sq[q] - rz[q]) / jss  # dt_q = -(s_q + c.da0) / J*''
        st.dtdq[q] = dts[q]
        # sum over P of da_q (cos, sin) with da_q = da0 - z dt_q
        s1 = -rwc[q] - cz * dts[q]
        s2 = -rws[q] - sz * dts[q]
        col0 = -dsig * (g[G0] * s1 + g[G0_T] * dts[q] * sc)
        col1 = -dsig * (g[G0] * s2 + g[G0_T] * dts[q] * ss)
        if q < 2:
            jx[0, q] = col0
            jx[1, q] = col1
        else:
            jv[0, q - 2] = col0
            jv[1, q - 2] = col1
