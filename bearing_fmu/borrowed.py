"""Arrays handed down compiled layers without numba's reference counts.

numba counts references to every array a compiled function receives: a call increments the
count of each array of its arguments (an atomic operation) and decrements it on return,
whatever the function uses. The coupled step hands the structure's arrays (about 60, and 31
per mesh) and the bearing groups' down several layers at every iteration; on the paper's case
these counts were a fifth of a step's time (``perf`` on an in-process run; numba's reference
pruning leaves the counts of a function's arguments in place when its body has branches or
loops).

:func:`borrowed` returns the same arrays (the same data, shapes, strides and types) without a
reference to their memory: numba's counts of an array without one are a test for a null
pointer. The caller keeps the arrays alive for as long as the borrowed ones are used, which a
compiled call does for its arguments: :func:`orchestrator.coupling.step.coupled_steps` borrows
its structure's and bearings' arrays at entry and hands out none of them (it returns the laws,
arrays of its own); :func:`gear_fmu.step.kernel.advance_step` (a structure's step taken alone,
the gear-shaft FMU's) borrows its arguments. A borrowed array must not be returned to Python
nor kept beyond the call.
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic, overload

__all__ = ["borrowed"]


@intrinsic
def _borrowed_array(typingctx, array):
    """The array's structure with a null memory-info and parent pointer: the same type."""

    def codegen(context, builder, signature, args):
        out = context.make_array(signature.args[0])(context, builder, value=args[0])
        out.meminfo = cgutils.get_null_value(out.meminfo.type)
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()

    return array(array), codegen


def borrowed(value):
    """``value`` with every array in it (in tuples, nested) borrowed (module docstring);
    anything else as it is. Compiled code only."""
    raise NotImplementedError("compiled code only")


@overload(borrowed)
def _borrowed(value):
    if isinstance(value, types.Array):
        return lambda value: _borrowed_array(value)
    if isinstance(value, types.BaseTuple) and len(value) > 0:
        # one statement per member: a tuple's members have types of their own
        source = ("def impl(value):\n    return ("
                  + "".join(f"borrowed(value[{k}]), " for k in range(len(value))) + ")\n")
        namespace = {"borrowed": borrowed}
        exec(source, namespace)  # the source depends on the tuple's length only
        return namespace["impl"]
    return lambda value: value
