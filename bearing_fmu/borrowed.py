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

:func:`held` is the other end, for a compiled call made from Python at every step: numba
unboxes each array of a call's arguments (a memory-info allocated and freed per array, about
60 ns), about 3.7 us for the 61 arrays of the gear-shaft FMU's step, which it takes twice or
three times per coupled step. :class:`Held` keeps a tuple of arrays in one numba object
(numba's ``structref``): a call unboxes one pointer (a tuple of 60 arrays: 5.2 us per call
of a compiled function from Python, 1.3 us held; ``benchmarks/held_arrays.py``). The object
holds references to its arrays, so they stay alive as long as it does; it is built again
when one of them is replaced.
"""

from __future__ import annotations

from numba import njit
from numba.core import cgutils, types
from numba.experimental import structref
from numba.extending import intrinsic, overload, typeof_impl

__all__ = ["Held", "borrowed", "held"]


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


@structref.register
class HeldType(types.StructRef):
    """numba's type of :class:`Held`: one field, ``arrays`` (a tuple of any types)."""

    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(t)) for name, t in fields)


class Held(structref.StructRefProxy):
    """A tuple of arrays held in one numba object (module docstring): compiled code reads it
    as ``held.arrays``; Python builds it with :func:`held`."""


structref.define_boxing(HeldType, Held)


@typeof_impl.register(Held)
def _typeof_held(value, context):
    # (numba's generic typeof tries the buffer protocol and cffi first: 2.4 us a call)
    return value._type


def _new_held(arrays):
    raise NotImplementedError("compiled code only")


@overload(_new_held)
def _new_held_impl(arrays):
    typ = HeldType([("arrays", arrays)])

    def impl(arrays):
        out = structref.new(typ)
        out.arrays = arrays
        return out

    return impl


@njit(cache=True)
def held(arrays):
    """A :class:`Held` of the tuple ``arrays`` (references to the same arrays, not copies)."""
    return _new_held(arrays)
