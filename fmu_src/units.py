"""The one unit table: case-file quantities, FMU unit definitions and results channels.

Every physical quantity of the package has a *dimension* (``"length"``, ``"stiffness"``, ...)
listed once in :data:`DIMENSIONS` with

* its SI unit symbol, used for FMU variables, results-file attributes and messages;
* its FMI 2.0 ``BaseUnit`` exponents (kg, m, s, rad; ``rad`` counts, as FMI 2.0 section 2.2.2
  says, so ``rad/s`` is ``rad="1" s="-1"``);
* the spellings a case file accepts, each with its factor to SI.

A case-file quantity is a number in the SI unit or a string ``"value unit"``; a field accepts
only units of its own dimension, so ``clearance = "150 N"`` is an error that names the field,
the unit and what was expected.

>>> parse_quantity("4 mm", "length", "gears.pinion.module")
0.004
>>> parse_quantity(20, "angle", "gears.pinion.pressure_angle")  # numbers are SI: rad
20.0
>>> round(parse_quantity("20 deg", "angle", "x"), 6)
0.349066
>>> DIMENSIONS["angular_speed"].base
{'rad': 1, 's': -1}
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

__all__ = ["DIMENSIONS", "Dimension", "UnitError", "describe", "parse_quantity",
           "parse_speed_profile", "symbol"]


class UnitError(ValueError):
    """A quantity with a wrong, unknown or missing unit."""


@dataclass(frozen=True)
class Dimension:
    """A physical dimension: SI symbol, FMI base-unit exponents, accepted spellings."""

    name: str
    symbol: str
    base: dict = field(default_factory=dict)
    aliases: dict = field(default_factory=dict)  # spelling -> factor to SI (symbol included)


_PI = math.pi
#: The unit table: dimension name -> :class:`Dimension`.
#:
#: :meta hide-value:
DIMENSIONS: dict[str, Dimension] = {d.name: d for d in (
    Dimension("length", "m", {"m": 1}, {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6,
                                        "cm": 1e-2}),
    Dimension("angle", "rad", {"rad": 1}, {"rad": 1.0, "deg": _PI / 180.0}),
    Dimension("mass", "kg", {"kg": 1}, {"kg": 1.0, "g": 1e-3}),
    Dimension("pressure", "Pa", {"kg": 1, "m": -1, "s": -2},
              {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}),
    Dimension("viscosity", "Pa.s", {"kg": 1, "m": -1, "s": -1},
              {"Pa.s": 1.0, "Pa s": 1.0, "mPa.s": 1e-3, "cP": 1e-3}),
    Dimension("angular_speed", "rad/s", {"rad": 1, "s": -1},
              {"rad/s": 1.0, "rpm": 2.0 * _PI / 60.0}),
    Dimension("torque", "N.m", {"kg": 1, "m": 2, "s": -2}, {"N.m": 1.0, "N m": 1.0, "Nm": 1.0}),
    Dimension("density", "kg/m^3", {"kg": 1, "m": -3}, {"kg/m^3": 1.0, "kg/m3": 1.0}),
    Dimension("force", "N", {"kg": 1, "m": 1, "s": -2}, {"N": 1.0, "kN": 1e3}),
    Dimension("stiffness", "N/m", {"kg": 1, "s": -2}, {"N/m": 1.0}),
    Dimension("damping", "N.s/m", {"kg": 1, "s": -1}, {"N.s/m": 1.0, "N s/m": 1.0}),
    Dimension("time", "s", {"s": 1}, {"s": 1.0, "ms": 1e-3}),
    Dimension("velocity", "m/s", {"m": 1, "s": -1}, {"m/s": 1.0}),
    Dimension("acceleration", "m/s^2", {"m": 1, "s": -2}, {"m/s^2": 1.0, "m/s2": 1.0}),
    Dimension("dimensionless", "1", {}, {"1": 1.0, "-": 1.0}),
    Dimension("inertia", "kg.m^2", {"kg": 1, "m": 2}, {"kg.m^2": 1.0, "kg m^2": 1.0,
                                                      "kg.m2": 1.0, "kg m2": 1.0}),
    Dimension("torsional_stiffness", "N.m/rad", {"kg": 1, "m": 2, "s": -2, "rad": -1},
              {"N.m/rad": 1.0, "N m/rad": 1.0, "Nm/rad": 1.0}),
    Dimension("torsional_damping", "N.m.s/rad", {"kg": 1, "m": 2, "s": -1, "rad": -1},
              {"N.m.s/rad": 1.0, "N m s/rad": 1.0, "Nms/rad": 1.0}),
    Dimension("frequency", "Hz", {"s": -1}, {"Hz": 1.0, "kHz": 1e3}),
    Dimension("rate", "1/s", {"s": -1}, {"1/s": 1.0}),
)}

#: accepted spelling -> (factor to SI, dimension)
_SPELLINGS: dict[str, tuple[float, str]] = {
    spelling: (factor, d.name) for d in DIMENSIONS.values()
    for spelling, factor in d.aliases.items()
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def symbol(dimension: str) -> str:
    """The SI unit symbol of a dimension (``"stiffness"`` -> ``"N/m"``)."""
    return DIMENSIONS[dimension].symbol


def describe(dimension: str) -> str:
    """A dimension as a noun phrase with its article, for messages: ``"angular_speed"`` ->
    ``"an angular speed"``, ``"dimensionless"`` -> ``"a dimensionless number"``.

    >>> describe("angular_speed"), describe("length"), describe("inertia")
    ('an angular speed', 'a length', 'an inertia')
    """
    words = "dimensionless number" if dimension == "dimensionless" else dimension.replace("_", " ")
    return f"{'an' if words[0] in 'aeiou' else 'a'} {words}"


def _form(dimension: str) -> str:
    """How a value of ``dimension`` is written, for messages: no number is suggested, since
    the one the user meant may be in any of the units (160 meant in mm is not '160 m').

    >>> _form("mass"), _form("dimensionless")
    ("a number and one of the units kg, g, e.g. '0.5 kg'", "a number, e.g. '0.5'")
    """
    if dimension == "dimensionless":
        return "a number, e.g. '0.5'"
    units = ", ".join(DIMENSIONS[dimension].aliases)
    return f"a number and one of the units {units}, e.g. '0.5 {symbol(dimension)}'"


def parse_quantity(value, dimension: str, field: str) -> float:
    """A case-file value as a float in SI units.

    Parameters
    ----------
    value : int, float or str
        A number (taken in the SI unit of ``dimension``) or ``"number unit"``.
    dimension : str
        Expected dimension (a key of :data:`DIMENSIONS`).
    field : str
        Dotted name of the field, for error messages.
    """
    si = symbol(dimension)
    expected = describe(dimension)
    if isinstance(value, bool):
        raise UnitError(f"{field}: expected {expected} (a number in {si} or 'number unit'), "
                        f"got {value!r}")
    if isinstance(value, (int, float)):
        out = float(value)
    elif isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise UnitError(f"{field}: cannot read {value!r} as {_form(dimension)}")
        number, unit = m.groups()
        unit = unit or si
        if unit not in _SPELLINGS:
            raise UnitError(f"{field}: unknown unit {unit!r} in {value!r}; {expected} takes one "
                            f"of the units {', '.join(DIMENSIONS[dimension].aliases)}")
        factor, dim = _SPELLINGS[unit]
        if dim != dimension:
            raise UnitError(f"{field}: {value!r} is {describe(dim)}, expected {expected}: "
                            f"{_form(dimension)}")
        out = float(number) * factor
    else:
        raise UnitError(f"{field}: expected {expected} (a number in {si} or 'number unit'), "
                        f"got {type(value).__name__} {value!r}")
    if not math.isfinite(out):
        raise UnitError(f"{field}: {value!r} is not finite")
    return out


#: the units of a window of the report (:func:`parse_window`): mesh periods of the fastest
#: mesh, a time, revolutions of a named shaft
WINDOW_UNITS = ("periods", "time", "revolutions")
_REVOLUTIONS = re.compile(r"^(?:revolutions?|revs?)\s+of\s+(?:the\s+)?(?:shaft\s+)?(\S+)$")


def parse_window(value, field: str = "simulation.window") -> tuple[float, str, str] | None:
    """The window of a run's report and figures as written in a case or on the command line:
    ``""`` (the default rule: :func:`orchestrator.analysis.metrics.report_window`) -> None;
    ``"26 periods"`` (mesh periods of the fastest mesh, the unit of ``mesh_periods``),
    ``"0.05 s"`` (any time unit), ``"2 revolutions of gear_shaft"`` -> ``(count, unit,
    shaft)``, ``unit`` one of :data:`WINDOW_UNITS`, ``count`` [-] or [s] > 0, ``shaft`` the
    name given ("" unless revolutions). :class:`UnitError` naming ``field`` otherwise.

    >>> parse_window("26 periods"), parse_window("50 ms"), parse_window("2 rev of gear_shaft")
    ((26.0, 'periods', ''), (0.05, 'time', ''), (2.0, 'revolutions', 'gear_shaft'))
    """
    forms = ("'26 periods' (mesh periods of the fastest mesh), '0.05 s' or '2 revolutions of "
             "<shaft>'")
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    m = _QUANTITY.match(value) if isinstance(value, str) else None
    if not m:
        raise UnitError(f"{field}: cannot read {value!r} as a window: write {forms}")
    number, rest = float(m.group(1)), m.group(2)
    if not (math.isfinite(number) and number > 0.0):
        raise UnitError(f"{field}: {value!r}: the window must be longer than 0")
    if rest in ("periods", "period", "mesh periods", "mesh period"):
        return number, "periods", ""
    rev = _REVOLUTIONS.match(rest)
    if rev:
        return number, "revolutions", rev.group(1)
    if rest in _SPELLINGS and _SPELLINGS[rest][1] == "time":
        return number * _SPELLINGS[rest][0], "time", ""
    raise UnitError(f"{field}: cannot read {value!r} as a window: write {forms}")


_RAMP = re.compile(r"^\s*ramp\s+to\s+(.+?)\s+in\s+(.+?)(?:\s+after\s+(.+?))?\s*$", re.IGNORECASE)
_TABLE = re.compile(r"^\s*table\s+(.*?)\s*$", re.IGNORECASE | re.DOTALL)


def parse_speed_profile(value, field: str = "drive.speed_profile") -> tuple | None:
    """The input speed's profile as written in a case or on the command line: ``""`` (a
    constant ``drive.speed``) -> None; ``"ramp to 400 rad/s in 2 s"`` (from ``drive.speed``
    at t = 0, linear, then constant), optionally ``"... after 0.5 s"`` (the ramp's start) ->
    ``("ramp", (final speed [rad/s], duration [s], start [s]))``; ``"table 0 s: 300 rad/s,
    1 s: 400 rad/s, 3 s: 350 rad/s"`` (linear between the points, the last speed after them;
    the first at 0 s) -> ``("table", ((t [s], speed [rad/s]), ...))``
    (:class:`gear_fmu.speed_profile.SpeedProfile`). :class:`UnitError` naming ``field``
    otherwise, a table whose times do not increase included.

    >>> parse_speed_profile("ramp to 3000 rpm in 1.5 s after 100 ms")
    ('ramp', (314.1592653589793, 1.5, 0.1))
    >>> parse_speed_profile("table 0 s: 300 rad/s, 0.5 s: 400 rad/s")
    ('table', ((0.0, 300.0), (0.5, 400.0)))
    """
    forms = ("'ramp to 400 rad/s in 2 s', 'ramp to 3000 rpm in 1.5 s after 0.1 s' or "
             "'table 0 s: 300 rad/s, 1 s: 400 rad/s'")
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    ramp = _RAMP.match(value) if isinstance(value, str) else None
    table = _TABLE.match(value) if isinstance(value, str) else None
    if ramp:
        speed = parse_quantity(ramp.group(1), "angular_speed", field)
        duration = parse_quantity(ramp.group(2), "time", field)
        start = parse_quantity(ramp.group(3), "time", field) if ramp.group(3) else 0.0
        if speed < 0.0:
            raise UnitError(f"{field}: {value!r}: the final speed {speed:g} rad/s must be >= 0")
        if duration <= 0.0:
            raise UnitError(f"{field}: {value!r}: the ramp's duration {duration:g} s must be "
                            f"> 0")
        if start < 0.0:
            raise UnitError(f"{field}: {value!r}: the ramp's start {start:g} s must be >= 0")
        return "ramp", (speed, duration, start)
    if not table:
        raise UnitError(f"{field}: cannot read {value!r} as a speed profile: write {forms}")
    points = []
    for item in table.group(1).split(","):
        parts = item.split(":")
        if len(parts) != 2:
            raise UnitError(f"{field}: cannot read {item.strip()!r} in {value!r} as a point "
                            f"'time: speed' (e.g. '1 s: 400 rad/s')")
        t = parse_quantity(parts[0].strip(), "time", field)
        w = parse_quantity(parts[1].strip(), "angular_speed", field)
        if w < 0.0:
            raise UnitError(f"{field}: {item.strip()!r}: the speed {w:g} rad/s must be >= 0")
        if points and not t > points[-1][0]:
            raise UnitError(f"{field}: {item.strip()!r} after {points[-1][0]:g} s: the "
                            f"times of a table increase")
        points.append((t, w))
    if points[0][0] != 0.0:
        raise UnitError(f"{field}: {value!r}: the table starts at {points[0][0]:g} s; its "
                        f"first point is at 0 s (the static solution's speed)")
    return "table", tuple(points)
