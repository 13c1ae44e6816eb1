"""The tridiagonal linear complementarity problem of the hybrid method (Eq. 4 on the Ritz nodes).

Minimising the Ritz functional over ``a >= 0`` is the LCP ``a >= 0, w = A a - b >= 0,
a.w = 0`` with A symmetric cyclic tridiagonal (a Stieltjes matrix): the Swift-Stieber condition
(Eq. 4) at the discrete free boundaries. Solved exactly by a primal-dual active set with flux
extrapolation (docs/hybrid-method.md, section 4); the twisted Thomas factors of ``A_PP`` over
the runs of consecutive active nodes serve the Newton on t and the Jacobians too.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.hybrid._workspace import COS, CP, CV, LO, NEW, PIV, A, B, D, W, Z, kernel

#: extrapolating active-set passes before falling back to the plain primal-dual active set
EXTRAP_PASSES = 12


@kernel
def factor_solve(ws, active, order, runs, rhs, out):
    """Twisted Thomas factors of A_PP over the runs of consecutive active nodes, and the
    solution of A_PP out_P = rhs_P (out = 0 off P), in one walk of the ring.

    The ring is walked from the node after an inactive one, so no run wraps (no cyclic
    coupling left). Each run is factorised from both ends towards its middle node at once:
    two independent recurrences the processor overlaps (a Thomas sweep is a chain of
    divisions, bound by their latency), the middle solved last, then both halves substituted
    back outwards. Returns the number of runs; run r covers positions ``runs[r] <= k <
    runs[n + r]`` of ``order``, whose factors :func:`substitute` uses for further
    right-hand sides.
    """
    n = active.shape[0]
    inact0 = 0
    for i in range(n):
        if not active[i]:
            inact0 = i
            break
    start = inact0 + 1 if inact0 < n - 1 else 0
    m1 = n - start
    for k in range(m1):  # the ring from start in two plain ranges: no test per node
        order[k] = start + k
    for k in range(m1, n):
        order[k] = k - m1
    nr = 0
    k = np.int64(0)  # (not numba's literal 0: _twisted_run compiled once)
    while k < n:
        if not active[order[k]]:
            out[order[k]] = 0.0
            k += 1
            continue
        end = k + 1
        while end < n and active[order[end]]:
            end += 1
        runs[nr] = k
        runs[n + nr] = end
        nr += 1
        _twisted_run(ws, order, k, end, rhs, out)
        k = end
    return nr


@kernel
def _twisted_run(ws, order, k0, k1, rhs, out):
    """Factors and solution on the run of positions k0 <= k < k1 (:func:`factor_solve`).

    With m = (k0 + k1) // 2 the middle position: for k < m, ``piv[k]`` and ``cp[k]`` are the
    forward (top-down) inverse pivot and A(k, k+1) piv[k]; for k > m, the backward
    (bottom-up) ones with A(k, k-1) piv[k]; ``piv[m]`` is the inverse of the middle's Schur
    complement. Node order[k] couples to order[k + 1] by lo[order[k]].
    """
    d = ws[D]
    lo = ws[LO]
    cp = ws[CP]
    piv = ws[PIV]
    m = (k0 + k1) // 2
    nb = k1 - 1 - m  # bottom-up steps; the top-down ones are nb or nb + 1
    ct = 0.0  # top: cp of the previous position, its y, its coupling to the next
    yt = 0.0
    lt = 0.0
    cb = 0.0  # bottom: the same from below
    yb = 0.0
    for j in range(nb):
        it = order[k0 + j]
        p = 1.0 / (d[it] - lt * ct)
        piv[k0 + j] = p
        yt = (rhs[it] - lt * yt) * p
        out[it] = yt
        lt = lo[it]
        ct = lt * p
        cp[k0 + j] = ct
        kb = k1 - 1 - j
        ib = order[kb]
        ub = lo[ib]
        q = 1.0 / (d[ib] - ub * cb)
        piv[kb] = q
        yb = (rhs[ib] - ub * yb) * q
        out[ib] = yb
        cb = lo[order[kb - 1]] * q
        cp[kb] = cb
    if m - k0 > nb:  # one more top-down step
        it = order[m - 1]
        p = 1.0 / (d[it] - lt * ct)
        piv[m - 1] = p
        yt = (rhs[it] - lt * yt) * p
        out[it] = yt
        lt = lo[it]
        ct = lt * p
        cp[m - 1] = ct
    im = order[m]
    um = lo[im] if nb > 0 else 0.0
    p = 1.0 / (d[im] - lt * ct - um * cb)
    piv[m] = p
    x = (rhs[im] - lt * yt - um * yb) * p
    out[im] = x
    _back_substitute(order, cp, k0, m, nb, x, out)


@kernel
def _back_substitute(order, cp, k0, m, nb, x, out):
    """The two halves of a run of :func:`_twisted_run` (positions from k0, middle m, nb
    bottom-up steps) substituted back outwards from the middle's solution x: ``out`` holds
    the eliminated right-hand side and receives the solution."""
    xt = x
    xb = x
    for j in range(nb):
        it = order[m - 1 - j]
        xt = out[it] - cp[m - 1 - j] * xt
        out[it] = xt
        ib = order[m + 1 + j]
        xb = out[ib] - cp[m + 1 + j] * xb
        out[ib] = xb
    if m - k0 > nb:
        it = order[k0]
        out[it] = out[it] - cp[k0] * xt


@kernel
def substitute(ws, active, order, runs, nr, rhs, out):
    """Solve A_PP out_P = rhs_P with the factors of :func:`factor_solve`; out = 0 off P."""
    n = out.shape[0]
    lo = ws[LO]
    cp = ws[CP]
    piv = ws[PIV]
    for i in range(n):
        if not active[i]:
            out[i] = 0.0
    for r in range(nr):
        k0 = runs[r]
        k1 = runs[n + r]
        m = (k0 + k1) // 2
        nb = k1 - 1 - m
        yt = 0.0
        lt = 0.0
        yb = 0.0
        for j in range(nb):
            it = order[k0 + j]
            yt = (rhs[it] - lt * yt) * piv[k0 + j]
            out[it] = yt
            lt = lo[it]
            kb = k1 - 1 - j
            ib = order[kb]
            yb = (rhs[ib] - lo[ib] * yb) * piv[kb]
            out[ib] = yb
        if m - k0 > nb:
            it = order[m - 1]
            yt = (rhs[it] - lt * yt) * piv[m - 1]
            out[it] = yt
            lt = lo[it]
        im = order[m]
        um = lo[im] if nb > 0 else 0.0
        x = (rhs[im] - lt * yt - um * yb) * piv[m]
        out[im] = x
        _back_substitute(order, cp, k0, m, nb, x, out)


@kernel
def substitute3(ws, active, order, runs, nr):
    """Three solves with the factors of :func:`factor_solve`, each the arithmetic of
    :func:`substitute`: the Newton on t's z = A_PP^-1 c (row CV -> Z) and the Jacobian's
    adjoint w = A_PP^-1 (cos, sin)_P (rows COS, SIN -> W, W + 1; docs/hybrid-method.md,
    section 6). The three chains of each half run side by side: the factors are loaded once
    and the processor overlaps the chains."""
    n = active.shape[0]
    lo = ws[LO]
    cp = ws[CP]
    piv = ws[PIV]
    r0 = ws[CV]
    rc = ws[COS]
    rs = ws[COS + 1]
    o0 = ws[Z]
    oc = ws[W]
    os_ = ws[W + 1]
    for i in range(n):
        if not active[i]:
            o0[i] = 0.0
            oc[i] = 0.0
            os_[i] = 0.0
    for r in range(nr):
        k0 = runs[r]
        k1 = runs[n + r]
        m = (k0 + k1) // 2
        nb = k1 - 1 - m
        lt = 0.0
        t0 = 0.0
        tc = 0.0
        ts = 0.0
        b0 = 0.0
        bc = 0.0
        bs = 0.0
        for j in range(nb):
            it = order[k0 + j]
            p = piv[k0 + j]
            kb = k1 - 1 - j
            ib = order[kb]
            ub = lo[ib]
            pb = piv[kb]
            t0 = (r0[it] - lt * t0) * p
            tc = (rc[it] - lt * tc) * p
            ts = (rs[it] - lt * ts) * p
            o0[it] = t0
            oc[it] = tc
            os_[it] = ts
            b0 = (r0[ib] - ub * b0) * pb
            bc = (rc[ib] - ub * bc) * pb
            bs = (rs[ib] - ub * bs) * pb
            o0[ib] = b0
            oc[ib] = bc
            os_[ib] = bs
            lt = lo[it]
        if m - k0 > nb:
            it = order[m - 1]
            p = piv[m - 1]
            t0 = (r0[it] - lt * t0) * p
            tc = (rc[it] - lt * tc) * p
            ts = (rs[it] - lt * ts) * p
            o0[it] = t0
            oc[it] = tc
            os_[it] = ts
            lt = lo[it]
        im = order[m]
        um = lo[im] if nb > 0 else 0.0
        p = piv[m]
        t0 = (r0[im] - lt * t0 - um * b0) * p
        tc = (rc[im] - lt * tc - um * bc) * p
        ts = (rs[im] - lt * ts - um * bs) * p
        o0[im] = t0
        oc[im] = tc
        os_[im] = ts
        b0 = t0
        bc = tc
        bs = ts
        for j in range(nb):
            it = order[m - 1 - j]
            ct = cp[m - 1 - j]
            ib = order[m + 1 + j]
            cb = cp[m + 1 + j]
            t0 = o0[it] - ct * t0
            tc = oc[it] - ct * tc
            ts = os_[it] - ct * ts
            o0[it] = t0
            oc[it] = tc
            os_[it] = ts
            b0 = o0[ib] - cb * b0
            bc = oc[ib] - cb * bc
            bs = os_[ib] - cb * bs
            o0[ib] = b0
            oc[ib] = bc
            os_[ib] = bs
        if m - k0 > nb:
            it = order[k0]
            o0[it] = o0[it] - cp[k0] * t0
            oc[it] = oc[it] - cp[k0] * tc
            os_[it] = os_[it] - cp[k0] * ts


@kernel
def solve_lcp(ws, active, order, runs, pinned, maxpass):
    """Primal-dual active set for a >= 0, w = A a - b >= 0, a.w = 0 (section 4).

    Each pass solves A_PP a_P = b_P and sets P <- {a_i > 0 in P} U {w_i < 0 off P}; during the
    first passes an inactive node next to a film end that enters P also brings in the
    following inactive nodes while their summed deficit sum(-b) stays below the end flux
    -A_ej a_e (flux extrapolation: the film end moves by many nodes per pass). Stops when P
    repeats; the solution is then the exact LCP solution. Returns (passes, runs, converged).
    """
    n = active.shape[0]
    a = ws[A]
    b = ws[B]
    lo = ws[LO]
    new = ws[NEW]
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
        nr = factor_solve(ws, active, order, runs, b, a)
        extrap = it < EXTRAP_PASSES
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
