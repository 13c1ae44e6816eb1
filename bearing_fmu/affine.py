"""Affine bearing laws: the linearised bearing force of Eq. (17)-(18).

``F(X, Xdot) = F0 - Kb X - Cb Xdot`` per bearing, in whatever frame the arrays are given
(local for a bearing model, global (s, t) for the structure and the master). The same type
serves three uses:

* the linear analysis (paper Sec. 3.3.1, Eq. 17-20): Kb and Cb of a film model frozen at the
  static position X0 (:class:`bearing_fmu.linear.LinearBearing`);
* the bearing terms of the structure's Newmark step (Eq. 14, 16): the tangent ``Kb + 2/dt Cb``
  and the force at the new state (:mod:`gear_fmu.structure`);
* the master's Newton on the coupled system: each bearing linearised at the last iterate
  (:mod:`orchestrator.coupling.master`), and the same arrays packed into the gear-shaft FMU's inputs
  (:func:`fmu_src.contract.pack_laws`).

Arrays have any leading shape (one bearing: ``(2,)``, ``(2, 2)``; four bearings: ``(4, 2)``,
``(4, 2, 2)``); a journal state is ``[x, y, xdot, ydot]`` along the last axis.

>>> import numpy as np
>>> law = AffineLaws.linearise(np.array([1e-5, 0.0, 0.0, 0.0]), np.array([-1e3, 0.0]),
...                            1e8 * np.eye(2), 1e5 * np.eye(2))
>>> law.force(np.array([2e-5, 0.0, 0.0, 1e-3]))
array([-2000.,  -100.])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from bearing_fmu.frames import law_to_global, state_to_local

__all__ = ["AffineLaws", "pairwise_sum"]


@dataclass
class AffineLaws:
    """``F = f0 - kb X - cb Xdot`` (Eq. 17 written about X = 0, Xdot = 0).

    Attributes
    ----------
    f0 : (..., 2) array
        Force at X = 0, Xdot = 0 [N].
    kb : (..., 2, 2) array
        Stiffness Kb = -dF/dX [N/m] (Eq. 18; row = force component).
    cb : (..., 2, 2) array
        Damping Cb = -dF/dXdot [N s/m] (Eq. 18).
    """

    f0: np.ndarray
    kb: np.ndarray
    cb: np.ndarray
    #: the journal states (..., 4) the law was linearised about and the force there (..., 2),
    #: when it was (:meth:`linearise`): what an FMU connection carries (:meth:`expansion`)
    states: np.ndarray | None = None
    force_at: np.ndarray | None = None

    @classmethod
    def linearise(cls, states, force, kb, cb) -> AffineLaws:
        """Eq. (17) about the journal states ``[x, y, xdot, ydot]`` (..., 4) at which the
        bearings gave ``force`` (..., 2), ``kb`` and ``cb`` (..., 2, 2) (Eq. 18)."""
        states = np.array(states, dtype=float)
        force = np.array(force, dtype=float)
        x = states[..., None, :2]
        v = states[..., None, 2:]
        f0 = force + (kb * x).sum(axis=-1) + (cb * v).sum(axis=-1)
        return cls(f0, np.array(kb, copy=True), np.array(cb, copy=True), states, force)

    def relinearise(self, states, force, kb, cb) -> tuple[float, AffineLaws]:
        """The master's test and update in one compiled call, for a set of bearings
        (``states`` (nb, 4), ``force`` (nb, 2), ``kb``, ``cb`` (nb, 2, 2), as the bearings gave
        them at ``states``): the relative mismatch ``||F - F_law|| / ||F||`` of this law
        (2-norms over the whole set; :class:`orchestrator.coupling.master.Master`) and the law
        :meth:`linearise` gives there (Eq. 17, the same arithmetic)."""
        states = np.ascontiguousarray(states, dtype=float)
        force = np.ascontiguousarray(force, dtype=float)
        mismatch, f0, kb, cb = _relinearise(
            states, force, np.ascontiguousarray(kb, dtype=float),
            np.ascontiguousarray(cb, dtype=float), self.f0, self.kb, self.cb)
        return mismatch, AffineLaws(f0, kb, cb, states.copy(), force.copy())

    def expansion(self):
        """``(states, force, kb, cb)``: the expansion point of the law and the bearing's output
        there, from which :meth:`linearise` rebuilds it exactly (a law given by ``f0`` alone
        is its expansion about X = 0, Xdot = 0)."""
        if self.states is None:
            zeros = np.zeros((*np.shape(self.f0)[:-1], 4))
            return zeros, np.array(self.f0, copy=True), self.kb, self.cb
        return self.states, self.force_at, self.kb, self.cb

    def blend(self, other: AffineLaws, weight: float) -> AffineLaws:
        """The law ``weight * other + (1 - weight) * self``, coefficient by coefficient (the
        master's relaxation, :mod:`orchestrator.coupling.master`); given by ``f0`` alone."""
        w, r = weight, 1.0 - weight
        return AffineLaws(w * other.f0 + r * self.f0, w * other.kb + r * self.kb,
                          w * other.cb + r * self.cb)

    def force(self, states) -> np.ndarray:
        """Force of the laws at journal states ``[x, y, xdot, ydot]`` (..., 4) [N]."""
        states = np.asarray(states)
        x = states[..., None, :2]
        v = states[..., None, 2:]
        return self.f0 - (self.kb * x).sum(axis=-1) - (self.cb * v).sum(axis=-1)


@njit(cache=True)
def _relinearise(states, force, kb, cb, f0_old, kb_old, cb_old):
    """:meth:`AffineLaws.relinearise` on (nb, ...) arrays: the sums of two products in the
    order of :meth:`AffineLaws.force` and :meth:`AffineLaws.linearise`; the squares of the
    two norms added in numpy's pairwise order (:func:`pairwise_sum`). Returns (mismatch, f0,
    copies of kb and cb)."""
    nb = states.shape[0]
    f0 = np.empty((nb, 2))
    d2 = np.empty(2 * nb)
    f2 = np.empty(2 * nb)
    for b in range(nb):
        x0 = states[b, 0]
        x1 = states[b, 1]
        v0 = states[b, 2]
        v1 = states[b, 3]
        for r in range(2):
            law = (f0_old[b, r] - (kb_old[b, r, 0] * x0 + kb_old[b, r, 1] * x1)
                   - (cb_old[b, r, 0] * v0 + cb_old[b, r, 1] * v1))
            f = force[b, r]
            d = f - law
            d2[2 * b + r] = d * d
            f2[2 * b + r] = f * f
            f0[b, r] = f + (kb[b, r, 0] * x0 + kb[b, r, 1] * x1) + (cb[b, r, 0] * v0
                                                                   + cb[b, r, 1] * v1)
    mismatch = math.sqrt(pairwise_sum(d2)) / max(math.sqrt(pairwise_sum(f2)), 1e-300)
    return mismatch, f0, kb.copy(), cb.copy()


@njit(cache=True)
def pairwise_sum(a):
    """The sum of a contiguous vector in numpy's pairwise order (``np.sum`` of numpy 2,
    ``pairwise_sum`` of its umath loops): left to right below 8 values; up to 128, eight
    running sums over the blocks of 8, added as ``((r0 + r1) + (r2 + r3)) + ((r4 + r5) +
    (r6 + r7))``, then the rest left to right; above, the halves (cut at a multiple of 8)
    summed so and added. Any length: the sums of the master and the structure over the
    bearings of any train."""
    n = a.size
    if n < 8:
        res = -0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r = a[:8].copy()
        i = 8
        while i < n - n % 8:
            for j in range(8):
                r[j] += a[i + j]
            i += 8
        res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        while i < n:
            res += a[i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return pairwise_sum(a[:half]) + pairwise_sum(a[half:])


@njit(cache=True)
def affine_global(q, s, f0, kb, cb, out):
    """One law ``F = f0 - kb X - cb Xdot`` given in a local frame (``local = q global``),
    evaluated at the global state ``s`` [s, t, sdot, tdot]; ``out`` (5, 2) receives the
    force, kb and cb in global components (:func:`bearing_fmu.frames.law_to_global`): the
    arithmetic of :meth:`AffineLaws.force` and of
    :meth:`bearing_fmu.base.BearingModel.evaluate_global`, in their order."""
    x, y, xd, yd = state_to_local(q, s)
    loc = np.empty((5, 2))
    for r in range(2):
        loc[0, r] = f0[r] - (kb[r, 0] * x + kb[r, 1] * y) - (cb[r, 0] * xd + cb[r, 1] * yd)
        for c in range(2):
            loc[1 + r, c] = kb[r, c]
            loc[3 + r, c] = cb[r, c]
    law_to_global(q, loc, out)


def affine_set_arguments(q, laws) -> tuple:
    """The arguments of :func:`affine_set_global` before the states and the output: the
    frames ``q`` (k, 2, 2) and the ``laws``' f0 (k, 2), kb and cb (k, 2, 2) stacked, each
    C-contiguous (no law: the types of a set of none)."""
    k = len(laws)
    return (np.ascontiguousarray(q, dtype=np.float64).reshape(k, 2, 2),
            np.array([law.f0 for law in laws], dtype=np.float64).reshape(k, 2),
            np.array([law.kb for law in laws], dtype=np.float64).reshape(k, 2, 2),
            np.array([law.cb for law in laws], dtype=np.float64).reshape(k, 2, 2))


@njit(cache=True)
def affine_set_global(q, f0, kb, cb, s, out):
    """:func:`affine_global` for a set of laws in one call, in their order: ``q`` (nb, 2, 2),
    ``f0`` (nb, 2), ``kb``, ``cb`` (nb, 2, 2) stacked, the global states ``s`` (nb, 4), the
    results into ``out`` (nb, 5, 2); the same arithmetic as one call per law. Returns
    ``(-1, 0)`` as ``bearing_fmu.hybrid._kernels.hybrid_set_global`` does when every bearing
    gave its law (an affine law always does)."""
    for b in range(s.shape[0]):
        affine_global(q[b], s[b], f0[b], kb[b], cb[b], out[b])
    return -1, 0
