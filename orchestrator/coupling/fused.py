"""The master's coupled step in one compiled call, for the in-process structure and a set of
hybrid bearings.

:meth:`orchestrator.coupling.master.Master.step` iterates in Python: per iteration a
structure step, the bearings at the new journal states, the test and the new laws
(:meth:`bearing_fmu.affine.AffineLaws.relinearise`), the state restored. In-process each of
these is already one compiled kernel, and the Python between them (objects, checks, copies,
dispatch) cost about a third of an iteration of the paper's case. :func:`coupled_step` runs
the same iteration with the same kernels (:func:`gear_fmu.step.kernel.advance`,
``bearing_fmu.hybrid._kernels.hybrid_set_global``, ``bearing_fmu.affine._relinearise``) in the
same order on the same numbers, so a step gives the bits of the Python loop, and of the same
step through FMUs (the tests compare them). The structure's state is not saved and restored:
every iteration starts from the same (X, Xdot, Xddot) and writes the new state into buffers.

What the compiled loop does not take (a step with contact events, whose sub-steps and
acceleration jumps are Python, or timing on) goes through the Python loop:
:meth:`FusedStep.step` returns None and the master iterates itself. Failures come back as
status codes and are raised in Python with the messages of the Python loop.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from bearing_fmu.affine import AffineLaws, _relinearise
from bearing_fmu.hybrid._kernels import hybrid_set_global
from gear_fmu.step.condensation import N_GEAR
from gear_fmu.step.kernel import CONVERGED, advance
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


@njit(cache=True)
def coupled_step(hh, g_const, s0, w, x, v, a, f_c, unb_coef, t1,  # structure before the laws
                 h, angle, err, has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1,
                 pitch2, used0, has_used, f_scale, s_tol, s_max_iter,  # ... after the laws
                 force, stiff, active, inside, delta, load, xis, zout, residuals, x1, v1, a1,
                 b_state, b_active, ws, iws, trig, coef, q, states, omega, clearance, fs, res,
                 out,  # the bearings (hybrid_set_global's arguments)
                 f0, kb, cb, tol, max_iterations, relaxation, stall, mismatches):
    """The iteration of :meth:`orchestrator.coupling.master.Master.step` from the laws
    ``f0, kb, cb`` (nb, 2), (nb, 2, 2) [N, N/m, N s/m].

    The structure's arguments are :func:`gear_fmu.step.kernel.advance`'s without the laws,
    the bearings' ``hybrid_set_global``'s (``states`` (nb, 4) receives the journal states of
    each iterate, ``out`` (nb, 5, 2) the bearings' results there); ``mismatches``
    (max_iterations,) receives each iteration's relative mismatch.

    Returns ``(outcome, iterations, structure status, structure passes, total mesh load,
    contact length, failed bearing, its status, relaxed, mismatch, f0, kb, cb)``: the
    outcome (:data:`ACCEPTED` ...), the structure kernel's returns of the last iteration, the
    bearing set's, whether the step was relaxed, and the mismatch and the law the bearings
    give at the last iterate (accepted: the next step's; the law used, else).
    """
    nb = states.shape[0]
    relaxed = False
    mismatch = np.inf
    for it in range(1, max_iterations + 1):
        status, k, total, length = advance(
            hh, g_const, s0, w, x, v, a, f_c, unb_coef, t1, f0, kb, cb, h, angle, err,
            has_err, geo, xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, used0,
            has_used, f_scale, s_tol, s_max_iter, force, stiff, active, inside, delta, load,
            xis, zout, residuals, x1, v1, a1)
        if status != CONVERGED:
            return (STRUCTURE_FAILED, it, status, k, total, length, -1, 0, relaxed, mismatch,
                    f0, kb, cb)
        for b in range(nb):  # Structure.journal_states
            for c in range(2):
                states[b, c] = x1[N_GEAR + 2 * b + c]
                states[b, 2 + c] = v1[N_GEAR + 2 * b + c]
        bad, b_status = hybrid_set_global(b_state, b_active, ws, iws, trig, coef, q, states,
                                          omega, clearance, fs, res, out)
        if bad >= 0:
            return (BEARING_FAILED, it, status, k, total, length, bad, b_status, relaxed,
                    mismatch, f0, kb, cb)
        mismatch, f0_new, kb_new, cb_new = _relinearise(
            states, np.ascontiguousarray(out[:, 0]), np.ascontiguousarray(out[:, 1:3]),
            np.ascontiguousarray(out[:, 3:5]), f0, kb, cb)
        if mismatch <= tol:
            return (ACCEPTED, it, status, k, total, length, -1, 0, relaxed, mismatch, f0_new,
                    kb_new, cb_new)
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
    return (NOT_CONVERGED, max_iterations, CONVERGED, 0, 0.0, 0.0, -1, 0, relaxed, mismatch,
            f0, kb, cb)


class FusedStep:
    """:meth:`~orchestrator.coupling.master.Master.step` as one :func:`coupled_step` for an
    in-process structure (:class:`orchestrator.coupling.inprocess.InProcessStructure`) and
    in-process hybrid bearings of one n
    (:class:`orchestrator.coupling.inprocess.ModelBearings` with a
    :attr:`~orchestrator.coupling.inprocess.ModelBearings.hybrid_set`);
    :func:`orchestrator.coupling.system.build_master` gives it to the master when both are."""

    def __init__(self, structure, bearings):
        if bearings.hybrid_set is None:
            raise ValueError("FusedStep: the bearings are not one set of hybrid bearings")
        self.structure = structure
        self.bearings = bearings
        self._mismatches = None

    @staticmethod
    def fits(structure, bearings) -> bool:
        """Whether the slaves can take the compiled step."""
        return (isinstance(structure, InProcessStructure)
                and isinstance(bearings, ModelBearings) and bearings.hybrid_set is not None)

    def step(self, master, t: float, dt: float) -> StepReport | None:
        """The master's step from t to t + dt [s] (same arguments, counters and errors), or
        None for a step the compiled loop does not take (module docstring)."""
        st = self.structure.cycle.check_step(t, dt)
        plan = st.compiled_step(dt)
        if plan is None:
            return None
        head, tail, outputs, _ = plan
        bearings = self.bearings
        nb = len(bearings.models)
        states, out = np.empty((nb, 4)), np.empty((nb, 5, 2))
        if self._mismatches is None or self._mismatches.size != master.max_iterations:
            self._mismatches = np.empty(master.max_iterations)
        laws = master.laws
        (outcome, it, status, k, total, length, bad, b_status, relaxed, mismatch,
         f0, kb, cb) = coupled_step(
            *head, *tail, *outputs, *bearings.hybrid_set.kernel_arguments(states, out),
            laws.f0, laws.kb, laws.cb, master.tol, master.max_iterations, RELAXATION, STALL,
            self._mismatches)
        evaluations = it - (outcome == STRUCTURE_FAILED)
        master.total_iterations += it - (outcome in (STRUCTURE_FAILED, BEARING_FAILED))
        master.total_bearing_evaluations += evaluations
        master.relaxed_steps += bool(relaxed)
        bearings.evaluations += nb * (evaluations - (outcome == BEARING_FAILED))
        if outcome == STRUCTURE_FAILED:
            st.end_compiled_step(plan, status, k, total, length)  # raises the structure's
        if outcome == BEARING_FAILED:
            bearings.raise_set_failure(bad, b_status, states)
        bearings.record_states(states)
        if outcome == NOT_CONVERGED:
            raise CouplingError(not_converged(t, dt, master.max_iterations, mismatch,
                                              master.tol))
        st.end_compiled_step(plan, status, k, total, length)
        new = AffineLaws(f0, kb, cb, states.copy(), out[:, 0].copy())
        master.laws = new
        return StepReport(it, mismatch, out[:, 0], new, states)
