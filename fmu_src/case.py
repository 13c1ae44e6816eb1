"""Case files (TOML): the schema, in one table, the loader that checks it and the writer.

Every field is listed once in :data:`FIELDS` with its dimension, shape, default and bounds; the
bearing-model settings (``bearings.nodes``, ...) are generated from the options the registered
models declare (:class:`bearing_fmu.base.ModelOption`). The loader converts quantities to SI
(:mod:`fmu_src.units`), rejects unknown sections and keys, and names the field in every error.
``docs/case-files.md`` is rendered from the same table.

A quantity is a number in SI units or a string ``"value unit"`` (``"4 mm"``, ``"20 deg"``).
The paper's cases ship with the package (``models``) and load by name
(:func:`load_case`, :func:`shipped_cases`), from any working directory.
"""

from __future__ import annotations

import difflib
import json
import math
import re
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from bearing_fmu import MODELS as _BEARING_TABLE
from bearing_fmu import model_class
from fmu_src.units import UnitError, parse_quantity, symbol
from gear_fmu.drivetrain import OUTPUT_ENDS, Drivetrain
from gear_fmu.mesh.geometry import GearGeometryError, GearPair, zero_backlash_centre_distance
from gear_fmu.modal.damping import BASES, DAMPING_KINDS, DampingModel

__all__ = ["BEARING_MODELS", "FIELDS", "Case", "CaseError", "Field", "check_override", "damping",
           "drivetrain", "gear_pair", "load_case", "model_option_fields", "parse_toml",
           "read_case_text", "schema_markdown", "shipped_case", "shipped_cases"]

BEARING_MODELS = tuple(_BEARING_TABLE)


class CaseError(ValueError):
    """A case file that cannot be run; the message names the field."""


@dataclass(frozen=True)
class Field:
    """One entry of the schema.

    ``kind`` is a dimension of :data:`fmu_src.units.DIMENSIONS`, or ``"count"`` (positive
    integer), ``"text"``, ``"choice"`` or ``"flag"``. ``shape`` is None for a scalar or the
    length of a list (a scalar is broadcast to the list).
    """

    key: str
    kind: str
    doc: str
    shape: int | None = None
    default: Any = None
    required: bool = True
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple = ()


def _f(key, kind, doc, **kw):
    if "default" in kw and "required" not in kw:
        kw["required"] = False
    return Field(key, kind, doc, **kw)


_POS = dict(minimum=0.0, exclusive_minimum=True)

#: The schema: every field of a case file, once, in the order of ``docs/case-files.md``.
#:
#: :meta hide-value:
FIELDS: tuple[Field, ...] = (
    _f("case.name", "text", "identifier of the case (results are named after it)"),
    _f("case.description", "text", "free text", default=""),
    # gear pair, paper Table 1 (coefficients of the wheels: Table 1's 1.4 / 1.0 are the rack
    # cutter's, so each wheel has addendum 1.0 m and dedendum 1.4 m)
    _f("gear_pair.teeth", "count", "numbers of teeth [pinion, gear]", shape=2, minimum=5),
    _f("gear_pair.module", "length", "normal module m_n", **_POS),
    _f("gear_pair.pressure_angle", "angle", "normal pressure angle alpha_n", **_POS,
       maximum=0.7),
    _f("gear_pair.helix_angle", "angle", "helix angle beta (0 = spur)", default=0.0,
       minimum=0.0, maximum=0.7),
    _f("gear_pair.profile_shift", "dimensionless", "profile shift coefficients [x1, x2]",
       shape=2, default=[0.0, 0.0], minimum=-1.0, maximum=1.0),
    _f("gear_pair.addendum_coefficient", "dimensionless", "addendum of the wheels / m_n",
       default=1.0, **_POS),
    _f("gear_pair.dedendum_coefficient", "dimensionless", "dedendum of the wheels / m_n",
       default=1.25, **_POS),
    _f("gear_pair.face_width", "length", "face widths [pinion, gear]", shape=2, **_POS),
    _f("gear_pair.centre_distance", "length", "operating centre distance", **_POS),
    _f("gear_pair.mass", "mass", "gear body masses [pinion, gear] (Table 1)", shape=2, **_POS),
    _f("gear_pair.polar_inertia", "inertia", "polar inertias of the gear bodies [pinion, gear] "
       "(0: those of a steel annulus of the body's mass, gear_fmu.system)", shape=2,
       default=[0.0, 0.0], minimum=0.0),
    _f("gear_pair.diametral_inertia", "inertia", "diametral inertias of the gear bodies "
       "[pinion, gear] (0: derived as the polar ones)", shape=2, default=[0.0, 0.0],
       minimum=0.0),
    # shafts, Table 2
    _f("shafts.outer_diameter", "length", "outer diameters [pinion shaft, gear shaft]",
       shape=2, **_POS),
    _f("shafts.inner_diameter", "length", "bore diameters [pinion shaft, gear shaft]",
       shape=2, minimum=0.0),
    _f("shafts.length", "length", "length of both shafts (bearing to bearing)", **_POS),
    _f("shafts.young_modulus", "pressure", "Young's modulus E", **_POS),
    _f("shafts.poisson_ratio", "dimensionless", "Poisson's ratio nu", minimum=0.0,
       maximum=0.5),
    _f("shafts.density", "density", "density rho", **_POS),
    _f("shafts.elements", "count", "Timoshenko elements per shaft (even)", default=8,
       minimum=2),
    # drivetrain in torsion (not in the paper; defaults: input end free, output end clamped)
    _f("drivetrain.motor_inertia", "inertia", "motor inertia on the input end of the pinion "
       "shaft (0: no motor)", default=0.0, minimum=0.0),
    _f("drivetrain.motor_coupling_stiffness", "torsional_stiffness", "stiffness of a "
       "coupling between the motor and the input end (0: motor attached rigidly)", default=0.0,
       minimum=0.0),
    _f("drivetrain.motor_coupling_damping", "torsional_damping", "viscous damping of the "
       "motor coupling", default=0.0, minimum=0.0),
    _f("drivetrain.output_end", "choice", "torsion at the gear shaft's output end: clamped "
       "(a load of infinite inertia) or load (the load inertia, the resisting torque "
       "T z2/z1 acting on it)", default="clamped", choices=OUTPUT_ENDS),
    _f("drivetrain.load_inertia", "inertia", "load inertia on the output end (output_end = "
       "load)", default=0.0, minimum=0.0),
    _f("drivetrain.load_coupling_stiffness", "torsional_stiffness", "stiffness of a coupling "
       "between the output end and the load (0: load attached rigidly)", default=0.0,
       minimum=0.0),
    _f("drivetrain.load_coupling_damping", "torsional_damping", "viscous damping of the load "
       "coupling", default=0.0, minimum=0.0),
    # bearings, Table 3: order 1, 2 (pinion shaft), 3, 4 (gear shaft)
    _f("bearings.model", "choice", "bearing model (the FMU BearingHybrid, ... by that name)",
       default="hybrid", choices=BEARING_MODELS),
    _f("bearings.diameter", "length", "bearing diameters D [1, 2, 3, 4]", shape=4, **_POS),
    _f("bearings.length", "length", "bearing lengths L [1, 2, 3, 4]", shape=4, **_POS),
    _f("bearings.clearance", "length", "radial clearances C [1, 2, 3, 4]", shape=4, **_POS),
    _f("bearings.viscosity", "viscosity", "lubricant dynamic viscosity mu", shape=4, **_POS),
    # operating point, Sec. 4.1
    _f("operation.speed", "angular_speed", "pinion (input) speed omega", **_POS),
    _f("operation.torque", "torque", "input torque T on the pinion shaft (> 0: the teeth "
       "stay in contact only under load)", **_POS),
    _f("operation.unbalance", "length", "unbalance eccentricity e_mu [pinion shaft, gear "
       "shaft] (Eq. 10)", shape=2, default=[0.0, 0.0], minimum=0.0),
    _f("operation.gravity", "flag", "include gravity (along -t)", default=False),
    # numerics, Sec. 4
    _f("simulation.damping_ratio", "dimensionless", "damping ratio zeta of the modal "
       "damping, or of the Rayleigh damping at rayleigh_frequencies", default=0.03,
       minimum=0.0, maximum=0.99),
    _f("simulation.damping_model", "choice", "structural damping: modal (zeta on every mode "
       "of the damping_basis) or rayleigh (alpha M + beta K, gear_fmu.modal.damping)",
       default="modal", choices=DAMPING_KINDS),
    _f("simulation.damping_basis", "choice", "modes of the modal damping: bearings (shafts, "
       "mean mesh and the bearings' static film stiffness) or structure (shafts and mean mesh)",
       default="bearings", choices=BASES),
    _f("simulation.rayleigh_frequencies", "frequency", "[f1, f2] at which the Rayleigh "
       "damping has the ratio damping_ratio (0, 0: use rayleigh_alpha, rayleigh_beta)",
       shape=2, default=[0.0, 0.0], minimum=0.0),
    _f("simulation.rayleigh_alpha", "rate", "mass coefficient alpha of the Rayleigh damping",
       default=0.0, minimum=0.0),
    _f("simulation.rayleigh_beta", "time", "stiffness coefficient beta of the Rayleigh "
       "damping", default=0.0, minimum=0.0),
    _f("simulation.mesh_damping_ratio", "dimensionless", "mesh damping as the ratio of the "
       "two-inertia mesh mode (0: none)", default=0.0, minimum=0.0, maximum=0.99),
    _f("simulation.mesh_damping", "damping", "mesh damping coefficient along the line of "
       "action (0: none; exclusive with mesh_damping_ratio)", default=0.0, minimum=0.0),
    _f("simulation.consistent_start", "flag", "start the transient from the acceleration of "
       "the unbalance at t = 0 instead of zero (gear_fmu.structure)", default=True),
    _f("simulation.locate_contact", "flag", "cut steps at the angles where contact lines "
       "enter or leave the path of contact, so that Newmark keeps order 2 "
       "(gear_fmu.structure)", default=True),
    _f("simulation.steps_per_mesh_period", "count", "time steps per mesh period",
       default=32, minimum=4),
    _f("simulation.mesh_periods", "count", "mesh periods simulated", default=2048, minimum=1),
    _f("simulation.tolerance", "dimensionless", "convergence limit l of the coupled Newton",
       default=1e-5, **_POS, maximum=0.1),
    _f("simulation.max_iterations", "count", "coupled iterations per step before failing",
       default=30, minimum=1),
)



def model_option_fields() -> tuple[Field, ...]:
    """``bearings.<key>`` fields for the options of every registered bearing model.

    An option declared by several models (``nodes``: hybrid, fd, linear) is one field; its
    bounds are the widest of the declarations (the chosen model's own bounds are checked after
    loading), its default the constructors' (which must agree).
    """
    merged: dict[str, list] = {}
    for name in BEARING_MODELS:
        cls = model_class(name)
        defaults = cls.option_defaults()
        for opt in cls.options:
            merged.setdefault(opt.key, []).append((name, opt, defaults[opt.key]))
    out = []
    for key, decl in merged.items():
        _, opt, default = decl[0]
        if any(d != default or o.kind != opt.kind for _, o, d in decl):
            raise RuntimeError(f"bearing option {key!r} is declared with different kinds or "
                               f"defaults by {', '.join(n for n, _, _ in decl)}")
        mins = [o.minimum for _, o, _ in decl]
        maxs = [o.maximum for _, o, _ in decl]
        models = ", ".join(n for n, _, _ in decl)
        out.append(_f(f"bearings.{key}", opt.kind, f"{opt.doc} [models: {models}]",
                      default=default,
                      minimum=None if None in mins else min(mins),
                      maximum=None if None in maxs else max(maxs),
                      exclusive_minimum=all(o.exclusive_minimum for _, o, _ in decl)))
    return tuple(out)


_at = next(i for i, f in enumerate(FIELDS) if f.key == "operation.speed")
FIELDS = FIELDS[:_at] + model_option_fields() + FIELDS[_at:]
_BY_KEY = {f.key: f for f in FIELDS}
_SECTIONS = {f.key.split(".")[0] for f in FIELDS}


@dataclass(frozen=True)
class Case:
    """A checked case: ``values[key]`` in SI units, keyed as in :data:`FIELDS`."""

    values: dict
    source: str

    def __getitem__(self, key: str):
        return self.values[key]

    def with_overrides(self, overrides: dict) -> Case:
        """A copy with some fields replaced (values as in a case file), checked again."""
        raw = dict(self.values)
        for key, value in overrides.items():
            raw[key] = check_override(key, value)
        _check_consistency(raw, _overridden(self.source, overrides))
        return Case(raw, self.source)

    @property
    def name(self) -> str:
        """The case's name (``case.name``)."""
        return self.values["case.name"]

    def to_toml(self, header: bool = True) -> str:
        """The case as a case file (SI numbers): reloads to the same values, bit for bit.
        ``header=False``: without the comment naming the source file (the case's content
        alone, e.g. to hash it)."""
        sections: dict[str, list[str]] = {}
        for key, value in self.values.items():
            if value is None:
                continue
            section, name = key.split(".")
            sections.setdefault(section, []).append(f"{name} = {_toml_value(value)}")
        parts = [f"# written by fmu_src.case from {self.source} (SI units)"] if header else []
        for section, lines in sections.items():
            parts.append(f"\n[{section}]")
            parts.extend(lines)
        return "\n".join(parts) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write the non-finite value {value!r} to a case file")
        return repr(value)  # shortest round-trip form: the case reloads bit for bit
    if isinstance(value, str):
        return json.dumps(value)  # a valid TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to a case file")


def _scalar(field: Field, value, name: str):
    kind = field.kind
    if kind == "text":
        if not isinstance(value, str):
            raise CaseError(f"{name}: expected text, got {value!r}")
        return value
    if kind == "choice":
        if value not in field.choices:
            raise CaseError(f"{name}: {value!r} is not one of {', '.join(field.choices)}")
        return value
    if kind == "flag":
        if not isinstance(value, bool):
            raise CaseError(f"{name}: expected true or false, got {value!r}")
        return value
    if kind == "count":
        if isinstance(value, bool) or not isinstance(value, int):
            raise CaseError(f"{name}: expected an integer, got {value!r}")
        out = value
    else:
        try:
            out = parse_quantity(value, kind, name)
        except UnitError as exc:
            raise CaseError(str(exc)) from None
    unit = "" if kind == "count" else f" {symbol(kind)}"
    violated = bound_violation(out, field.minimum, field.maximum, field.exclusive_minimum)
    if violated:
        raise CaseError(f"{name} = {value!r}: must be {violated[0]} {violated[1]}{unit}")
    return out


def bound_violation(value, minimum=None, maximum=None, exclusive_minimum=False):
    """The bound ``value`` breaks as ``(relation, limit)`` (``(">", 0.0)``, ``(">=", 5)``,
    ``("<=", 0.7)``), or None: the one check behind case fields, model options and FMU
    variables."""
    if minimum is not None and (value < minimum or (exclusive_minimum and value == minimum)):
        return (">" if exclusive_minimum else ">="), minimum
    if maximum is not None and value > maximum:
        return "<=", maximum
    return None


def _convert(field: Field, value):
    if field.shape is None:
        if isinstance(value, list):
            raise CaseError(f"{field.key}: expected one value, got a list")
        return _scalar(field, value, field.key)
    if not isinstance(value, list):
        value = [value] * field.shape
    if len(value) != field.shape:
        raise CaseError(f"{field.key}: expected {field.shape} values, got {len(value)}")
    return [_scalar(field, v, f"{field.key}[{i}]") for i, v in enumerate(value)]


def _unknown_key(key: str) -> str | None:
    """Why ``key`` is not a case field (with the closest field when one is close, as a typo's
    correction), or None for a field."""
    if key in _BY_KEY:
        return None
    parts = key.split(".")
    if len(parts) != 2 or not all(parts):
        same_name = [f.key for f in FIELDS if f.key.split(".")[1] == key]
        return (f"{key!r} is not section.key (e.g. operation.speed)"
                + (f"; did you mean {' or '.join(same_name)}?" if same_name else ""))
    section = parts[0]
    close = difflib.get_close_matches(key, _BY_KEY, n=1, cutoff=0.75)
    hint = f"; did you mean {close[0]}?" if close else ""
    if section not in _SECTIONS:
        return (f"unknown section [{section}] in {key}{hint} (sections: "
                f"{', '.join(sorted(_SECTIONS))})")
    known = [f.key.split(".")[1] for f in FIELDS if f.key.startswith(section + ".")]
    return f"unknown field {key}{hint} ([{section}] takes {', '.join(known)})"


def check_override(key: str, value):
    """One override (``"section.key"``, a value as in a case file) on its own: the value in SI
    units, or :class:`CaseError` naming the key (a typo gets the closest field) and the value,
    never a case file (the override is not in one)."""
    why = _unknown_key(str(key))
    if why:
        raise CaseError(why)
    return _convert(_BY_KEY[key], value)


def _overridden(source: str, overrides: dict) -> str:
    """The source of a case in messages once ``overrides`` replaced some of its fields: a
    value the file does not hold is not blamed on the file alone."""
    if not overrides:
        return source
    return f"{source} with {', '.join(map(str, overrides))} overridden"


def parse_case(data: dict, source: str = "<case>") -> Case:
    """Check a parsed TOML document against :data:`FIELDS`."""
    for section, content in data.items():
        if section not in _SECTIONS:
            close = difflib.get_close_matches(section, _SECTIONS, n=1, cutoff=0.75)
            raise CaseError(f"{source}: unknown section [{section}]"
                            + (f"; did you mean [{close[0]}]?" if close else "")
                            + f" (sections: {', '.join(sorted(_SECTIONS))})")
        if not isinstance(content, dict):
            raise CaseError(f"{source}: [{section}] must be a table")
        for key in content:
            why = _unknown_key(f"{section}.{key}")
            if why:
                raise CaseError(f"{source}: {why}")
    values = {}
    for field in FIELDS:
        section, key = field.key.split(".")
        if key in data.get(section, {}):
            values[field.key] = _convert(field, data[section][key])
        elif field.required:
            raise CaseError(f"{source}: missing field {field.key} ({field.doc})")
        else:
            values[field.key] = field.default
    _check_consistency(values, source)
    return Case(values, source)


def _check_consistency(v: dict, source: str) -> None:
    for i in range(2):
        if v["shafts.inner_diameter"][i] >= v["shafts.outer_diameter"][i]:
            raise CaseError(f"{source}: shafts.inner_diameter[{i}] = "
                            f"{v['shafts.inner_diameter'][i]} m must be smaller than "
                            f"shafts.outer_diameter[{i}] = {v['shafts.outer_diameter'][i]} m")
    for i in range(4):
        if v["bearings.clearance"][i] >= 0.5 * v["bearings.diameter"][i]:
            raise CaseError(f"{source}: bearings.clearance[{i}] must be smaller than the "
                            f"bearing radius")
    _check_physics(v, source)
    if v["shafts.elements"] % 2:
        raise CaseError(f"{source}: shafts.elements = {v['shafts.elements']} must be even "
                        f"(the gear sits at mid-span)")
    # the chosen bearing model's own bounds on its options
    for opt in model_class(v["bearings.model"]).options:
        value, key = v[f"bearings.{opt.key}"], f"bearings.{opt.key}"
        unit = "" if opt.kind == "count" else f" {symbol(opt.kind)}"
        violated = bound_violation(value, opt.minimum, opt.maximum, opt.exclusive_minimum)
        if violated:
            raise CaseError(f"{source}: {key} = {value!r}: the {v['bearings.model']} model "
                            f"needs {violated[0]} {violated[1]}{unit}")


def _check_physics(v: dict, source: str) -> None:
    """The gear geometry, the drivetrain and the damping model, checked by their classes; the
    messages name the case fields (:func:`gear_pair`, :func:`drivetrain`, :func:`damping`)."""
    try:
        gear_pair(v)
    except GearGeometryError as exc:
        raise CaseError(f"{source}: {_geometry_message(v, exc)}") from None
    try:
        drivetrain(v)
        damping(v)
    except ValueError as exc:
        raise CaseError(f"{source}: {exc}") from None


# --- the objects the checks build: fmu_src.description builds the system with these same
# functions (it re-exports them), so that a case that loads is a case that builds.
def gear_pair(case) -> GearPair:
    """Table 1 fields -> :class:`gear_fmu.mesh.geometry.GearPair` (checked geometry; a Case or its
    values)."""
    return GearPair(
        teeth=tuple(case["gear_pair.teeth"]),
        module=case["gear_pair.module"],
        pressure_angle=case["gear_pair.pressure_angle"],
        centre_distance=case["gear_pair.centre_distance"],
        face_width=tuple(case["gear_pair.face_width"]),
        helix_angle=case["gear_pair.helix_angle"],
        profile_shift=tuple(case["gear_pair.profile_shift"]),
        addendum_coefficient=case["gear_pair.addendum_coefficient"],
        dedendum_coefficient=case["gear_pair.dedendum_coefficient"],
        young=case["shafts.young_modulus"],
        poisson=case["shafts.poisson_ratio"],
    )


def drivetrain(case) -> Drivetrain:
    """``drivetrain.*`` fields -> :class:`gear_fmu.drivetrain.Drivetrain` (a Case or its
    values; one field per attribute, same name); its errors name the fields."""
    return Drivetrain(**{f.name: case[f"drivetrain.{f.name}"] for f in fields(Drivetrain)})


def damping(case) -> DampingModel:
    """``simulation.damping_*``, ``rayleigh_*``, ``mesh_damping*`` fields ->
    :class:`gear_fmu.modal.damping.DampingModel` (a Case or its values)."""
    try:
        return DampingModel(
            kind=case["simulation.damping_model"], ratio=case["simulation.damping_ratio"],
            basis=case["simulation.damping_basis"],
            rayleigh_frequencies=tuple(case["simulation.rayleigh_frequencies"]),
            rayleigh_alpha=case["simulation.rayleigh_alpha"],
            rayleigh_beta=case["simulation.rayleigh_beta"],
            mesh_ratio=case["simulation.mesh_damping_ratio"],
            mesh_coefficient=case["simulation.mesh_damping"])
    except ValueError as exc:
        raise ValueError(f"simulation damping fields: {exc}") from None


def _geometry_message(v: dict, exc: Exception) -> str:
    """A gear-geometry error in the case's terms: the [gear_pair] fields that set the mesh,
    and the centre distance at which the profile shifts would mesh without backlash."""
    a = v["gear_pair.centre_distance"]
    shifts = list(v["gear_pair.profile_shift"])
    try:
        a0 = zero_backlash_centre_distance(v["gear_pair.teeth"], v["gear_pair.module"],
                                           v["gear_pair.pressure_angle"],
                                           v["gear_pair.helix_angle"], shifts)
    except (ValueError, ZeroDivisionError):
        a0 = math.nan
    hint = ""
    if math.isfinite(a0) and abs(a0 - a) > 1e-6:
        hint = (f"; with gear_pair.profile_shift = {shifts} the gears mesh without backlash at "
                f"gear_pair.centre_distance = {a0 * 1e3:.3f} mm: set that centre distance or "
                f"profile shifts that fit {a * 1e3:.3f} mm")
    return (f"gear_pair (centre_distance = {a * 1e3:.3f} mm, profile_shift = {shifts}, "
            f"addendum_coefficient = {v['gear_pair.addendum_coefficient']:g}, "
            f"dedendum_coefficient = {v['gear_pair.dedendum_coefficient']:g}): {exc}{hint}")


def shipped_cases() -> dict[str, Path]:
    """The case files shipped with the package (the folder ``models/``, installed as the
    package ``gsb_models``): ``{name: path}``."""
    from importlib.resources import files

    folder = Path(str(files("gsb_models")))
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}


def shipped_case(name: str) -> Case:
    """The shipped case ``name`` (``"baguet2010_spur"``), read from the package whatever the
    working directory holds: what code that an FMU host or a worker runs loads by name."""
    shipped = shipped_cases()
    if name not in shipped:
        raise CaseError(f"no shipped case {name!r}; shipped cases: {', '.join(shipped)}")
    return load_case(shipped[name])


def resolve_case(path_or_name: str | Path) -> Path:
    """A case file by path, or by the name of a shipped case (``"baguet2010_spur"``)."""
    path = Path(path_or_name)
    if path.is_file():
        return path
    shipped = shipped_cases()
    stem = path.name[:-5] if path.name.endswith(".toml") else path.name
    if str(path_or_name) in (stem, f"{stem}.toml") and stem in shipped:
        return shipped[stem]  # a folder of that name (a run's results, say) is not the case
    if path.is_dir():
        raise CaseError(f"{path}: a folder, not a case file")
    raise CaseError(f"case file not found: {path_or_name} (not a file; shipped cases: "
                    f"{', '.join(shipped)})")


def load_case(path: str | Path, overrides: dict | None = None) -> Case:
    """Read and check a case file (a path, or the name of a shipped case); ``overrides``
    (``{"section.key": value}``, values as in a case file) replace fields before the checks.
    An override that is wrong on its own is named as such, not as the file's
    (:func:`check_override`)."""
    path = resolve_case(path)
    overrides = overrides or {}
    for key, value in overrides.items():
        check_override(key, value)
    data = parse_toml(read_case_text(path), str(path))
    case = parse_case(_apply_overrides(data, overrides), _overridden(str(path), overrides))
    return Case(case.values, str(path))


#: leading bytes of the binary files a case argument is mistaken for -> what the file is
_SIGNATURES = {
    b"\x89HDF\r\n\x1a\n": "an HDF5 file (a results file of gsb run or gsb sweep? `gsb run "
                           "--resume {path}` continues a run, `gsb plot {path}` draws it)",
    b"PK\x03\x04": "a ZIP archive (an FMU or SSP archive? gsb run takes an SSP archive by its "
                   ".ssp name)",
    b"\x89PNG\r\n\x1a\n": "a PNG image",
    b"%PDF": "a PDF document",
    b"\x1f\x8b": "a gzip archive",
}


def read_case_text(path: str | Path) -> str:
    """The text of a case file, or :class:`CaseError` naming the file and why it is not one
    (unreadable, a known binary format, not UTF-8 text)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise CaseError(f"{path}: cannot read the case file ({exc.strerror or exc})") from None
    for signature, what in _SIGNATURES.items():
        # HDF5 may put its signature after a user block of 512, 1024, ... bytes
        offsets = (0, 512, 1024, 2048, 4096) if signature.startswith(b"\x89HDF") else (0,)
        if any(raw.startswith(signature, at) for at in offsets):
            raise CaseError(f"{path}: not a case file: {what.format(path=path)}; a case file "
                            f"is TOML text") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CaseError(f"{path}: not a case file: not UTF-8 text (byte {raw[exc.start]:#04x} "
                        f"at offset {exc.start}); a case file is TOML text") from None


_TOML_WHERE = re.compile(r"^(?P<msg>.*) \(at line (?P<line>\d+), column (?P<col>\d+)\)$",
                         re.DOTALL)


def parse_toml(text: str, source: str) -> dict:
    """A case's TOML text as a dict, or :class:`CaseError` naming ``source`` and the line and
    column of a syntax error."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = _TOML_WHERE.match(str(exc))
        where = f"{source}, line {m['line']}, column {m['col']}" if m else source
        raise CaseError(f"{where}: not valid TOML: {m['msg'] if m else exc}") from None


def _apply_overrides(data: dict, overrides: dict) -> dict:
    for key, value in overrides.items():
        section, name = str(key).split(".")
        table = data.setdefault(section, {})
        if not isinstance(table, dict):
            raise CaseError(f"override {key!r}: [{section}] is not a table")
        table[name] = value
    return data


def schema_markdown() -> str:
    """The schema as a Markdown table (docs/case-files.md)."""
    rows = ["| field | kind | shape | default | meaning |", "| --- | --- | --- | --- | --- |"]
    for f in FIELDS:
        kind = f.kind if f.kind in ("text", "count", "flag", "choice") else \
            f"{f.kind} [{symbol(f.kind)}]"
        if f.choices:
            kind += ": " + " / ".join(f.choices)
        default = "required" if f.required else repr(f.default)
        rows.append(f"| `{f.key}` | {kind} | {f.shape or 1} | {default} | {f.doc} |")
    return "\n".join(rows)


def document() -> str:
    """The text of docs/case-files.md."""
    return (
        "# Case files\n\n"
        "Generated from `fmu_src/case.py` (`python -m fmu_src.case > "
        "docs/case-files.md`); a test keeps the two in sync.\n\n"
        "A case is a TOML file with the sections below. A quantity is a number in the SI unit "
        "shown, or a string `\"value unit\"` (`\"4 mm\"`, `\"20 deg\"`, `\"150 um\"`, "
        "`\"325 rad/s\"`, `\"3000 rpm\"`); a unit of the wrong kind, an unknown section or "
        "key, a missing field or a value out of bounds stops the run before it starts, with "
        "the field named. A single value given for a list field applies to every entry. "
        "`gsb run` options override fields without editing the file. The `bearings` fields "
        "after `viscosity` are generated from the options the registered bearing models "
        "declare (`bearing_fmu.base.ModelOption`). Examples: the shipped cases "
        + ", ".join(f"`{n}`" for n in shipped_cases())
        + " (`models/`; `gsb run <name>` runs one by name).\n\n" + schema_markdown() + "\n"
    )


if __name__ == "__main__":
    print(document(), end="")


def layout(case):
    """PROVISIONAL (until the train schema lands): the single-stage case's layout."""
    from gear_fmu.layout import BearingSpec, Drive, GearSpec, Layout, MeshSpec, ShaftSpec

    v = case.values if isinstance(case, Case) else case
    length = v["shafts.length"]
    mat = dict(young=v["shafts.young_modulus"], poisson=v["shafts.poisson_ratio"],
               density=v["shafts.density"], element_length=length / v["shafts.elements"])
    names = ("pinion_shaft", "gear_shaft")
    shafts = tuple(ShaftSpec(n, (length,), (v["shafts.outer_diameter"][i],),
                             (v["shafts.inner_diameter"][i],), **mat)
                   for i, n in enumerate(names))
    beta = v["gear_pair.helix_angle"]
    hands = ("left", "right") if beta > 0.0 else ("", "")
    gears = tuple(GearSpec(
        g, names[i], 0.5 * length, v["gear_pair.teeth"][i], v["gear_pair.module"],
        v["gear_pair.pressure_angle"], v["gear_pair.face_width"][i], v["gear_pair.mass"][i],
        helix_angle=beta, hand=hands[i], profile_shift=v["gear_pair.profile_shift"][i],
        addendum_coefficient=v["gear_pair.addendum_coefficient"],
        dedendum_coefficient=v["gear_pair.dedendum_coefficient"],
        polar_inertia=v["gear_pair.polar_inertia"][i],
        diametral_inertia=v["gear_pair.diametral_inertia"][i],
        unbalance=v["operation.unbalance"][i], unbalance_mass="shaft")
        for i, g in enumerate(("pinion", "gear")))
    meshes = (MeshSpec("mesh", ("pinion", "gear"), v["gear_pair.centre_distance"]),)
    model = v["bearings.model"]
    opts = tuple((o.key, v[f"bearings.{o.key}"]) for o in model_class(model).options)
    bearings = tuple(BearingSpec(
        str(j + 1), names[j // 2], 0.0 if j % 2 == 0 else length, model,
        v["bearings.diameter"][j], v["bearings.length"][j], v["bearings.clearance"][j],
        v["bearings.viscosity"][j], opts) for j in range(4))
    drive = Drive("pinion_shaft", "gear_shaft", v["operation.speed"], v["operation.torque"],
                  drivetrain=drivetrain(v),
                  gravity=(0.0, -9.81) if v["operation.gravity"] else (0.0, 0.0))
    return Layout(shafts, gears, meshes, bearings, drive)
