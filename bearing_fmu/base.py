"""The one interface every journal-bearing model implements.

Frames and units (the contract shared by every bearing model and FMU)
---------------------------------------------------------------------
* Local frame (x, y) of the bearing, origin at the bearing centre O, journal centre O'.
  The journal rotates about +z at ``omega`` [rad/s] (counter-clockwise seen from +z,
  x towards y), Baguet & Jacquenot (2010) Fig. 3.
* State: journal-centre displacement ``x, y`` [m] and velocity ``xdot, ydot`` [m/s].
* Output: film force on the journal ``F = (Fx, Fy)`` [N], stiffness ``Kb = -dF/dX`` [N/m] and
  damping ``Cb = -dF/dXdot`` [N s/m] (2x2, row = force component, column = state component),
  paper Eq. (18).

Dimensionless core (paper Eq. 2-5 and Nomenclature)
---------------------------------------------------
``xbar = x/C``, ``xbar_dot = xdot/(C omega)``, ``Fbar = F / (6 mu omega R^2 (R/C)^2)``,
``xi = z/R``, ``lambda_ = L/D``.  Film models (hybrid, short, finite difference) implement
:meth:`FilmBearingModel.film_force` on these variables; the SI scaling lives here, once.
"""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from bearing_fmu.reynolds import force_scale, pressure_scale

__all__ = [
    "BearingData",
    "BearingError",
    "BearingModel",
    "BearingResult",
    "EccentricityError",
    "FilmBearingModel",
    "FilmForce",
    "ModelOption",
]


class BearingError(ValueError):
    """Invalid bearing input (geometry, fluid, state)."""


class EccentricityError(BearingError):
    """The journal touches or leaves the clearance circle (eccentricity ratio >= 1)."""


def _require_positive_finite(name: str, value: float, unit: str) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise BearingError(f"{name} = {value!r} {unit}: must be finite and > 0")
    return value


@dataclass(frozen=True)
class BearingData:
    """Geometry and lubricant of one plain journal bearing (paper Table 3).

    Parameters
    ----------
    diameter : float
        Bearing diameter D = 2R [m].
    length : float
        Bearing length L [m].
    clearance : float
        Radial clearance C [m].
    viscosity : float
        Dynamic viscosity mu [Pa s].

    Examples
    --------
    >>> b = BearingData(diameter=0.070, length=0.050, clearance=150e-6, viscosity=0.0288)
    >>> round(b.lambda_, 4)
    0.7143
    """

    diameter: float
    length: float
    clearance: float
    viscosity: float

    def __post_init__(self) -> None:
        _require_positive_finite("diameter", self.diameter, "m")
        _require_positive_finite("length", self.length, "m")
        _require_positive_finite("clearance", self.clearance, "m")
        _require_positive_finite("viscosity", self.viscosity, "Pa s")
        if self.clearance >= 0.5 * self.diameter:
            raise BearingError(
                f"clearance = {self.clearance!r} m must be smaller than the radius "
                f"{0.5 * self.diameter!r} m"
            )

    @property
    def radius(self) -> float:
        """Bearing radius R = D/2 [m]."""
        return 0.5 * self.diameter

    @property
    def lambda_(self) -> float:
        """Slenderness lambda = L/D [-] (half-length in units of R: xi in [-lambda, lambda])."""
        return self.length / self.diameter

    def force_scale(self, omega: float) -> float:
        """Force scale 6 mu omega R^2 (R/C)^2 [N] of Eq. (5) at speed omega [rad/s]."""
        return force_scale(self.viscosity, omega, self.radius, self.clearance)

    def pressure_scale(self, omega: float) -> float:
        """Pressure scale 6 mu omega (R/C)^2 [Pa] of Eq. (2) at speed omega [rad/s]."""
        return pressure_scale(self.viscosity, omega, self.radius, self.clearance)

    def sommerfeld(self, omega: float, load: float) -> float:
        """Sommerfeld number S = (R/C)^2 mu N / P, N = omega/2pi [rev/s], P = W/(L D) [Pa]."""
        n = omega / (2.0 * math.pi)
        p = load / (self.length * self.diameter)
        return (self.radius / self.clearance) ** 2 * self.viscosity * n / p


class FilmForce(NamedTuple):
    """Dimensionless film force and its derivatives (paper Eq. 5).

    ``force`` = (Fbar_x, Fbar_y); ``d_position[i, j] = dFbar_i / dxbar_j``;
    ``d_velocity[i, j] = dFbar_i / dxbar_dot_j``. Derivatives are None when not requested.
    (A named tuple: built on every call of the hot path.)
    """

    force: np.ndarray
    d_position: np.ndarray | None = None
    d_velocity: np.ndarray | None = None


@dataclass(frozen=True)
class BearingResult:
    """Film force [N] and its linearisation in SI units, local frame."""

    force: np.ndarray  # (2,) N
    stiffness: np.ndarray  # (2, 2) N/m, Kb = -dF/dX
    damping: np.ndarray  # (2, 2) N s/m, Cb = -dF/dXdot
    extra: dict = field(default_factory=dict)


def check_state(xbar: float, ybar: float, xbar_dot: float, ybar_dot: float) -> float:
    """Validate a dimensionless journal state and return its eccentricity ratio.

    Raises
    ------
    EccentricityError
        If the eccentricity ratio sqrt(xbar^2 + ybar^2) >= 1 (journal on or outside the
        clearance circle), with the value and the limit in the message.
    BearingError
        For non-finite components.
    """
    for name, v in (("xbar", xbar), ("ybar", ybar), ("xbar_dot", xbar_dot), ("ybar_dot", ybar_dot)):
        if not math.isfinite(v):
            raise BearingError(f"journal state {name} = {v!r} is not finite")
    eps = math.hypot(xbar, ybar)
    if eps >= 1.0:
        raise EccentricityError(
            f"eccentricity ratio {eps:.6g} (xbar = {xbar:.6g}, ybar = {ybar:.6g}) "
            f"must be < 1: the journal touches the bearing"
        )
    return eps


@dataclass(frozen=True)
class ModelOption:
    """One setting of a bearing model that a case file and an FMU parameter can carry.

    The case field is ``bearings.<key>`` and the bearing FMU parameter is ``<key>``; both are
    generated from these declarations (:mod:`fmu_src.case`, :mod:`fmu_src.contract`), so an
    option added to a model class reaches the case files, the FMUs and their documentation
    without further edits. The default is the constructor's.

    Attributes
    ----------
    key : str
        Name in the case file's ``[bearings]`` table and of the FMU parameter.
    argument : str
        Keyword of the model's constructor that receives the value.
    kind : str
        ``"count"`` (integer), ``"flag"`` or a dimension of :mod:`fmu_src.units`
        (``"stiffness"`` [N/m], ``"damping"`` [N s/m], ...); values are SI.
    doc : str
        One line for the schema and the FMU description.
    minimum, maximum : float or None
        Bounds (checked by the case loader and the FMU setters).
    exclusive_minimum : bool
        The minimum itself is excluded.
    """

    key: str
    argument: str
    kind: str
    doc: str
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False


class BearingModel(ABC):
    """A bearing law: journal state in the local frame -> force, Kb, Cb (SI).

    Subclasses: :class:`FilmBearingModel` (Reynolds-equation models) and the constant-
    coefficient laws (linearised 8-coefficient, lumped spring).

    Adding a model (the pattern of ``scipy.integrate.solve_ivp``'s methods): write a subclass
    in its own module with a unique :attr:`name`, declare its case/FMU settings in
    :attr:`options`, implement :meth:`evaluate` (or :meth:`FilmBearingModel.film_force`), and
    add one line to :data:`bearing_fmu.MODELS`. Its FMU (``Bearing<Name>``), its case fields
    and its command-line name follow from that;
    ``tests/bearing_fmu/test_bearing_models.py`` checks every registered model (finite force,
    Jacobians against central differences, a coupled step through its FMU).
    """

    #: key of the model in :data:`bearing_fmu.MODELS` and on the command line
    name: str = ""
    #: settings a case file or an FMU parameter can carry (:class:`~bearing_fmu.base.ModelOption`)
    options: tuple[ModelOption, ...] = ()
    #: True for a model whose law is affine in the journal state (Eq. 17) once initialised:
    #: :meth:`affine_law` then gives it, and the master's compiled steps evaluate it
    #: (:mod:`orchestrator.coupling.step`)
    affine: bool = False

    def __init__(self, bearing: BearingData) -> None:
        if not isinstance(bearing, BearingData):
            raise TypeError(f"bearing must be BearingData, got {type(bearing).__name__}")
        self.bearing = bearing

    @classmethod
    def from_parameters(cls, bearing: BearingData, **options) -> BearingModel:
        """The model of ``bearing`` with settings by option key (case field / FMU parameter).

        Declared :attr:`options` are renamed to their constructor keywords; any other keyword
        passes straight through to the constructor (e.g. ``tol`` of the hybrid model).

        Raises
        ------
        BearingError
            For a keyword the model does not take (the message lists the ones it does).
        """
        by_key = {o.key: o.argument for o in cls.options}
        kwargs = {by_key.get(k, k): v for k, v in options.items()}
        accepted = cls._keywords()
        unknown = sorted(k for k in options if by_key.get(k, k) not in accepted)
        if unknown:
            raise BearingError(
                f"{cls.name} bearing model: no option {', '.join(map(repr, unknown))}; it takes "
                f"{', '.join(sorted(set(by_key) | (accepted - set(by_key.values())))) or 'none'}")
        return cls(bearing, **kwargs)

    @classmethod
    def _keywords(cls) -> set[str]:
        """Keyword arguments of the constructor after ``bearing``."""
        params = list(inspect.signature(cls.__init__).parameters.values())[2:]
        return {p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}

    @classmethod
    def option_defaults(cls) -> dict:
        """``{option key: default}`` of :attr:`options` (the constructor's defaults)."""
        params = inspect.signature(cls.__init__).parameters
        return {o.key: params[o.argument].default for o in cls.options}

    @abstractmethod
    def evaluate(
        self, x: float, y: float, xdot: float, ydot: float, omega: float
    ) -> BearingResult:
        """Film force [N], Kb [N/m] and Cb [N s/m] at a journal state [m, m/s], speed [rad/s]."""

    def evaluate_global(self, q: np.ndarray, state: np.ndarray, omega: float,
                        out: np.ndarray) -> None:
        """:meth:`evaluate` at a journal state given in another frame, results in that frame.

        ``q`` (2, 2) turns its components into the model's local ones (``local = q global``,
        :class:`bearing_fmu.frames.LocalFrame`), ``state`` is [s, t, sdot, tdot] [m, m/s].
        Writes ``out`` (5, 2): row 0 the force [N], rows 1-2 Kb [N/m], rows 3-4 Cb [N s/m]
        (``F = q^T F_loc``, ``K = q^T K_loc q``). What the bearing sets and FMUs call on the
        hot path; a model may override it with one compiled call giving the same numbers.
        """
        loc = q @ np.reshape(state, (2, 2)).T
        r = self.evaluate(loc[0, 0], loc[1, 0], loc[0, 1], loc[1, 1], omega)
        qt = q.T
        out[0] = qt @ r.force
        out[1:3] = qt @ r.stiffness @ q
        out[3:5] = qt @ r.damping @ q

    def affine_law(self, omega: float):
        """The law at speed ``omega`` [rad/s] as Eq. (17) in the local frame
        (:class:`bearing_fmu.affine.AffineLaws`; :func:`bearing_fmu.affine.affine_global`
        evaluates it as :meth:`evaluate_global` does, bit for bit) when it is affine in the
        state now (:attr:`affine`), else None."""
        return None

    def end_initialization(self, x: float, y: float, omega: float) -> None:  # noqa: B027
        """Called once the static solution X0 is known, with the journal position there [m]
        and the speed [rad/s] (FMI: fmi2ExitInitializationMode). Nothing by default; the
        linearised model freezes its 8 coefficients here (paper Sec. 3.3)."""

    def get_state(self):
        """What :meth:`set_state` needs to restore the model's behaviour (copied arrays and
        numbers; None for a model without memory). Used for the FMU state (fmi2GetFMUstate)
        and the resume checkpoint; a model with memory needs its array layout in
        :mod:`fmu_src.states` to be saved to bytes."""
        return None

    def set_state(self, state) -> None:  # noqa: B027 - a model without memory: nothing
        """Restore a state of :meth:`get_state` (on a model built with the same parameters)."""


def check_omega(omega: float) -> float:
    """``omega`` [rad/s] as a float; BearingError naming the value unless finite and > 0."""
    omega = float(omega)
    if not math.isfinite(omega) or omega <= 0.0:
        raise BearingError(f"shaft speed omega = {omega!r} rad/s: must be finite and > 0")
    return omega


class FilmBearingSet:
    """Film bearings of one model evaluated in one compiled call, bit for bit the numbers of
    one ``evaluate_global`` per bearing (a subclass gives the model's kernel: the hybrid set,
    the short one). Holds the arrays every such call takes: the global-to-local rotations
    ``_q`` (nb, 2, 2), the speeds ``_omega`` [rad/s], the radial clearances ``_clearance`` [m]
    and the force scales of Eq. (5) at those speeds ``_fs`` [N].

    Parameters
    ----------
    models : sequence of FilmBearingModel
        Of the subclass's model (:meth:`fits`).
    q : (nb, 2, 2) array
        Global-to-local rotation of each bearing (:class:`bearing_fmu.frames.LocalFrame`).
    omegas : (nb,) array
        Shaft speed at each bearing [rad/s], > 0.
    """

    #: what :meth:`fits` asks of the models, for the error of a set that does not fit
    kind = "film bearings"

    def __init__(self, models, q, omegas):
        if not self.fits(models):
            raise ValueError(f"{type(self).__name__}: the models must be {self.kind}")
        self.models = list(models)
        self._q = np.ascontiguousarray(q, dtype=float)
        self._omega = np.array([check_omega(w) for w in omegas], dtype=float)
        self._clearance = np.array([m.bearing.clearance for m in self.models])
        self._fs = np.array([m.bearing.force_scale(w)
                             for m, w in zip(self.models, self._omega, strict=True)])

    @staticmethod
    def fits(models) -> bool:
        """Whether the models can share one call."""
        raise NotImplementedError

    def set_speeds(self, omegas) -> None:
        """The shaft speed at each bearing [rad/s] (> 0) from the next call on, and the force
        scales of Eq. (5) at them (a run-up: the arrays the compiled calls take, in place)."""
        self._omega[:] = [check_omega(w) for w in omegas]
        self._fs[:] = [m.bearing.force_scale(w) for m, w in zip(self.models, self._omega,
                                                                  strict=True)]

    def raise_status(self, b, status, states) -> None:
        """Raise the error of bearing ``b`` (0-based) whose call returned ``status`` at the
        global journal states ``states`` (nb, 4) (its model's ``raise_status``), with its
        index in ``bearing_index``."""
        try:
            self.models[b].raise_status(status, self._q[b], states[b], self._omega[b])
        except BearingError as exc:
            exc.bearing_index = int(b)
            raise


class FilmBearingModel(BearingModel):
    """A model that solves the dimensionless Reynolds problem (Eq. 2-4).

    Subclasses implement :meth:`film_force`; the SI scaling and the input checks are done
    here once for all of them.
    """

    @abstractmethod
    def film_force(
        self,
        xbar: float,
        ybar: float,
        xbar_dot: float = 0.0,
        ybar_dot: float = 0.0,
        jacobian: bool = True,
    ) -> FilmForce:
        """Dimensionless force (Eq. 5) and its derivatives at a dimensionless state (Eq. 3).

        The caller has validated the state (:func:`~bearing_fmu.base.check_state`).
        """

    def dimensionless(
        self,
        xbar: float,
        ybar: float,
        xbar_dot: float = 0.0,
        ybar_dot: float = 0.0,
        jacobian: bool = True,
    ) -> FilmForce:
        """Validated :meth:`film_force`."""
        check_state(xbar, ybar, xbar_dot, ybar_dot)
        return self.film_force(float(xbar), float(ybar), float(xbar_dot), float(ybar_dot), jacobian)

    def evaluate(
        self, x: float, y: float, xdot: float, ydot: float, omega: float
    ) -> BearingResult:
        omega = check_omega(omega)
        c = self.bearing.clearance
        ff = self.dimensionless(x / c, y / c, xdot / (c * omega), ydot / (c * omega), True)
        fs = self.bearing.force_scale(omega)
        return BearingResult(
            force=fs * ff.force,
            stiffness=-(fs / c) * ff.d_position,
            damping=-(fs / (c * omega)) * ff.d_velocity,
        )
