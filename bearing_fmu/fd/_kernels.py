"""Multigrid cycles of the finite-difference Reynolds solver (:mod:`bearing_fmu.fd.model`).

Truncated nonsmooth Newton multigrid (TNNMG) on the grids of :mod:`bearing_fmu.fd._grid`: the
linear V-cycle for the truncated defect equation, one TNNMG cycle, the solve to a tolerance,
nested iteration from the coarsest level, and the force of Eq. (5) from the pressure.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.fd._grid import (
    ROUND_FLOOR,
    _ct,
    _lv,
    apply_a,
    coarse_direct,
    interpolate_add,
    interpolate_solution,
    level_coefficients,
    linear_gs,
    natural_residual,
    projected_gs,
    residual,
    restrict,
)
from bearing_fmu.reynolds import nodal_force


@njit(cache=True)
def linear_vcycle(l0, nts, ms, offs, coffs, kinds, ct, cx, e, r, tmp, mask, nu1, nu2,
                  mask_rule):
    """One V(nu1, nu2) cycle for the truncated correction equation, levels l0 .. L-1.

    ``r`` on level l0 and the masks of level l0 - 1 .. L-1 are set by the caller (the coarse
    masks by :func:`restrict`). Result in ``e`` on level l0.
    """
    nl = nts.shape[0]
    for lv in range(l0, nl - 1):
        nt, m = nts[lv], ms[lv]
        el = _lv(e, offs[lv], nt, m)
        rl = _lv(r, offs[lv], nt, m)
        tl = _lv(tmp, offs[lv], nt, m)
        ml = _lv(mask, offs[lv], nt, m)
        ctl = _ct(ct, coffs[lv], nt)
        cxl = _ct(cx, coffs[lv], nt)
        el[:, :] = 0.0
        # np.bool_(...): plain bools, not numba's literals (each sweep compiled once)
        linear_gs(el, rl, ctl, cxl, nt, m, ml, nu1, np.bool_(False))
        residual(el, rl, ctl, cxl, nt, m, tl)
        ntc, mc = nts[lv + 1], ms[lv + 1]
        restrict(tl, ml, nt, m, _lv(r, offs[lv + 1], ntc, mc), _lv(mask, offs[lv + 1], ntc, mc),
                 ntc, mc, kinds[lv], mask_rule)
    lv = nl - 1
    nt, m = nts[lv], ms[lv]
    coarse_direct(_lv(e, offs[lv], nt, m), _lv(r, offs[lv], nt, m), _ct(ct, coffs[lv], nt),
                  _ct(cx, coffs[lv], nt), nt, m, _lv(mask, offs[lv], nt, m))
    for lv in range(nl - 2, l0 - 1, -1):
        nt, m = nts[lv], ms[lv]
        ntc, mc = nts[lv + 1], ms[lv + 1]
        el = _lv(e, offs[lv], nt, m)
        ml = _lv(mask, offs[lv], nt, m)
        interpolate_add(_lv(e, offs[lv + 1], ntc, mc), ntc, mc, el, ml, nt, m, kinds[lv], 1.0)
        linear_gs(el, _lv(r, offs[lv], nt, m), _ct(ct, coffs[lv], nt), _ct(cx, coffs[lv], nt),
                  nt, m, ml, nu2, np.bool_(True))


@njit(cache=True)
def _weighted_dot(a, b, nt, m):
    s = 0.0
    for i in range(nt):
        for j in range(1, m):
            s += 2.0 * a[i, j] * b[i, j]
        s += a[i, m] * b[i, m]
    return s


@njit(cache=True)
def tnnmg_cycle(lv, nts, ms, offs, coffs, kinds, ct, cx, p, b, e, r, tmp, mask, pin0, nu1, nu2,
                mask_rule):
    """One truncated nonsmooth Newton multigrid cycle for the obstacle problem on level lv.

    1. nu1 projected Gauss-Seidel sweeps (monotone: decrease the energy J = p.Ap/2 - b.p);
    2. truncation: the nodes with p = 0 (and the pinned row) get no coarse correction;
       the residual there is dropped;
    3. one linear V-cycle on the coarser levels for the truncated defect equation;
    4. the correction is projected onto p >= 0 and scaled by the exact minimiser of J along it
       (line search; J is quadratic), which keeps the iteration monotone and convergent;
    5. nu2 projected Gauss-Seidel sweeps.
    """
    nt, m = nts[lv], ms[lv]
    pl = _lv(p, offs[lv], nt, m)
    bl = _lv(b, offs[lv], nt, m)
    ctl = _ct(ct, coffs[lv], nt)
    cxl = _ct(cx, coffs[lv], nt)
    rl = _lv(r, offs[lv], nt, m)
    el = _lv(e, offs[lv], nt, m)
    tl = _lv(tmp, offs[lv], nt, m)
    ml = _lv(mask, offs[lv], nt, m)
    projected_gs(pl, bl, ctl, cxl, nt, m, pin0, nu1, np.bool_(False))
    if lv < nts.shape[0] - 1:
        for i in range(nt):
            for j in range(m + 1):
                ml[i, j] = pl[i, j] <= 0.0 or (pin0 and i == 0)
        residual(pl, bl, ctl, cxl, nt, m, rl)
        ntc, mc = nts[lv + 1], ms[lv + 1]
        restrict(rl, ml, nt, m, _lv(r, offs[lv + 1], ntc, mc), _lv(mask, offs[lv + 1], ntc, mc),
                 ntc, mc, kinds[lv], mask_rule)
        linear_vcycle(lv + 1, nts, ms, offs, coffs, kinds, ct, cx, e, r, tmp, mask, nu1, nu2,
                      mask_rule)
        el[:, :] = 0.0
        interpolate_add(_lv(e, offs[lv + 1], ntc, mc), ntc, mc, el, ml, nt, m, kinds[lv], 1.0)
        # projection onto p >= 0, then exact line search on J along the projected direction
        amax = 1e300
        for i in range(nt):
            for j in range(1, m + 1):
                v = el[i, j]
                if pl[i, j] + v < 0.0:
                    v = -pl[i, j]
                    el[i, j] = v
                if v < 0.0:
                    amax = min(amax, -pl[i, j] / v)
        apply_a(el, ctl, cxl, nt, m, tl)
        vav = _weighted_dot(el, tl, nt, m)
        if vav > 0.0:
            alpha = _weighted_dot(rl, el, nt, m) / vav
            alpha = min(max(alpha, 0.0), amax)
            for i in range(nt):
                for j in range(1, m + 1):
                    v = pl[i, j] + alpha * el[i, j]
                    pl[i, j] = v if v > 0.0 else 0.0
    projected_gs(pl, bl, ctl, cxl, nt, m, pin0, nu2, np.bool_(True))


@njit(cache=True)
def solve_level(lv, nts, ms, offs, coffs, kinds, ct, cx, p, b, e, r, tmp, mask, pin0, nu1, nu2,
                mask_rule, tol, maxit, history):
    """TNNMG cycles on level lv until the natural residual <= tol * max|b|.

    Returns the number of cycles (negative if maxit was reached); ``history[k]`` receives the
    relative natural residual after cycle k (history[0]: initial).
    """
    nt, m = nts[lv], ms[lv]
    pl = _lv(p, offs[lv], nt, m)
    bl = _lv(b, offs[lv], nt, m)
    ctl = _ct(ct, coffs[lv], nt)
    cxl = _ct(cx, coffs[lv], nt)
    tl = _lv(tmp, offs[lv], nt, m)
    bmax = 0.0
    for i in range(nt):
        for j in range(1, m + 1):
            bmax = max(bmax, abs(bl[i, j]))
    if pin0:
        pl[0, :] = 0.0
    if bmax == 0.0:  # no source (f = 0, e.g. a centred journal at rest): p = 0 exactly
        pl[:, :] = 0.0
        if history.shape[0] > 0:
            history[0] = 0.0
        return 0
    nat, big = natural_residual(pl, bl, ctl, cxl, nt, m, pin0, tl)
    res = nat / bmax
    if history.shape[0] > 0:
        history[0] = res
    k = 0
    # the attainable residual is limited by rounding in A p - b: about ROUND_FLOOR * max a_ii p
    while res > max(tol, ROUND_FLOOR * big / bmax):
        if k >= maxit:
            return -k
        tnnmg_cycle(lv, nts, ms, offs, coffs, kinds, ct, cx, p, b, e, r, tmp, mask, pin0, nu1,
                    nu2, mask_rule)
        k += 1
        nat, big = natural_residual(pl, bl, ctl, cxl, nt, m, pin0, tl)
        res = nat / bmax
        if k < history.shape[0]:
            history[k] = res
    return k


@njit(cache=True)
def setup_levels(lam, x, y, xd, yd, theta0, nts, ms, offs, coffs, ct, cx, b):
    """Coefficients and loads of every level (rediscretised Eq. 2-3)."""
    for lv in range(nts.shape[0]):
        nt, m = nts[lv], ms[lv]
        level_coefficients(lam, x, y, xd, yd, theta0, nt, m, _ct(ct, coffs[lv], nt),
                           _ct(cx, coffs[lv], nt), _lv(b, offs[lv], nt, m))


@njit(cache=True)
def full_multigrid(nts, ms, offs, coffs, kinds, ct, cx, p, b, e, r, tmp, mask, pin0, nu1, nu2,
                   mask_rule, coarse_cycles):
    """Nested iteration: projected GS on the coarsest level, then on each finer level the
    interpolated coarse solution followed by ``coarse_cycles`` TNNMG cycles (level 0 excluded:
    the caller iterates there to the tolerance)."""
    nl = nts.shape[0]
    lv = nl - 1
    nt, m = nts[lv], ms[lv]
    pl = _lv(p, offs[lv], nt, m)
    pl[:, :] = 0.0
    projected_gs(pl, _lv(b, offs[lv], nt, m), _ct(ct, coffs[lv], nt), _ct(cx, coffs[lv], nt),
                 nt, m, pin0, 50 * (nt + m), np.bool_(False))
    for lv in range(nl - 2, -1, -1):
        nt, m = nts[lv], ms[lv]
        ntc, mc = nts[lv + 1], ms[lv + 1]
        interpolate_solution(_lv(p, offs[lv + 1], ntc, mc), ntc, mc, _lv(p, offs[lv], nt, m),
                             nt, m, kinds[lv])
        if lv > 0:
            for _ in range(coarse_cycles):
                tnnmg_cycle(lv, nts, ms, offs, coffs, kinds, ct, cx, p, b, e, r, tmp, mask, pin0,
                            nu1, nu2, mask_rule)


@njit(cache=True)
def film_force_of(p, nt, m, theta0, lam):
    """(Fx, Fy) of Eq. (5) (:func:`bearing_fmu.reynolds.nodal_force`): periodic trapezoid in
    theta, trapezoid in xi over the full length (mirror of the half, p = 0 at the edges)."""
    dth = 2.0 * math.pi / nt
    dxi = lam / m
    line = np.empty(nt)
    cs = np.empty(nt)
    sn = np.empty(nt)
    for i in range(nt):
        s = 0.0
        for j in range(1, m):
            s += 2.0 * p[i, j]
        s += p[i, m]
        line[i] = s
        th = theta0 + i * dth
        cs[i] = math.cos(th)
        sn[i] = math.sin(th)
    out = np.empty(2)
    nodal_force(line, cs, sn, dth * dxi, out)
    return out[0], out[1]
