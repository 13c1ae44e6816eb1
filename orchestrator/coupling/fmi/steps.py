"""The master's coupled steps through the FMUs in one compiled call.

:meth:`orchestrator.coupling.master.Master.step` iterates in Python. Through the FMUs each
iteration is a handful of FMI calls (the gear-shaft FMU's laws, doStep and journals, each
bearing FMU's state and law, the state restored), and the Python around them (ctypes'
conversions, the slaves' wrappers, the master's objects and checks) cost about as much as the
bearings' compiled laws. :func:`fmu_steps` makes the same FMI calls in the same order with the
same arguments (:mod:`orchestrator.coupling.fmi.calls`), the laws packed
(:func:`fmu_src.contract.pack_law_arrays`) and relinearised
(``bearing_fmu.affine._relinearise``) by the kernels the Python loop uses, so a step gives the
bits of the loop. The gear-shaft FMU's doStep and its state's save and restore still run its
slave's Python; the bearing FMUs and the gear-shaft FMU's laws and journals are served by
their native layer (``fmu_src/native/patches``) without Python.

A block of steps is one call (:class:`FmuSteps`, the master's ``fused``). A call that fails
stops at once and returns which call failed with its status; the error is raised in Python
with the message of the Python loop (``FmuSteps._raise``). The FMUs' log messages named
there are those since the block began (the loop names those since the failing call; a
successful step logs nothing). Bearing FMUs without the Jacobian outputs (finite differences
in Python) and a gear-shaft FMU in initialisation mode take the Python loop.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bearing_fmu.affine import AffineLaws, _relinearise
from fmu_src.contract import pack_law_arrays
from orchestrator.coupling.fmi.bearings import FmuBearings, _failed
from orchestrator.coupling.fmi.calls import address, fmi_do_step, fmi_real, fmi_state
from orchestrator.coupling.fmi.instance import status_name
from orchestrator.coupling.fmi.structure import FmuStructure
from orchestrator.coupling.master import (
    RELAXATION,
    STALL,
    CompiledSteps,
    CouplingError,
    StepBlock,
    not_converged,
    relaxed_law,
)

__all__ = ["FmuSteps", "fmu_steps"]

#: where :func:`fmu_steps` takes the gear-shaft FMU's functions and component (``gear``)
SET_REAL, GET_REAL, DO_STEP, GET_STATE, SET_STATE, FREE_STATE, COMPONENT = range(7)
#: the outcomes of a step of :func:`fmu_steps`: accepted, or the call that failed
(ACCEPTED, GET_STATE_FAILED, LAWS_FAILED, STEP_FAILED, JOURNALS_FAILED, JOURNALS_NOT_FINITE,
 BEARING_SET_FAILED, BEARING_GET_FAILED, BEARING_NOT_FINITE, RESTORE_FAILED, NOT_CONVERGED,
 OUTPUTS_FAILED) = range(12)
_DOUBLE, _VR = 8, 4  # bytes of an fmi2Real and an fmi2ValueReference


@njit(cache=True)
def _finite(values) -> bool:
    for x in values:
        if not math.isfinite(x):
            return False
    return True


@njit(cache=True)
def fmu_steps(n, times, dt, gear, law_vr, law_val, journal_vr, journal_val, output_vr,
              output_val, saved, bearing_calls, state_vr, law_out_vr, bearing_states,
              bearing_laws, f0, kb, cb, x0, force0, expanded, tol, max_iterations, relaxation,
              stall, mismatches, rec_states, rec_force, rec_outputs, rec_iterations):
    """``n`` steps of the master (:meth:`orchestrator.coupling.master.Master.step`) through
    the FMUs, step i from ``times[i]`` [s] to ``times[i] + dt``, from the laws of Eq. (17)
    ``f0, kb, cb`` (nb, 2), (nb, 2, 2) [N, N/m, N s/m], with their expansion point ``x0``
    (nb, 4) and force there ``force0`` (nb, 2) when ``expanded`` (what the gear-shaft FMU's
    law inputs carry, :meth:`bearing_fmu.affine.AffineLaws.expansion`), until one is not
    accepted.

    ``gear``: the gear-shaft FMU's function addresses and component (:data:`SET_REAL` ...);
    ``law_vr``/``law_val`` (56,), ``journal_vr``/``journal_val`` (16,) and
    ``output_vr``/``output_val`` (6, :data:`fmu_src.contract.GEAR_OUTPUTS`' order) its value
    references and values; ``saved`` (1,) int64, where fmi2GetFMUstate writes. Per bearing b:
    ``bearing_calls[b]`` fmi2SetReal, fmi2GetReal and the component; ``state_vr[b]`` (4)
    and ``law_out_vr[b]`` (10) its value references, ``bearing_states[b]`` and
    ``bearing_laws[b]`` (10: force, Kb, Cb row by row) its values. ``mismatches``
    (max_iterations,) the iterations' mismatches. Step i writes its journal states, bearing
    forces, the six outputs and iterations into row i of ``rec_states`` ... ``rec_iterations``.

    Returns ``(accepted steps, relaxed steps, outcome, iteration, status, bearing, mismatch,
    kept, relaxed, f0, kb, cb, x0, force0)``: for the last step its outcome
    (:data:`ACCEPTED` ...), the iteration and the failed call's status and bearing (or -1),
    its mismatch; the mismatch of the last step recorded (NaN before one), whether the last
    step was relaxed, and the laws the next step starts from (expanded once a step is
    accepted).
    """
    nb = bearing_states.shape[0]
    comp = gear[COMPONENT]
    law_rows = law_val.reshape(nb, 14)
    states = np.empty((nb, 4))
    zeros = np.zeros((nb, 4))
    relaxed_steps = 0
    outcome, it, status, bad, relaxed, mismatch, kept = ACCEPTED, 0, 0, -1, False, 0.0, np.nan
    for i in range(n):
        status = fmi_state(gear[GET_STATE], comp, saved.ctypes.data)
        if status > 1:
            return (i, relaxed_steps, GET_STATE_FAILED, 0, status, -1, mismatch, kept, False,
                    f0, kb, cb, x0, force0)
        # the master's iteration (Master.step): Newton on the bearings through their laws
        law_f0, law_kb, law_cb, law_x, law_force, law_expanded = f0, kb, cb, x0, force0, expanded
        outcome, relaxed, mismatch, bad = NOT_CONVERGED, False, np.inf, -1
        for it in range(1, max_iterations + 1):
            if law_expanded:  # FmuStructure.set_bearing_laws: the law's expansion
                pack_law_arrays(law_x, law_force, law_kb, law_cb, law_rows)
            else:
                pack_law_arrays(zeros, law_f0, law_kb, law_cb, law_rows)
            status = fmi_real(gear[SET_REAL], comp, law_vr.ctypes.data, law_vr.size,
                              law_val.ctypes.data)
            if status > 1:
                outcome = LAWS_FAILED
                break
            status = fmi_do_step(gear[DO_STEP], comp, times[i], dt)
            if status != 0:
                outcome = STEP_FAILED
                break
            status = fmi_real(gear[GET_REAL], comp, journal_vr.ctypes.data, journal_vr.size,
                              journal_val.ctypes.data)
            if status > 1:
                outcome = JOURNALS_FAILED
                break
            if not _finite(journal_val):
                outcome = JOURNALS_NOT_FINITE
                break
            states[:] = journal_val.reshape(nb, 4)
            bearing_states[:] = states
            for b in range(nb):  # FmuBearings.evaluate
                status = fmi_real(bearing_calls[b, 0], bearing_calls[b, 2],
                                  state_vr.ctypes.data + b * 4 * _VR, 4,
                                  bearing_states.ctypes.data + b * 4 * _DOUBLE)
                if status > 1:
                    outcome, bad = BEARING_SET_FAILED, b
                    break
                status = fmi_real(bearing_calls[b, 1], bearing_calls[b, 2],
                                  law_out_vr.ctypes.data + b * 10 * _VR, 10,
                                  bearing_laws.ctypes.data + b * 10 * _DOUBLE)
                if status > 1:
                    outcome, bad = BEARING_GET_FAILED, b
                    break
                if not _finite(bearing_laws[b]):
                    outcome, bad = BEARING_NOT_FINITE, b
                    break
            if bad >= 0:
                break
            out = bearing_laws.reshape(nb, 5, 2)
            force = np.ascontiguousarray(out[:, 0])
            mismatch, f0_new, kb_new, cb_new = _relinearise(
                states, force, np.ascontiguousarray(out[:, 1:3]),
                np.ascontiguousarray(out[:, 3:5]), law_f0, law_kb, law_cb)
            if mismatch <= tol:
                outcome = ACCEPTED
                f0, kb, cb, x0, force0, expanded = (f0_new, kb_new, cb_new, states.copy(),
                                                    force.copy(), True)
                break
            was_relaxed = relaxed
            relaxed, law_f0, law_kb, law_cb = relaxed_law(
                it, mismatch, mismatches, relaxed, stall, relaxation, f0_new, kb_new, cb_new,
                law_f0, law_kb, law_cb)
            relaxed_steps += relaxed and not was_relaxed
            if relaxed:  # a blended law is given by f0 alone
                law_expanded = False
            else:
                law_x, law_force, law_expanded = states.copy(), force.copy(), True
            status = fmi_state(gear[SET_STATE], comp, saved[0])
            if status > 1:
                outcome = RESTORE_FAILED
                break
        fmi_state(gear[FREE_STATE], comp, saved.ctypes.data)
        if outcome != ACCEPTED:
            return (i, relaxed_steps, outcome, it, status, bad, mismatch, kept, relaxed, f0, kb,
                    cb, x0, force0)
        # FmuStructure.step_outputs: mesh force, transmission error, gear nodes
        status = fmi_real(gear[GET_REAL], comp, output_vr.ctypes.data, output_vr.size,
                          output_val.ctypes.data)
        if status > 1:
            return (i, relaxed_steps, OUTPUTS_FAILED, it, status, -1, mismatch, kept, relaxed,
                    f0, kb, cb, x0, force0)
        rec_states[i] = states
        rec_force[i] = force0
        rec_outputs[i] = output_val
        rec_iterations[i] = it
        kept = mismatch
    return (n, relaxed_steps, ACCEPTED, it, status, -1, mismatch, kept, relaxed, f0, kb, cb, x0,
            force0)


class FmuSteps(CompiledSteps):
    """:meth:`~orchestrator.coupling.master.Master.step` through the gear-shaft FMU
    (:class:`~orchestrator.coupling.fmi.structure.FmuStructure`) and bearing FMUs with the
    Jacobian outputs (:class:`~orchestrator.coupling.fmi.bearings.FmuBearings`) as one
    :func:`fmu_steps` per block of steps; :func:`orchestrator.coupling.system.build_master`
    gives it to the master as its ``fused`` step when they are."""

    def __init__(self, structure: FmuStructure, bearings: FmuBearings):
        if not self.fits(structure, bearings):
            raise ValueError("FmuSteps: the gear-shaft FMU and bearing FMUs with the Jacobian "
                             "outputs only")
        self.structure = structure
        self.bearings = bearings
        st, nb = structure, len(bearings.slaves)
        self._gear = np.array([address(f) for f in (st._set_real, st._get_real, st._do_step,
                                                    st._get_state, st._set_state,
                                                    st._free_state)] + [address(st._c)],
                              dtype=np.int64)
        self._law_vr = np.array(st._law_vr, dtype=np.uint32)
        self._law_val = np.empty(len(self._law_vr))
        self._journal_vr = np.array(st._jr_vr, dtype=np.uint32)
        self._journal_val = np.empty(len(self._journal_vr))
        self._output_vr = np.array(st._ex_vr, dtype=np.uint32)
        self._output_val = np.empty(len(self._output_vr))
        self._saved = np.zeros(1, dtype=np.int64)
        self._bearing_calls = np.array([[address(s), address(g), address(c)]
                                        for s, g, c in bearings._calls], dtype=np.int64)
        self._state_vr = np.array([list(v) for v in bearings._in_vr], dtype=np.uint32)
        self._law_out_vr = np.array([list(v) for v in bearings._out_vr], dtype=np.uint32)
        self._bearing_states = np.empty((nb, 4))
        self._bearing_laws = np.empty((nb, 10))
        self._mismatches = None

    @staticmethod
    def fits(structure, bearings) -> bool:
        """Whether the slaves can take the compiled step: FMUs, every bearing FMU with the
        Jacobian outputs (a force-only FMU's come from finite differences in Python)."""
        return (isinstance(structure, FmuStructure) and isinstance(bearings, FmuBearings)
                and bool(bearings.slaves) and not any(bearings.force_only))

    def _block(self, master, t: float, dt: float, n: int, time_of) -> StepBlock | None:
        """Up to ``n`` steps from t [s] in one :func:`fmu_steps` call, step k from
        ``time_of(k)`` [s]; the master's counters and laws and the structure's time and step
        count as the loop leaves them."""
        st, bearings = self.structure, self.bearings
        if st.in_init or st.slave.fmu is None or not bearings.slaves:
            return None  # the Python loop leaves initialisation, or says what is closed
        nb = len(bearings.slaves)
        times = np.array([time_of(k) for k in range(n)], dtype=float)
        if self._mismatches is None or self._mismatches.size != master.max_iterations:
            self._mismatches = np.empty(master.max_iterations)
        rec = (np.empty((n, nb, 4)), np.empty((n, nb, 2)), np.empty((n, 6)),
               np.empty(n, dtype=np.int64))
        laws = master.laws
        states, force_at, kb, cb = laws.expansion()
        since = len(st.slave.messages)
        n_steps = st.n_steps
        (count, relaxed_steps, outcome, it, status, bad, mismatch, kept, _, f0, kb, cb, x0,
         force0) = fmu_steps(
            n, times, float(dt), self._gear, self._law_vr,
            self._law_val, self._journal_vr, self._journal_val, self._output_vr,
            self._output_val, self._saved, self._bearing_calls, self._state_vr,
            self._law_out_vr, self._bearing_states, self._bearing_laws,
            np.ascontiguousarray(laws.f0, dtype=float), np.ascontiguousarray(kb, dtype=float),
            np.ascontiguousarray(cb, dtype=float), np.ascontiguousarray(states, dtype=float),
            np.ascontiguousarray(force_at, dtype=float), laws.states is not None, master.tol,
            master.max_iterations, RELAXATION, STALL, self._mismatches, *rec)
        its = rec[3][:count]
        master.relaxed_steps += relaxed_steps
        accepted = count + (outcome == OUTPUTS_FAILED)  # that step was accepted, not recorded
        done = int(its.sum()) + (it if outcome == OUTPUTS_FAILED else 0)
        master.total_iterations += done
        master.total_bearing_evaluations += done
        if accepted:
            master.laws = AffineLaws(f0, kb, cb, x0, force0)
            st.t, st.n_steps = float(times[accepted - 1] + dt), n_steps + accepted
        outputs = rec[2][:count]
        block = StepBlock(count, rec[0][:count], rec[1][:count], outputs[:, 0].copy(),
                          outputs[:, 1].copy(), outputs[:, 2:].reshape(count, 2, 2), its, kept)
        if outcome != ACCEPTED:
            try:
                self._raise(master, float(times[count]), dt, outcome, it, status, bad, mismatch,
                            since)
            except Exception as exc:  # handed to the caller with the rows (as the loop does)
                block.error = exc
        return block

    def _raise(self, master, t, dt, outcome, it, status, bad, mismatch, since) -> None:
        """The error of a step from t [s] that :func:`fmu_steps` did not accept (``outcome``
        at iteration ``it``, the failed call's ``status``, bearing ``bad``), with the message
        and the counters of the Python loop."""
        st, bearings = self.structure, self.bearings
        evaluated = it - (outcome in (LAWS_FAILED, STEP_FAILED, JOURNALS_FAILED,
                                      JOURNALS_NOT_FINITE))
        iterated = evaluated - (outcome in (BEARING_SET_FAILED, BEARING_GET_FAILED,
                                            BEARING_NOT_FINITE))
        if outcome != OUTPUTS_FAILED:
            master.total_iterations += max(iterated, 0)
            master.total_bearing_evaluations += max(evaluated, 0)
        n_start = st.n_steps
        if outcome in (JOURNALS_FAILED, JOURNALS_NOT_FINITE, RESTORE_FAILED,
                       *range(BEARING_SET_FAILED, BEARING_NOT_FINITE + 1)):
            st.t, st.n_steps = t + dt, n_start + 1  # after the doStep, as the loop leaves it
        if outcome == GET_STATE_FAILED:
            st._fail("fmi2GetFMUstate", status)
        if outcome == LAWS_FAILED:
            st._fail("setting the bearing laws", status)
        if outcome == STEP_FAILED:
            st._fail(f"doStep {n_start + 1} from t = {t:.9g} s (dt = {dt:.6g} s) failed",
                     status, since, where=False)
        if outcome == JOURNALS_FAILED:
            st._fail("reading the journal states", status, since)
        if outcome == JOURNALS_NOT_FINITE:
            st._fail("reading the journal states failed", since=since)
        if outcome in (BEARING_SET_FAILED, BEARING_GET_FAILED, BEARING_NOT_FINITE):
            s = bearings.slaves[bad]
            state = self._bearing_states[bad]
            if outcome == BEARING_NOT_FINITE:
                raise _failed(bad, s, state, f"non-finite outputs; FMU log: {s.log_tail()}")
            what = "fmi2SetReal" if outcome == BEARING_SET_FAILED else "fmi2GetReal"
            raise _failed(bad, s, state, f"{what} returned {status_name(status)}; FMU log: "
                                         f"{s.log_tail()}")
        if outcome == RESTORE_FAILED:
            st._fail("fmi2SetFMUstate", status)
        if outcome == OUTPUTS_FAILED:
            st._fail("reading outputs", status)
        raise CouplingError(not_converged(t, dt, master.max_iterations, mismatch, master.tol))
