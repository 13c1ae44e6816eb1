"""The hybrid bearing's law as a C function, for an FMU's native layer to call without Python.

:data:`hybrid_law` is the address of ``int64_t law(const int64_t *context, double *buffer)``
on the law buffer and context of :mod:`bearing_fmu.hybrid.law_buffer`. It calls the same
compiled :func:`~bearing_fmu.hybrid._kernels.hybrid_global` on the same arrays as
:meth:`HybridBearing.evaluate_global <bearing_fmu.hybrid.model.HybridBearing.evaluate_global>`,
so the outputs and the warm start it leaves are the same bits as the slave's Python path. On
failure it returns the status (the kernel's, :data:`~bearing_fmu.hybrid._kernels.BAD_STATE` or
:data:`~bearing_fmu.hybrid.law_buffer.NOT_FINITE`), writes it into the buffer and leaves the
outputs stale; the library then takes the Python path, which raises the error the status names
and logs it (:meth:`fmu_src.slaves.bearing.BearingSlave._evaluate`). Importing this module
compiles the function (or loads it from numba's cache): only a hybrid bearing FMU does.
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
from bearing_fmu.hybrid.law_buffer import (
    CTX_ACTIVE,
    CTX_COEF,
    CTX_IWS,
    CTX_NODES,
    CTX_RES,
    CTX_SIZE,
    CTX_STATE,
    CTX_TRIG,
    CTX_WS,
    IO_C,
    IO_DIRTY,
    IO_EVAL,
    IO_FS,
    IO_LAW,
    IO_OMEGA,
    IO_Q,
    IO_SIZE,
    IO_SOLVES,
    IO_STATE,
    IO_STATUS,
    NOT_FINITE,
)

__all__ = ["hybrid_law"]

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
