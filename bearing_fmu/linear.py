"""Linearised 8-coefficient bearing (paper Sec. 3.3.1, Eq. 17-18).

``F(X, Xdot) = F0 - Kb (X - X0) - Cb Xdot``, with Kb, Cb frozen at the static position X0.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.base import BearingModel, BearingResult, _check_omega

__all__ = ["LinearBearing"]


def _as_matrix(name: str, value) -> np.ndarray:
    m = np.array(value, dtype=float)
    if m.shape != (2, 2) or not np.all(np.isfinite(m)):
        raise ValueError(f"{name} must be a finite 2x2 matrix, got {value!r}")
    return m


class LinearBearing(BearingModel):
    """Eq. (17): force affine in the state, constant 8 coefficients.

    Parameters
    ----------
    bearing : BearingData
    position0 : (2,) array
        Static journal position X0 = (x0, y0) [m] (local frame).
    force0 : (2,) array
        Static film force F_b0 = F_b(X0) [N].
    stiffness, damping : (2, 2) arrays
        Kb = -dF/dX [N/m] and Cb = -dF/dXdot [N s/m] at X0 (Eq. 18).
    omega : float
        Shaft speed [rad/s] at which the coefficients hold; evaluating at another speed is an
        error (the coefficients depend on speed).

    Examples
    --------
    >>> from bearing_fmu.base import BearingData
    >>> b = BearingData(0.07, 0.05, 150e-6, 0.0288)
    >>> k, c = np.eye(2) * 1e8, np.eye(2) * 1e5
    >>> lin = LinearBearing(b, [1e-5, -5e-5], [0.0, 1000.0], k, c, 325.0)
    >>> lin.evaluate(1e-5, -5e-5, 0.0, 0.0, 325.0).force
    array([   0., 1000.])
    """

    name = "linear"

    def __init__(self, bearing, position0, force0, stiffness, damping, omega):
        super().__init__(bearing)
        self.position0 = np.array(position0, dtype=float).reshape(2)
        self.force0 = np.array(force0, dtype=float).reshape(2)
        self.stiffness = _as_matrix("stiffness", stiffness)
        self.damping = _as_matrix("damping", damping)
        self.omega = _check_omega(omega)

    @classmethod
    def linearise(cls, model: BearingModel, x0: float, y0: float, omega: float) -> LinearBearing:
        """8 coefficients of ``model`` at the static position (x0, y0) [m], speed omega [rad/s]."""
        r = model.evaluate(x0, y0, 0.0, 0.0, omega)
        return cls(model.bearing, (x0, y0), r.force, r.stiffness, r.damping, omega)

    def evaluate(self, x, y, xdot, ydot, omega) -> BearingResult:
        omega = _check_omega(omega)
        if not np.isclose(omega, self.omega, rtol=1e-12, atol=0.0):
            raise ValueError(
                f"linear bearing coefficients hold at omega = {self.omega} rad/s, "
                f"evaluated at omega = {omega} rad/s"
            )
        dx = np.array([x, y], dtype=float) - self.position0
        v = np.array([xdot, ydot], dtype=float)
        force = self.force0 - self.stiffness @ dx - self.damping @ v
        return BearingResult(
            force=force, stiffness=self.stiffness.copy(), damping=self.damping.copy()
        )
