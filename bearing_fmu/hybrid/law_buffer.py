"""The law buffer: a bearing FMU's journal state and law in one float64 array.

A bearing FMU's slave (:class:`fmu_src.slaves.bearing.BearingSlave`) keeps its journal state,
its law and their bookkeeping in one float64 array, the *law buffer* (its layout: the ``IO_*``
constants in this module's source), and, for the hybrid model, the addresses of the model's
arrays in an int64 array, the *context* (:func:`fill_context`). The patched FMU library
(``fmu_src/native/patches/0011-native-bearing-law.patch``) then serves the master's two calls
of a coupled iteration itself: fmi2SetReal of the four state inputs writes the buffer, and
fmi2GetReal of the ten law outputs calls the compiled law
(``bearing_fmu.hybrid._native.hybrid_law``) when the state changed. Neither enters Python.
The slave *arms* the buffer (:func:`arm`) after an evaluation of its own; the library serves
the calls only while it is armed.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.hybrid.axial import AXIAL_COEF

__all__ = ["CTX_SIZE", "IO_SIZE", "LAYOUT", "NOT_FINITE", "arm", "fill_context"]

#: the layout's name: the library serves the calls natively only for a buffer it knows. The
#: patch repeats IO_LAW, IO_DIRTY and IO_ARMED: a change of the layout changes this name there
#: and here
LAYOUT = "gsb-bearing-law-1"

# --- the law buffer (float64) ------------------------------------------------------------------
IO_STATE = 0  # 0-3: the journal state s, t, s_dot, t_dot [m, m/s] (the inputs)
IO_LAW = 4  # 4-13: force [N], Kb [N/m], Cb [N s/m] (the outputs, contract order)
IO_EVAL = 14  # 14-17: the state the law was evaluated at
IO_SOLVES = 18  # evaluations so far
IO_DIRTY = 19  # 1.0: the inputs changed since the law was evaluated
IO_ARMED = 20  # 1.0: the library may evaluate the law itself (the slave sets and clears it)
IO_STATUS = 21  # the status of the library's last failed evaluation (0: none pending)
IO_Q = 22  # 22-25: Q, the global-to-local rotation (2 x 2, row-major)
IO_OMEGA = 26  # shaft speed [rad/s]
IO_C = 27  # radial clearance [m]
IO_FS = 28  # the force scale of Eq. (5) at omega [N]
#: the law buffer's length
IO_SIZE = 29

# --- the context (int64): the model's arrays ---------------------------------------------------
CTX_NODES, CTX_STATE, CTX_ACTIVE, CTX_WS, CTX_IWS, CTX_TRIG, CTX_COEF, CTX_RES = range(8)
#: the context's length
CTX_SIZE = 8

#: the compiled law's status for a law with a non-finite output (a kernel's are >= -1)
NOT_FINITE = -2


def fill_context(ctx: np.ndarray, io: np.ndarray, model, q) -> None:
    """Write into ``ctx`` (int64, :data:`CTX_SIZE`) the addresses of the arrays of the
    :class:`~bearing_fmu.hybrid.model.HybridBearing` ``model``, valid while the model lives and
    keeps them (it never replaces them: its state is set in place), and into the law buffer
    ``io`` its frame ``q`` (q00, q01, q10, q11) and clearance."""
    arrays = {CTX_STATE: model._state, CTX_ACTIVE: model._active, CTX_WS: model._ws,
              CTX_IWS: model._iws, CTX_TRIG: model._trig, CTX_COEF: AXIAL_COEF,
              CTX_RES: model._res}
    for slot, a in arrays.items():
        if not a.flags.c_contiguous:
            raise ValueError(f"context slot {slot}: the array is not C-contiguous")
        ctx[slot] = a.ctypes.data
    ctx[CTX_NODES] = model.n
    io[IO_Q:IO_Q + 4] = q
    io[IO_C] = model.bearing.clearance


def arm(io: np.ndarray, model) -> None:
    """Arm the law buffer ``io`` after an evaluation of ``model`` (its context filled by
    :func:`fill_context`): the speed and force scale of that evaluation, which the next ones
    at the same speed use."""
    io[IO_OMEGA], io[IO_FS] = model._scale
    io[IO_ARMED] = 1.0
