"""Grids of the finite-difference Reynolds solver (:mod:`bearing_fmu.fd.model`): discrete Eq.
(2)-(3),
smoothers, residuals and the transfers between levels (the cycles: :mod:`bearing_fmu.fd._kernels`).

Grid of one level: ``n_t`` periodic nodes ``theta_i = theta_0 + i dtheta`` and the half length
``xi_j = -lambda + j dxi``, ``j = 0 .. m`` (``j = 0``: the bearing edge, p = 0; ``j = m``: the
mid-plane xi = 0, where the mirror condition ``p_{m+1} = p_{m-1}`` holds by the symmetry
xi -> -xi of Eq. 2-3). A level is stored row-major as ``(n_t, m + 1)`` inside one flat array
per quantity, at offset ``off[l]``; column 0 is the edge and stays zero.

Discrete Eq. (2), one row per node, multiplied by the cell area ``dtheta dxi`` (so that the
operator of the *full* domain is symmetric positive definite, a Stieltjes matrix):

    (A p)_ij = ct_i (p_ij - p_i+1,j) + ct_i-1 (p_ij - p_i-1,j) + cx_i (2 p_ij - p_i,j-1 - p_i,j+1)
    ct_i = h(theta_i + dtheta/2)^3 dxi / dtheta,   cx_i = h(theta_i)^3 dtheta / dxi,
    b_ij = f(theta_i) dtheta dxi.

Inner products and energies are those of the full domain: weight 2 for ``j < m`` and 1 for the
mid-plane row ``j = m``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.reynolds import film_thickness, source, source_coefficients

# transfer types between level l and l + 1
BOTH, THETA_ONLY, XI_ONLY = 0, 1, 2
#: rounding floor of the natural residual relative to max a_ii p_i (a few ulp)
ROUND_FLOOR = 4e-15


@njit(cache=True)
def level_coefficients(lam, x, y, xd, yd, theta0, nt, m, ct, cx, b):
    """Face/node coefficients and load of one level (Eq. 3), in place: ct, cx (nt,), b (nt, m+1)."""
    dth = 2.0 * math.pi / nt
    dxi = lam / m
    a, c = source_coefficients(x, y, xd, yd)
    for i in range(nt):
        th = theta0 + i * dth
        h = film_thickness(x, y, math.cos(th), math.sin(th))
        thf = th + 0.5 * dth
        hf = film_thickness(x, y, math.cos(thf), math.sin(thf))
        ct[i] = hf * hf * hf * dxi / dth
        cx[i] = h * h * h * dth / dxi
        f = source(a, c, math.cos(th), math.sin(th)) * dth * dxi
        b[i, 0] = 0.0
        for j in range(1, m + 1):
            b[i, j] = f


@njit(cache=True, inline="always")
def _up(j, m):
    """Index of the upper xi neighbour (mirror at the mid-plane j = m)."""
    return j + 1 if j < m else m - 1


@njit(cache=True)
def projected_gs(p, b, ct, cx, nt, m, pin0, sweeps, reverse):
    """Red-black projected Gauss-Seidel for the obstacle problem (exact local LCP solves): the
    Swift-Stieber condition of Eq. (4) as p >= 0, A p - b >= 0, p (A p - b) = 0 per node.

    ``p_ij <- max(0, (b_ij + sum of neighbour fluxes) / a_ii)``; row i = 0 stays zero when
    ``pin0`` (film start pinned at theta_0). ``reverse`` swaps the colour order.
    """
    for _ in range(sweeps):
        for cc in range(2):
            col = 1 - cc if reverse else cc
            for i in range(nt):
                if pin0 and i == 0:
                    continue
                im = i - 1 if i > 0 else nt - 1
                ip = i + 1 if i < nt - 1 else 0
                cti = ct[i]
                ctm = ct[im]
                cxi = cx[i]
                d = cti + ctm + 2.0 * cxi
                j0 = 1 + ((i + 1 + col) & 1)
                for j in range(j0, m + 1, 2):
                    s = (b[i, j] + cti * p[ip, j] + ctm * p[im, j]
                         + cxi * (p[i, j - 1] + p[i, _up(j, m)]))
                    v = s / d
                    p[i, j] = v if v > 0.0 else 0.0


@njit(cache=True)
def linear_gs(e, r, ct, cx, nt, m, mask, sweeps, reverse):
    """Red-black Gauss-Seidel for A e = r with e = 0 where ``mask`` (truncated unknowns)."""
    for _ in range(sweeps):
        for cc in range(2):
            col = 1 - cc if reverse else cc
            for i in range(nt):
                im = i - 1 if i > 0 else nt - 1
                ip = i + 1 if i < nt - 1 else 0
                cti = ct[i]
                ctm = ct[im]
                cxi = cx[i]
                d = cti + ctm + 2.0 * cxi
                j0 = 1 + ((i + 1 + col) & 1)
                for j in range(j0, m + 1, 2):
                    if mask[i, j]:
                        e[i, j] = 0.0
                    else:
                        s = r[i, j] + cti * e[ip, j] + ctm * e[im, j] + cxi * (
                            e[i, j - 1] + e[i, _up(j, m)])
                        e[i, j] = s / d


@njit(cache=True)
def apply_a(p, ct, cx, nt, m, out):
    """out = A p (area-scaled rows)."""
    for i in range(nt):
        im = i - 1 if i > 0 else nt - 1
        ip = i + 1 if i < nt - 1 else 0
        cti = ct[i]
        ctm = ct[im]
        cxi = cx[i]
        d = cti + ctm + 2.0 * cxi
        out[i, 0] = 0.0
        for j in range(1, m + 1):
            out[i, j] = d * p[i, j] - cti * p[ip, j] - ctm * p[im, j] - cxi * (
                p[i, j - 1] + p[i, _up(j, m)])


@njit(cache=True)
def residual(p, b, ct, cx, nt, m, out):
    """out = b - A p; returns the scaled natural residual max |min(a_ii p, A p - b)|."""
    apply_a(p, ct, cx, nt, m, out)
    nat = 0.0
    for i in range(nt):
        im = i - 1 if i > 0 else nt - 1
        d = ct[i] + ct[im] + 2.0 * cx[i]
        for j in range(1, m + 1):
            w = out[i, j] - b[i, j]
            out[i, j] = -w
            v = min(d * p[i, j], w)
            if abs(v) > nat:
                nat = abs(v)
    return nat


@njit(cache=True)
def natural_residual(p, b, ct, cx, nt, m, pin0, work):
    """(max |min(a_ii p, A p - b)|, max a_ii p) over the free unknowns (pinned row excluded).

    The second value sets the rounding floor of the first (about 1e-16 times it).
    """
    apply_a(p, ct, cx, nt, m, work)
    nat = 0.0
    big = 0.0
    for i in range(nt):
        if pin0 and i == 0:
            continue
        im = i - 1 if i > 0 else nt - 1
        d = ct[i] + ct[im] + 2.0 * cx[i]
        for j in range(1, m + 1):
            dp = d * p[i, j]
            big = max(big, dp)
            v = min(dp, work[i, j] - b[i, j])
            if abs(v) > nat:
                nat = abs(v)
    return nat, big


@njit(cache=True)
def restrict(rf, maskf, ntf, mf, rc, maskc, ntc, mc, kind, mask_rule):
    """Full weighting rc = P^T (truncated rf) and the coarse mask.

    Fine residuals at masked nodes are dropped (truncation). ``mask_rule`` 0: a coarse node is
    masked when the fine node at the same place is (injection); 1: when any fine node of its
    interpolation stencil is masked.
    """
    for ic in range(ntc):
        for jc in range(mc + 1):
            rc[ic, jc] = 0.0
            maskc[ic, jc] = False
    for ic in range(ntc):
        for jc in range(1, mc + 1):
            if kind == BOTH:
                i0, j0 = 2 * ic, 2 * jc
                di0, di1, dj0, dj1 = -1, 1, -1, 1
            elif kind == THETA_ONLY:
                i0, j0 = 2 * ic, jc
                di0, di1, dj0, dj1 = -1, 1, 0, 0
            else:
                i0, j0 = ic, 2 * jc
                di0, di1, dj0, dj1 = 0, 0, -1, 1
            acc = 0.0
            anym = False
            for di in range(di0, di1 + 1):
                i = (i0 + di) % ntf
                wi = 1.0 if di == 0 else 0.5
                for dj in range(dj0, dj1 + 1):
                    j = j0 + dj
                    if j > mf:
                        j = 2 * mf - j
                    if j <= 0:
                        continue
                    if maskf[i, j]:
                        anym = True
                        continue
                    wj = 1.0 if dj == 0 else 0.5
                    acc += wi * wj * rf[i, j]
            rc[ic, jc] = acc
            if mask_rule == 0:
                maskc[ic, jc] = maskf[i0, j0]
            else:
                maskc[ic, jc] = anym


@njit(cache=True)
def interpolate_add(ec, ntc, mc, ef, maskf, ntf, mf, kind, alpha):
    """ef += alpha * (bilinear interpolation of ec) at the unmasked fine nodes."""
    for i in range(ntf):
        if kind == XI_ONLY:
            ia, ib, wa = i, i, 1.0
        else:
            ia = i // 2
            if i % 2 == 0:
                ib, wa = ia, 1.0
            else:
                ib, wa = (ia + 1) % ntc, 0.5
        for j in range(1, mf + 1):
            if maskf[i, j]:
                continue
            if kind == THETA_ONLY:
                ja, jb, wj = j, j, 1.0
            else:
                ja = j // 2
                if j % 2 == 0:
                    jb, wj = ja, 1.0
                else:
                    jb, wj = ja + 1, 0.5  # ja + 1 <= mc since mf = 2 mc is even
            if wa == 1.0:
                va = ec[ia, ja] if wj == 1.0 else wj * (ec[ia, ja] + ec[ia, jb])
            else:
                if wj == 1.0:
                    va = 0.5 * (ec[ia, ja] + ec[ib, ja])
                else:
                    va = 0.25 * (ec[ia, ja] + ec[ia, jb] + ec[ib, ja] + ec[ib, jb])
            ef[i, j] += alpha * va


@njit(cache=True)
def interpolate_solution(pc, ntc, mc, pf, ntf, mf, kind):
    """pf = bilinear interpolation of pc (nested iteration start), all nodes."""
    for i in range(ntf):
        for j in range(mf + 1):
            pf[i, j] = 0.0
    nomask = np.zeros((ntf, mf + 1), dtype=np.bool_)
    interpolate_add(pc, ntc, mc, pf, nomask, ntf, mf, kind, 1.0)


@njit(cache=True)
def coarse_direct(e, r, ct, cx, nt, m, mask):
    """Exact solve of the (masked) linear system on the coarsest level (dense)."""
    n = nt * m
    a = np.zeros((n, n))
    rhs = np.zeros(n)
    for i in range(nt):
        im = i - 1 if i > 0 else nt - 1
        ip = i + 1 if i < nt - 1 else 0
        d = ct[i] + ct[im] + 2.0 * cx[i]
        for j in range(1, m + 1):
            k = i * m + (j - 1)
            if mask[i, j]:
                a[k, k] = 1.0
                continue
            rhs[k] = r[i, j]
            a[k, k] += d
            if not mask[ip, j]:
                a[k, ip * m + j - 1] -= ct[i]
            if not mask[im, j]:
                a[k, im * m + j - 1] -= ct[im]
            if j > 1 and not mask[i, j - 1]:
                a[k, i * m + j - 2] -= cx[i]
            ju = _up(j, m)
            if ju > 0 and not mask[i, ju]:
                a[k, i * m + ju - 1] -= cx[i]
    sol = np.linalg.solve(a, rhs)
    for i in range(nt):
        e[i, 0] = 0.0
        for j in range(1, m + 1):
            e[i, j] = sol[i * m + j - 1]


@njit(cache=True)
def _lv(arr, off, nt, m):
    return arr[off : off + nt * (m + 1)].reshape((nt, m + 1))


@njit(cache=True)
def _ct(arr, coff, nt):
    return arr[coff : coff + nt]
