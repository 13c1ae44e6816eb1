"""Journal-bearing physics: Reynolds-equation film models and constant-coefficient laws.

See :mod:`bearing_fmu.base` for the interface and the frame/unit contract. Models are chosen by
name from :data:`MODELS` (the way ``solve_ivp`` picks a method from a table).
"""

from importlib import import_module

from bearing_fmu.base import (
    BearingData,
    BearingError,
    BearingModel,
    BearingResult,
    EccentricityError,
    FilmBearingModel,
    FilmForce,
)

#: model name -> (module, class); film models solve the Reynolds equation (Eq. 2-5)
MODELS = {
    "hybrid": ("bearing_fmu.hybrid", "HybridBearing"),
    "short": ("bearing_fmu.short_bearing", "ShortBearing"),
    "fd": ("bearing_fmu.fd", "FiniteDifferenceBearing"),
    "linear": ("bearing_fmu.linear", "LinearBearing"),
    "lumped": ("bearing_fmu.lumped", "LumpedSpringBearing"),
}
FILM_MODELS = ("hybrid", "short", "fd")


def model_class(name: str) -> type[BearingModel]:
    """The bearing-model class registered under ``name`` in :data:`MODELS`."""
    try:
        module, cls = MODELS[name]
    except KeyError:
        raise ValueError(
            f"unknown bearing model {name!r}; available: {', '.join(MODELS)}"
        ) from None
    return getattr(import_module(module), cls)


__all__ = [
    "FILM_MODELS",
    "MODELS",
    "BearingData",
    "BearingError",
    "BearingModel",
    "BearingResult",
    "EccentricityError",
    "FilmBearingModel",
    "FilmForce",
    "model_class",
]
