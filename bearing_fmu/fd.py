"""Finite-difference Reynolds solver with cavitation and multigrid: the accuracy reference.

Table 4 case 4 of the paper. The dimensionless Reynolds equation (Eq. 2-3) is discretised by the
conservative 5-point finite-volume stencil on an ``n_theta x n_xi`` grid (theta periodic,
``p = 0`` at ``xi = ±lambda``), ``h^3`` taken exactly at the cell faces in theta and at the
nodes in xi (h does not depend on xi). The Swift-Stieber condition (Eq. 4) is the discrete
obstacle problem

    p >= 0,   A p - b >= 0,   p . (A p - b) = 0,

the same variational inequality the hybrid method solves, so both converge to one solution.
It is solved exactly by a primal-dual active-set loop (the pressurised set P is updated from the
signs of p and of the residual until it repeats); each pass solves ``A_PP p_P = b_P`` with
conjugate gradients preconditioned by algebraic multigrid (pyamg, smoothed aggregation; its
V-cycle converges in a number of iterations independent of the mesh), or with a sparse direct
factorisation (``linear_solver="direct"``). Warm start: the previous call's active set.

Forces (Eq. 5) by the trapezoidal rule (second order). Jacobians by numerical differentiation
of the force, as in the paper's case 4 (``jacobian_scheme="forward"``, or ``"central"``).
:func:`reference_film_force` Richardson-extrapolates successive refinements.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from bearing_fmu.base import BearingData, FilmBearingModel, FilmForce

__all__ = ["FiniteDifferenceBearing", "reference_film_force", "reynolds_operator"]


def reynolds_operator(lam, x, y, xd, yd, n_theta, n_xi, theta0=0.0):
    """Matrix A (CSR), load b, node angles and steps of the discrete Eq. (2).

    Unknowns: interior xi nodes j = 1 .. n_xi - 1 of every theta node i (index i*(n_xi-1)+j-1).
    Rows are scaled by the cell area dtheta*dxi so that A is symmetric positive definite.
    """
    dth = 2.0 * math.pi / n_theta
    dxi = 2.0 * lam / n_xi
    th = theta0 + np.arange(n_theta) * dth
    h = 1.0 - x * np.cos(th) - y * np.sin(th)
    thf = th + 0.5 * dth
    hf3 = (1.0 - x * np.cos(thf) - y * np.sin(thf)) ** 3  # face i+1/2
    f = (y + 2.0 * xd) * np.cos(th) + (2.0 * yd - x) * np.sin(th)
    nj = n_xi - 1
    N = n_theta * nj
    idx = np.arange(N).reshape(n_theta, nj)
    cth = hf3 * dxi / dth  # theta fluxes, face i+1/2
    cxi = h**3 * dth / dxi  # xi fluxes at node i
    cth_m = np.roll(cth, 1)
    diag = (cth + cth_m)[:, None] + 2.0 * cxi[:, None] * np.ones((1, nj))
    rows = [idx.ravel()]
    cols = [idx.ravel()]
    vals = [diag.ravel()]
    # theta neighbours (periodic)
    rows.append(idx.ravel())
    cols.append(np.roll(idx, -1, axis=0).ravel())
    vals.append(-np.repeat(cth, nj))
    rows.append(idx.ravel())
    cols.append(np.roll(idx, 1, axis=0).ravel())
    vals.append(-np.repeat(cth_m, nj))
    # xi neighbours (Dirichlet at the ends)
    rows.append(idx[:, 1:].ravel())
    cols.append(idx[:, :-1].ravel())
    vals.append(-np.repeat(cxi, nj - 1))
    rows.append(idx[:, :-1].ravel())
    cols.append(idx[:, 1:].ravel())
    vals.append(-np.repeat(cxi, nj - 1))
    A = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(N, N))
    b = np.repeat(f, nj) * dth * dxi
    return A, b, th, dth, dxi


def _solve(A, b, method, tol):
    if method == "direct":
        from scipy.sparse.linalg import splu

        return splu(A.tocsc()).solve(b)
    import pyamg

    ml = pyamg.smoothed_aggregation_solver(A, symmetry="symmetric", max_coarse=64)
    residuals = []
    x = ml.solve(b, tol=tol, accel="cg", maxiter=200, residuals=residuals)
    if residuals[-1] > tol * max(np.linalg.norm(b), 1e-300) * 10:
        raise RuntimeError(f"multigrid did not converge: residual {residuals[-1]:.3e}")
    return x


def solve_complementarity(A, b, active, method="multigrid", tol=1e-12, maxit=1000,
                          pinned=None):
    """Primal-dual active set on p >= 0, Ap - b >= 0, p(Ap - b) = 0. Returns (p, active, passes)."""
    N = b.shape[0]
    A = A.tocsr()
    active = active.copy()
    if pinned is not None:
        active[pinned] = False
    for passes in range(1, maxit + 1):
        p = np.zeros(N)
        P = np.flatnonzero(active)
        if P.size:
            p[P] = _solve(A[P][:, P], b[P], method, tol)
        w = A @ p - b
        new = (active & (p > 0.0)) | (~active & (w < 0.0))
        if pinned is not None:
            new[pinned] = False
        if np.array_equal(new, active):
            return p, active, passes
        active = new
    raise RuntimeError(f"active set did not settle in {maxit} passes")


class FiniteDifferenceBearing(FilmBearingModel):
    """2-D finite-difference/multigrid Reynolds solver (the reference, Table 4 case 4).

    Parameters
    ----------
    bearing : BearingData
    n_theta, n_xi : int
        Intervals around and along the bearing (paper: 192 x 32); n_xi even.
    linear_solver : {"multigrid", "direct"}
    jacobian_scheme : {"central", "forward"}
    jacobian_step : float
        Step in the dimensionless state for the numerical Jacobian.
    pinned_start : bool
        p = 0 on the line of maximum film thickness (Raimondi-Boyd convention).
    """

    name = "fd"

    def __init__(self, bearing, n_theta=192, n_xi=32, linear_solver="multigrid",
                 jacobian_scheme="central", jacobian_step=1e-6, pinned_start=False,
                 tol=1e-12):
        super().__init__(bearing)
        if n_theta < 8 or n_xi < 4 or n_xi % 2:
            raise ValueError(f"mesh {n_theta} x {n_xi}: need n_theta >= 8 and even n_xi >= 4")
        if linear_solver not in ("multigrid", "direct"):
            raise ValueError(f"linear_solver {linear_solver!r}: 'multigrid' or 'direct'")
        if jacobian_scheme not in ("central", "forward"):
            raise ValueError(f"jacobian_scheme {jacobian_scheme!r}: 'central' or 'forward'")
        self.n_theta = int(n_theta)
        self.n_xi = int(n_xi)
        self.linear_solver = linear_solver
        self.jacobian_scheme = jacobian_scheme
        self.jacobian_step = float(jacobian_step)
        self.pinned_start = bool(pinned_start)
        self.tol = tol
        self._active = None
        self.solves = 0
        self.last_info = None

    @classmethod
    def from_lambda(cls, lambda_, **kw) -> FiniteDifferenceBearing:
        """A model of the dimensionless problem, which depends on L/D only."""
        return cls(BearingData(diameter=1.0, length=lambda_, clearance=1e-3, viscosity=1.0), **kw)

    def pressure(self, x, y, xd=0.0, yd=0.0):
        """(theta, xi, p[theta, xi]) including the zero boundary rows in xi."""
        theta0 = math.atan2(y, x) + math.pi if self.pinned_start else 0.0
        A, b, th, _, _ = reynolds_operator(self.bearing.lambda_, x, y, xd, yd,
                                           self.n_theta, self.n_xi, theta0)
        nj = self.n_xi - 1
        active = self._active if self._active is not None and self._active.size == b.size \
            else b > 0
        pinned = np.arange(nj) if self.pinned_start else None
        p, active, passes = solve_complementarity(A, b, active, self.linear_solver, self.tol,
                                                  pinned=pinned)
        self._active = active
        self.solves += 1
        self.last_info = dict(active_set_passes=passes)
        P = np.zeros((self.n_theta, self.n_xi + 1))
        P[:, 1:-1] = p.reshape(self.n_theta, nj)
        xi = np.linspace(-self.bearing.lambda_, self.bearing.lambda_, self.n_xi + 1)
        return th, xi, P

    def pressure_field(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, n_xi=None):
        """Dimensionless pressure for plots (theta [rad], xi [-], p[theta, xi])."""
        return self.pressure(xbar, ybar, xbar_dot, ybar_dot)

    def _force(self, x, y, xd, yd):
        th, xi, P = self.pressure(x, y, xd, yd)
        dth = 2.0 * math.pi / self.n_theta
        dxi = xi[1] - xi[0]
        pint = P.sum(axis=1) * dxi  # trapezoid in xi (zero end values)
        return -dth * np.array([np.dot(pint, np.cos(th)), np.dot(pint, np.sin(th))])

    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        st = np.array([xbar, ybar, xbar_dot, ybar_dot], dtype=float)
        f = self._force(*st)
        if not jacobian:
            return FilmForce(f)
        active0 = self._active
        jac = np.zeros((2, 4))
        h = self.jacobian_step
        for j in range(4):
            d = np.zeros(4)
            d[j] = h
            self._active = active0
            fp = self._force(*(st + d))
            if self.jacobian_scheme == "central":
                self._active = active0
                jac[:, j] = (fp - self._force(*(st - d))) / (2.0 * h)
            else:
                jac[:, j] = (fp - f) / h
        self._active = active0
        return FilmForce(f, jac[:, :2], jac[:, 2:])


def reference_film_force(lambda_, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0,
                         levels=((384, 64), (768, 128))):
    """Richardson-extrapolated force from successive refinements (second order).

    Returns (force, info) with info = dict(forces per level, observed order when three levels
    are given, estimated error of the finest level).
    """
    forces = []
    mask, mask_shape = None, None
    for nt, nx in levels:
        model = FiniteDifferenceBearing.from_lambda(lambda_, n_theta=nt, n_xi=nx,
                                                    linear_solver="direct")
        if mask is not None:  # start from the coarser level's film region
            m = mask.reshape(mask_shape)
            m = np.repeat(np.repeat(m, nt // mask_shape[0], axis=0), (nx - 1) // m.shape[1] + 1,
                          axis=1)[:, : nx - 1]
            model._active = m.ravel().copy()
        forces.append(model.dimensionless(xbar, ybar, xbar_dot, ybar_dot, jacobian=False).force)
        mask, mask_shape = model._active, (nt, nx - 1)
    forces = np.array(forces)
    ext = forces[-1] + (forces[-1] - forces[-2]) / 3.0
    info = dict(levels=[list(lv) for lv in levels], forces=forces.tolist(),
                error_finest=float(np.linalg.norm(forces[-1] - ext) / np.linalg.norm(ext)))
    if len(levels) >= 3:
        m = np.linalg.norm(forces, axis=1)
        info["observed_order"] = float(np.log2(abs((m[-3] - m[-2]) / (m[-2] - m[-1]))))
    return ext, info
