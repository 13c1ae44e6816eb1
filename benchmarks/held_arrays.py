"""Microseconds per call of a compiled function from Python: N arrays as a tuple argument
against the same arrays held in one numba object (:func:`bearing_fmu.borrowed.held`).

Usage: ``python benchmarks/held_arrays.py [--arrays N] [--calls N]``

The function reads one number of each array; what is timed is numba's dispatch (the types of
the arguments) and unboxing (a memory-info per array, none for the held object), what the
gear-shaft FMU's step pays at each call (:meth:`gear_fmu.structure.Structure.step`).
"""

from __future__ import annotations

import argparse
import timeit

import numpy as np
from numba import njit

from bearing_fmu.borrowed import held


@njit(cache=True, inline="always")  # (a call would copy the held tuple's arrays by value)
def _first_of_each(arrays, x):
    s = x[0]
    for k in range(len(arrays)):
        s += arrays[k][0]
    return s


@njit(cache=True)
def _first_of_each_held(h, x):
    return _first_of_each(h.arrays, x)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arrays", type=int, default=60)
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args()
    arrays = tuple(np.ones(10) for _ in range(args.arrays))
    h, x = held(arrays), np.ones(3)
    assert _first_of_each(arrays, x) == _first_of_each_held(h, x) == args.arrays + 1.0
    n = args.calls
    as_tuple = min(timeit.repeat(lambda: _first_of_each(arrays, x), number=n, repeat=5)) / n
    as_held = min(timeit.repeat(lambda: _first_of_each_held(h, x), number=n, repeat=5)) / n
    build = min(timeit.repeat(lambda: held(arrays), number=200, repeat=3)) / 200
    print(f"{args.arrays} arrays: {as_tuple * 1e6:.2f} us per call as a tuple, "
          f"{as_held * 1e6:.2f} us held ({as_tuple / as_held:.1f} x); building the held "
          f"object {build * 1e6:.1f} us (best of 5 x {n} calls)")


if __name__ == "__main__":
    main()
