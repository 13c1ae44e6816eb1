"""The finite-difference Reynolds problem on a full grid, solved directly: the independent
check of the multigrid of :mod:`bearing_fmu.fd.model` (``linear_solver="direct"``).

* :func:`reynolds_operator`: the discrete Eq. (2)-(3) of :mod:`bearing_fmu.fd.model` (same stencil
  as the multigrid kernels) as a sparse matrix on the full grid;
* :func:`solve_complementarity`: the Swift-Stieber LCP (Eq. 4) by a primal-dual active set with
  sparse LU.

The converged reference force built on the model
(:func:`bearing_fmu.fd.model.reference_film_force`) is in :mod:`bearing_fmu.fd.model`, which this
module stays below: it knows the grid, not the model.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_fmu.reynolds import film_thickness, source, source_coefficients

__all__ = ["reynolds_operator", "solve_complementarity"]


def reynolds_operator(lam, x, y, xd, yd, n_theta, n_xi, theta0=0.0):
    """Matrix A (CSR), load b, node angles and steps of the discrete Eq. (2), full grid.

    Unknowns: interior xi nodes j = 1 .. n_xi - 1 of every theta node i (index
    ``i*(n_xi-1) + j-1``). Rows are scaled by the cell area ``dtheta dxi`` (A symmetric
    positive definite). Same stencil as the multigrid kernels.
    """
    import scipy.sparse as sp  # (here: not at every start of the package)

    dth = 2.0 * math.pi / n_theta
    dxi = 2.0 * lam / n_xi
    th = theta0 + np.arange(n_theta) * dth
    h = film_thickness.py_func(x, y, np.cos(th), np.sin(th))  # Eq. (3)
    thf = th + 0.5 * dth
    hf3 = film_thickness.py_func(x, y, np.cos(thf), np.sin(thf)) ** 3  # face i+1/2
    f = source.py_func(*source_coefficients.py_func(x, y, xd, yd), np.cos(th), np.sin(th))
    nj = n_xi - 1
    n = n_theta * nj
    idx = np.arange(n).reshape(n_theta, nj)
    cth = hf3 * dxi / dth
    cxi = h**3 * dth / dxi
    cth_m = np.roll(cth, 1)
    diag = (cth + cth_m)[:, None] + 2.0 * cxi[:, None] * np.ones((1, nj))
    rows = [idx.ravel(), idx.ravel(), idx.ravel(), idx[:, 1:].ravel(), idx[:, :-1].ravel()]
    cols = [idx.ravel(), np.roll(idx, -1, axis=0).ravel(), np.roll(idx, 1, axis=0).ravel(),
            idx[:, :-1].ravel(), idx[:, 1:].ravel()]
    vals = [diag.ravel(), -np.repeat(cth, nj), -np.repeat(cth_m, nj),
            -np.repeat(cxi, nj - 1), -np.repeat(cxi, nj - 1)]
    a = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n))
    b = np.repeat(f, nj) * dth * dxi
    return a, b, th, dth, dxi


def solve_complementarity(a, b, active, method="direct", tol=None, maxit=1000, pinned=None):
    """Primal-dual active set on p >= 0, Ap - b >= 0, p (Ap - b) = 0 with sparse LU solves.

    Finite for a Stieltjes matrix (Hintermuller, Ito & Kunisch 2003). ``active`` (bool): the
    initial pressurised set. Returns (p, active, passes).
    """
    from scipy.sparse.linalg import splu

    if method != "direct":
        raise ValueError(f"method = {method!r}: only 'direct' (the multigrid is the model's)")
    n = b.shape[0]
    a = a.tocsr()
    active = np.asarray(active, dtype=bool).copy()
    if pinned is not None:
        active[pinned] = False
    for passes in range(1, maxit + 1):
        p = np.zeros(n)
        sel = np.flatnonzero(active)
        if sel.size:
            p[sel] = splu(a[sel][:, sel].tocsc()).solve(b[sel])
        w = a @ p - b
        new = (active & (p > 0.0)) | (~active & (w < 0.0))
        if pinned is not None:
            new[pinned] = False
        if np.array_equal(new, active):
            return p, active, passes
        active = new
    raise RuntimeError(f"active set did not settle in {maxit} passes")
