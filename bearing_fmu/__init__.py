"""Journal-bearing physics: Reynolds-equation film models and constant-coefficient laws.

See :mod:`bearing_fmu.base` for the interface and the frame/unit contract.
"""

from bearing_fmu.base import (
    BearingData,
    BearingError,
    BearingModel,
    BearingResult,
    EccentricityError,
    FilmBearingModel,
    FilmForce,
)

__all__ = [
    "BearingData",
    "BearingError",
    "BearingModel",
    "BearingResult",
    "EccentricityError",
    "FilmBearingModel",
    "FilmForce",
]
