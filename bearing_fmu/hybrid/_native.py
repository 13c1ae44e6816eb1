"""The hybrid bearing's law as a C function, for an FMU's native layer to call without Python.

A bearing FMU's slave keeps its journal state and law in one float64 array, the *law buffer*
(layout :data:`IO_STATE` ... :data:`IO_SIZE`), and the addresses of its model's arrays in an
int64 array, the *context* (:func:`fill_context`). The patched FMU library
(``fmu_src/native/patches/0011-native-bearing-law.patch``) then serves the master's two calls
of a coupled iteration itself: fmi2SetReal of the four state inputs writes the buffer, and
fmi2GetReal of the ten law outputs calls :data:`hybrid_law` when the state changed. Neither
enters Python.

:data:`hybrid_law` calls the same compiled :func:`~bearing_fmu.hybrid._kernels.hybrid_global`
on the same arrays as :meth:`HybridBearing.evaluate_global
<bearing_fmu.hybrid.model.HybridBearing.evaluate_global>`, so the outputs and the warm start
it leaves are the same bits as the slave's Python path. On failure it returns the status
(the kernel's, :data:`~bearing_fmu.hybrid._kernels.BAD_STATE` or :data:`NOT_FINITE`) and
leaves the outputs stale; the library then takes the Python path, which raises the error the
status names and logs it (:meth:`fmu_src.slaves.bearing.BearingSlave._evaluate`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray, cfunc, njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from bearing_fmu.hybrid import _workspace as _ws
from bearing_fmu.hybrid._kernels import hybrid_global
from bearing_fmu.hybrid.axial import AXIAL_COEF

__all__ = ["CTX_SIZE", "IO_SIZE", "LAYOUT", "NOT_FINITE", "arm", "fill_context", "hybrid_law"]

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
IO_SIZE = 29

# --- the context (int64): the model's arrays ---------------------------------------------------
CTX_NODES, CTX_STATE, CTX_ACTIVE, CTX_WS, CTX_IWS, CTX_TRIG, CTX_COEF, CTX_RES = range(8)
CTX_SIZE = 8

#: :data:`hybrid_law`'s status for a law with a non-finite output (a kernel's are >= -1)
NOT_FINITE = -2

_N_COEF = AXIAL_COEF.shape[1]


@intrinsic
def _pointer(typingctx, address):
    """The int64 ``address`` as a ``void*`` (for :func:`numba.carray`)."""
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)
    return types.voidptr(types.int64), codegen


@njit(cache=True)
def _law(ctx, io):
    n = ctx[CTX_NODES]
    state = carray(_pointer(ctx[CTX_STATE]), (1,), _ws.STATE)
    active = carray(_pointer(ctx[CTX_ACTIVE]), (n,), np.bool_)
    ws = carray(_pointer(ctx[CTX_WS]), (_ws.WS_ROWS, n), np.float64)
    iws = carray(_pointer(ctx[CTX_IWS]), (2, 2 * n), np.int64)
    trig = carray(_pointer(ctx[CTX_TRIG]), (8, n), np.float64)
    coef = carray(_pointer(ctx[CTX_COEF]), (4, _N_COEF), np.float64)
    res = carray(_pointer(ctx[CTX_RES]), (5, 2), np.float64)
    q = io[IO_Q:IO_Q + 4].reshape((2, 2))
    out = io[IO_LAW:IO_LAW + 10].reshape((5, 2))
    s = io[IO_STATE:IO_STATE + 4]
    status = hybrid_global(state, active, ws, iws, trig, coef, q, s, io[IO_OMEGA], io[IO_C],
                           io[IO_FS], res, out)
    if status == 0:
        for i in range(10):
            if not math.isfinite(io[IO_LAW + i]):
                status = NOT_FINITE
    if status != 0:
        io[IO_STATUS] = status
        return status
    for i in range(4):
        io[IO_EVAL + i] = s[i]
    io[IO_SOLVES] += 1.0
    io[IO_DIRTY] = 0.0
    return 0


@cfunc(types.int64(types.CPointer(types.int64), types.CPointer(types.float64)), cache=True)
def _law_c(ctx, io):
    return _law(carray(ctx, (CTX_SIZE,)), carray(io, (IO_SIZE,)))


#: ``int64_t law(const int64_t *context, double *buffer)``: the address of the C function
hybrid_law = _law_c.address


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
