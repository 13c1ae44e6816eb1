"""One structural Newmark step on the condensed DOFs: right-hand side, tangent and update.

With the history terms of Eq. (12) (:func:`gear_fmu.step.newmark.newmark_history`) and the constant
part of the tangent condensed onto the gear and bearing DOFs (:mod:`gear_fmu.step.condensation`),
:func:`prepare_step` adds the external loads (the unbalances of Eq. 10) and the affine bearing
laws F0 - Kb X - Cb Xdot (Eq. 17) of every bearing to the right-hand side and ``Kb + c1 Cb``
to the tangent (Eq. 14, 16); after the Newton/contact loop
:func:`gear_fmu.step.kernel.advance` recovers the
eliminated DOFs and updates velocities and accelerations (Eq. 12). :func:`check_laws` validates
the laws.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gear_fmu.step.newmark import newmark_coefficients, newmark_history

__all__ = ["check_laws", "check_laws_fast", "column_nonzeros", "history_memo",
           "history_products", "matvec_t", "matvec_t_sparse", "prepare_step"]


def history_memo(n: int) -> np.ndarray:
    """An empty memo of :func:`history_products` for n DOFs."""
    memo = np.zeros(5 * n + 1)
    memo[0] = np.nan  # no dt equals NaN: the first call computes
    return memo


@njit(cache=True)
def _same_bits(u, w):
    """u and w have the same bits (NaN never does: the memo then computes)."""
    return u == w and (u != 0.0 or math.copysign(1.0, u) == math.copysign(1.0, w))


@njit(cache=True)
def matvec_t(at, x):
    """``at.T @ x``: ``out[i] = sum_j at[j, i] x[j]``, summed in the order of j.

    The compiled step's products, in a fixed order: BLAS (``@``) shares a product of a
    hundred rows among its threads and takes rows by kernels that depend on the CPU, so its
    last bits would depend on the caller's BLAS thread setting
    (:mod:`bearing_fmu.blas_threads`). Over a transposed matrix stored C-contiguous, four
    rows of ``at`` at a time: each entry is still the sequence of multiplications and
    additions in the order of j (the same bits as one row at a time), read and written once
    per four rows, whatever the vector width (214 x 107 on the development machine: 2.1 us,
    against 2.5 us one row at a time)."""
    out = np.zeros(at.shape[1])
    _add_rows_t(at, x, 0, out)
    return out


@njit(cache=True, inline="always")
def _add_rows_t(at, x, first, out):
    """``out[i] += at[j, i] x[j]`` for the rows ``j >= first`` in their order, four at a time
    (:func:`matvec_t`)."""
    k, n = at.shape
    k4 = k - (k - first) % 4
    for j in range(first, k4, 4):
        x0, x1, x2, x3 = x[j], x[j + 1], x[j + 2], x[j + 3]
        for i in range(n):
            out[i] = (((out[i] + at[j, i] * x0) + at[j + 1, i] * x1) + at[j + 2, i] * x2
                      + at[j + 3, i] * x3)
    for j in range(k4, k):
        xj = x[j]
        for i in range(n):
            out[i] += at[j, i] * xj


@njit(cache=True)
def matvec_t_sparse(at, indptr, indices, x):
    """:func:`matvec_t` of an ``at`` whose first ``m = indptr.size - 1`` rows are sparse
    (M's half of [M C]^T: M is 4 % nonzero in the paper's case): row j < m is taken at its
    nonzero columns ``indices[indptr[j]:indptr[j + 1]]`` only (:func:`column_nonzeros`).

    The same bits as :func:`matvec_t` for a finite ``x``: each entry is still the sequence of
    its terms in the order of j, and a term left out is ``0 * x[j]``, a zero of either sign,
    which added to a sum leaves it as it is (a sum from +0 is never -0). A non-finite
    ``x[j]`` reaches the nonzero columns of row j only (the step has failed anyway)."""
    m = indptr.size - 1
    out = np.zeros(at.shape[1])
    for j in range(m):
        xj = x[j]
        for p in range(indptr[j], indptr[j + 1]):
            i = indices[p]
            out[i] += at[j, i] * xj
    _add_rows_t(at, x, m, out)
    return out


def column_nonzeros(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(indptr, indices)`` (int64): the rows of the nonzero entries of each column j of
    ``matrix``, ``indices[indptr[j]:indptr[j + 1]]`` in increasing order, as
    :func:`matvec_t_sparse` takes the rows of ``matrix.T``."""
    cols, rows = np.nonzero(np.asarray(matrix).T)  # (row-major order of the transpose)
    indptr = np.zeros(matrix.shape[1] + 1, dtype=np.int64)
    np.cumsum(np.bincount(cols, minlength=matrix.shape[1]), out=indptr[1:])
    return indptr, np.ascontiguousarray(rows, dtype=np.int64)


@njit(cache=True)
def history_products(mc, g_t, x, v, a, dt, nc, memo):
    """``b = [M C] [p; q]``, the history terms of Eq. (12)
    (:func:`gear_fmu.step.newmark.newmark_history`), and ``out = g b_r`` (the condensation
    of its r part), memoised; ``mc`` = ([M C]^T (2n, n), then the nonzero rows of each
    column of M, :func:`column_nonzeros`) as :func:`matvec_t_sparse` takes them and ``g_t`` = g^T
    (:class:`gear_fmu.step.condensation.Condensation`) as :func:`matvec_t` takes it.

    The master computes a step again at each of its iterations from the same (X, Xd, Xdd)
    and dt, and these two products (107 x 214 and 107 x 87 in the paper's case) do not
    depend on the bearing laws: they were a fifth of the structure's step. ``memo``
    (:func:`history_memo`, 5n + 1) keeps the bits of the last inputs ``[dt, X, Xd, Xdd]``
    and both products; when the inputs have the same bits, the products are the memo's,
    otherwise they are computed and kept. The memo belongs to one [M C] and one
    condensation per dt (:class:`gear_fmu.structure.Structure` empties it when C changes).
    An empty memo (size 0) computes without keeping. Returns ``(b, out)``, each (n,).
    """
    n = x.shape[0]
    if memo.shape[0] == 5 * n + 1:
        hit = _same_bits(memo[0], dt)
        i = 0
        while hit and i < n:
            hit = (_same_bits(memo[1 + i], x[i]) and _same_bits(memo[1 + n + i], v[i])
                   and _same_bits(memo[1 + 2 * n + i], a[i]))
            i += 1
        if hit:
            return memo[1 + 3 * n:1 + 4 * n], memo[1 + 4 * n:]
    pq = newmark_history(x, v, a, dt)
    b = matvec_t_sparse(mc[0], mc[1], mc[2], pq)
    out = matvec_t(g_t, b[nc:])  # -W^T b_r, then A_rr^-1 b_r
    if memo.shape[0] == 5 * n + 1:
        memo[0] = dt
        memo[1:1 + n] = x
        memo[1 + n:1 + 2 * n] = v
        memo[1 + 2 * n:1 + 3 * n] = a
        memo[1 + 3 * n:1 + 4 * n] = b
        memo[1 + 4 * n:] = out
    return b, out


@njit(cache=True)
def prepare_step(mc, g_t, g_const, x, v, a, f_c, unb, unb_idx, f0, kb, cb, s0, dt, ng, memo):
    """Right-hand side and condensed tangent of one Newmark step (Eq. 12, 14, 16).

    ``mc`` = ([M C]^T (2n, n), M's nonzeros) turns the Newmark history [p; q]
    into b = M p + C q (:func:`history_products`); ``g_t``
    (:class:`gear_fmu.step.condensation.Condensation`) condenses its r part
    (:func:`history_products`, with its ``memo``). Only ``g_t`` depends on the step's length:
    a new length costs its condensation, not a product with [M C] (what a step that does
    not recur with the mesh period asks at most cut steps). ``unb`` (nu, 2): the unbalance
    forces of Eq. (10) [N] on the condensed DOFs ``unb_idx`` (nu, 2); bearing j's law (Eq. 17)
    acts on the condensed DOFs ``ng + 2 j``, ``ng + 2 j + 1``.
    Returns ``s_lin`` (nc, nc) = S0 + Kb + c1 Cb, ``z0`` (nc,) and ``y`` = A_rr^-1 b_r.
    """
    nc = s0.shape[0]
    _, c1, _ = newmark_coefficients(dt)
    b, out = history_products(mc, g_t, x, v, a, dt, nc, memo)
    z0 = np.empty(nc)
    for i in range(nc):
        z0[i] = b[i] + out[i] + g_const[i] + f_c[i]
    for i in range(unb.shape[0]):
        z0[unb_idx[i, 0]] += unb[i, 0]
        z0[unb_idx[i, 1]] += unb[i, 1]
    y = out[nc:] + g_const[nc:]
    s_lin = s0.copy()
    for j in range(f0.shape[0]):
        o = ng + 2 * j
        for r in range(2):
            acc = f0[j, r]
            for c in range(2):
                acc += cb[j, r, c] * (c1 * x[o + c] + v[o + c])
                s_lin[o + r, o + c] += kb[j, r, c] + c1 * cb[j, r, c]
            z0[o + r] += acc
    return s_lin, z0, y


@njit(cache=True)
def _all_finite(f0, kb, cb):
    """True when every entry of the bearing laws is finite."""
    return np.isfinite(f0).all() and np.isfinite(kb).all() and np.isfinite(cb).all()


def check_laws(f0, kb, cb, nb: int):
    """Bearing laws as float arrays of shapes (nb, 2), (nb, 2, 2), (nb, 2, 2), all finite."""
    f0 = np.asarray(f0, dtype=float)
    kb = np.asarray(kb, dtype=float)
    cb = np.asarray(cb, dtype=float)
    if f0.shape != (nb, 2) or kb.shape != (nb, 2, 2) or cb.shape != (nb, 2, 2):
        raise ValueError(
            f"bearing laws shapes F0 {f0.shape}, Kb {kb.shape}, Cb {cb.shape}: expected "
            f"({nb}, 2), ({nb}, 2, 2), ({nb}, 2, 2) for {nb} bearings"
        )
    if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(kb)) and np.all(np.isfinite(cb))):
        raise ValueError("bearing laws contain non-finite values")
    return f0, kb, cb


def check_laws_fast(f0, kb, cb, nb: int):
    """Shape and finiteness check of the laws at the cost of one compiled test (hot path)."""
    nd = np.ndarray
    if (type(f0) is nd and type(kb) is nd and type(cb) is nd
            and f0.shape == (nb, 2) and kb.shape == (nb, 2, 2) and cb.shape == (nb, 2, 2)
            and f0.dtype == np.float64 and kb.dtype == np.float64 and cb.dtype == np.float64
            and _all_finite(f0, kb, cb)):
        return f0, kb, cb
    return check_laws(f0, kb, cb, nb)
