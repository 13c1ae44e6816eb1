"""Hybrid method for finite journal bearings (paper Sec. 2.2.2, Eq. 6-7; Table 4 cases 0, 2, 3).

Separated pressure ``p(theta, xi) = [cosh(k lambda) - cosh(k xi)] a(theta)`` (Eq. 6), ``a``
piecewise linear on n periodic nodes (Eq. 7). For fixed ``t = (k lambda)^2`` the Ritz
minimisation of the Reynolds functional over ``a >= 0`` is a symmetric cyclic tridiagonal
linear complementarity problem, solved exactly by a primal-dual active set (the Swift-Stieber
condition, Eq. 4, holds at the discrete free boundaries by construction); ``t`` is then moved by
Newton on the reduced functional ``J*(t)`` (3-5 iterations cold, 1 warm). Forces and their
derivatives with respect to (x, y, xdot, ydot) come from the same factorisation with the active
set frozen, differentiated through ``t`` (no numerical differentiation).

The derivation, with the axial integrals and the Jacobian formulas, is in
``docs/hybrid-method.md``; the kernels are in :mod:`bearing_fmu.hybrid._kernels`, the axial
integrals in :mod:`bearing_fmu.hybrid.axial`.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_fmu.base import (
    BearingError,
    BearingModel,
    FilmBearingModel,
    FilmBearingSet,
    FilmForce,
    ModelOption,
    check_omega,
    check_state,
)
from bearing_fmu.hybrid import _kernels as _k
from bearing_fmu.hybrid import _workspace as _ws
from bearing_fmu.hybrid.axial import AXIAL_COEF, axial_shape

__all__ = ["HybridBearing", "HybridConvergenceError", "HybridSet", "thread_count",
           "threading_layer"]

_STATUS = {
    1: "the active-set (LCP) iteration did not converge",
    2: "the Newton iteration on t = (k lambda)^2 did not converge",
    3: "the Ritz matrix is not a Stieltjes matrix (theta mesh too coarse for this L/D): "
       "increase n",
}


class HybridConvergenceError(BearingError):
    """The hybrid solver failed at a state (message gives the state and the reason)."""


class HybridBearing(FilmBearingModel):
    """Hybrid (separated Ritz / variational-inequality) Reynolds solver, analytic Jacobians.

    Parameters
    ----------
    bearing : BearingData
    n : int
        Circumferential nodes of a(theta) (paper: 192; Table 4 case 3: 384). At least 16, and
        the Ritz matrix must stay a Stieltjes matrix, roughly ``n > 4 / (L/D)`` (checked).
    pinned_start : bool
        Impose p = 0 on the line of maximum film thickness (the convention of Raimondi &
        Boyd's design tables). The paper's formulation (default) leaves the film start free.
    tol : float
        Relative accuracy of the force. Newton on t stops when the step dt is below
        ``tol (1 + |t|)``, or when it is below ``sqrt(tol / CORRECTOR_ERROR) (1 + |t|)``: that
        last step is then taken as the corrector ``a - z dt`` without a new solve, whose force
        error, below ``CORRECTOR_ERROR (dt / (1 + |t|))^2`` (measured), stays below ``tol``;
        the Jacobians' error is O(dt): about 1e-4 relative at most at the default 1e-8
        (9.6e-5 measured), below the force's discretisation error at n = 192 (2e-4).
        ``CORRECTOR_ERROR`` is in :mod:`bearing_fmu.hybrid._kernels`.
    maxit : int
        Newton iterations on t.

    Attributes
    ----------
    last_info : dict
        Diagnostics of the last call: ``t = (k lambda)^2``, ``k``, ``t_iterations`` (Newton
        passes on t), ``lcp_iterations`` (active-set passes summed over them), ``last_dt``.

    Examples
    --------
    >>> from bearing_fmu.base import BearingData
    >>> hb = HybridBearing(BearingData(1.0, 1.0, 1e-3, 1.0), pinned_start=True)
    >>> f = hb.dimensionless(0.6, 0.0).force
    >>> round(float(1.0 / (3 * np.pi * np.hypot(*f))), 3)  # Sommerfeld number; R&B: 0.121
    0.121
    """

    name = "hybrid"
    options = (ModelOption("nodes", "n", "count",
                           "circumferential nodes (hybrid n: nodes of a(theta), paper 192; fd "
                           "n_theta: grid intervals)", minimum=16),)

    def __init__(self, bearing, n=192, pinned_start=False, tol=1e-8, maxit=30):
        super().__init__(bearing)
        if int(n) != n or n < 16:
            raise ValueError(f"n = {n!r} circumferential nodes: need an integer of at least 16")
        if not (0.0 < tol <= 1e-6):
            raise ValueError(f"tol = {tol!r}: must be in (0, 1e-6]")
        if int(maxit) != maxit or maxit < 1:
            raise ValueError(f"maxit = {maxit!r}: must be an integer >= 1")
        self.n = int(n)
        self.pinned_start = bool(pinned_start)
        self.tol = float(tol)
        self.maxit = int(maxit)
        (self._state, self._active, self._ws, self._iws,
         self._trig) = _ws.new_workspace(self.n, bearing.lambda_, self.tol, self.maxit,
                                          self.pinned_start)
        self._res = np.empty((5, 2))  # evaluate_global's scratch (the law)
        self._scale = (math.nan, math.nan)  # (omega, force scale of Eq. 5) of the last call

    def reset(self) -> None:
        """Forget the warm start (active set, t, predictor): the next call starts cold."""
        self._state["cold"] = True
        self._state["predict"] = False
        self._state["t"] = 1.0

    def get_state(self):
        """The warm start (state record and pressurised set), copied: a model restored with it
        gives the same results, bit for bit, as this one from here on."""
        return self._state.copy(), self._active.copy()

    def set_state(self, state) -> None:
        record, active = state
        self._state[...] = record
        self._active[...] = active

    @property
    def last_info(self) -> dict:
        """Diagnostics of the last call (see the class docstring)."""
        st = self._state[0]
        t = float(st["t"])
        return dict(t=t, k=math.sqrt(abs(t)) / self.bearing.lambda_,
                    t_iterations=int(st["t_iterations"]),
                    lcp_iterations=int(st["lcp_iterations"]), last_dt=float(st["last_dt"]))

    def film_force(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, jacobian=True):
        """Dimensionless force (Eq. 5) and its analytic derivatives; warm-started.

        One kernel call; see :mod:`bearing_fmu.hybrid._kernels`.
        """
        res = np.empty((5, 2))
        if _k.hybrid_kernel(self._state, xbar, ybar, xbar_dot, ybar_dot, jacobian,
                            self._active, self._ws, self._iws, self._trig, AXIAL_COEF, res):
            self._fail(xbar, ybar, xbar_dot, ybar_dot)
        if not jacobian:
            return FilmForce(res[0])
        return FilmForce(res[0], res[1:3], res[3:5])

    def evaluate_global(self, q, state, omega, out):
        """One compiled call (``bearing_fmu.hybrid._kernels.hybrid_global``): the numbers of
        :meth:`~bearing_fmu.base.FilmBearingModel.evaluate` and the frame conversions of the
        base class."""
        omega = check_omega(omega)
        if omega != self._scale[0]:
            self._scale = (omega, self.bearing.force_scale(omega))
        status = _k.hybrid_global(self._state, self._active, self._ws, self._iws, self._trig,
                                  AXIAL_COEF, q, state, omega, self.bearing.clearance,
                                  self._scale[1], self._res, out)
        if status != 0:
            self.raise_status(status, q, state, omega)

    def raise_status(self, status, q, state, omega):
        """Raise the error of a failed :meth:`evaluate_global` (kernel status ``status`` at
        the global state ``state`` [m, m/s] of the frame ``q``): the state check's error, or
        :class:`HybridConvergenceError` (and a cold start next time)."""
        if status == _k.BAD_STATE:
            BearingModel.evaluate_global(self, q, state, omega, np.empty((5, 2)))
        x, y, xd, yd = (q @ np.reshape(state, (2, 2)).T).T.ravel()
        c = self.bearing.clearance
        self._fail(x / c, y / c, xd / (c * omega), yd / (c * omega))

    def _fail(self, *state):
        code = int(self._state[0]["status"])
        self.reset()
        raise HybridConvergenceError(
            f"hybrid solver (n = {self.n}, L/D = {self.bearing.lambda_:.6g}) at state "
            f"(xbar, ybar, xbar_dot, ybar_dot) = ({', '.join(f'{float(v):.6g}' for v in state)})"
            f": {_STATUS.get(code, code)}")

    def pressure_field(self, xbar, ybar, xbar_dot=0.0, ybar_dot=0.0, n_xi=33):
        """Dimensionless pressure p(theta, xi) of Eq. (6)-(7) for plotting.

        Returns
        -------
        theta : ndarray (n + 1,)
            Node angles [rad] in [0, 2 pi], the first node repeated at the end.
        xi : ndarray (n_xi,)
            Axial coordinate z/R in [-lambda, lambda].
        p : ndarray (n + 1, n_xi)
            ``p[i, j] = g(xi_j / lambda; t) a(theta_i)`` (pressure scale
            6 mu omega (R/C)^2 in :meth:`bearing_fmu.base.BearingData.pressure_scale`).
        """
        check_state(xbar, ybar, xbar_dot, ybar_dot)
        if int(n_xi) != n_xi or n_xi < 2:
            raise ValueError(f"n_xi = {n_xi!r}: need an integer >= 2")
        self.film_force(float(xbar), float(ybar), float(xbar_dot), float(ybar_dot), False)
        a = self._ws[_ws.A].copy()
        theta0 = float(self._state[0]["theta0"])
        th = np.mod(theta0 + np.arange(self.n) * 2 * math.pi / self.n, 2 * math.pi)
        start = int(np.argmin(th))
        th = np.roll(th, -start)
        a = np.roll(a, -start)
        th = np.append(th, th[0] + 2 * math.pi)
        a = np.append(a, a[0])
        lam = self.bearing.lambda_
        xi = np.linspace(-lam, lam, int(n_xi))
        g = axial_shape(xi / lam, float(self._state[0]["t"]))
        return th, xi, np.outer(a, g)


class HybridSet(FilmBearingSet):
    """Hybrid bearings of equal n evaluated in one compiled call
    (``bearing_fmu.hybrid._kernels.hybrid_set_global``): the numbers of one
    :meth:`HybridBearing.evaluate_global` per bearing, bit for bit, without the Python and the
    dispatch of four calls.

    The bearings' workspaces are moved into stacked arrays of which each bearing keeps a view,
    so that its own methods (warm start, state, reset) act on the same memory. Parameters as
    :class:`bearing_fmu.base.FilmBearingSet`, the models hybrid bearings of one n.
    """

    kind = "hybrid bearings of one n"

    def __init__(self, models, q, omegas):
        super().__init__(models, q, omegas)
        self._states = np.concatenate([m._state for m in self.models])
        self._active = np.stack([m._active for m in self.models])
        self._ws = np.stack([m._ws for m in self.models])
        self._iws = np.stack([m._iws for m in self.models])
        self._trig = np.stack([m._trig for m in self.models])
        self._res = np.stack([m._res for m in self.models])
        for b, m in enumerate(self.models):
            m._state, m._active, m._ws = self._states[b:b + 1], self._active[b], self._ws[b]
            m._iws, m._trig, m._res = self._iws[b], self._trig[b], self._res[b]
        self.threads = 1  # use_threads
        self._status = np.zeros(len(self.models), dtype=np.int64)  # hybrid_set_threads's

    @staticmethod
    def fits(models) -> bool:
        """Whether the models can share one call: all :class:`HybridBearing`, of one n."""
        return (len(models) > 0 and all(type(m) is HybridBearing for m in models)
                and len({m.n for m in models}) == 1)

    def use_threads(self, threads: int) -> int:
        """Share the bearings among ``threads`` threads (1: one after the other, the default):
        ``hybrid_set_threads`` instead of ``hybrid_set_global``, the same bits. Worth it with
        a core to spare: the threads wait for work by spinning, so each keeps a core busy
        while the set is in use (numba's OpenMP layer). Returns the thread count in use: 1,
        with a :class:`RuntimeWarning` saying what is missing, when numba has no OpenMP or TBB
        threading layer here (:func:`threading_layer`). ValueError for a count that is not a
        whole number from 1 to numba's ``NUMBA_NUM_THREADS``."""
        threads = thread_count(threads, "threads = ")
        if threads > 1 and threading_layer() is None:
            import warnings

            warnings.warn(f"threads = {threads}: numba has no OpenMP or TBB threading layer "
                          "here, so the bearings run on 1 thread (install the GNU OpenMP "
                          "runtime, libgomp.so.1, e.g. apt install libgomp1, or pip install "
                          "tbb)", RuntimeWarning, stacklevel=2)
            threads = 1
        self.threads = threads
        return threads

    def evaluate_global(self, states, out) -> None:
        """Film force [N], Kb [N/m], Cb [N s/m] (global frame) of every bearing at its global
        journal state ``states`` (nb, 4) [m, m/s] into ``out`` (nb, 5, 2) (rows as
        :meth:`HybridBearing.evaluate_global`). A failing bearing raises that bearing's
        error, with its index in ``bearing_index`` (0-based)."""
        args = self.kernel_arguments()
        kernel = _k.hybrid_set_global if self.threads == 1 else _k.hybrid_set_threads
        b, status = kernel(*args, states, out)
        if b >= 0:
            self.raise_status(b, status, states)

    def kernel_arguments(self) -> tuple:
        """The arguments of ``hybrid_set_global`` before the journal states and the output
        (11), or of ``hybrid_set_threads`` on more than one thread (12: the statuses' array
        after them): what a compiled caller passes on (:mod:`orchestrator.coupling.step`).
        On more than one thread this also gives the calling thread that many numba threads
        (``numba.set_num_threads``, a setting of the calling thread) for the calls that
        follow."""
        args = (self._states, self._active, self._ws, self._iws, self._trig, AXIAL_COEF,
                self._q, self._omega, self._clearance, self._fs, self._res)
        if self.threads == 1:
            return args
        import numba

        numba.set_num_threads(self.threads)
        return (*args, self._status)


def thread_count(threads, what: str) -> int:
    """``threads`` as a whole number from 1 to numba's ``NUMBA_NUM_THREADS`` (what
    :meth:`HybridSet.use_threads` takes); ValueError naming the value after ``what`` (such as
    ``"--threads "``) and the limit otherwise."""
    import numba

    limit = numba.config.NUMBA_NUM_THREADS
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or not (
            1 <= threads <= limit):
        raise ValueError(f"{what}{threads!r}: need a whole number from 1 to {limit} (numba's "
                         "NUMBA_NUM_THREADS on this machine)")
    return int(threads)


def threading_layer() -> str | None:
    """The threading layer numba runs :meth:`HybridSet.use_threads`'s threads on, ``"omp"`` or
    ``"tbb"``, or None when neither loads here. Its ``"workqueue"`` layer is never taken: it
    was six times slower than OpenMP for the paper's bearings (machine A) and aborts a process
    that launches parallel kernels from two threads at once. Asked before the first parallel
    call, this restricts numba's choice to those two (its ``"threadsafe"`` setting) unless
    ``NUMBA_THREADING_LAYER`` chose otherwise."""
    import numba
    from numba.np.ufunc import parallel

    if not parallel._is_initialized and numba.config.THREADING_LAYER == "default":
        numba.config.THREADING_LAYER = "threadsafe"
    try:
        parallel._launch_threads()
    except ValueError:  # "No threading layer could be loaded"
        return None
    layer = numba.threading_layer()
    return layer if layer in ("omp", "tbb") else None
