"""The finite-difference Reynolds problem on a full grid, solved directly, and the converged
reference force (paper Table 4 case 4 and beyond).

* :func:`reynolds_operator`: the discrete Eq. (2)-(3) of :mod:`bearing_fmu.fd` (same stencil as
  the multigrid kernels) as a sparse matrix on the full grid;
* :func:`solve_complementarity`: the Swift-Stieber LCP (Eq. 4) by a primal-dual active set with
  sparse LU, an independent check of the multigrid;
* :func:`reference_film_force`: Richardson extrapolation of successive refinements.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import scipy.sparse as sp

from bearing_fmu.base import check_state
from bearing_fmu.reynolds import film_thickness, source, source_coefficients

__all__ = ["reference_film_force", "reynolds_operator", "solve_complementarity"]


def reynolds_operator(lam, x, y, xd, yd, n_theta, n_xi, theta0=0.0):
    """Matrix A (CSR), load b, node angles and steps of the discrete Eq. (2), full grid.

    Unknowns: interior xi nodes j = 1 .. n_xi - 1 of every theta node i (index
    ``i*(n_xi-1) + j-1``). Rows are scaled by the cell area ``dtheta dxi`` (A symmetric
    positive definite). Same stencil as the multigrid kernels.
    """
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


def reference_film_force(lambda_, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0,
                         levels=((192, 32), (384, 64), (768, 128)), **kw):
    """Richardson-extrapolated force from successive refinements (second-order scheme).

    Parameters
    ----------
    lambda_ : float
        L/D.
    xbar, ybar, xbar_dot, ybar_dot : float
        Dimensionless state (Eq. 3).
    levels : sequence of (n_theta, n_xi)
        At least two meshes, each the previous one refined by 2 in both directions.
    **kw
        Passed to :class:`~bearing_fmu.fd.FiniteDifferenceBearing` (e.g. ``pinned_start``).

    Returns
    -------
    force : ndarray (2,)
        ``F_fine + (F_fine - F_prev) / 3`` (Richardson with the theoretical order 2).
    info : dict
        ``forces`` per level; ``error_finest``: ``|F_fine - force| / |force|``; with three or more
        levels also ``observed_order`` (from the force magnitudes), ``force_observed_order``
        (extrapolated with it) and ``error_estimate``: the relative distance between the
        extrapolations with order 2 and with the observed order, or between the last two
        order-2 extrapolations if larger/3 (an estimate of the error of ``force``).
    """
    levels = [tuple(int(v) for v in lv) for lv in levels]
    if len(levels) < 2:
        raise ValueError(f"levels = {levels}: need at least two meshes")
    for (a0, b0), (a1, b1) in itertools.pairwise(levels):
        if a1 != 2 * a0 or b1 != 2 * b0:
            raise ValueError(f"levels = {levels}: each mesh must double the previous one")
    check_state(xbar, ybar, xbar_dot, ybar_dot)
    forces = []
    from bearing_fmu.fd import FiniteDifferenceBearing

    for nt, nx in levels:
        model = FiniteDifferenceBearing.from_lambda(lambda_, n_theta=nt, n_xi=nx, **kw)
        forces.append(model.dimensionless(xbar, ybar, xbar_dot, ybar_dot, jacobian=False).force)
    forces = np.array(forces)
    ext = forces[-1] + (forces[-1] - forces[-2]) / 3.0
    norm = float(np.linalg.norm(ext))
    info = dict(levels=[list(lv) for lv in levels], forces=forces.tolist(),
                error_finest=float(np.linalg.norm(forces[-1] - ext) / norm))
    if len(levels) >= 3:
        mag = np.linalg.norm(forces, axis=1)
        d1, d2 = mag[-3] - mag[-2], mag[-2] - mag[-1]
        order = float(np.log2(abs(d1 / d2))) if d2 != 0.0 else float("inf")
        info["observed_order"] = order
        prev = forces[-2] + (forces[-2] - forces[-3]) / 3.0
        est = float(np.linalg.norm(ext - prev)) / norm / 3.0
        if math.isfinite(order) and order > 0.5:
            f_obs = forces[-1] + (forces[-1] - forces[-2]) / (2.0**order - 1.0)
            info["force_observed_order"] = f_obs.tolist()
            est = max(est, float(np.linalg.norm(ext - f_obs)) / norm)
        info["error_estimate"] = est
    return ext, info
