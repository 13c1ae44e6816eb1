"""The master's coupled step in one compiled call, for the in-process structure and a set of
hybrid bearings (Table 4 case 2) or of linear ones (case 0).

:meth:`orchestrator.coupling.master.Master.step` iterates in Python: per iteration a
structure step, the bearings at the new journal states, the test and the new laws
(:meth:`bearing_fmu.affine.AffineLaws.relinearise`), the state restored. In-process each of
these is already one compiled kernel, and the Python between them (objects, checks, copies,
dispatch) cost about a third of an iteration of the paper's case. :func:`coupled_step` runs
the same iteration with the same kernels (:func:`gear_fmu.step.kernel.advance`,
``bearing_fmu.hybrid._kernels.hybrid_set_global`` or ``bearing_fmu.affine.affine_set_global``,
``bearing_fmu.affine._relinearise``) in the same order on the same numbers, so a step gives
the bits of the Python loop, and of the same step through FMUs (the tests compare them). The
structure's state is not saved and restored: every iteration starts from the same
(X, Xdot, Xddot) and writes the new state into buffers.

A step cut at its contact events is one call too (:func:`gear_fmu.step.kernel.advance_pieces`);
what the compiled loop does not take (timing on, more sub-steps than
:data:`gear_fmu.structure.MAX_PIECES`) goes through the Python loop:
:meth:`FusedStep.step` returns None and the master iterates itself. Failures come back as
status codes and are raised in Python with the messages of the Python loop.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from bearing_fmu.affine import AffineLaws, _relinearise, affine_set_global
from bearing_fmu.hybrid._kernels import hybrid_set_global, hybrid_set_threads
from bearing_fmu.linear import LinearBearing, LinearisedBearing
from gear_fmu.step.condensation import N_GEAR
from gear_fmu.step.kernel import CONVERGED, advance_pieces
from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
from orchestrator.coupling.master import (
    RELAXATION,
    STALL,
    CouplingError,
    StepReport,
    not_converged,
)

__all__ = ["FusedStep", "coupled_step"]

#: :func:`coupled_step` outcomes
ACCEPTED, STRUCTURE_FAILED, BEARING_FAILED, NOT_CONVERGED = 0, 1, 2, 3
#: the lengths of the bearing set's arguments that tell its kind (:func:`evaluate_set`)
HYBRID_ARGUMENTS, THREADED_ARGUMENTS, AFFINE_ARGUMENTS = 11, 12, 4


def evaluate_set(bearings, states, out):
    """The bearing set in compiled code: ``hybrid_set_global(*bearings, states, out)`` for the
    arrays of a hybrid set (:meth:`bearing_fmu.hybrid.model.HybridSet.kernel_arguments`, 11
    of them; ``hybrid_set_threads`` for its 12 on more than one thread),
    ``affine_set_global(*bearings, states, out)`` for stacked affine laws
    (:meth:`orchestrator.coupling.inprocess.ModelBearings.affine_laws`, 4): chosen when
    :func:`coupled_step` compiles, so each kind has its own compiled (and cached) version.
    Returns ``(failed bearing or -1, its status)``."""
    raise NotImplementedError("evaluate_set runs in compiled code only")


@overload(evaluate_set)
def _evaluate_set(bearings, states, out):
    if len(bearings) == HYBRID_ARGUMENTS:
        def hybrid(bearings, states, out):
            b = bearings
            return hybrid_set_global(b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8],
                                     b[9], b[10], states, out)
        return hybrid
    if len(bearings) == THREADED_ARGUMENTS:
        def threaded(bearings, states, out):
            b = bearings
            return hybrid_set_threads(b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8],
                                      b[9], b[10], b[11], states, out)
        return threaded
    if len(bearings) == AFFINE_ARGUMENTS:
        def affine(bearings, states, out):
            b = bearings
            return affine_set_global(b[0], b[1], b[2], b[3], states, out)
        return affine
    return None


@njit(cache=True)
def coupled_step(n_pieces, hh, g_const, s0, w, table, event, err, err_after, x, v, a, f_c,
                 unb_coef,  # the structure before the laws (advance_pieces)
                 has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, cache,
                 tangent, used0, has_used, f_scale, s_tol, s_max_iter,
                 m_gear,  # ... after the laws
                 force, stiff, active, inside, delta, load, xis, zout, residuals, x1, v1, a1,
                 bearings, states, out,  # the bearing set (evaluate_set)
                 f0, kb, cb, tol, max_iterations, relaxation, stall, mismatches):
    """The iteration of :meth:`orchestrator.coupling.master.Master.step` from the affine laws
    of Eq. (17) ``f0, kb, cb`` (nb, 2), (nb, 2, 2) [N, N/m, N s/m].

    The structure's arguments are :func:`gear_fmu.step.kernel.advance_pieces`'s without the
    laws (a step cut at its contact events, or one piece); ``bearings`` the set's arrays
    (:func:`evaluate_set`), ``states`` (nb, 4) receives the journal states of each iterate
    and ``out`` (nb, 5, 2) the bearings' results there; ``mismatches`` (max_iterations,)
    receives each iteration's relative mismatch.

    Returns ``(outcome, iterations, structure status, its sub-step, structure passes, total
    mesh load, contact length, failed bearing, its status, relaxed, mismatch, f0, kb, cb)``:
    the outcome (:data:`ACCEPTED` ...), the structure kernel's returns of the last iteration,
    the bearing set's, whether the step was relaxed, and the mismatch and the law the
    bearings give at the last iterate (accepted: the next step's; the law used, else).
    """
    nb = states.shape[0]
    relaxed = False
    mismatch = np.inf
    for it in range(1, max_iterations + 1):
        status, piece, k, total, length = advance_pieces(
            n_pieces, hh, g_const, s0, w, table, event, err, err_after, x, v, a, f_c, unb_coef,
            f0, kb, cb, has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2,
            cache, tangent, used0, has_used, f_scale, s_tol, s_max_iter, m_gear, force, stiff,
            active, inside, delta, load, xis, zout, residuals, x1, v1, a1)
        if status != CONVERGED:
            return (STRUCTURE_FAILED, it, status, piece, k, total, length, -1, 0, relaxed,
                    mismatch, f0, kb, cb)
        for b in range(nb):  # Structure.journal_states
            for c in range(2):
                states[b, c] = x1[N_GEAR + 2 * b + c]
                states[b, 2 + c] = v1[N_GEAR + 2 * b + c]
        bad, b_status = evaluate_set(bearings, states, out)
        if bad >= 0:
            return (BEARING_FAILED, it, status, piece, k, total, length, bad, b_status,
                    relaxed, mismatch, f0, kb, cb)
        mismatch, f0_new, kb_new, cb_new = _relinearise(
            states, np.ascontiguousarray(out[:, 0]), np.ascontiguousarray(out[:, 1:3]),
            np.ascontiguousarray(out[:, 3:5]), f0, kb, cb)
        if mismatch <= tol:
            return (ACCEPTED, it, status, piece, k, total, length, -1, 0, relaxed, mismatch,
                    f0_new, kb_new, cb_new)
        mismatches[it - 1] = mismatch
        if not relaxed and it >= 3 and mismatch > stall * mismatches[it - 3]:
            relaxed = True
        if relaxed:  # AffineLaws.blend, in its order
            r = 1.0 - relaxation
            f0 = relaxation * f0_new + r * f0
            kb = relaxation * kb_new + r * kb
            cb = relaxation * cb_new + r * cb
        else:
            f0, kb, cb = f0_new, kb_new, cb_new
    return (NOT_CONVERGED, max_iterations, CONVERGED, 0, 0, 0.0, 0.0, -1, 0, relaxed,
            mismatch, f0, kb, cb)


class FusedStep:
    """:meth:`~orchestrator.coupling.master.Master.step` as one :func:`coupled_step` for an
    in-process structure (:class:`orchestrator.coupling.inprocess.InProcessStructure`) and
    in-process bearings (:class:`orchestrator.coupling.inprocess.ModelBearings`) that are
    hybrid bearings of one n (its
    :attr:`~orchestrator.coupling.inprocess.ModelBearings.hybrid_set`) or linear ones (its
    :meth:`~orchestrator.coupling.inprocess.ModelBearings.affine_laws`, once frozen at X0);
    :func:`orchestrator.coupling.system.build_master` gives it to the master when they are."""

    def __init__(self, structure, bearings):
        if not self.fits(structure, bearings):
            raise ValueError("FusedStep: an in-process structure and in-process hybrid or "
                             "linear bearings only")
        self.structure = structure
        self.bearings = bearings
        self._mismatches = None

    @staticmethod
    def fits(structure, bearings) -> bool:
        """Whether the slaves can take the compiled step (the linear bearings: once frozen)."""
        return (isinstance(structure, InProcessStructure) and isinstance(bearings, ModelBearings)
                and (bearings.hybrid_set is not None
                     or all(isinstance(m, LinearBearing | LinearisedBearing)
                            for m in bearings.models)))

    def _bearing_arguments(self):
        """The set's arrays for :func:`evaluate_set`, or None (linear bearings not frozen)."""
        if self.bearings.hybrid_set is not None:
            return self.bearings.hybrid_set.kernel_arguments()
        return self.bearings.affine_laws()

    def step(self, master, t: float, dt: float) -> StepReport | None:
        """The master's step from t to t + dt [s] (same arguments, counters and errors), or
        None for a step the compiled loop does not take (module docstring)."""
        st = self.structure.cycle.check_step(t, dt)
        arrays = self._bearing_arguments()
        plan = None if arrays is None else st.compiled_step(dt)
        if plan is None:
            return None
        head, tail, outputs, _ = plan
        bearings = self.bearings
        nb = len(bearings.models)
        states, out = np.empty((nb, 4)), np.empty((nb, 5, 2))
        if self._mismatches is None or self._mismatches.size != master.max_iterations:
            self._mismatches = np.empty(master.max_iterations)
        laws = master.laws
        (outcome, it, status, piece, k, total, length, bad, b_status, relaxed, mismatch,
         f0, kb, cb) = coupled_step(
            *head, *tail, *outputs, arrays, states, out, laws.f0, laws.kb, laws.cb,
            master.tol, master.max_iterations, RELAXATION, STALL, self._mismatches)
        evaluations = it - (outcome == STRUCTURE_FAILED)
        master.total_iterations += it - (outcome in (STRUCTURE_FAILED, BEARING_FAILED))
        master.total_bearing_evaluations += evaluations
        master.relaxed_steps += bool(relaxed)
        bearings.evaluations += nb * (evaluations - (outcome == BEARING_FAILED))
        if outcome == STRUCTURE_FAILED:
            st.end_compiled_step(plan, status, piece, k, total, length)  # raises its error
        if outcome == BEARING_FAILED:
            bearings.raise_set_failure(bad, b_status, states)
        bearings.record_states(states)
        if outcome == NOT_CONVERGED:
            raise CouplingError(not_converged(t, dt, master.max_iterations, mismatch,
                                              master.tol))
        st.end_compiled_step(plan, status, piece, k, total, length)
        new = AffineLaws(f0, kb, cb, states.copy(), out[:, 0].copy())
        master.laws = new
        return StepReport(it, mismatch, out[:, 0], new, states)
