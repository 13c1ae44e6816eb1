"""One BLAS thread for this project's linear algebra: the same bits whatever the thread count.

OpenBLAS (numpy's and scipy's) shares a product, a solve or an eigen-decomposition of a matrix
of about a hundred rows or more among its threads, and how it shares it changes the last bits
(the blocks and the rows left over take different kernels; the exact path was not traced).
The structure of the paper's case has 108 degrees of freedom: its static solution, its damping
matrix and the matrices its Newmark step is built from came out with other last bits in a
process with one BLAS thread than in one with two, and a run moved by up to 3.3e-9 of an
output's largest value within 16 steps (the helical case).

The thread count of a process is not the user's choice alone. Dask's nanny sets
``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 in its own process's
environment before it starts a worker (``distributed.nanny.pre-spawn-environ``) and leaves them
there: the sweep's workers, and every process started after a sweep by the process that ran it
(an FMU host, a ``gsb`` command), computed with one thread, ``gsb run`` with every core.

:func:`one_blas_thread` runs a function with every BLAS library of the process limited to one
thread (threadpoolctl's controllers of the libraries; scikit-learn limits its BLAS with
threadpoolctl), and restores the previous limits when the outermost such call returns. The
structure, its static and dynamic solves and the modal analyses are decorated with it, and the
long loops (a run, an FMU's step) enter :data:`ONE_BLAS_THREAD` once, so that the calls inside
cost a counter. The matrices of this project are small: one thread costs nothing measurable,
and is faster on busy cores.

An FMU's process is another matter (:func:`limit_for_good`): FMI hosts call FMUs from several
threads at once (ecos steps them in its own threads), a limit set from a thread the host
created did not hold there (OpenBLAS 0.3 of scipy 1.17's wheels: the count read back stayed 2),
and a threaded OpenBLAS called from two threads at once corrupted its work (an LU factorisation
of the gear-shaft FMU came out singular or crashed the host, at random). Each FMU instance
therefore limits the process's BLAS to one thread for good, and an FMU's bootstrap sets
``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 before numpy loads, unless the host
chose them.
"""

from __future__ import annotations

import functools
import threading
import warnings

__all__ = ["ONE_BLAS_THREAD", "limit_for_good", "one_blas_thread"]


class _OneBlasThread:
    """A context (re-entrant, shared by the threads of a process): BLAS limited to one thread
    from the outermost entry to the last exit."""

    def __init__(self):
        self._lock = threading.Lock()
        self._depth = 0
        self._libraries = None  # threadpoolctl's controllers of the BLAS libraries
        self._restore = []  # (library, its thread count before the outermost entry)
        #: set by :func:`limit_for_good`: one thread from then on, nothing to set or restore
        self.for_good = False

    def _blas(self) -> list:
        """The BLAS libraries of the process (threadpoolctl's controllers, found once)."""
        if self._libraries is None:
            import numpy  # noqa: F401 - both BLAS libraries loaded before the controller looks
            import scipy.linalg  # noqa: F401
            from threadpoolctl import ThreadpoolController

            self._libraries = ThreadpoolController().select(user_api="blas").lib_controllers
            if not self._libraries:
                warnings.warn(
                    "threadpoolctl finds no BLAS library in this process, so the thread count "
                    "of numpy's and scipy's linear algebra cannot be set to 1: results may "
                    "differ in their last digits between processes with other thread counts; "
                    "set OPENBLAS_NUM_THREADS=1 (or MKL_NUM_THREADS=1) before starting Python",
                    RuntimeWarning, stacklevel=4)
        return self._libraries

    def _limit(self) -> None:
        """Each BLAS library to one thread, what it had kept for :meth:`_unlimit`. The
        libraries' own calls, not threadpoolctl's ``limit``: that one also reads every
        library's version and settings, at 13 us against 5 us for an FMU's doStep."""
        self._restore = []
        for library in self._blas():
            n = library.get_num_threads()
            if n != 1:
                library.set_num_threads(1)
                if n is not None:  # unknown (no such call in that build): left at one
                    self._restore.append((library, n))

    def _unlimit(self) -> None:
        for library, n in self._restore:
            library.set_num_threads(n)
        self._restore = []

    def __enter__(self):
        with self._lock:
            if self._depth == 0:
                self._limit()
            self._depth += 1
        return self

    def __exit__(self, *exc) -> bool:
        with self._lock:
            self._depth -= 1
            if self._depth == 0:
                self._unlimit()
        return False


#: ``with ONE_BLAS_THREAD:`` around a loop of decorated calls (module docstring)
ONE_BLAS_THREAD = _OneBlasThread()


def one_blas_thread(func):
    """Decorator: ``func`` runs inside :data:`ONE_BLAS_THREAD`."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        if ONE_BLAS_THREAD.for_good:  # (an FMU's process, on its hot path)
            return func(*args, **kwargs)
        with ONE_BLAS_THREAD:
            return func(*args, **kwargs)

    return wrapper


def limit_for_good() -> None:
    """Every BLAS library of the process to one thread, not restored (module docstring: an FMU
    instance's process). Called from the thread that creates the instance. An enclosing
    ``with ONE_BLAS_THREAD`` then restores nothing when it ends, and decorated calls no
    longer set and restore the limit."""
    with ONE_BLAS_THREAD._lock:
        for library in ONE_BLAS_THREAD._blas():
            if library.get_num_threads() != 1:
                library.set_num_threads(1)
        ONE_BLAS_THREAD._restore = []
        ONE_BLAS_THREAD.for_good = True
