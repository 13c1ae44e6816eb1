"""Affine bearing laws: the linearised bearing force of Eq. (17)-(18).

``F(X, Xdot) = F0 - Kb X - Cb Xdot`` per bearing, in whatever frame the arrays are given
(local for a bearing model, global (s, t) for the structure and the master). The same type
serves three uses:

* the linear analysis (paper Sec. 3.3.1, Eq. 17-20): Kb and Cb of a film model frozen at the
  static position X0 (:class:`bearing_fmu.linear.LinearBearing`);
* the bearing terms of the structure's Newmark step (Eq. 14, 16): the tangent ``Kb + 2/dt Cb``
  and the force at the new state (:mod:`gear_fmu.structure`);
* the master's Newton on the coupled system: each bearing linearised at the last iterate
  (:mod:`orchestrator.master`), and the same arrays packed into the gear-shaft FMU's inputs
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

from dataclasses import dataclass

import numpy as np

__all__ = ["AffineLaws"]


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

    def expansion(self):
        """``(states, force, kb, cb)``: the expansion point of the law and the bearing's output
        there, from which :meth:`linearise` rebuilds it exactly (a law given by ``f0`` alone
        is its expansion about X = 0, Xdot = 0)."""
        if self.states is None:
            zeros = np.zeros((*np.shape(self.f0)[:-1], 4))
            return zeros, np.array(self.f0, copy=True), self.kb, self.cb
        return self.states, self.force_at, self.kb, self.cb

    def force(self, states) -> np.ndarray:
        """Force of the laws at journal states ``[x, y, xdot, ydot]`` (..., 4) [N]."""
        states = np.asarray(states)
        x = states[..., None, :2]
        v = states[..., None, 2:]
        return self.f0 - (self.kb * x).sum(axis=-1) - (self.cb * v).sum(axis=-1)
