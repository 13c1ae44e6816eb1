"""Borrowed arrays (bearing_fmu.borrowed): the same memory and types, no reference counts;
held arrays: one numba object that keeps a tuple of arrays alive."""

import gc
import sys

import numpy as np
from numba import njit, typeof
from numba.core.runtime import _nrt_python, rtsys

from bearing_fmu.borrowed import Held, borrowed, held


@njit
def _down(t):
    """A layer below: reads every member, writes through the first array."""
    a, (b, c), r, s = t
    a[0, 1] = 7.0
    return a.sum() + b.sum() + c.sum() + r["x"].sum() + s


@njit
def _borrow_and_pass(t):
    u = borrowed(t)
    return _down(u), _down(t)


def _members():
    a = np.arange(6.0).reshape(2, 3)
    b = np.arange(4, dtype=np.int64)
    c = np.array([[[True, False]]])
    r = np.zeros(3, dtype=[("x", np.float64), ("n", np.int64)])
    r["x"] = [1.5, 2.5, 3.5]
    return a, (b, c), r, 2.0


def test_a_borrowed_tuple_reads_and_writes_the_callers_memory():
    """Every array of a nested tuple (float, int, bool, record) reads as the original and a
    write through the borrowed one lands in the caller's array; a scalar passes through."""
    t = _members()
    expected = 6.0 * 5.0 / 2.0 - 1.0 + 7.0 + 6.0 + 1.0 + 7.5 + 2.0  # a after a[0, 1] = 7
    via_borrowed, direct = _borrow_and_pass(t)
    assert via_borrowed == direct == expected
    assert t[0][0, 1] == 7.0


def test_borrowing_keeps_numbas_allocation_count_balanced():
    """No meminfo is created or leaked by borrowing: numba's runtime counts the same
    allocations and frees around calls that borrow as around calls that do not."""
    t = _members()
    _borrow_and_pass(t)  # compiled
    was_on = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats()
        for _ in range(100):
            _borrow_and_pass(t)
        after = rtsys.get_allocation_stats()
    finally:
        if not was_on:
            _nrt_python.memsys_disable_stats()
    assert after.alloc - before.alloc == after.free - before.free
    assert after.mi_alloc - before.mi_alloc == after.mi_free - before.mi_free
    # the counts did count: a memory-info per array the calls unbox from Python
    assert after.mi_alloc - before.mi_alloc >= 100


def test_a_borrowed_array_keeps_its_type():
    """The layers below are compiled once for borrowed and owned arguments (the same
    types): a borrowed array is not a new numba type."""
    t = _members()
    _borrow_and_pass(t)
    assert len(_down.signatures) == 1


@njit
def _read_held(h):
    """The held tuple as :func:`_down` reads it."""
    return _down(h.arrays)


def test_held_arrays_are_the_callers_and_outlive_its_references():
    """A held tuple (nested, float, int, bool, record arrays, a scalar) reads as the
    original, a write through it lands in the caller's array, and the arrays stay alive once
    the caller has dropped its own references (the object holds them)."""
    t = _members()
    h = held(t)
    assert isinstance(h, Held)
    expected = 6.0 * 5.0 / 2.0 - 1.0 + 7.0 + 6.0 + 1.0 + 7.5 + 2.0
    assert _read_held(h) == expected
    assert t[0][0, 1] == 7.0
    a = np.arange(3.0)
    before = sys.getrefcount(a)
    h2 = held((a,))
    assert sys.getrefcount(a) == before + 1  # the object holds the array
    del h2
    gc.collect()
    assert sys.getrefcount(a) == before  # and lets it go with itself
    h = held(_members())  # no reference left but the held object's
    gc.collect()
    np.ones((1000, 1000))  # (memory that a freed array's would be reused for)
    assert _read_held(h) == expected


def test_a_held_object_is_typed_as_numba_types_it():
    """The registered fast typeof gives numba's own type of the object (the one its boxing
    carries), so a compiled call finds the signature compiled for it."""
    h = held(_members())
    assert typeof(h) is h._numba_type_
    _read_held(h)
    _read_held(held(_members()))
    assert len(_read_held.signatures) == 1
