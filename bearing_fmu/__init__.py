"""Journal-bearing physics: Reynolds-equation film models and constant-coefficient laws.

See :mod:`bearing_fmu.base` for the interface, the frame/unit contract and how to add a model;
:mod:`bearing_fmu.reynolds` for the equations every film model shares (Eq. 2-5). Models are
chosen by name from :data:`MODELS`, the one registry (the way ``solve_ivp`` picks a method):
the bearing FMUs, the case schema's ``bearings.model`` choices and the command line derive
from it.
"""

from importlib import import_module

from bearing_fmu import numba_cache

numba_cache.install()  # before any kernel is defined: numba's cache per version of the code

from bearing_fmu.base import (  # noqa: E402
    BearingData,
    BearingError,
    BearingModel,
    BearingResult,
    EccentricityError,
    FilmBearingModel,
    FilmForce,
    ModelOption,
)

#: model name -> "module:class"; film models solve the Reynolds equation (Eq. 2-5)
MODELS = {
    "hybrid": "bearing_fmu.hybrid.model:HybridBearing",
    "short": "bearing_fmu.short_bearing:ShortBearing",
    "fd": "bearing_fmu.fd.model:FiniteDifferenceBearing",
    "linear": "bearing_fmu.linear:LinearisedBearing",
    "lumped": "bearing_fmu.lumped:LumpedSpringBearing",
}


def model_class(name: str) -> type[BearingModel]:
    """The bearing-model class registered under ``name`` in :data:`MODELS`."""
    try:
        module, cls = MODELS[name].split(":")
    except KeyError:
        raise BearingError(
            f"unknown bearing model {name!r}; available: {', '.join(MODELS)}"
        ) from None
    return getattr(import_module(module), cls)


def is_film_model(name: str) -> bool:
    """True for the models that solve the Reynolds equation (their force has a scale)."""
    return issubclass(model_class(name), FilmBearingModel)


__all__ = [
    "MODELS",
    "BearingData",
    "BearingError",
    "BearingModel",
    "BearingResult",
    "EccentricityError",
    "FilmBearingModel",
    "FilmForce",
    "ModelOption",
    "is_film_model",
    "model_class",
]
