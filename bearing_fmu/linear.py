"""Linearised 8-coefficient bearing (paper Sec. 3.3.1, Eq. 17-18; Table 4 case 0).

``F(X, Xdot) = F0 - Kb (X - X0) - Cb Xdot``, with Kb, Cb of a film model frozen at the static
position X0 (:class:`bearing_fmu.affine.AffineLaws`).

* :class:`LinearBearing`: the frozen law itself (X0, F0, Kb, Cb, speed).
* :class:`LinearisedBearing`: the registered ``linear`` model. It runs its film model (the
  hybrid method) until :meth:`~bearing_fmu.base.BearingModel.end_initialization` gives it the
  static position, then freezes the 8 coefficients there; in the FMU that call is
  fmi2ExitInitializationMode, in-process the master's end of the static solution.
"""

from __future__ import annotations

import numpy as np

from bearing_fmu.affine import AffineLaws, affine_global
from bearing_fmu.base import BearingModel, BearingResult, check_omega
from bearing_fmu.hybrid.model import HybridBearing

__all__ = ["LinearBearing", "LinearisedBearing"]


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
    affine = True

    def __init__(self, bearing, position0, force0, stiffness, damping, omega):
        super().__init__(bearing)
        self.position0 = np.array(position0, dtype=float).reshape(2)
        self.force0 = np.array(force0, dtype=float).reshape(2)
        self.omega = check_omega(omega)
        self.law = AffineLaws.linearise(np.concatenate([self.position0, [0.0, 0.0]]),
                                        self.force0, _as_matrix("stiffness", stiffness),
                                        _as_matrix("damping", damping))

    @property
    def stiffness(self) -> np.ndarray:
        """Kb [N/m] (Eq. 18)."""
        return self.law.kb

    @property
    def damping(self) -> np.ndarray:
        """Cb [N s/m] (Eq. 18)."""
        return self.law.cb

    @classmethod
    def linearise(cls, model: BearingModel, x0: float, y0: float, omega: float) -> LinearBearing:
        """8 coefficients of ``model`` at the static position (x0, y0) [m], speed omega [rad/s].

        ``model`` is evaluated there twice: the second call starts from the first's solution,
        so that a solver ending with a first-order corrector (the hybrid model's Newton on t,
        whose Jacobians are then off by up to 1e-4) gives the Jacobians of a converged solve.
        """
        model.evaluate(x0, y0, 0.0, 0.0, omega)
        r = model.evaluate(x0, y0, 0.0, 0.0, omega)
        return cls(model.bearing, (x0, y0), r.force, r.stiffness, r.damping, omega)

    def check_speed(self, omega) -> float:
        """``omega`` [rad/s] if the coefficients hold at it, else the error naming both."""
        omega = check_omega(omega)
        if not abs(omega - self.omega) <= 1e-12 * abs(self.omega):
            raise ValueError(
                f"linear bearing coefficients hold at omega = {self.omega} rad/s, "
                f"evaluated at omega = {omega} rad/s"
            )
        return omega

    def affine_law(self, omega) -> AffineLaws:
        """The frozen law (:meth:`check_speed`: only at the speed it holds at)."""
        self.check_speed(omega)
        return self.law

    def evaluate(self, x, y, xdot, ydot, omega) -> BearingResult:
        self.check_speed(omega)
        force = self.law.force(np.array([x, y, xdot, ydot], dtype=float))
        return BearingResult(force=force, stiffness=self.law.kb.copy(),
                             damping=self.law.cb.copy())

    def evaluate_global(self, q, state, omega, out) -> None:
        """The law of Eq. (17) in the frame of ``q`` in one compiled call (the arithmetic
        of :meth:`evaluate` and the base class's frame conversions)."""
        self.check_speed(omega)
        law = self.law
        affine_global(q, state, law.f0, law.kb, law.cb, out)


class LinearisedBearing(BearingModel):
    """The registered ``linear`` model: a film model until X0 is known, then its linearisation
    (Eq. 17-18); with these bearings the structure's step solves the linear system of
    Eq. (19).

    Parameters
    ----------
    bearing : BearingData
    film : BearingModel, optional
        The model run during the static solution and linearised at X0 (default: the hybrid
        method with its defaults; :meth:`from_parameters` passes the hybrid options on).

    Attributes
    ----------
    frozen : LinearBearing or None
        The frozen law once :meth:`end_initialization` has been called.
    """

    name = "linear"
    options = HybridBearing.options
    affine = True

    def __init__(self, bearing, film: BearingModel | None = None):
        super().__init__(bearing)
        self.film = HybridBearing(bearing) if film is None else film
        self.frozen: LinearBearing | None = None

    @classmethod
    def from_parameters(cls, bearing, **options) -> LinearisedBearing:
        """The hybrid film model with ``options`` (its options), to be linearised at X0."""
        return cls(bearing, HybridBearing.from_parameters(bearing, **options))

    @classmethod
    def option_defaults(cls) -> dict:
        return HybridBearing.option_defaults()

    def end_initialization(self, x, y, omega) -> None:
        """Freeze Eq. (18) at the static position (x, y) [m], speed omega [rad/s]."""
        self.frozen = LinearBearing.linearise(self.film, x, y, omega)

    def affine_law(self, omega) -> AffineLaws | None:
        """The frozen law once :meth:`end_initialization` froze it, None before."""
        return None if self.frozen is None else self.frozen.affine_law(omega)

    def evaluate(self, x, y, xdot, ydot, omega) -> BearingResult:
        law = self.film if self.frozen is None else self.frozen
        return law.evaluate(x, y, xdot, ydot, omega)

    def evaluate_global(self, q, state, omega, out) -> None:
        law = self.film if self.frozen is None else self.frozen
        law.evaluate_global(q, state, omega, out)

    def get_state(self):
        """The film model's warm start and the frozen law (X0, F0, Kb, Cb, speed; None before
        the freeze)."""
        fz = self.frozen
        law = None if fz is None else [fz.position0.tolist(), fz.force0.tolist(),
                                       fz.stiffness.tolist(), fz.damping.tolist(), fz.omega]
        return self.film.get_state(), law

    def set_state(self, state) -> None:
        film, law = state
        self.film.set_state(film)
        if law is None:
            self.frozen = None
            return
        p0, f0, k, c, omega = law
        self.frozen = LinearBearing(self.bearing, p0, f0, np.array(k), np.array(c), omega)
