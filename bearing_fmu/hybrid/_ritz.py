"""Ritz discretisation of the hybrid method: element integrals and the tridiagonal system.

With ``a(theta)`` piecewise linear on n periodic nodes (Eq. 7) and the axial shape of Eq. (6)
integrated out (:mod:`bearing_fmu.hybrid.axial`), the Ritz functional of Eq. (2) is
``J(a) = 1/2 a.(G2 K + G1 M) a - G0 F.a`` with the h^3-weighted stiffness K and mass M of the
hat functions and the load ``F_i = int f l_i`` (docs/hybrid-method.md, sections 2-3). This
module computes K and M (and their derivatives in x and y for the Jacobians) by a 3-point Gauss
rule per element and assembles ``A = G2 K + G1 M``, ``b = G0 F``.
"""

from __future__ import annotations

from bearing_fmu.hybrid._workspace import (
    FB,
    G0,
    G1,
    G2,
    GT0,
    GT2,
    GW0,
    GW1,
    KD,
    KE,
    KL,
    LO,
    M11,
    M12,
    M22,
    MD,
    ML,
    X0,
    B,
    D,
    kernel,
)
from bearing_fmu.reynolds import film_thickness


@kernel
def element_integrals(x, y, trig, ws, delta, jac):
    """Element stiffness k_e = int w l'^2 and mass moments int w l_a l_b, 3-point Gauss, for
    w = h^3 (Eq. 3) and (with ``jac``) w = dh^3/dx = -3h^2 cos, dh^3/dy = -3h^2 sin; then the
    nodal diagonals and couplings of K and M for w = h^3 (docs/hybrid-method.md, section 3)."""
    n = ws.shape[1]
    gw0 = GW0
    gw1 = GW1
    wa0 = gw0 * (1.0 - GT0) ** 2 * delta
    wa1 = gw1 * 0.25 * delta
    wa2 = gw0 * (1.0 - GT2) ** 2 * delta
    wb0 = gw0 * GT0 * (1.0 - GT0) * delta
    wb1 = gw1 * 0.25 * delta
    wc0 = wa2  # tau^2 at tau_0 = (1 - tau_2)^2
    wc2 = wa0
    gk0 = gw0 / delta
    gk1 = gw1 / delta
    ke = ws[KE]
    m11 = ws[M11]
    m12 = ws[M12]
    m22 = ws[M22]
    c0 = trig[0]
    c1 = trig[1]
    c2 = trig[2]
    s0 = trig[3]
    s1 = trig[4]
    s2 = trig[5]
    for i in range(n):
        h0 = film_thickness(x, y, c0[i], s0[i])
        h1 = film_thickness(x, y, c1[i], s1[i])
        h2 = film_thickness(x, y, c2[i], s2[i])
        w0 = h0 * h0 * h0
        w1 = h1 * h1 * h1
        w2 = h2 * h2 * h2
        ke[i] = gk0 * (w0 + w2) + gk1 * w1
        m11[i] = wa0 * w0 + wa1 * w1 + wa2 * w2
        m12[i] = wb0 * (w0 + w2) + wb1 * w1
        m22[i] = wc0 * w0 + wa1 * w1 + wc2 * w2
    if jac:
        for r in range(2):
            rke = ws[X0 + 4 * r]
            rm11 = ws[X0 + 4 * r + 1]
            rm12 = ws[X0 + 4 * r + 2]
            rm22 = ws[X0 + 4 * r + 3]
            e0 = trig[3 * r]
            e1 = trig[3 * r + 1]
            e2 = trig[3 * r + 2]
            for i in range(n):
                h0 = film_thickness(x, y, c0[i], s0[i])
                h1 = film_thickness(x, y, c1[i], s1[i])
                h2 = film_thickness(x, y, c2[i], s2[i])
                u0 = -3.0 * h0 * h0 * e0[i]
                u1 = -3.0 * h1 * h1 * e1[i]
                u2 = -3.0 * h2 * h2 * e2[i]
                rke[i] = gk0 * (u0 + u2) + gk1 * u1
                rm11[i] = wa0 * u0 + wa1 * u1 + wa2 * u2
                rm12[i] = wb0 * (u0 + u2) + wb1 * u1
                rm22[i] = wc0 * u0 + wa1 * u1 + wc2 * u2
    im = n - 1
    for i in range(n):
        ws[KD, i] = ke[im] + ke[i]
        ws[KL, i] = -ke[i]
        ws[MD, i] = m22[im] + m11[i]
        ws[ML, i] = m12[i]
        im = i


@kernel(inline="always")
def km_node(ke, m11, m12, m22, a, im, i, ip):
    """``((K a)_i, (M a)_i)`` for the element integrals ``ke, m11, m12, m22`` (one weight of
    :func:`element_integrals`) at node i of the ring, ``im, ip`` its neighbours i - 1, i + 1:
    the hat functions of element i - 1 and element i meet at node i."""
    return ((ke[im] + ke[i]) * a[i] - ke[i] * a[ip] - ke[im] * a[im],
            (m22[im] + m11[i]) * a[i] + m12[i] * a[ip] + m12[im] * a[im])


@kernel
def assemble(g, ws):
    """A = G2 K + G1 M (diagonal and couplings), b = G0 F; returns max of the couplings
    (A is a Stieltjes matrix, as the active-set method needs, when it is < 0)."""
    n = ws.shape[1]
    d = ws[D]
    lo = ws[LO]
    b = ws[B]
    kd = ws[KD]
    kl = ws[KL]
    md = ws[MD]
    ml = ws[ML]
    fb = ws[FB]
    g0 = g[G0]
    g1 = g[G1]
    g2 = g[G2]
    lmax = -1e300
    for i in range(n):
        d[i] = g2 * kd[i] + g1 * md[i]
        lo[i] = g2 * kl[i] + g1 * ml[i]
        b[i] = g0 * fb[i]
        if lo[i] > lmax:
            lmax = lo[i]
    return lmax
