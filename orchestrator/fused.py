"""The master's coupled iteration in one compiled call, for the in-process slaves.

One iteration of :meth:`orchestrator.master.Master.step` is: the structure's Newmark step with
the current affine laws (Eq. 11-17), the journal states of its result, the bearings evaluated
there (Eq. 5-7, 18) and the mismatch and re-linearisation of the laws (Eq. 17). In process,
each piece is a compiled kernel (:func:`gear_fmu.step_kernel.advance`,
``bearing_fmu._hybrid_kernels.hybrid_global``,
:meth:`~bearing_fmu.affine.AffineLaws.relinearise`) and the time between them went to Python.
:func:`coupled_iteration` calls the same kernels, in the same order, on the same arrays, so the
master's results are unchanged to the last bit (``tests/test_golden.py``);
:class:`FusedIteration` prepares its arguments and takes its outcome through the structure's
and the bearings' own methods, errors included.

It serves the paper's configuration: a :class:`gear_fmu.mesh.MeshElement` structure stepping
without contact events inside the step, and hybrid bearings. Any other step (one cut at a
contact event, benchmark timers) or bearing set goes the general way, through the slaves'
interfaces.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from bearing_fmu._hybrid_kernels import hybrid_global
from bearing_fmu.affine import AffineLaws, _relinearise
from bearing_fmu.axial import AXIAL_COEF
from bearing_fmu.hybrid import HybridBearing
from gear_fmu.condensation import N_GEAR
from gear_fmu.step_assembly import check_laws_fast
from gear_fmu.step_kernel import CONVERGED, advance

__all__ = ["FusedIteration", "coupled_iteration"]


@njit(cache=True)
def coupled_iteration(step_args, x1, v1, work, qs, omegas, clearances, scales, res, out,
                      f0_old, kb_old, cb_old):
    """Step, journal states, bearings and re-linearisation (module docstring).

    ``step_args``: the arguments of :func:`gear_fmu.step_kernel.advance` (``x1``, ``v1``
    among them: its output state); ``work``: the hybrid workspaces of the bearings
    ``(states, active sets, work spaces, index spaces, trig tables)``, one tuple each;
    ``qs`` (nb, 2, 2) their frames, ``omegas``, ``clearances``, ``scales`` (force scale of
    Eq. 5) per bearing; ``out`` (nb, 5, 2) receives force, Kb and Cb (global frame); the old
    laws ``f0_old`` ... ``cb_old``.

    Returns ``(step outcome, journal states (nb, 4), bearing status, bearing index, mismatch,
    f0, kb, cb)``: the step's outcome as :func:`gear_fmu.step_kernel.advance` returns it (the
    rest is not computed unless it converged), a bearing status other than 0 for the first
    bearing that failed, and the new laws.
    """
    nb = qs.shape[0]
    states = np.empty((nb, 4))
    f0 = np.empty((nb, 2))
    kb = np.empty((nb, 2, 2))
    cb = np.empty((nb, 2, 2))
    outcome = advance(*step_args)
    if outcome[0] != CONVERGED:
        return outcome, states, 0, -1, 0.0, f0, kb, cb
    for b in range(nb):
        for i in range(2):
            states[b, i] = x1[N_GEAR + 2 * b + i]
            states[b, 2 + i] = v1[N_GEAR + 2 * b + i]
    states_w, active_w, ws_w, iws_w, trig_w = work
    for b in range(nb):
        status = hybrid_global(states_w[b], active_w[b], ws_w[b], iws_w[b], trig_w[b],
                               AXIAL_COEF, qs[b], states[b], omegas[b], clearances[b],
                               scales[b], res, out[b])
        if status != 0:
            return outcome, states, status, b, 0.0, f0, kb, cb
    mismatch, f0, kb, cb = _relinearise(states, out[:, 0], out[:, 1:3], out[:, 3:5], f0_old,
                                        kb_old, cb_old)
    return outcome, states, 0, -1, mismatch, f0, kb, cb


class FusedIteration:
    """:func:`coupled_iteration` for an in-process structure and hybrid bearings.

    Build it with :meth:`build` (None when the slaves are not of that kind); call it as the
    master's iteration: ``(mismatch, new laws, bearing force, journal states)``, or None when
    this step must go the general way.
    """

    def __init__(self, structure, bearings):
        self.slave = structure
        self.st = structure.structure
        self.bearings = bearings
        models = bearings.models
        self._work = tuple(tuple(getattr(m, name) for m in models)
                           for name in ("_state", "_active", "_ws", "_iws", "_trig"))
        self._q = np.ascontiguousarray(bearings._q)
        self._omegas = np.array(bearings.omegas)
        self._clearances = np.array([m.bearing.clearance for m in models])
        self._scales = np.array([m.bearing.force_scale(w)
                                 for m, w in zip(models, bearings.omegas, strict=True)])
        self._res = np.empty((5, 2))

    @classmethod
    def build(cls, structure, bearings) -> FusedIteration | None:
        """The fused iteration of these slaves, or None if they are not an in-process
        structure with the mesh element and a set of hybrid bearings."""
        from orchestrator.inprocess import InProcessStructure, ModelBearings

        if not (isinstance(structure, InProcessStructure) and isinstance(bearings, ModelBearings)
                and all(type(m) is HybridBearing for m in bearings.models)
                and structure.structure._mesh_arrays is not None):
            return None
        return cls(structure, bearings)

    def __call__(self, t: float, dt: float, laws: AffineLaws):
        st = self.st
        if abs(t - st.t) > 1e-9 * max(dt, abs(t)) or not st.single_piece(dt):
            return None  # the general way: its checks and its contact events
        f0, kb, cb = check_laws_fast(laws.f0, laws.kb, laws.cb)
        t1 = st.t + dt
        args = st.advance_arguments(dt, t1, st.pinion_angle(t1), f0, kb, cb)
        nb = self._q.shape[0]
        out = np.empty((nb, 5, 2))
        outcome, states, status, bad, mismatch, f0n, kbn, cbn = coupled_iteration(
            args, args[-3], args[-2], self._work, self._q, self._omegas, self._clearances,
            self._scales, self._res, out, f0, kb, cb)
        self.slave._laws = laws
        st.commit_advance(outcome, args, t1, f"Newmark step {st.n_steps + 1}")
        st.t = t1
        st.n_steps += 1
        bearings = self.bearings
        bearings._states = states.copy()
        if status != 0:
            bearings.models[bad].raise_status(status, self._q[bad], states[bad],
                                              self._omegas[bad])
        bearings.evaluations += nb
        force = out[:, 0]
        return (mismatch, AffineLaws(f0n, kbn, cbn, states.copy(), force.copy()), force,
                states)
