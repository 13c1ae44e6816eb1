"""Quantities in case files: a number in SI units, or a string ``"value unit"``.

Only the units a gear/bearing engineer writes are known; each maps to its SI factor and
dimension, and a field accepts only units of its own dimension, so ``clearance = "150 N"`` is
an error that names the field, the unit and what was expected.

>>> parse_quantity("4 mm", "length", "gear_pair.module")
0.004
>>> parse_quantity(20, "angle", "gear_pair.pressure_angle")  # numbers are SI: rad
20.0
>>> round(parse_quantity("20 deg", "angle", "x"), 6)
0.349066
"""

from __future__ import annotations

import math
import re

__all__ = ["UNITS", "UnitError", "parse_quantity"]


class UnitError(ValueError):
    """A quantity with a wrong, unknown or missing unit."""


#: unit -> (SI factor, dimension)
UNITS: dict[str, tuple[float, str]] = {
    "m": (1.0, "length"), "mm": (1e-3, "length"), "um": (1e-6, "length"),
    "µm": (1e-6, "length"), "cm": (1e-2, "length"),
    "rad": (1.0, "angle"), "deg": (math.pi / 180.0, "angle"),
    "kg": (1.0, "mass"), "g": (1e-3, "mass"),
    "Pa": (1.0, "pressure"), "kPa": (1e3, "pressure"), "MPa": (1e6, "pressure"),
    "GPa": (1e9, "pressure"),
    "Pa.s": (1.0, "viscosity"), "Pa s": (1.0, "viscosity"), "mPa.s": (1e-3, "viscosity"),
    "cP": (1e-3, "viscosity"),
    "rad/s": (1.0, "angular_speed"), "rpm": (2.0 * math.pi / 60.0, "angular_speed"),
    "N.m": (1.0, "torque"), "N m": (1.0, "torque"), "Nm": (1.0, "torque"),
    "kg/m^3": (1.0, "density"), "kg/m3": (1.0, "density"),
    "N": (1.0, "force"), "N/m": (1.0, "stiffness"), "N.s/m": (1.0, "damping"),
    "s": (1.0, "time"), "ms": (1e-3, "time"),
    "1": (1.0, "dimensionless"), "-": (1.0, "dimensionless"),
}

#: the SI unit a bare number is taken in, per dimension (for messages)
SI_UNIT = {"length": "m", "angle": "rad", "mass": "kg", "pressure": "Pa", "viscosity": "Pa.s",
           "angular_speed": "rad/s", "torque": "N.m", "density": "kg/m^3", "force": "N",
           "stiffness": "N/m", "damping": "N.s/m", "time": "s", "dimensionless": "1"}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def parse_quantity(value, dimension: str, field: str) -> float:
    """A case-file value as a float in SI units.

    Parameters
    ----------
    value : int, float or str
        A number (taken in the SI unit of ``dimension``) or ``"number unit"``.
    dimension : str
        Expected dimension (a key of :data:`SI_UNIT`).
    field : str
        Dotted name of the field, for error messages.
    """
    if isinstance(value, bool):
        raise UnitError(f"{field}: expected a {dimension} value, got {value!r}")
    if isinstance(value, (int, float)):
        out = float(value)
    elif isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise UnitError(f"{field}: cannot read {value!r} as 'number unit' "
                            f"(e.g. '4 {SI_UNIT[dimension]}')")
        number, unit = m.groups()
        unit = unit or SI_UNIT[dimension]
        if unit not in UNITS:
            raise UnitError(f"{field}: unknown unit {unit!r} in {value!r}; "
                            f"a {dimension} takes one of "
                            f"{', '.join(u for u, (_, d) in UNITS.items() if d == dimension)}")
        factor, dim = UNITS[unit]
        if dim != dimension:
            raise UnitError(f"{field}: {value!r} is a {dim}, expected a {dimension} "
                            f"(e.g. '{number} {SI_UNIT[dimension]}')")
        out = float(number) * factor
    else:
        raise UnitError(f"{field}: expected a {dimension} value, got {type(value).__name__} "
                        f"{value!r}")
    if not math.isfinite(out):
        raise UnitError(f"{field}: {value!r} is not finite")
    return out
