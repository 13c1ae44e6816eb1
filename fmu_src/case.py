"""Case files (TOML): the schema of a parallel-axis gear train, the loader that checks it and
the writer.

A case names its components in tables: ``[shafts.<name>]``, ``[gears.<name>]``,
``[meshes.<name>]``, ``[bearings.<name>]``, ``[discs.<name>]``, and sets the train once in
``[case]``, ``[drive]`` and ``[simulation]``. Every field is declared once in :data:`FIELDS`,
the instance part of its key a ``*`` (``shafts.*.length``), with its dimension, shape, default
and bounds; the bearing-model settings (``bearings.*.nodes``, ...) are generated from the
options the registered models declare (:class:`bearing_fmu.base.ModelOption`). The loader
converts quantities to SI (:mod:`fmu_src.units`), rejects unknown sections and keys (the
closest key as a hint), names the field in every error, and builds the gear train
(:func:`fmu_src.train.layout`, one gear pair per mesh) so that a case that loads is a case that
builds. ``docs/case-files.md`` is rendered from the same table.

A loaded :class:`Case` is flat: ``case["shafts.pinion_shaft.outer_diameter"]``,
``case["bearings.3.clearance"]``, ``case["drive.speed"]`` in SI (lists for list fields).
Overrides use the same keys, a ``*`` for every instance (``bearings.*.model``). Files in the
single-stage schema of earlier versions are translated (:mod:`fmu_src.legacy_case`).

A quantity is a number in SI units or a string ``"value unit"`` (``"4 mm"``, ``"20 deg"``).
The shipped cases (``models``) load by name (:func:`load_case`, :func:`shipped_cases`), from
any working directory.
"""

from __future__ import annotations

import copy
import difflib
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from bearing_fmu import MODELS as _BEARING_TABLE
from bearing_fmu import model_class
from fmu_src import legacy_case, train
from fmu_src.fields import (
    FREE,
    CaseError,
    Field,
    bound_violation,
    convert,
    instance_names,
    option_fields,
    template,
    toml_value,
)
from fmu_src.fields import field_spec as _f
from fmu_src.legacy_case import LegacyCaseWarning
from fmu_src.units import UnitError, parse_speed_profile, parse_window, symbol
from gear_fmu.drivetrain import OUTPUT_ENDS
from gear_fmu.layout import HANDS, UNBALANCE_MASSES, LayoutError, check_name
from gear_fmu.mesh.geometry import GearGeometryError
from gear_fmu.modal.damping import BASES, DAMPING_KINDS

__all__ = ["BEARING_MODELS", "FIELDS", "INSTANCE_SECTIONS", "SECTIONS", "Case", "CaseError",
           "Field", "LegacyCaseWarning", "bound_violation", "check_override", "document",
           "field_of", "load_case", "model_option_fields", "parse_case", "parse_toml",
           "read_case_text", "resolve_case", "schema_markdown", "shipped_case",
           "shipped_cases", "varying_speed_refusal"]

BEARING_MODELS = tuple(_BEARING_TABLE)
#: the sections of a case file, in the order a case is written
SECTIONS = ("case", "shafts", "gears", "meshes", "bearings", "discs", "drive", "simulation")
#: the sections of named instances (``[shafts.<name>]``); the others appear once
INSTANCE_SECTIONS = ("shafts", "gears", "meshes", "bearings", "discs")
#: an instance of each section, in words (messages)
_KIND = {"shafts": "shaft", "gears": "gear", "meshes": "mesh", "bearings": "bearing",
         "discs": "disc"}

_POS = dict(minimum=0.0, exclusive_minimum=True)
_ANGLE = dict(minimum=0.0, maximum=0.7)
_UNBALANCE_MASS = ("which mass the eccentricity carries: body (the body's own) or shaft (the "
                   "shaft with everything on it, the paper's Eq. 10)")


def model_option_fields() -> tuple[Field, ...]:
    """``bearings.*.<key>`` fields for the options of every registered bearing model (one
    field per option key: :func:`fmu_src.fields.option_fields`)."""
    return option_fields("bearings.*.")


def _body_fields(section: str) -> tuple[Field, ...]:
    """The mass, inertia and unbalance fields of a gear or a disc."""
    derived = " (0: those of a steel annulus, gear_fmu.system)" if section == "gears" else ""
    return (
        _f(f"{section}.*.mass", "mass", "body mass", **_POS),
        _f(f"{section}.*.polar_inertia", "inertia", f"polar inertia of the body{derived}",
           default=0.0, minimum=0.0),
        _f(f"{section}.*.diametral_inertia", "inertia", f"diametral inertia of the body"
           f"{derived}", default=0.0, minimum=0.0),
        _f(f"{section}.*.unbalance", "length", "unbalance eccentricity e_mu (Eq. 10)",
           default=0.0, minimum=0.0),
        _f(f"{section}.*.unbalance_phase", "angle", "angle of the eccentricity at t = 0 "
           "(from the s axis, turning with the shaft)", default=0.0),
        _f(f"{section}.*.unbalance_mass", "choice", _UNBALANCE_MASS, default="body",
           choices=UNBALANCE_MASSES),
    )


def _place_fields(section: str) -> tuple[Field, ...]:
    what = {"gears": "face centre", "bearings": "bearing centre", "discs": "disc"}[section]
    return (
        _f(f"{section}.*.shaft", "text", "the shaft it sits on (a [shafts.<name>] name)"),
        _f(f"{section}.*.position", "length", f"{what} from the shaft's start", minimum=0.0),
    )


#: The schema: every field of a case file, once, in the order of ``docs/case-files.md``.
#:
#: :meta hide-value:
FIELDS: tuple[Field, ...] = (
    _f("case.name", "text", "identifier of the case (results are named after it)"),
    _f("case.description", "text", "free text", default=""),
    # shafts: stepped, hollow, one material each (the paper's Table 2: one segment)
    _f("shafts.*.length", "length", "lengths of the segments from the shaft's start (one "
       "value: a shaft of one segment)", shape=FREE, min_items=1, **_POS),
    _f("shafts.*.outer_diameter", "length", "outer diameter of each segment", shape="length",
       **_POS),
    _f("shafts.*.inner_diameter", "length", "bore diameter of each segment (0: solid)",
       shape="length", default=0.0, minimum=0.0),
    _f("shafts.*.young_modulus", "pressure", "Young's modulus E (of the shaft and of the "
       "teeth of the gears it drives)", **_POS),
    _f("shafts.*.poisson_ratio", "dimensionless", "Poisson's ratio nu", minimum=0.0,
       maximum=0.5),
    _f("shafts.*.density", "density", "density rho", **_POS),
    _f("shafts.*.element_length", "length", "longest Timoshenko element (0: the shaft's "
       "length / 8)", default=0.0, minimum=0.0),
    _f("shafts.*.offset", "length", "global z of the shaft's start", default=0.0),
    _f("shafts.*.axial_stiffness", "stiffness", "thrust spring on the axial DOF at the "
       "shaft's first bearing (not in the paper)", default=1e9, **_POS),
    # gears (paper Table 1 for one wheel); the two gears of a mesh share module, pressure
    # angle, helix angle and tooth proportions (gear_fmu.layout)
    *_place_fields("gears"),
    _f("gears.*.teeth", "count", "number of teeth", minimum=5),
    _f("gears.*.module", "length", "normal module m_n", **_POS),
    _f("gears.*.pressure_angle", "angle", "normal pressure angle alpha_n", **_POS,
       maximum=0.7),
    _f("gears.*.helix_angle", "angle", "helix angle beta (0: spur)", default=0.0, **_ANGLE),
    _f("gears.*.hand", "choice", "helix hand (required when helical; \"\" for spur): a pair "
       "has opposite hands", default="", choices=HANDS),
    _f("gears.*.profile_shift", "dimensionless", "profile shift coefficient x", default=0.0,
       minimum=-1.0, maximum=1.0),
    _f("gears.*.face_width", "length", "face width b", **_POS),
    _f("gears.*.addendum_coefficient", "dimensionless", "addendum / m_n", default=1.0,
       **_POS),
    _f("gears.*.dedendum_coefficient", "dimensionless", "dedendum / m_n", default=1.25,
       **_POS),
    *_body_fields("gears"),
    _f("gears.*.tip_relief", "length", "tip relief amplitude at the tip", default=0.0,
       minimum=0.0),
    _f("gears.*.relief_length", "length", "extent of the tip relief along the line of "
       "action", default=0.0, minimum=0.0),
    _f("gears.*.pitch_errors", "length", "pitch deviation of each tooth along the base "
       "normal (one per tooth, or none)", shape=FREE, default=[]),
    _f("gears.*.runout", "length", "eccentricity of the teeth on the shaft", default=0.0,
       minimum=0.0),
    _f("gears.*.runout_phase", "angle", "angle of the runout at t = 0", default=0.0),
    # meshes
    _f("meshes.*.gears", "text", "the two gears in mesh (names of [gears.<name>] tables on "
       "two shafts)", shape=2),
    _f("meshes.*.centre_distance", "length", "operating centre distance a", **_POS),
    _f("meshes.*.direction", "angle", "angle from the s axis to the line of centres, from "
       "the shaft of gears[1] to that of gears[2]", default=0.0),
    _f("meshes.*.slices", "count", "slices across the face width (mesh element)",
       default=20, minimum=1),
    _f("meshes.*.crowning", "length", "lead crowning of the pair", default=0.0, minimum=0.0),
    _f("meshes.*.lead_slope", "length", "helix slope deviation across the face width",
       default=0.0),
    _f("meshes.*.relief_exponent", "dimensionless", "tip relief shape: 1 linear, 2 "
       "parabolic", default=2.0, minimum=1.0, maximum=2.0),
    # bearings (paper Table 3 for one bearing), each its own model
    *_place_fields("bearings"),
    _f("bearings.*.model", "choice", "bearing model (its FMU: BearingHybrid, ... by that "
       "name)", default="hybrid", choices=BEARING_MODELS),
    _f("bearings.*.diameter", "length", "bearing diameter D", **_POS),
    _f("bearings.*.length", "length", "bearing length L", **_POS),
    _f("bearings.*.clearance", "length", "radial clearance C", **_POS),
    _f("bearings.*.viscosity", "viscosity", "lubricant dynamic viscosity mu", **_POS),
    *model_option_fields(),
    # discs: rigid bodies without teeth (coupling hubs, impellers, ...)
    *_place_fields("discs"),
    *_body_fields("discs"),
    # the drive: power in, power out, the motor and the load in torsion (not in the paper)
    _f("drive.input_shaft", "text", "the shaft the input torque drives (it turns about +z "
       "at drive.speed)"),
    _f("drive.input_position", "length", "where the input torque acts, from the input "
       "shaft's start (default: its start)", default=None, minimum=0.0),
    _f("drive.speed", "angular_speed", "input shaft speed omega (the other shafts' speeds follow "
       "from the gear ratios)", **_POS),
    _f("drive.speed_profile", "text", "a run-up or run-down of the input speed: 'ramp to 400 "
       "rad/s in 2 s' (from drive.speed, linear, then constant; '... after 0.5 s' delays it) "
       "or 'table 0 s: 325 rad/s, 1 s: 400 rad/s, 2 s: 350 rad/s' (linear between the "
       "points, from drive.speed at 0 s); empty: drive.speed throughout "
       "(gear_fmu.speed_profile)", default=""),
    _f("drive.torque", "torque", "input torque T (> 0: the teeth stay in contact only under "
       "load)", **_POS),
    _f("drive.motor_inertia", "inertia", "motor inertia at the input (0: no motor)",
       default=0.0, minimum=0.0),
    _f("drive.motor_coupling_stiffness", "torsional_stiffness", "stiffness of a coupling "
       "between the motor and the input (0: motor attached rigidly)", default=0.0,
       minimum=0.0),
    _f("drive.motor_coupling_damping", "torsional_damping", "viscous damping of the motor "
       "coupling", default=0.0, minimum=0.0),
    _f("drive.output_shaft", "text", "the shaft whose output the load resists"),
    _f("drive.output_position", "length", "where the resisting torque acts, from the output "
       "shaft's start (default: its end)", default=None, minimum=0.0),
    _f("drive.output_end", "choice", "torsion at the output: clamped (a load of infinite "
       "inertia) or load (the load inertia, the resisting torque acting on it)",
       default="clamped", choices=OUTPUT_ENDS),
    _f("drive.load_inertia", "inertia", "load inertia at the output (output_end = load)",
       default=0.0, minimum=0.0),
    _f("drive.load_coupling_stiffness", "torsional_stiffness", "stiffness of a coupling "
       "between the output and the load (0: load attached rigidly)", default=0.0,
       minimum=0.0),
    _f("drive.load_coupling_damping", "torsional_damping", "viscous damping of the load "
       "coupling", default=0.0, minimum=0.0),
    _f("drive.gravity", "acceleration", "gravity [g_s, g_t] ([0, -9.81]: along -t)",
       shape=2, default=[0.0, 0.0]),
    # numerics, paper Sec. 4
    _f("simulation.damping_ratio", "dimensionless", "damping ratio zeta of the modal "
       "damping, or of the Rayleigh damping at rayleigh_frequencies", default=0.03,
       minimum=0.0, maximum=0.99),
    _f("simulation.damping_model", "choice", "structural damping: modal (zeta on every mode "
       "of the damping_basis) or rayleigh (alpha M + beta K, gear_fmu.modal.damping)",
       default="modal", choices=DAMPING_KINDS),
    _f("simulation.damping_basis", "choice", "modes of the modal damping: bearings (shafts, "
       "mean meshes and the bearings' static film stiffness) or structure (shafts and mean "
       "meshes)", default="bearings", choices=BASES),
    _f("simulation.rayleigh_frequencies", "frequency", "[f1, f2] at which the Rayleigh "
       "damping has the ratio damping_ratio (0, 0: use rayleigh_alpha, rayleigh_beta)",
       shape=2, default=[0.0, 0.0], minimum=0.0),
    _f("simulation.rayleigh_alpha", "rate", "mass coefficient alpha of the Rayleigh damping",
       default=0.0, minimum=0.0),
    _f("simulation.rayleigh_beta", "time", "stiffness coefficient beta of the Rayleigh "
       "damping", default=0.0, minimum=0.0),
    _f("simulation.mesh_damping_ratio", "dimensionless", "damping of every mesh as the ratio "
       "of its two-inertia mesh mode (0: none)", default=0.0, minimum=0.0, maximum=0.99),
    _f("simulation.mesh_damping", "damping", "damping coefficient of every mesh along its "
       "line of action (0: none; exclusive with mesh_damping_ratio)", default=0.0,
       minimum=0.0),
    _f("simulation.consistent_start", "flag", "start the transient from the acceleration of "
       "the unbalance at t = 0 instead of zero (gear_fmu.structure)", default=True),
    _f("simulation.locate_contact", "flag", "cut steps at the angles where contact lines "
       "enter or leave the path of contact, so that Newmark keeps order 2 "
       "(gear_fmu.structure)", default=True),
    _f("simulation.gyroscopic", "flag", "gyroscopic moments of the shafts, gears and discs "
       "spinning at their speeds, in the transient and the modes (gear_fmu.timoshenko; the "
       "paper neglects them)", default=True),
    _f("simulation.steps_per_mesh_period", "count", "time steps per mesh period of the "
       "fastest mesh", default=32, minimum=4),
    _f("simulation.mesh_periods", "count", "mesh periods of the fastest mesh simulated",
       default=2048, minimum=1),
    _f("simulation.window", "text", "the last part of the run that R, the peak-to-peak, the "
       "line amplitudes and the figures are taken over: '26 periods' (of the fastest mesh), "
       "'0.05 s' or '2 revolutions of <shaft>'; empty: the last revolution of the slowest "
       "shaft, or the last half of a shorter run (orchestrator.analysis.metrics"
       ".report_window)", default=""),
    _f("simulation.tolerance", "dimensionless", "convergence limit l of the coupled Newton",
       default=1e-5, **_POS, maximum=0.1),
    _f("simulation.max_iterations", "count", "coupled iterations per step before failing",
       default=30, minimum=1),
)
_BY_KEY = {f.key: f for f in FIELDS}
_IN_SECTION = {s: tuple(f for f in FIELDS if f.key.split(".")[0] == s) for s in SECTIONS}
#: field names that would set a speed where the train derives it
_SPEEDS = ("speed", "omega", "rpm", "input_speed")


# ---------------------------------------------------------------------------- keys
def field_of(key: str) -> Field:
    """The schema field of a case key or an override key (``"bearings.3.clearance"``,
    ``"gears.*.unbalance"`` -> the field ``gears.*.unbalance``), or
    :class:`~fmu_src.fields.CaseError` saying why the key is none (the closest field as a
    hint)."""
    why = _unknown_key(str(key))
    if why:
        raise CaseError(why)
    return _BY_KEY[template(key, INSTANCE_SECTIONS)]


def _closest(key: str, keys, table: bool = False) -> str:
    """"; did you mean <the closest of keys>?" ("[...]" around it for a ``table``), or ""."""
    close = difflib.get_close_matches(key, keys, n=1, cutoff=0.75)
    if not close:
        return ""
    return f"; did you mean {f'[{close[0]}]' if table else close[0]}?"


def _unknown_key(key: str) -> str | None:
    """Why ``key`` is not a key of a case field (with the closest field or the current key of
    a single-stage one as a hint), or None for a field."""
    parts = key.split(".")
    section = parts[0]
    renamed = legacy_case.new_key(key)
    if renamed:
        return (f"{key} is a field of the single-stage schema of earlier versions: it is now "
                f"{renamed} (docs/case-files.md)")
    if len(parts) == 1:
        same = [f.key for f in FIELDS if f.name == key]
        return (f"{key!r} is not section.key or section.name.key (drive.speed, "
                "bearings.3.clearance)" + (f"; did you mean {' or '.join(same)}?" if same else ""))
    if section not in SECTIONS:
        return (f"unknown section [{section}] in {key}{_closest(key, _BY_KEY)}: a key is "
                f"section.key or section.name.key (sections: {', '.join(SECTIONS)})")
    known = [f.name for f in _IN_SECTION[section]]
    if section in INSTANCE_SECTIONS:
        if len(parts) != 3 or not all(parts):
            return (f"{key!r} is not {section}.<name>.<field> ([{section}.<name>] is one "
                    f"{_KIND[section]}; * stands for every one: {section}.*.{known[0]})")
        try:
            if parts[1] != "*":
                check_name(_KIND[section], parts[1])
        except LayoutError as exc:
            return f"{key}: {exc}"
    elif len(parts) != 2 or not all(parts):
        return f"{key!r} is not {section}.<field> (e.g. {_IN_SECTION[section][0].key})"
    if template(key, INSTANCE_SECTIONS) in _BY_KEY:
        return None
    if parts[-1] in _SPEEDS and section in INSTANCE_SECTIONS:
        return (f"unknown field {key}: the speed is set once, at drive.speed (the input "
                "shaft's), and every other shaft's follows from the gear ratios")
    hint = _closest(template(key, INSTANCE_SECTIONS), _BY_KEY)
    if section in INSTANCE_SECTIONS:  # the hint for the instance the key names
        hint = hint.replace(f"{section}.*.", f"{section}.{parts[1]}.")
    where = f"[{section}.<name>]" if section in INSTANCE_SECTIONS else f"[{section}]"
    return f"unknown field {key}{hint} ({where} takes {', '.join(known)})"


def check_override(key: str, value):
    """One override (``"drive.speed"``, ``"bearings.3.model"``, ``"gears.*.unbalance"``; a key
    of the single-stage schema for a file in it) with its value as in a case file, on its own:
    the value in SI units (a scalar of a per-segment field stays a scalar), or
    :class:`~fmu_src.fields.CaseError` naming the key (a typo gets the closest field) and the
    value, never a case file (the override is not in one)."""
    key = str(key)
    if legacy_case.new_key(key):  # applies to a single-stage file only (load_case)
        return legacy_case.check_override(key, value)
    return convert(field_of(key), value, key)


def _overridden(source: str, overrides: dict) -> str:
    """The source of a case in messages once ``overrides`` replaced some of its fields: a
    value the file does not hold is not blamed on the file alone."""
    if not overrides:
        return source
    return f"{source} with {', '.join(map(str, overrides))} overridden"


def _apply_overrides(data: dict, overrides: dict) -> dict:
    """Case data (parsed TOML, current schema) with ``overrides`` replacing fields: a ``*``
    instance sets the field of every instance of its section."""
    for key, value in overrides.items():
        key = str(key)
        field_of(key)
        parts = key.split(".")
        table = data.setdefault(parts[0], {})
        if not isinstance(table, dict):
            raise CaseError(f"override {key}: [{parts[0]}] is not a table")
        if len(parts) == 2:
            table[parts[1]] = copy.deepcopy(value)
            continue
        section, name, field = parts
        kind = _KIND[section]
        if name == "*" and not table:
            raise CaseError(f"override {key}: the case has no {section}")
        if name != "*" and name not in table:
            raise CaseError(f"override {key}: the case has no {kind} {name!r}"
                            f"{_closest(name, list(table))} ({section}: "
                            f"{', '.join(table) or 'none'})")
        for target in (table if name == "*" else [name]):
            table[target][field] = copy.deepcopy(value)
    return data


# ---------------------------------------------------------------------------- the case
@dataclass(frozen=True)
class Case:
    """A checked case: ``values[key]`` in SI units, keyed by the full dotted keys
    (``"shafts.pinion_shaft.length"``, ``"drive.speed"``), instances in file order."""

    values: dict
    source: str

    def __getitem__(self, key: str):
        return self.values[key]

    def names(self, kind: str) -> list[str]:
        """The instance names of a section (``"shafts"``, ``"gears"``, ``"meshes"``,
        ``"bearings"``, ``"discs"``) in file order."""
        if kind not in INSTANCE_SECTIONS:
            raise ValueError(f"names({kind!r}): one of {', '.join(INSTANCE_SECTIONS)}")
        return instance_names(self.values, kind)

    def data(self) -> dict:
        """The case as nested tables (``{"shafts": {"input": {"length": [...]}}, ...}``, SI
        values, fields left at None out): what a case file of it parses to."""
        out: dict = {}
        for key, value in self.values.items():
            if value is None:
                continue
            *path, name = key.split(".")
            table = out
            for part in path:
                table = table.setdefault(part, {})
            table[name] = copy.deepcopy(value)
        return out

    def with_overrides(self, overrides: dict) -> Case:
        """A copy with some fields replaced (values as in a case file, ``*`` for every
        instance), checked again as a whole."""
        for key, value in overrides.items():
            check_override(key, value)
        data = _apply_overrides(self.data(), overrides)
        case = parse_case(data, _overridden(self.source, overrides))
        return Case(case.values, self.source)

    @property
    def name(self) -> str:
        """The case's name (``case.name``)."""
        return self.values["case.name"]

    def to_toml(self, header: bool = True) -> str:
        """The case as a case file of the current schema (SI numbers): reloads to the same
        values, bit for bit. ``header=False``: without the comment naming the source file
        (the case's content alone, e.g. to hash it)."""
        parts = [f"# written by fmu_src.case from {self.source} (SI units)"] if header else []
        for section, content in self.data().items():
            tables = content.items() if section in INSTANCE_SECTIONS else [(None, content)]
            for name, table in tables:
                parts.append(f"\n[{section}]" if name is None else f"\n[{section}.{name}]")
                parts.extend(f"{k} = {toml_value(v)}" for k, v in table.items())
        return "\n".join(parts) + "\n"


# ---------------------------------------------------------------------------- reading
def _check_tables(data: dict, source: str) -> None:
    """Known sections; a table per section, a table per instance with a valid name."""
    for section, content in data.items():
        if section not in SECTIONS:
            hint = _closest(section, SECTIONS, table=True)
            raise CaseError(f"{source}: unknown section [{section}]{hint} (sections: "
                            f"{', '.join(SECTIONS)})")
        if not isinstance(content, dict):
            raise CaseError(f"{source}: [{section}] must be a table")
        if section not in INSTANCE_SECTIONS:
            continue
        for name, table in content.items():
            if not isinstance(table, dict):
                raise CaseError(f"{source}: {section}.{name} = {table!r}: [{section}] holds "
                                f"one table per {_KIND[section]}, [{section}.<name>]")
            try:
                check_name(_KIND[section], name)
            except LayoutError as exc:
                raise CaseError(f"{source}: [{section}.{name}]: {exc}") from None


def _read_table(section: str, table: dict, prefix: str, source: str) -> dict:
    """The fields of one table (``prefix``: ``"drive."`` or ``"shafts.input."``) in SI, the
    defaults filled in."""
    for key in table:
        why = _unknown_key(prefix + key)
        if why:
            raise CaseError(f"{source}: {why}")
    out = {}
    for field in _IN_SECTION[section]:
        key = prefix + field.name
        sibling = field.shape if isinstance(field.shape, str) and field.shape != FREE else None
        length = len(out[prefix + sibling]) if sibling else None
        try:
            if field.name in table:
                out[key] = convert(field, table[field.name], key, length)
            elif field.required:
                raise CaseError(f"missing field {key} ({field.doc})")
            elif length is not None:
                out[key] = convert(field, field.default, key, length)
            else:
                out[key] = copy.copy(field.default)
        except CaseError as exc:
            raise CaseError(f"{source}: {exc}") from None
    return out


def parse_case(data: dict, source: str = "<case>") -> Case:
    """Check parsed case data against :data:`FIELDS` and build its train; data in the
    single-stage schema is translated first (:func:`fmu_src.legacy_case.translate`)."""
    if legacy_case.is_legacy(data):
        data = legacy_case.translate(data, source)
    _check_tables(data, source)
    values: dict = {}
    for section in SECTIONS:
        content = data.get(section, {})
        if section in INSTANCE_SECTIONS:
            for name, table in content.items():
                values.update(_read_table(section, table, f"{section}.{name}.", source))
        else:
            values.update(_read_table(section, content, f"{section}.", source))
    _check_model_options(values, source)
    _check_train(values, source)
    _check_window(values, source)
    _check_speed_profile(values, source)
    return Case(values, source)


def _check_speed_profile(v: dict, source: str) -> None:
    """``drive.speed_profile`` readable (:func:`fmu_src.units.parse_speed_profile`), a table
    starting at ``drive.speed``, and a varying speed only with what follows it: film bearings
    need a speed > 0 throughout and the linear model's coefficients hold at one speed."""
    text = v["drive.speed_profile"]
    try:
        given = parse_speed_profile(text)
    except UnitError as exc:
        raise CaseError(f"{source}: {exc}") from None
    if given is None:
        return
    kind, data = given
    where = f"{source}: drive.speed_profile = {text!r}"
    w0 = v["drive.speed"]
    if kind == "table" and data[0][1] != w0:
        raise CaseError(f"{where}: starts at {data[0][1]:g} rad/s, and drive.speed = {w0:g} "
                        f"rad/s (the static solution's speed): make them equal")
    speeds = [w for _, w in data] if kind == "table" else [w0, data[0]]
    if all(w == w0 for w in speeds):
        return
    why = varying_speed_refusal(v, min(speeds))
    if why is not None:
        raise CaseError(f"{where}: {why}")


def varying_speed_refusal(values, lowest: float, models: bool = True) -> str | None:
    """Why a case (its field ``values``) cannot follow an input speed that varies down to
    ``lowest`` [rad/s], or None: a linear bearing's coefficients hold at one speed, and a
    film carries no load at rest.
    ``models``: whether the bearings' own models run (not when a bearing FMU of the user's
    replaces them). The one rule of a case's ``drive.speed_profile`` and of the transmission
    FMU's input ``speed``."""
    for name in instance_names(values, "bearings") if models else ():
        model = values[f"bearings.{name}.model"]
        if model == "linear":
            return (f"bearing {name} is linear, whose coefficients hold at one speed; a varying "
                    f"speed needs a film model (hybrid, short, fd) or lumped")
        if lowest <= 0.0 and model != "lumped":
            return (f"reaches {lowest:g} rad/s, where the film of bearing {name} ({model}) "
                    f"carries no load: keep the speed above 0 rad/s")
    return None


def _check_window(v: dict, source: str) -> None:
    """``simulation.window`` readable (:func:`fmu_src.units.parse_window`), its shaft one of
    the train's."""
    try:
        window = parse_window(v["simulation.window"])
    except UnitError as exc:
        raise CaseError(f"{source}: {exc}") from None
    shafts = instance_names(v, "shafts")
    if window is not None and window[1] == "revolutions" and window[2] not in shafts:
        raise CaseError(f"{source}: simulation.window = {v['simulation.window']!r}: no shaft "
                        f"{window[2]!r}; the shafts are {', '.join(shafts)}"
                        f"{_closest(window[2], shafts)}")


def _check_model_options(v: dict, source: str) -> None:
    """Each bearing's options within its own model's bounds."""
    for name in instance_names(v, "bearings"):
        model = v[f"bearings.{name}.model"]
        for opt in model_class(model).options:
            key = f"bearings.{name}.{opt.key}"
            unit = "" if opt.kind == "count" else f" {symbol(opt.kind)}"
            violated = bound_violation(v[key], opt.minimum, opt.maximum, opt.exclusive_minimum)
            if violated:
                raise CaseError(f"{source}: {key} = {v[key]!r}: the {model} model needs "
                                f"{violated[0]} {violated[1]}{unit}")


def _check_train(v: dict, source: str) -> None:
    """The layout, the gear pair of every mesh and the damping model, built by
    :mod:`fmu_src.train` (whose messages name the fields)."""
    try:
        train.gear_pairs(v, train.layout(v))
        train.damping(v)
    except (LayoutError, GearGeometryError, ValueError) as exc:
        raise CaseError(f"{source}: {exc}") from None


# ---------------------------------------------------------------------------- files
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
    (``{"section.name.key": value}``, ``*`` for every instance, values as in a case file)
    replace fields before the checks. An override that is wrong on its own is named as such,
    not as the file's (:func:`check_override`). A file in the single-stage schema of earlier
    versions is translated (:mod:`fmu_src.legacy_case`, with a
    :class:`~fmu_src.legacy_case.LegacyCaseWarning`), the overrides with its keys applied
    before the translation."""
    path = resolve_case(path)
    overrides = dict(overrides or {})
    for key, value in overrides.items():
        check_override(key, value)
    data = parse_toml(read_case_text(path), str(path))
    source = _overridden(str(path), overrides)
    if legacy_case.is_legacy(data):
        old = {k: v for k, v in overrides.items() if legacy_case.is_legacy_key(str(k))}
        data = legacy_case.translate(legacy_case.apply_overrides(data, old),
                                     _overridden(str(path), old), str(path))
        overrides = {k: v for k, v in overrides.items() if k not in old}
    case = parse_case(_apply_overrides(data, overrides), source)
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
    """The text of a case file, or :class:`~fmu_src.fields.CaseError` naming the file and why
    it is not one (unreadable, a known binary format, not UTF-8 text)."""
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
    """A case's TOML text as a dict, or :class:`~fmu_src.fields.CaseError` naming ``source``
    and the line and column of a syntax error."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = _TOML_WHERE.match(str(exc))
        where = f"{source}, line {m['line']}, column {m['col']}" if m else source
        raise CaseError(f"{where}: not valid TOML: {m['msg'] if m else exc}") from None


# ---------------------------------------------------------------------------- documentation
def schema_markdown() -> str:
    """The schema as a Markdown table (docs/case-files.md)."""
    rows = ["| field | kind | shape | default | meaning |", "| --- | --- | --- | --- | --- |"]
    for f in FIELDS:
        kind = f.kind if f.kind in ("text", "count", "flag", "choice") else \
            f"{f.kind} [{symbol(f.kind)}]"
        if f.choices:
            kind += ": " + " / ".join(c or '""' for c in f.choices)
        default = "required" if f.required else repr(f.default)
        rows.append(f"| `{f.key}` | {kind} | {f.shape_text} | {default} | {f.doc} |")
    return "\n".join(rows)


_EXAMPLE = '''```toml
[case]
name = "my_reducer"

[shafts.input]                     # one table per shaft, gear, mesh, bearing, disc
length = ["40 mm", "120 mm"]       # two segments
outer_diameter = ["40 mm", "50 mm"]
young_modulus = "210 GPa"
poisson_ratio = 0.3
density = "7850 kg/m^3"

[gears.pinion]
shaft = "input"
position = "100 mm"                # from the shaft's start
teeth = 21
module = "3 mm"
pressure_angle = "20 deg"
face_width = "40 mm"
mass = "1.2 kg"

[meshes.stage1]
gears = ["pinion", "wheel"]        # the wheel on another shaft
centre_distance = "150 mm"
direction = "0 deg"                # line of centres from the input shaft to the other

[bearings.in_a]
shaft = "input"
position = "40 mm"
diameter = "40 mm"
length = "25 mm"
clearance = "40 um"
viscosity = "0.02 Pa.s"

[drive]
input_shaft = "input"
speed = "3000 rpm"
torque = "200 N.m"
output_shaft = "output"
```'''

_LEGACY = (
    "## Single-stage files of earlier versions\n\n"
    "A file with the sections `[gear_pair]`, `[operation]` or `[drivetrain]`, or with "
    "`[shafts]` and `[bearings]` holding lists per shaft and per bearing, describes the "
    "paper's layout (the single-stage schema of earlier versions). It "
    "still runs: it is translated (`fmu_src/legacy_case.py`) into shafts `pinion_shaft`, "
    "`gear_shaft` (one segment each, `element_length = length / elements`), gears `pinion`, "
    "`gear` at mid-span (a helical pinion left-hand, its gear right-hand), mesh `mesh`, "
    "bearings `1`, `2` (pinion shaft) and `3`, `4` (gear shaft) at the shafts' ends, each of "
    "`bearings.model`; `operation.unbalance = [e1, e2]` becomes each gear's `unbalance` with "
    "`unbalance_mass = \"shaft\"` (Eq. 10), `operation.gravity = true` becomes "
    "`drive.gravity = [0, -9.81]`, the drive enters at the pinion shaft's start and leaves at "
    "the gear shaft's end. Loading one warns once (`fmu_src.case.LegacyCaseWarning`); "
    "`gsb case --upgrade FILE` writes it in the current schema. Overrides with the old keys "
    "(`--set operation.speed=...`) apply to such a file before the translation; an old key "
    "on a current file is an error that names the new key.\n"
)


def document() -> str:
    """The text of docs/case-files.md."""
    return (
        "# Case files\n\n"
        "Generated from `fmu_src/case.py` (`python -m fmu_src.case > "
        "docs/case-files.md`); a test keeps the two in sync.\n\n"
        "A case is a TOML file describing a parallel-axis gear train: one table per shaft, "
        "gear, mesh, bearing and disc, named by you (`[shafts.input]`, `[bearings.3]`; names "
        "of letters, digits and `_`: they name FMU ports and result labels), and the "
        "sections `[case]`, `[drive]` and `[simulation]` once. Positions are measured along "
        "each shaft from its start. The input shaft turns about +z at `drive.speed`; every "
        "other shaft's speed and direction follow from the gear ratios, and its axis lies "
        "at each mesh's `centre_distance` in the mesh's `direction` (`gear_fmu/layout.py`). "
        "The gear graph must be a tree joining every shaft, every mesh on the path from the "
        "input shaft to the output shaft; each shaft sits on at least two bearings. An "
        "excerpt (the shipped `two_stage_reducer` and `overhung_pinion` are whole trains):\n\n"
        + _EXAMPLE + "\n\n"
        "A quantity is a number in the SI unit shown, or a string `\"value unit\"` (`\"4 mm\"`, "
        "`\"20 deg\"`, `\"150 um\"`, `\"325 rad/s\"`, `\"3000 rpm\"`); a unit of the wrong "
        "kind, an unknown section or key, a missing field, a value out of bounds, an unknown "
        "shaft or gear name, gears that do not mesh or parts that overlap on a shaft stop the "
        "run before it starts, with the field named. A single value given for a per-segment "
        "field applies to every segment. In the table a `*` stands for an instance's name. "
        "`gsb run` options override fields without editing the file (`--set "
        "bearings.*.model=short` sets every bearing, `--set bearings.3.clearance=\"120 um\"` "
        "one). The `bearings` fields after `viscosity` are generated from the options the "
        "registered bearing models declare (`bearing_fmu.base.ModelOption`); each bearing's "
        "values are checked against its own model's bounds. Examples: the shipped cases "
        + ", ".join(f"`{n}`" for n in shipped_cases())
        + " (`models/`; `gsb run <name>` runs one by name).\n\n" + schema_markdown() + "\n\n"
        + _LEGACY
    )


if __name__ == "__main__":
    print(document(), end="")

