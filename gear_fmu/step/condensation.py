"""Static condensation of the structure's constant matrices onto the nonlinear DOFs.

Within a Newmark step only the meshes (the six DOFs of every gear node) and the bearing laws
(u, v of every bearing node) change the tangent of Eq. (14); the rest,
``A = c0 M + c1 C + K_shaft`` (Eq. 12, 14), is constant at fixed dt. With the free DOFs
ordered ``[c; r]`` the r block is eliminated once per dt (:class:`Condensation`:
``W = A_rr^-1 A_rc``, Schur complement ``S0 = A_cc - A_cr W``), and each Newton/contact
iteration solves a dense nc x nc system (:func:`gauss_solve`; 20 x 20 in the paper's case: two
gear nodes, four bearings).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numba import njit

__all__ = ["Condensation", "CondensationSlots", "gauss_solve"]


class Condensation:
    """Static condensation of a constant matrix A (ordered [c; r]) onto c.

    A is symmetric positive definite without gyroscopic terms (Cholesky factors of A_rr);
    with them (``symmetric=False``: the skew ``2/dt Omega G`` of :mod:`gear_fmu.timoshenko`
    in ``c1 C``) A_rr is factored by LU and its two off-diagonal blocks are kept apart.

    Attributes
    ----------
    w : (n_r, nc) array
        ``A_rr^-1 A_rc``: the r DOFs follow c as ``X_r = A_rr^-1 b_r - W X_c``.
    s0 : (nc, nc) array
        Schur complement ``A_cc - A_cr W``.
    g : (nc + n_r, n_r) array
        ``(-A_cr A_rr^-1; A_rr^-1)`` (``-W^T`` on top when A is symmetric): applied to ``b_r``
        it gives the correction of the condensed right-hand side and ``A_rr^-1 b_r``.
    g_t, w_t : arrays
        ``g`` and ``w`` transposed, C-contiguous, as the compiled step's products take them
        (:func:`gear_fmu.step.assembly.matvec_t`).
    """

    def __init__(self, a: np.ndarray, nc: int, symmetric: bool = True):
        acc, acr, arr = a[:nc, :nc], a[:nc, nc:], a[nc:, nc:]
        eye = np.eye(arr.shape[0])
        if symmetric:
            arr_inv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(arr), eye)
            self.w = arr_inv @ acr.T  # A_rr^-1 A_rc
            left = self.w.T  # A_cr A_rr^-1
        else:
            arr_inv = scipy.linalg.lu_solve(scipy.linalg.lu_factor(arr), eye)
            self.w = arr_inv @ a[nc:, :nc]
            left = acr @ arr_inv
        self.s0 = acc - acr @ self.w
        # rows: (-A_cr A_rr^-1, A_rr^-1) applied to b_r gives (z correction, y)
        self.g = np.ascontiguousarray(np.vstack([-left, arr_inv]))
        self.g_t = np.ascontiguousarray(self.g.T)
        self.w_t = np.ascontiguousarray(self.w.T)


class CondensationSlots:
    """The condensations of the sub-step lengths of a run, stacked for a compiled loop over
    steps (:meth:`gear_fmu.structure.Structure.steps_plan`): slot k holds ``(g_t, g_const, s0,
    w_t)`` of one length h [s] as the structure's ``_dynamic(h)`` gives them (copies: the same
    numbers). At most ``CAPACITY`` lengths (the sub-steps of a step commensurate with the
    mesh periods recur: the paper's spur case has at most 128 at its 32 steps per period,
    its helical case 54, the two-stage reducer about 120); a full set starts again empty."""

    CAPACITY = 128

    def __init__(self):
        self._index: dict[float, int] = {}
        self._stacks: tuple | None = None
        self._n = 0
        #: counts the clearings (a slot number is valid within one generation only)
        self.generation = 0

    def clear(self) -> None:
        """Forget every slot (the condensations changed: damping, torque)."""
        self._index.clear()
        self._n = 0
        self.generation += 1

    def make_room(self, lengths, first: bool) -> bool:
        """Whether the slots can take sub-steps of ``lengths`` [s] besides the ones they hold;
        for the ``first`` step of a plan they are emptied if they cannot."""
        new = len({h for h in lengths if h not in self._index})
        if self._n + new <= self.CAPACITY:
            return True
        if first:
            self.clear()
            return new <= self.CAPACITY
        return False

    def slot(self, h: float, dynamic) -> int:
        """The slot of sub-step length ``h`` [s], filled from ``dynamic(h)`` -> ``(cond,
        g_const)`` the first time (after :meth:`make_room` said there is room)."""
        k = self._index.get(h)
        if k is None:
            cond, g_const = dynamic(h)
            parts = (cond.g_t, g_const, cond.s0, cond.w_t)
            if self._stacks is None or self._n == len(self._stacks[0]):
                size = min(self.CAPACITY, max(4, 2 * self._n))
                stacks = tuple(np.empty((size, *p.shape)) for p in parts)
                if self._stacks is not None:
                    for new, old in zip(stacks, self._stacks, strict=True):
                        new[:self._n] = old[:self._n]
                self._stacks = stacks
            for stack, part in zip(self._stacks, parts, strict=True):
                stack[self._n] = part
            k = self._index[h] = self._n
            self._n += 1
        return k

    def arrays(self) -> tuple:
        """``(g_t, g_const, s0, w_t)`` of every slot, stacked along the first axis (rows past
        the filled slots hold nothing: a slot number indexes them; no views, a compiled step
        takes them at every call)."""
        return self._stacks


@njit(cache=True)
def gauss_solve(s, rhs):
    """Solve ``s x = rhs`` in place by Gaussian elimination with partial pivoting (small dense
    systems; ``s`` and ``rhs`` are overwritten, ``rhs`` returns x). Returns (x, ok): ok is False
    for a zero pivot or a non-finite solution."""
    nc = rhs.size
    for k in range(nc):
        p = k
        big = abs(s[k, k])
        for i in range(k + 1, nc):
            if abs(s[i, k]) > big:
                big = abs(s[i, k])
                p = i
        if big == 0.0:
            return rhs, False
        if p != k:
            for j in range(nc):
                tmp = s[k, j]
                s[k, j] = s[p, j]
                s[p, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[p]
            rhs[p] = tmp
        piv = s[k, k]
        for i in range(k + 1, nc):
            f = s[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, nc):
                    s[i, j] -= f * s[k, j]
                rhs[i] -= f * rhs[k]
    for i in range(nc - 1, -1, -1):
        acc = rhs[i]
        for j in range(i + 1, nc):
            acc -= s[i, j] * rhs[j]
        rhs[i] = acc / s[i, i]
    ok = True
    for i in range(nc):
        if not np.isfinite(rhs[i]):
            ok = False
    return rhs, ok
