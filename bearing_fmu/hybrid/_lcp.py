"""The tridiagonal linear complementarity problem of the hybrid method (Eq. 4 on the Ritz nodes).

Minimising the Ritz functional over ``a >= 0`` is the LCP ``a >= 0, w = A a - b >= 0,
a.w = 0`` with A symmetric cyclic tridiagonal (a Stieltjes matrix): the Swift-Stieber condition
(Eq. 4) at the discrete free boundaries. Solved exactly by a primal-dual active set with flux
extrapolation (docs/hybrid-method.md, section 4); the Thomas factors of ``A_PP`` over the runs
of consecutive active nodes serve the Newton on t and the Jacobians too.
"""

from __future__ import annotations

from numba import njit

from bearing_fmu.hybrid._workspace import CP, LO, NEW, PIV, A, B, D

#: extrapolating active-set passes before falling back to the plain primal-dual active set
EXTRAP_PASSES = 12


@njit(cache=True)
def factor_solve(ws, active, order, runs, rhs, out):
    """Thomas factors (inverse pivots) of A_PP over the runs of consecutive active nodes, and
    the solution of A_PP out_P = rhs_P (out = 0 off P), in one walk of the ring.

    The ring is walked from the node after an inactive one, so no run wraps (no cyclic
    coupling left). Each run is factorised and eliminated forwards in the same loop, the two
    recurrences being independent chains the processor overlaps, then substituted backwards.
    Returns the number of runs; run r covers positions ``runs[r] <= k < runs[n + r]`` of
    ``order``, whose factors :func:`substitute` uses for further right-hand sides.
    """
    n = active.shape[0]
    d = ws[D]
    lo = ws[LO]
    cp = ws[CP]
    piv = ws[PIV]
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
        i = order[k]
        if not active[i]:
            out[i] = 0.0
            k += 1
            continue
        start = k
        piv[k] = 1.0 / d[i]
        cp[k] = lo[i] * piv[k]
        prev = rhs[i] * piv[k]
        out[i] = prev
        k += 1
        while k < n and active[order[k]]:
            i = order[k]
            lk = lo[order[k - 1]]
            piv[k] = 1.0 / (d[i] - lk * cp[k - 1])
            cp[k] = lo[i] * piv[k]
            prev = (rhs[i] - lk * prev) * piv[k]
            out[i] = prev
            k += 1
        runs[nr] = start
        runs[n + nr] = k
        nr += 1
        nxt = prev
        for kb in range(k - 2, start - 1, -1):
            i = order[kb]
            nxt = out[i] - cp[kb] * nxt
            out[i] = nxt
    return nr


@njit(cache=True)
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


@njit(cache=True)
def substitute4(ws, active, order, runs, nr, r0, o0):
    """Four solves at once (rows r0..r0+3 -> rows o0..o0+3), as :func:`substitute`."""
    n = active.shape[0]
    lo = ws[LO]
    cp = ws[CP]
    piv = ws[PIV]
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
