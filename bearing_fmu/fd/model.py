"""Finite-difference Reynolds solver with cavitation and multigrid: the accuracy reference.

Table 4 case 4 of the paper ("M.M.", 192 x 32). Solves Eq. (2)-(4) in the paper's
dimensionless variables: ``h = 1 - x cos(theta) - y sin(theta)``,
``f = (y + 2 xdot) cos(theta) + (2 ydot - x) sin(theta)``, ``xi = z/R`` in ``[-lambda, lambda]``,
``lambda = L/D``, p = 0 at ``xi = ±lambda``, theta periodic.

Discretisation
--------------
Conservative 5-point finite-volume stencil on ``n_theta x n_xi`` intervals (second order):
``h^3`` taken exactly at the theta faces ``theta_i ± dtheta/2`` and at the nodes for the xi
fluxes (h does not depend on xi); rows scaled by the cell area, so the matrix A is a symmetric
Stieltjes matrix. The Swift-Stieber condition (Eq. 4) is the discrete obstacle problem

    p >= 0,   A p - b >= 0,   p . (A p - b) = 0          (linear complementarity, LCP)

i.e. the minimisation of ``J(p) = p.Ap/2 - b.p`` over ``p >= 0``: the variational inequality the
hybrid method solves (``docs/hybrid-method.md`` Sec. 2), so both converge to one solution and
the film start is free (``pinned_start=True`` imposes p = 0 on the line of maximum film
thickness instead, the Raimondi-Boyd convention; the grid is then rotated so that this line is
a grid line). The symmetry xi -> -xi of Eq. (2)-(3) halves the grid: nodes
``j = 0 .. n_xi/2`` with a mirror condition at the mid-plane.

Forces (Eq. 5) by the trapezoidal rule in both directions (second order; the integrand is C^1
across the free boundary).

Solver: truncated nonsmooth Newton multigrid (TNNMG)
----------------------------------------------------
Why this one: a projected FAS (Brandt-Cryer, Venner-Lubrecht) multigrid works in practice but
has no convergence guarantee near the free boundary, and an active-set outer loop around a
linear multigrid costs several full linear solves per call. TNNMG (Graser & Kornhuber,
J. Comput. Math. 27 (2009) 1-44) keeps the exact projected Gauss-Seidel of the LCP as the
fine-grid smoother (globally convergent on its own for a Stieltjes matrix) and adds, per cycle,
one linear V-cycle for the defect equation *truncated* to the current pressurised set (nodes
with p = 0 get no correction; coarse nodes inherit the mask), then projects the correction onto
p >= 0 and takes the exact minimiser of the quadratic J along it. Each step can only decrease J,
so the method converges from any start; once the cavitated set has settled it is a linear
multigrid on the pressurised region, with mesh-independent convergence factors (measured by
``tests/bearing_fmu/test_fd_model.py``: about 0.05-0.15 per cycle).

Coarse levels are rediscretised (h is analytic). Smoother: red-black point Gauss-Seidel;
coarsening: in both directions, or only in the strongly coupled direction when the mesh is
anisotropic (``(dxi/dtheta)^2`` outside [1/2, 2]: semi-coarsening keeps point smoothing
effective at any L/D); the coarsest level is solved exactly (dense). Cold starts use nested
iteration (full multigrid) from the coarsest level; later calls warm-start from the previous
pressure field. Stopping test: the natural residual of the LCP,
``max |min(a_ii p_i, (A p - b)_i)| <= tol * max |b_i|``.

Jacobians by numerical differentiation of the force, as in the paper's case 4
(``jacobian_scheme="forward"``, 4 extra solves; default ``"central"``, 8 extra solves), each
warm-started from the base solution and converged to ``jacobian_tol``.
:func:`reference_film_force` Richardson-extrapolates successive refinements.

The kernels are in :mod:`bearing_fmu.fd._grid` (grids, smoothers, transfers) and
:mod:`bearing_fmu.fd._kernels` (cycles); the direct solver in :mod:`bearing_fmu.fd.reference`.
``linear_solver="direct"`` replaces the multigrid by a primal-dual active set with sparse LU
(:func:`~bearing_fmu.fd.reference.solve_complementarity`): slow, but an independent check of
the multigrid.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from bearing_fmu.base import (
    BearingData,
    BearingError,
    FilmBearingModel,
    FilmForce,
    ModelOption,
    check_state,
)
from bearing_fmu.fd import _kernels as _k
from bearing_fmu.fd._grid import BOTH, THETA_ONLY, XI_ONLY
from bearing_fmu.fd.reference import (  # the direct solver
    reynolds_operator,
    solve_complementarity,
)
from bearing_fmu.reynolds import nodal_force

__all__ = [
    "FiniteDifferenceBearing",
    "MultigridConvergenceError",
    "build_hierarchy",
    "reference_film_force",
    "reynolds_operator",
    "solve_complementarity",
]

#: largest coarsest-level system solved densely
_MAX_COARSEST = 400


class MultigridConvergenceError(BearingError):
    """The multigrid iteration did not reach its tolerance (message gives state and residual)."""


def build_hierarchy(lam, n_theta, n_xi, anisotropy=2.0, min_unknowns=32):
    """Grid levels of the half domain: (nts, ms, kinds).

    Level 0 is ``n_theta x n_xi/2``. A level is coarsened in theta when ``n_t`` is even and
    ``n_t/2 >= 4``, in xi when ``m`` is even, in both when both are allowed and the coupling
    ratio ``q = (dxi/dtheta)^2`` lies in ``[1/anisotropy, anisotropy]``, else only in the
    strongly coupled direction (theta if q > 1). Stops at ``<= min_unknowns`` unknowns.
    """
    nts, ms, kinds = [int(n_theta)], [int(n_xi) // 2], []
    while nts[-1] * ms[-1] > min_unknowns:
        nt, m = nts[-1], ms[-1]
        can_t = nt % 2 == 0 and nt // 2 >= 4
        can_x = m % 2 == 0
        q = ((lam / m) / (2.0 * math.pi / nt)) ** 2
        if can_t and can_x and 1.0 / anisotropy <= q <= anisotropy:
            kind = BOTH
        elif can_t and (q > 1.0 or not can_x):
            kind = THETA_ONLY
        elif can_x:
            kind = XI_ONLY
        else:
            break
        kinds.append(kind)
        nts.append(nt // 2 if kind != XI_ONLY else nt)
        ms.append(m // 2 if kind != THETA_ONLY else m)
    kinds.append(0)
    return np.array(nts, np.int64), np.array(ms, np.int64), np.array(kinds, np.int64)


class FiniteDifferenceBearing(FilmBearingModel):
    """2-D finite-difference / multigrid Reynolds solver (the reference, Table 4 case 4).

    Parameters
    ----------
    bearing : BearingData
    n_theta : int
        Intervals around the bearing (paper: 192), at least 8.
    n_xi : int
        Intervals along the full length (paper: 32); even, at least 2.
    tol : float
        Relative natural residual of the LCP at which the multigrid stops (in (0, 1e-6]).
    pinned_start : bool
        p = 0 on the line of maximum film thickness (Raimondi-Boyd convention); default: free
        film start (the paper's variational inequality).
    jacobian_scheme : {"central", "forward"}
        Numerical differentiation of the force (the paper's case 4: forward, first order).
    jacobian_step : float
        Step in the dimensionless state (xbar, ybar, xbar_dot, ybar_dot).
    jacobian_tol : float
        Tolerance of the perturbed solves (tighter than ``tol``: their differences are divided
        by the step).
    linear_solver : {"multigrid", "direct"}
        ``"direct"``: active set + sparse LU on the full grid (independent check, slow).
    maxit : int
        Multigrid cycles per solve.
    nu : (int, int)
        Pre- and post-smoothing sweeps.
    warm_start : bool
        Start each solve from the previous pressure field (else nested iteration each time).

    Attributes
    ----------
    last_info : dict
        ``cycles`` (multigrid cycles of the last base solve), ``residual`` (its relative natural
        residual), ``history`` (residual after each cycle), ``levels`` (grid sizes).
    solves : int
        Reynolds problems solved so far (the paper's "Reynolds equations" count).
    """

    name = "fd"
    options = (ModelOption("nodes", "n_theta", "count",
                           "circumferential nodes (hybrid n: nodes of a(theta), paper 192; fd "
                           "n_theta: grid intervals)", minimum=8),
               ModelOption("axial_intervals", "n_xi", "count",
                           "axial grid intervals over the length (fd model; even)", minimum=2))

    def __init__(self, bearing, n_theta=192, n_xi=32, tol=1e-10, pinned_start=False,
                 jacobian_scheme="central", jacobian_step=1e-5, jacobian_tol=1e-12,
                 linear_solver="multigrid", maxit=100, nu=(2, 1), warm_start=True,
                 mask_rule=0):
        super().__init__(bearing)
        if int(n_theta) != n_theta or n_theta < 8:
            raise ValueError(f"n_theta = {n_theta!r}: need an integer >= 8")
        if int(n_xi) != n_xi or n_xi < 2 or n_xi % 2:
            raise ValueError(f"n_xi = {n_xi!r}: need an even integer >= 2 (mesh "
                             f"{n_theta} x {n_xi})")
        if not (0.0 < tol <= 1e-6) or not (0.0 < jacobian_tol <= 1e-6):
            raise ValueError(f"tol = {tol!r}, jacobian_tol = {jacobian_tol!r}: must be in "
                             "(0, 1e-6]")
        if linear_solver not in ("multigrid", "direct"):
            raise ValueError(f"linear_solver = {linear_solver!r}: 'multigrid' or 'direct'")
        if jacobian_scheme not in ("central", "forward"):
            raise ValueError(f"jacobian_scheme = {jacobian_scheme!r}: 'central' or 'forward'")
        if not (0.0 < jacobian_step < 0.1):
            raise ValueError(f"jacobian_step = {jacobian_step!r}: must be in (0, 0.1)")
        self.n_theta = int(n_theta)
        self.n_xi = int(n_xi)
        self.tol = float(tol)
        self.jacobian_tol = float(jacobian_tol)
        self.pinned_start = bool(pinned_start)
        self.jacobian_scheme = jacobian_scheme
        self.jacobian_step = float(jacobian_step)
        self.linear_solver = linear_solver
        self.maxit = int(maxit)
        self.nu = (int(nu[0]), int(nu[1]))
        self.warm_start = bool(warm_start)
        self.mask_rule = int(mask_rule)
        lam = bearing.lambda_
        self._nts, self._ms, self._kinds = build_hierarchy(lam, self.n_theta, self.n_xi)
        n_coarse = int(self._nts[-1] * self._ms[-1])
        if linear_solver == "multigrid" and n_coarse > _MAX_COARSEST:
            raise ValueError(
                f"mesh {self.n_theta} x {self.n_xi}: the multigrid hierarchy stops at "
                f"{self._nts[-1]} x {self._ms[-1]} = {n_coarse} unknowns (> {_MAX_COARSEST}); "
                "use n_theta and n_xi/2 with more factors of 2 (e.g. 192 x 32)")
        sizes = self._nts * (self._ms + 1)
        self._offs = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        self._coffs = np.concatenate([[0], np.cumsum(self._nts)[:-1]]).astype(np.int64)
        ntot, ctot = int(sizes.sum()), int(self._nts.sum())
        self._ct = np.zeros(ctot)
        self._cx = np.zeros(ctot)
        self._p = np.zeros(ntot)
        self._b = np.zeros(ntot)
        self._e = np.zeros(ntot)
        self._r = np.zeros(ntot)
        self._tmp = np.zeros(ntot)
        self._mask = np.zeros(ntot, dtype=np.bool_)
        self._hist = np.zeros(self.maxit + 1)
        self._have_p = False
        self._theta0 = 0.0
        self._active = None  # direct solver's warm start
        self._cycles = 0
        self.solves = 0
        self.last_info = {}

    @classmethod
    def from_lambda(cls, lambda_, **kw) -> FiniteDifferenceBearing:
        """A model of the dimensionless problem, which depends on L/D = ``lambda_`` only."""
        return cls(BearingData(diameter=1.0, length=lambda_, clearance=1e-3, viscosity=1.0), **kw)

    def reset(self) -> None:
        """Forget the warm start: the next solve starts with nested iteration."""
        self._have_p = False
        self._active = None

    def get_state(self):
        """The warm start (last pressure field, direct solver's active set), copied."""
        return (self._p.copy(), self._have_p,
                None if self._active is None else self._active.copy())

    def set_state(self, state) -> None:
        self._p[...] = state[0]
        self._have_p = state[1]
        self._active = None if state[2] is None else state[2].copy()

    # --- one Reynolds solve -------------------------------------------------------------
    def _theta0_of(self, x, y):
        return math.atan2(y, x) + math.pi if self.pinned_start else 0.0

    def _solve_mg(self, x, y, xd, yd, tol):
        """Solve the LCP on the half grid; returns (level-0 pressure view, theta0, cycles)."""
        theta0 = self._theta0_of(x, y)
        _k.setup_levels(self.bearing.lambda_, x, y, xd, yd, theta0, self._nts, self._ms,
                        self._offs, self._coffs, self._ct, self._cx, self._b)
        args = (self._nts, self._ms, self._offs, self._coffs, self._kinds, self._ct, self._cx,
                self._p, self._b, self._e, self._r, self._tmp, self._mask, self.pinned_start,
                self.nu[0], self.nu[1], self.mask_rule)
        if not (self.warm_start and self._have_p):
            _k.full_multigrid(*args, 1)
        self._hist[:] = 0.0
        cycles = _k.solve_level(0, *args, tol, self.maxit, self._hist)
        self._cycles = max(cycles, 0)
        nt, m = self.n_theta, self.n_xi // 2
        p = self._p[: nt * (m + 1)].reshape(nt, m + 1)
        self.solves += 1
        if cycles < 0:
            self._have_p = False
            raise MultigridConvergenceError(
                f"fd multigrid ({nt} x {self.n_xi}, L/D = {self.bearing.lambda_:.6g}) at state "
                f"(xbar, ybar, xbar_dot, ybar_dot) = {(x, y, xd, yd)}: relative residual "
                f"{self._hist[min(-cycles, self.maxit)]:.3e} > tol {tol:.1e} after {-cycles} "
                "cycles")
        self._have_p = True
        return p, theta0, cycles

    def _solve_direct(self, x, y, xd, yd):
        """Full-grid pressure (nt, n_xi - 1) by active set + sparse LU."""
        theta0 = self._theta0_of(x, y)
        a, b, *_ = reynolds_operator(self.bearing.lambda_, x, y, xd, yd, self.n_theta,
                                     self.n_xi, theta0)
        nj = self.n_xi - 1
        active = self._active if self._active is not None else b > 0
        pinned = np.arange(nj) if self.pinned_start else None
        p, active, passes = solve_complementarity(a, b, active, "direct", pinned=pinned)
        self._active = active
        self.solves += 1
        self.last_info = dict(active_set_passes=passes)
        return p.reshape(self.n_theta, nj), theta0

    def _force(self, x, y, xd, yd, tol):
        if self.linear_solver == "direct":
            p, theta0 = self._solve_direct(x, y, xd, yd)
            dth = 2.0 * math.pi / self.n_theta
            dxi = 2.0 * self.bearing.lambda_ / self.n_xi
            th = theta0 + np.arange(self.n_theta) * dth
            out = np.empty(2)
            nodal_force(p.sum(axis=1), np.cos(th), np.sin(th), dth * dxi, out)  # Eq. (5)
            return out
        p, theta0, _ = self._solve_mg(x, y, xd, yd, tol)
        fx, fy = _k.film_force_of(p, self.n_theta, self.n_xi // 2, theta0, self.bearing.lambda_)
        return np.array([fx, fy])

    # --- the FilmBearingModel interface -------------------------------------------------
    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        """Dimensionless force (Eq. 5) and, if asked, its numerical derivatives."""
        st = (xbar, ybar, xbar_dot, ybar_dot)
        f = self._force(*st, self.tol if not jacobian else self.jacobian_tol)
        if self.linear_solver == "multigrid":
            self._record_info()
        if not jacobian:
            return FilmForce(f)
        info = self.last_info
        base = (self._p.copy(), self._have_p, self._active)
        jac = np.zeros((2, 4))
        step = self.jacobian_step
        for k in range(4):
            sp_ = list(st)
            sp_[k] += step
            self._restore(base)
            fp = self._force(*sp_, self.jacobian_tol)
            if self.jacobian_scheme == "central":
                sm = list(st)
                sm[k] -= step
                self._restore(base)
                jac[:, k] = (fp - self._force(*sm, self.jacobian_tol)) / (2.0 * step)
            else:
                jac[:, k] = (fp - f) / step
        self._restore(base)
        self.last_info = info
        return FilmForce(f, jac[:, :2], jac[:, 2:])

    def _record_info(self):
        k = self._cycles
        self.last_info = dict(
            cycles=k, residual=float(self._hist[k]), history=self._hist[: k + 1].copy(),
            levels=[(int(a), 2 * int(b)) for a, b in zip(self._nts, self._ms, strict=True)])

    def _restore(self, base):
        self._p[:] = base[0]
        self._have_p = base[1]
        self._active = base[2]

    # --- pressure field -----------------------------------------------------------------
    def pressure(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0):
        """Pressure on the grid: (theta (n_theta,), xi (n_xi + 1,), p (n_theta, n_xi + 1)).

        ``theta_i = theta_0 + i dtheta`` (theta_0 = 0, or the h_max line when pinned), the edge
        rows ``xi = ±lambda`` included (zero).
        """
        check_state(xbar, ybar, xbar_dot, ybar_dot)
        lam = self.bearing.lambda_
        nt, nx = self.n_theta, self.n_xi
        full = np.zeros((nt, nx + 1))
        if self.linear_solver == "direct":
            p, theta0 = self._solve_direct(xbar, ybar, xbar_dot, ybar_dot)
            full[:, 1:-1] = p
        else:
            p, theta0, _ = self._solve_mg(xbar, ybar, xbar_dot, ybar_dot, self.tol)
            self._record_info()
            m = nx // 2
            full[:, : m + 1] = p
            full[:, m + 1 :] = p[:, m - 1 :: -1][:, : nx - m]
        th = theta0 + np.arange(nt) * 2.0 * math.pi / nt
        return th, np.linspace(-lam, lam, nx + 1), full

    def pressure_field(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0):
        """Dimensionless pressure for plots, the convention of the hybrid model.

        Returns
        -------
        theta : ndarray (n_theta + 1,)
            Node angles [rad] sorted in [0, 2 pi), the first repeated at the end (+ 2 pi).
        xi : ndarray (n_xi + 1,)
            z/R in [-lambda, lambda].
        p : ndarray (n_theta + 1, n_xi + 1)
            Pressure (scale :meth:`bearing_fmu.base.BearingData.pressure_scale`).
        """
        th, xi, p = self.pressure(xbar, ybar, xbar_dot, ybar_dot)
        th = np.mod(th, 2.0 * math.pi)
        start = int(np.argmin(th))
        th = np.roll(th, -start)
        p = np.roll(p, -start, axis=0)
        return np.append(th, th[0] + 2.0 * math.pi), xi, np.vstack([p, p[:1]])


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
        Passed to :class:`FiniteDifferenceBearing` (e.g. ``pinned_start``).

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
