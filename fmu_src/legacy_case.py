"""Single-stage case files of earlier versions, read as the two-shaft train of the paper.

Before the gear train was data (:mod:`gear_fmu.layout`), a case file described the paper's
layout only: one gear pair (``[gear_pair]``, lists ``[pinion, gear]``), two equal shafts
(``[shafts]``, lists ``[pinion shaft, gear shaft]``), four bearings at the shafts' ends
(``[bearings]``, lists ``[1, 2, 3, 4]``, one model), ``[operation]`` and ``[drivetrain]``.
Such a file still runs: :func:`translate` turns it into the current schema
(:mod:`fmu_src.case`) with a :class:`LegacyCaseWarning`:

* shafts ``pinion_shaft`` and ``gear_shaft``, one segment of ``shafts.length`` each,
  ``element_length = length / elements``;
* gears ``pinion`` and ``gear`` at mid-span, mesh ``mesh`` (direction 0), a helical pinion
  left-hand and its gear right-hand (the mesh element's convention, :mod:`gear_fmu.mesh.element`);
* bearings ``1``, ``2`` on the pinion shaft and ``3``, ``4`` on the gear shaft, at 0 and at the
  shaft's length, each of ``bearings.model``;
* ``operation.unbalance = [e1, e2]``: each gear's unbalance, of the shaft with all it carries
  (``unbalance_mass = "shaft"``, the paper's Eq. 10); ``operation.gravity = true``:
  ``drive.gravity = [0, -9.81]``;
* the drive: input at the pinion shaft's start, output at the gear shaft's end.

:data:`FIELDS` is that schema, kept only as the translator's input: the file's values are
checked against it (units, shapes, bounds, unknown keys) before they are translated, and
overrides given with its keys apply before the translation (:func:`apply_overrides`).
"""

from __future__ import annotations

import difflib
import warnings

from bearing_fmu import MODELS
from fmu_src.fields import CaseError, Field, convert, option_fields
from fmu_src.fields import field_spec as _f
from gear_fmu.drivetrain import OUTPUT_ENDS

__all__ = ["FIELDS", "SECTIONS", "LegacyCaseWarning", "apply_overrides", "check_override",
           "is_legacy", "is_legacy_key", "new_key", "translate"]


class LegacyCaseWarning(UserWarning):
    """A case file in the single-stage schema of earlier versions, read after translation."""


_POS = dict(minimum=0.0, exclusive_minimum=True)
_TWO, _FOUR = dict(shape=2), dict(shape=4)

#: the single-stage schema: its fields, with their shapes and bounds
FIELDS: tuple[Field, ...] = (
    _f("case.name", "text", "identifier of the case"),
    _f("case.description", "text", "free text", default=""),
    _f("gear_pair.teeth", "count", "teeth [pinion, gear]", **_TWO, minimum=5),
    _f("gear_pair.module", "length", "normal module", **_POS),
    _f("gear_pair.pressure_angle", "angle", "normal pressure angle", **_POS, maximum=0.7),
    _f("gear_pair.helix_angle", "angle", "helix angle", default=0.0, minimum=0.0, maximum=0.7),
    _f("gear_pair.profile_shift", "dimensionless", "profile shifts", **_TWO,
       default=[0.0, 0.0], minimum=-1.0, maximum=1.0),
    _f("gear_pair.addendum_coefficient", "dimensionless", "addendum / m_n", default=1.0,
       **_POS),
    _f("gear_pair.dedendum_coefficient", "dimensionless", "dedendum / m_n", default=1.25,
       **_POS),
    _f("gear_pair.face_width", "length", "face widths", **_TWO, **_POS),
    _f("gear_pair.centre_distance", "length", "centre distance", **_POS),
    _f("gear_pair.mass", "mass", "gear body masses", **_TWO, **_POS),
    _f("gear_pair.polar_inertia", "inertia", "polar inertias", **_TWO, default=[0.0, 0.0],
       minimum=0.0),
    _f("gear_pair.diametral_inertia", "inertia", "diametral inertias", **_TWO,
       default=[0.0, 0.0], minimum=0.0),
    _f("shafts.outer_diameter", "length", "outer diameters", **_TWO, **_POS),
    _f("shafts.inner_diameter", "length", "bore diameters", **_TWO, minimum=0.0),
    _f("shafts.length", "length", "length of both shafts", **_POS),
    _f("shafts.young_modulus", "pressure", "Young's modulus", **_POS),
    _f("shafts.poisson_ratio", "dimensionless", "Poisson's ratio", minimum=0.0, maximum=0.5),
    _f("shafts.density", "density", "density", **_POS),
    _f("shafts.elements", "count", "elements per shaft", default=8, minimum=2),
    _f("drivetrain.motor_inertia", "inertia", "motor inertia", default=0.0, minimum=0.0),
    _f("drivetrain.motor_coupling_stiffness", "torsional_stiffness", "motor coupling",
       default=0.0, minimum=0.0),
    _f("drivetrain.motor_coupling_damping", "torsional_damping", "motor coupling damping",
       default=0.0, minimum=0.0),
    _f("drivetrain.output_end", "choice", "output end", default="clamped",
       choices=OUTPUT_ENDS),
    _f("drivetrain.load_inertia", "inertia", "load inertia", default=0.0, minimum=0.0),
    _f("drivetrain.load_coupling_stiffness", "torsional_stiffness", "load coupling",
       default=0.0, minimum=0.0),
    _f("drivetrain.load_coupling_damping", "torsional_damping", "load coupling damping",
       default=0.0, minimum=0.0),
    _f("bearings.model", "choice", "bearing model", default="hybrid", choices=tuple(MODELS)),
    _f("bearings.diameter", "length", "diameters", **_FOUR, **_POS),
    _f("bearings.length", "length", "lengths", **_FOUR, **_POS),
    _f("bearings.clearance", "length", "radial clearances", **_FOUR, **_POS),
    _f("bearings.viscosity", "viscosity", "viscosities", **_FOUR, **_POS),
    *option_fields("bearings."),
    _f("operation.speed", "angular_speed", "pinion speed", **_POS),
    _f("operation.torque", "torque", "input torque", **_POS),
    _f("operation.unbalance", "length", "unbalance [pinion shaft, gear shaft]", **_TWO,
       default=[0.0, 0.0], minimum=0.0),
    _f("operation.gravity", "flag", "gravity along -t", default=False),
)
_BY_KEY = {f.key: f for f in FIELDS}
#: the sections of the single-stage schema; [simulation] is the current schema's
SECTIONS = ("case", "gear_pair", "shafts", "drivetrain", "bearings", "operation", "simulation")
#: sections only a single-stage file has
_OWN = ("gear_pair", "operation", "drivetrain")
#: the names the translation gives
SHAFTS, GEARS, MESH, BEARINGS = ("pinion_shaft", "gear_shaft"), ("pinion", "gear"), "mesh", \
    ("1", "2", "3", "4")
_RENAMED = {"gear_pair.centre_distance": "meshes.*.centre_distance",
            "shafts.elements": "shafts.*.element_length (a length: shaft length / elements)",
            "operation.speed": "drive.speed", "operation.torque": "drive.torque",
            "operation.unbalance": "gears.*.unbalance (with unbalance_mass = \"shaft\")",
            "operation.gravity": "drive.gravity ([g_s, g_t] in m/s^2)"}
_SECTION_TO = {"gear_pair": "gears.*.", "shafts": "shafts.*.", "bearings": "bearings.*.",
               "drivetrain": "drive."}


def is_legacy(data: dict) -> bool:
    """Whether a parsed case file is in the single-stage schema: a section of its own
    (``[gear_pair]``, ``[operation]``, ``[drivetrain]``), or a ``[shafts]``/``[bearings]``
    table of fields rather than of named instances and none of the current schema's own
    sections."""
    if any(s in data for s in _OWN):
        return True
    if any(s in data for s in ("gears", "meshes", "discs", "drive")):
        return False
    return any(isinstance(data.get(s), dict)
               and any(not isinstance(v, dict) for v in data[s].values())
               for s in ("shafts", "bearings"))


def is_legacy_key(key: str) -> bool:
    """Whether ``key`` is a field of the single-stage schema (``operation.speed``)."""
    return key in _BY_KEY


def new_key(key: str) -> str | None:
    """The current schema's key for a single-stage one (``"operation.speed"`` ->
    ``"drive.speed"``, ``"bearings.model"`` -> ``"bearings.*.model"``), None for another key
    or one both schemas share (``simulation.tolerance``)."""
    if key not in _BY_KEY or key.split(".")[0] in ("case", "simulation"):
        return None
    if key in _RENAMED:
        return _RENAMED[key]
    section, name = key.split(".")
    return _SECTION_TO[section] + name


def check_override(key: str, value):
    """One override with a single-stage key on its own: the value in SI, or
    :class:`fmu_src.fields.CaseError` naming the key and the value."""
    return convert(_BY_KEY[key], value, key)


def apply_overrides(data: dict, overrides: dict) -> dict:
    """A single-stage file's data with ``overrides`` (single-stage keys) replacing fields."""
    for key, value in overrides.items():
        section, name = key.split(".")
        data.setdefault(section, {})[name] = value
    return data


def _read(data: dict, source: str) -> dict:
    """The single-stage file's values in SI units, checked against :data:`FIELDS`."""
    for section, content in data.items():
        if section not in SECTIONS:
            close = difflib.get_close_matches(section, SECTIONS, n=1, cutoff=0.75)
            raise CaseError(f"{source}: unknown section [{section}] in a single-stage case "
                            "file" + (f"; did you mean [{close[0]}]?" if close else "")
                            + f" (its sections: {', '.join(SECTIONS)})")
        if not isinstance(content, dict):
            raise CaseError(f"{source}: [{section}] must be a table")
        if section == "simulation":
            continue  # the current schema's fields, checked after the translation
        for key in content:
            if f"{section}.{key}" not in _BY_KEY:
                known = [f.key for f in FIELDS if f.key.startswith(section + ".")]
                close = difflib.get_close_matches(f"{section}.{key}", known, n=1, cutoff=0.75)
                raise CaseError(f"{source}: unknown field {section}.{key} of the single-stage "
                                "schema" + (f"; did you mean {close[0]}?" if close else ""))
    values = {}
    for field in FIELDS:
        section, key = field.key.split(".")
        if key in data.get(section, {}):
            try:
                values[field.key] = convert(field, data[section][key], field.key)
            except CaseError as exc:
                raise CaseError(f"{source}: {exc}") from None
        elif field.required:
            raise CaseError(f"{source}: missing field {field.key} of the single-stage schema "
                            f"({field.doc})")
        else:
            values[field.key] = field.default
    return values


def _shafts(v: dict) -> dict:
    length = v["shafts.length"]
    return {name: {"length": [length], "outer_diameter": [v["shafts.outer_diameter"][i]],
                   "inner_diameter": [v["shafts.inner_diameter"][i]],
                   "young_modulus": v["shafts.young_modulus"],
                   "poisson_ratio": v["shafts.poisson_ratio"], "density": v["shafts.density"],
                   "element_length": length / v["shafts.elements"]}
            for i, name in enumerate(SHAFTS)}


def _gears(v: dict) -> dict:
    helical = v["gear_pair.helix_angle"] > 0.0
    out = {}
    for i, (name, hand) in enumerate(zip(GEARS, ("left", "right"), strict=True)):
        out[name] = {"shaft": SHAFTS[i], "position": 0.5 * v["shafts.length"],
                     "teeth": v["gear_pair.teeth"][i], "hand": hand if helical else "",
                     "unbalance": v["operation.unbalance"][i], "unbalance_mass": "shaft"}
        for key in ("module", "pressure_angle", "helix_angle", "addendum_coefficient",
                    "dedendum_coefficient"):
            out[name][key] = v[f"gear_pair.{key}"]
        for key in ("profile_shift", "face_width", "mass", "polar_inertia",
                    "diametral_inertia"):
            out[name][key] = v[f"gear_pair.{key}"][i]
    return out


def _bearings(v: dict) -> dict:
    options = {f.name: v[f.key] for f in option_fields("bearings.")}
    out = {}
    for j, name in enumerate(BEARINGS):
        out[name] = {"shaft": SHAFTS[j // 2], "position": v["shafts.length"] if j % 2 else 0.0,
                     "model": v["bearings.model"],
                     **{k: v[f"bearings.{k}"][j] for k in ("diameter", "length", "clearance",
                                                            "viscosity")},
                     **options}
    return out


def _drive(v: dict) -> dict:
    out = {"input_shaft": SHAFTS[0], "input_position": 0.0, "speed": v["operation.speed"],
           "torque": v["operation.torque"], "output_shaft": SHAFTS[1],
           "output_position": v["shafts.length"],
           "gravity": [0.0, -9.81] if v["operation.gravity"] else [0.0, 0.0]}
    out.update({k.split(".")[1]: value for k, value in v.items()
                if k.startswith("drivetrain.")})
    return out


def translate(data: dict, source: str, file: str | None = None) -> dict:
    """A single-stage file's data (parsed TOML) -> the data of the same case in the current
    schema (values in SI; module docstring), with a :class:`LegacyCaseWarning` naming
    ``source`` and, for a case ``file``, the command that upgrades it. Its values are checked
    against :data:`FIELDS` first (the messages name ``source`` and the single-stage keys)."""
    v = _read(data, source)
    upgrade = (f"`gsb case --upgrade {file}` writes it in the current schema "
               "(docs/case-files.md)" if file else "docs/case-files.md has the current schema")
    warnings.warn(f"{file or source} is a single-stage case file of an earlier version "
                  "([gear_pair], [operation], lists per shaft and bearing): read as the train "
                  "pinion_shaft, gear_shaft, bearings 1-4, without gyroscopic terms as then "
                  f"(simulation.gyroscopic = false); {upgrade}", LegacyCaseWarning,
                  stacklevel=2)
    return {"case": dict(data.get("case", {})), "shafts": _shafts(v), "gears": _gears(v),
            "meshes": {MESH: {"gears": list(GEARS),
                              "centre_distance": v["gear_pair.centre_distance"]}},
            "bearings": _bearings(v), "drive": _drive(v),
            # the schema's default turned gyroscopic terms on: such a file keeps its physics
            "simulation": {"gyroscopic": False, **data.get("simulation", {})}}
