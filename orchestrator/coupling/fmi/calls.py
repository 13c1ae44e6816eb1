"""FMI 2.0 functions called from compiled code, through their addresses.

fmpy loads an FMU's library with ctypes; each call from Python converts its arguments, checks
their types and releases and takes the GIL again, a few microseconds per call. The master's
compiled loop over the steps (:mod:`orchestrator.coupling.fmi.steps`) calls the same C
functions of the same library on the same component with the addresses this module reads
(:func:`address`) and numba intrinsics that cast an address to the function's C type
(``fmi2Functions.h``). The addresses are runtime arguments, so the compiled loop is cached
like any other kernel; the numbers are those of the same calls from Python.

The GIL stays held: an FMU whose functions enter Python (pythonfmu's) takes it again on the
same thread, as it does when ctypes calls it.
"""

from __future__ import annotations

import ctypes

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

__all__ = ["address", "fmi_do_step", "fmi_real", "fmi_state"]

_VOID_P = ir.IntType(8).as_pointer()
_STATUS = ir.IntType(32)  # fmi2Status: a C enum


def address(function) -> int:
    """The address of a ctypes function (an FMU library's ``fmi2...``) or the value of a
    ``c_void_p`` (a component) as an int."""
    if isinstance(function, ctypes.c_void_p):
        return int(function.value or 0)
    if isinstance(function, int):
        return function
    return int(ctypes.cast(function, ctypes.c_void_p).value)


@intrinsic
def fmi_real(typingctx, function, component, vrs, n, values):
    """``fmi2SetReal`` or ``fmi2GetReal`` at address ``function``: ``(fmi2Component,
    const fmi2ValueReference*, size_t, fmi2Real*)`` -> fmi2Status; ``vrs`` and ``values``
    are addresses (an array's ``ctypes.data``)."""
    sig = types.int32(types.int64, types.int64, types.int64, types.int64, types.int64)

    def codegen(context, builder, signature, args):
        f, c, vr, size, val = args
        fnty = ir.FunctionType(_STATUS, [_VOID_P, ir.IntType(32).as_pointer(), ir.IntType(64),
                                         ir.DoubleType().as_pointer()])
        call = builder.inttoptr(f, fnty.as_pointer())
        return builder.call(call, [builder.inttoptr(c, _VOID_P),
                                   builder.inttoptr(vr, ir.IntType(32).as_pointer()), size,
                                   builder.inttoptr(val, ir.DoubleType().as_pointer())])

    return sig, codegen


@intrinsic
def fmi_do_step(typingctx, function, component, t, h):
    """``fmi2DoStep(component, t, h, fmi2False)`` at address ``function`` -> fmi2Status."""
    sig = types.int32(types.int64, types.int64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        f, c, t0, step = args
        fnty = ir.FunctionType(_STATUS, [_VOID_P, ir.DoubleType(), ir.DoubleType(),
                                         ir.IntType(32)])
        call = builder.inttoptr(f, fnty.as_pointer())
        return builder.call(call, [builder.inttoptr(c, _VOID_P), t0, step,
                                   ir.Constant(ir.IntType(32), 0)])

    return sig, codegen


@intrinsic
def fmi_state(typingctx, function, component, state):
    """``fmi2GetFMUstate`` / ``fmi2FreeFMUstate`` (``state``: the address of an
    ``fmi2FMUstate``) or ``fmi2SetFMUstate`` (``state``: the state itself) at address
    ``function`` -> fmi2Status: each takes a component and one pointer."""
    sig = types.int32(types.int64, types.int64, types.int64)

    def codegen(context, builder, signature, args):
        f, c, s = args
        fnty = ir.FunctionType(_STATUS, [_VOID_P, _VOID_P])
        call = builder.inttoptr(f, fnty.as_pointer())
        return builder.call(call, [builder.inttoptr(c, _VOID_P), builder.inttoptr(s, _VOID_P)])

    return sig, codegen
