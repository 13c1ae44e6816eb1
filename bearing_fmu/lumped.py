"""Lumped-spring bearing: constant isotropic stiffness, optional constant damping.

The crude model of the paper's Fig. 16: ``F = -k X - c Xdot`` [N], no film, no speed dependence:
Eq. (17) with F0 = 0, Kb = k I and Cb = c I (:class:`bearing_fmu.affine.AffineLaws`), evaluated
as the linear model's law is, so that the master's compiled steps take it too.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_fmu.affine import AffineLaws, affine_global
from bearing_fmu.base import (
    BearingData,
    BearingError,
    BearingModel,
    BearingResult,
    ModelOption,
)

__all__ = ["LumpedSpringBearing"]


class LumpedSpringBearing(BearingModel):
    """Isotropic spring (and dashpot) at the bearing node.

    Parameters
    ----------
    bearing : BearingData
        Kept for a uniform interface (the FMUs share one variable list); not used by the law.
    stiffness : float
        k [N/m], > 0 (default 1e8).
    damping : float
        c [N s/m], >= 0 (default 0: no damping).

    Examples
    --------
    >>> b = BearingData(0.07, 0.05, 150e-6, 0.0288)
    >>> LumpedSpringBearing(b, 1e8).evaluate(1e-6, 0.0, 0.0, 0.0, 325.0).force
    array([-100.,    0.])
    """

    name = "lumped"
    affine = True
    options = (ModelOption("lumped_stiffness", "stiffness", "stiffness",
                           "isotropic stiffness k of the lumped-spring model", minimum=0.0,
                           exclusive_minimum=True),
               ModelOption("lumped_damping", "damping", "damping",
                           "isotropic damping c of the lumped-spring model", minimum=0.0))

    def __init__(self, bearing: BearingData, stiffness: float = 1e8, damping: float = 0.0):
        super().__init__(bearing)
        if not math.isfinite(stiffness) or stiffness <= 0.0:
            raise BearingError(f"lumped stiffness = {stiffness!r} N/m: must be finite and > 0")
        if not math.isfinite(damping) or damping < 0.0:
            raise BearingError(f"lumped damping = {damping!r} N s/m: must be finite and >= 0")
        self.k = float(stiffness)
        self.c = float(damping)
        self.law = AffineLaws(np.zeros(2), self.k * np.eye(2), self.c * np.eye(2))

    def affine_law(self, omega) -> AffineLaws:
        """The law at any speed: ``F = -k X - c Xdot``."""
        return self.law

    def evaluate(self, x, y, xdot, ydot, omega) -> BearingResult:
        force = self.law.force(np.array([x, y, xdot, ydot], dtype=float))
        return BearingResult(force=force, stiffness=self.law.kb.copy(),
                             damping=self.law.cb.copy())

    def evaluate_global(self, q, state, omega, out) -> None:
        """:meth:`evaluate` in the frame of ``q`` in one compiled call (the arithmetic of the
        base class's frame conversions)."""
        affine_global(q, state, self.law.f0, self.law.kb, self.law.cb, out)
