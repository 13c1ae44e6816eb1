"""The master's coupled steps in one compiled call, for the in-process structure and a set
of hybrid bearings (Table 4 case 2), of short bearings (case 1) or of affine laws (the linear
bearings of case 0, the lumped springs of Fig. 16:
:attr:`bearing_fmu.base.BearingModel.affine`).

:meth:`orchestrator.coupling.master.Master.step` iterates in Python: per iteration a
structure step, the bearings at the new journal states, the test and the new laws
(:meth:`bearing_fmu.affine.AffineLaws.relinearise`), the state restored. In-process each of
these is already one compiled kernel, and the Python between them (objects, checks, copies,
dispatch) cost about a third of an iteration of the paper's case. :func:`coupled_steps` runs
the same iteration with the same kernels (:func:`gear_fmu.step.kernel.advance`,
``bearing_fmu.hybrid._kernels.hybrid_set_global``,
:func:`bearing_fmu.short_bearing.short_set_global` or ``bearing_fmu.affine.affine_set_global``,
``bearing_fmu.affine._relinearise``) in the same order on the same numbers, so a step gives
the bits of the Python loop, and of the same step through FMUs (the tests compare them). The
structure's state is not saved and restored: every iteration starts from the same
(X, Xdot, Xddot) and writes the new state into buffers. A step cut at its contact events is
one call too (:func:`gear_fmu.step.kernel.advance_pieces`).

It takes many steps in one call (:meth:`Master.steps
<orchestrator.coupling.master.Master.steps>`, the runner's blocks): the Python between steps
(the step's plan, objects, counters, the results' row), about a fifth of a step, is paid per
block; the structure plans the steps of a block ahead
(:meth:`gear_fmu.structure.Structure.steps_plan`: the contact events are kinematic, known
before the step is solved). A single step is a block of one step. What the compiled
loop does not take (timing on, more sub-steps than :data:`gear_fmu.structure.MAX_PIECES`)
goes through the Python loop: the block is None and the master iterates
itself. Failures come back as status codes and are raised in Python with the messages of the
Python loop, after the steps of the block before the failed one are taken.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from bearing_fmu.affine import AffineLaws, _relinearise, affine_set_global
from bearing_fmu.hybrid._kernels import hybrid_set_global, hybrid_set_threads
from bearing_fmu.short_bearing import short_set_global
from gear_fmu.mesh.element import transmission_error
from gear_fmu.step.condensation import N_GEAR
from gear_fmu.step.kernel import CONVERGED, advance_pieces
from orchestrator.coupling.inprocess import InProcessStructure, ModelBearings
from orchestrator.coupling.master import (
    RELAXATION,
    STALL,
    CompiledSteps,
    CouplingError,
    StepBlock,
    not_converged,
    relaxed_law,
)

__all__ = ["FusedStep", "StepBlock", "coupled_steps"]

#: the outcomes of a step of :func:`coupled_steps`
ACCEPTED, STRUCTURE_FAILED, BEARING_FAILED, NOT_CONVERGED = 0, 1, 2, 3
#: the lengths of the bearing set's arguments that tell its kind (:func:`evaluate_set`)
HYBRID_ARGUMENTS, THREADED_ARGUMENTS, SHORT_ARGUMENTS, AFFINE_ARGUMENTS = 11, 12, 7, 4


def evaluate_set(bearings, states, out):
    """The bearing set in compiled code: ``hybrid_set_global(*bearings, states, out)`` for the
    arrays of a hybrid set (:meth:`bearing_fmu.hybrid.model.HybridSet.kernel_arguments`, 11
    of them; ``hybrid_set_threads`` for its 12 on more than one thread),
    ``short_set_global(*bearings, states, out)`` for a short set's 7
    (:meth:`bearing_fmu.short_bearing.ShortSet.kernel_arguments`),
    ``affine_set_global(*bearings, states, out)`` for stacked affine laws
    (:meth:`orchestrator.coupling.inprocess.ModelBearings.affine_laws`, 4): chosen when
    :func:`coupled_steps` compiles, so each kind has its own compiled (and cached) version.
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
    if len(bearings) == SHORT_ARGUMENTS:
        def short(bearings, states, out):
            b = bearings
            return short_set_global(b[0], b[1], b[2], b[3], b[4], b[5], b[6], states, out)
        return short
    if len(bearings) == AFFINE_ARGUMENTS:
        def affine(bearings, states, out):
            b = bearings
            return affine_set_global(b[0], b[1], b[2], b[3], states, out)
        return affine
    return None


@njit(cache=True)
def coupled_steps(n, counts, slots, mc, g_k, g_const_k, s0_k, w_k, tables, events, errs,
                  errs_after, x, v, a, f_c, unb_coef, has_err, geo, xi_tab, k_tab, zs, dl,
                  n_lines, dev, pitch1, pitch2, cache, tangent, f_scale, s_tol, s_max_iter,
                  m_gear, memo,  # the structure (Structure.steps_plan)
                  force, stiff, active, inside, delta, load, xis, zout, residuals, x1, v1, a1,
                  k_force, k_stiff, k_active, k_inside, k_delta, k_load, k_xis, k_zout,
                  bearings, states, out,  # the bearing set (evaluate_set)
                  f0, kb, cb, tol, max_iterations, relaxation, stall, mismatches,
                  rec_states, rec_force, rec_total, rec_gear, rec_iterations):
    """``n`` steps of the master (:meth:`orchestrator.coupling.master.Master.step`), each
    from the state and the affine laws of Eq. (17) ``f0, kb, cb`` (nb, 2), (nb, 2, 2)
    [N, N/m, N s/m] the step before accepted, until one is not accepted.

    Step i has ``counts[i]`` sub-steps (:meth:`gear_fmu.structure.Structure.steps_plan`),
    sub-step p ``mc`` ([M C]) and the condensation ``g_k[slots[i, p]]`` ... ``w_k[slots[i, p]]``
    (:class:`gear_fmu.step.condensation.CondensationSlots`; four slots,
    :data:`gear_fmu.structure.MAX_PIECES`) and row p of ``tables[i]``, ``events[i]``,
    ``errs[i]`` and ``errs_after[i]`` (row 0 of these for every step without gear errors):
    :func:`gear_fmu.step.kernel.advance_pieces`'s arguments, with ``memo`` the structure's
    memo of its history products (:func:`gear_fmu.step.assembly.history_products`: an
    iteration after the first reuses them). ``x, v, a`` (the state) and
    ``k_force`` ... ``k_zout`` (the mesh evaluation the last accepted step ended on;
    ``k_active`` its contact set, the next step's) are updated after each accepted step;
    ``force`` ... ``a1`` are the iterations' buffers. ``bearings`` the set's arrays
    (:func:`evaluate_set`), ``states`` (nb, 4) receives the journal states of each iterate and
    ``out`` (nb, 5, 2) the bearings' results there; ``mismatches`` (max_iterations,) each
    iteration's relative mismatch. Step i writes its accepted journal states, bearing forces,
    total mesh load, pinion and gear DOFs (``x1[:12]``) and iterations into row i of
    ``rec_states`` ... ``rec_iterations``.

    Returns ``(accepted steps, relaxed steps, total mesh load, contact length, f0, kb, cb)``
    of the accepted steps (the laws the next step starts from), then for the last step
    ``(outcome, iterations, structure status, its sub-step, structure passes, failed
    bearing, its status, relaxed, mismatch)``: the outcome (:data:`ACCEPTED` ...), the
    structure kernel's returns of the last iteration, the bearing set's, whether the step
    was relaxed, and its mismatch.
    """
    nb = states.shape[0]
    relaxed_steps = 0
    total_kept, length_kept = 0.0, 0.0
    outcome, it, status, piece, k, bad, b_status = ACCEPTED, 0, CONVERGED, 0, 0, -1, 0
    relaxed, mismatch, total, length = False, 0.0, 0.0, 0.0
    for i in range(n):
        row = i if has_err else 0
        k0, k1, k2, k3 = slots[i, 0], slots[i, 1], slots[i, 2], slots[i, 3]
        g = (g_k[k0], g_k[k1], g_k[k2], g_k[k3])
        g_const = (g_const_k[k0], g_const_k[k1], g_const_k[k2], g_const_k[k3])
        s0 = (s0_k[k0], s0_k[k1], s0_k[k2], s0_k[k3])
        w = (w_k[k0], w_k[k1], w_k[k2], w_k[k3])
        # the master's iteration (Master.step): Newton on the bearings through their laws
        law_f0, law_kb, law_cb = f0, kb, cb
        outcome, relaxed, mismatch = NOT_CONVERGED, False, np.inf
        for it in range(1, max_iterations + 1):
            status, piece, k, total, length = advance_pieces(
                counts[i], mc, g, g_const, s0, w, tables[i], events[i], errs[row],
                errs_after[row], x, v, a, f_c, unb_coef, law_f0, law_kb, law_cb, has_err, geo,
                xi_tab, k_tab, zs, dl, n_lines, dev, pitch1, pitch2, cache, tangent, k_active,
                True, f_scale, s_tol, s_max_iter, m_gear, force, stiff, active, inside, delta,
                load, xis, zout, residuals, x1, v1, a1, memo)
            if status != CONVERGED:
                outcome = STRUCTURE_FAILED
                break
            for b in range(nb):  # Structure.journal_states
                for c in range(2):
                    states[b, c] = x1[N_GEAR + 2 * b + c]
                    states[b, 2 + c] = v1[N_GEAR + 2 * b + c]
            bad, b_status = evaluate_set(bearings, states, out)
            if bad >= 0:
                outcome = BEARING_FAILED
                break
            mismatch, f0_new, kb_new, cb_new = _relinearise(
                states, np.ascontiguousarray(out[:, 0]), np.ascontiguousarray(out[:, 1:3]),
                np.ascontiguousarray(out[:, 3:5]), law_f0, law_kb, law_cb)
            if mismatch <= tol:
                outcome = ACCEPTED
                f0, kb, cb = f0_new, kb_new, cb_new
                break
            relaxed, law_f0, law_kb, law_cb = relaxed_law(
                it, mismatch, mismatches, relaxed, stall, relaxation, f0_new, kb_new, cb_new,
                law_f0, law_kb, law_cb)
        if outcome != ACCEPTED:
            return (i, relaxed_steps, total_kept, length_kept, f0, kb, cb, outcome, it,
                    status, piece, k, bad, b_status, relaxed, mismatch)
        # the step accepted: its row, the state and mesh evaluation the next starts from
        for b in range(nb):
            for c in range(4):
                rec_states[i, b, c] = states[b, c]
            for c in range(2):
                rec_force[i, b, c] = out[b, 0, c]
        for j in range(N_GEAR):
            rec_gear[i, j] = x1[j]
        rec_total[i] = total
        rec_iterations[i] = it
        relaxed_steps += relaxed
        total_kept, length_kept = total, length
        x[:] = x1
        v[:] = v1
        a[:] = a1
        k_force[:] = force
        k_stiff[:] = stiff
        k_active[:] = active
        k_inside[:] = inside
        k_delta[:] = delta
        k_load[:] = load
        k_xis[:] = xis
        k_zout[:] = zout
    return (n, relaxed_steps, total_kept, length_kept, f0, kb, cb, outcome, it, status, piece,
            k, bad, b_status, relaxed, mismatch)


class FusedStep(CompiledSteps):
    """:meth:`~orchestrator.coupling.master.Master.step` as one :func:`coupled_steps` for an
    in-process structure (:class:`orchestrator.coupling.inprocess.InProcessStructure`) and
    in-process bearings (:class:`orchestrator.coupling.inprocess.ModelBearings`) that are
    hybrid bearings of one n or short bearings (its
    :attr:`~orchestrator.coupling.inprocess.ModelBearings.compiled_set`) or affine ones (its
    :meth:`~orchestrator.coupling.inprocess.ModelBearings.affine_laws`, once frozen at X0);
    :func:`orchestrator.coupling.system.build_master` gives it to the master when they are."""

    def __init__(self, structure, bearings):
        if not self.fits(structure, bearings):
            raise ValueError("FusedStep: an in-process structure and in-process hybrid, "
                             "short or affine bearings only")
        self.structure = structure
        self.bearings = bearings
        self._mismatches = None

    @staticmethod
    def fits(structure, bearings) -> bool:
        """Whether the slaves can take the compiled step (the linear bearings: once frozen,
        :attr:`bearing_fmu.base.BearingModel.affine`)."""
        return (isinstance(structure, InProcessStructure) and isinstance(bearings, ModelBearings)
                and (bearings.compiled_set is not None
                     or all(m.affine for m in bearings.models)))

    def _bearing_arguments(self):
        """The set's arrays for :func:`evaluate_set`, or None (affine laws not frozen yet)."""
        if self.bearings.compiled_set is not None:
            return self.bearings.compiled_set.kernel_arguments()
        return self.bearings.affine_laws()

    def _block(self, master, t: float, dt: float, n: int, time_of) -> StepBlock | None:
        """Up to ``n`` steps from t [s] in one :func:`coupled_steps` call, until one fails or
        one would take the Python loop (:meth:`gear_fmu.structure.Structure.steps_plan`);
        ``time_of(k)``: the time [s] of the block's step k, as the caller's messages give
        it."""
        st = self.structure.cycle.check_step(t, dt)
        arrays = self._bearing_arguments()
        plan = None if arrays is None else st.steps_plan(dt, n)
        if plan is None:
            return None
        m, nb = len(plan.ends), len(self.bearings.models)
        states, out = np.empty((nb, 4)), np.empty((nb, 5, 2))
        rec = (np.empty((m, nb, 4)), np.empty((m, nb, 2)), np.empty(m), np.empty((m, N_GEAR)),
               np.empty(m, dtype=np.int64))
        laws = master.laws
        (count, relaxed_steps, total, length, f0, kb, cb, outcome, it, status, piece, k, bad,
         b_status, relaxed, mismatch) = coupled_steps(
            m, *plan.head, *plan.state, *plan.tail, *plan.work, *plan.kept, arrays, states,
            out, laws.f0, laws.kb, laws.cb, master.tol, master.max_iterations, RELAXATION,
            STALL, self._scratch(master), *rec)
        its = rec[4][:count]
        done = int(its.sum())
        master.total_iterations += done
        master.total_bearing_evaluations += done
        master.relaxed_steps += relaxed_steps
        self.bearings.evaluations += nb * done
        st.end_steps(plan, count, total, length)
        if count:
            self.bearings.record_states(rec[0][count - 1])
            master.laws = AffineLaws(f0, kb, cb, rec[0][count - 1].copy(),
                                     rec[1][count - 1].copy())
        gear = rec[3][:count]
        block = StepBlock(count, rec[0][:count], rec[1][:count], rec[2][:count],
                          transmission_error(st.mesh.pair.base_radius, gear),
                          gear.reshape(count, 2, 6)[:, :, :2], its, mismatch)
        if count < m:  # step count failed: its error, as the Python loop raises it
            self._count(master, outcome, it, relaxed)
            try:
                self._raise(master, time_of(count), dt, plan.work, plan.ends[count], outcome,
                            status, piece, k, bad, b_status, mismatch, states)
            except Exception as exc:  # handed to the caller with the rows
                block.error = exc
        return block

    def _scratch(self, master) -> np.ndarray:
        """The kernels' per-iteration mismatches, (max_iterations,)."""
        if self._mismatches is None or self._mismatches.size != master.max_iterations:
            self._mismatches = np.empty(master.max_iterations)
        return self._mismatches

    def _count(self, master, outcome, it, relaxed) -> None:
        """The master's and the bearings' counters after a step of :func:`coupled_steps`
        that ended with ``outcome`` after ``it`` iterations."""
        evaluations = it - (outcome == STRUCTURE_FAILED)
        master.total_iterations += it - (outcome in (STRUCTURE_FAILED, BEARING_FAILED))
        master.total_bearing_evaluations += evaluations
        master.relaxed_steps += bool(relaxed)
        self.bearings.evaluations += len(self.bearings.models) * (
            evaluations - (outcome == BEARING_FAILED))

    def _raise(self, master, t, dt, work, ends, outcome, status, piece, k, bad, b_status,
               mismatch, states) -> None:
        """The error of a step from t [s] that :func:`coupled_steps` did not accept, with
        the messages of the Python loop: ``work`` its buffers, ``ends`` the end times [s] of
        its sub-steps, the other arguments its returns."""
        if outcome == STRUCTURE_FAILED:
            self.structure.structure.raise_failed_step(status, k, work, ends[piece])
        if outcome == BEARING_FAILED:
            self.bearings.raise_set_failure(bad, b_status, states)
        self.bearings.record_states(states)
        raise CouplingError(not_converged(t, dt, master.max_iterations, mismatch, master.tol))
